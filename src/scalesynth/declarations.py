"""What a mechanism declares about its inputs, below the mechanisms: design parameters, options, and the largest
magnitude of any number a user gives. ``scalesynth.mechanisms.base`` re-exports these; modules the mechanisms build
on (the stiffness sections) read them from here, so nothing below the mechanisms imports them."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Parameter:
    """A numeric design parameter (a length unless ``unit`` says otherwise)."""

    name: str
    default: float
    doc: str
    unit: str = "length"
    positive: bool = True  # must be > 0; otherwise any finite value


@dataclass(frozen=True)
class Option:
    """A non-design setting (working mode, limits, offsets). ``default`` None means 'off' or 'derived'."""

    name: str
    default: Any
    doc: str


# Every number a user gives (design values, bounds, options, grid region, task, poses) is refused above this
# magnitude (config units): the kernels multiply up to a few lengths together and take powers up to 8 of them, and
# 1e12 keeps every such product far inside float64 (1e96 < 1.8e308), so every number written stays finite.
MAX_MAGNITUDE = 1e12
