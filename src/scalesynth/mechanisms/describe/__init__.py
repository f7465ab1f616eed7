"""Mechanisms as data: a description (schema), a leg library with closed-form IK (legs), the Numba field-kernel
template (kernel) and the Mechanism they make (mechanism). docs/describing.md is the user's guide."""

from __future__ import annotations

from pathlib import Path

from scalesynth.mechanisms.describe.mechanism import DescribedMechanism, from_description
from scalesynth.mechanisms.describe.schema import Description, load_description, parse_description

__all__ = ["Description", "DescribedMechanism", "builtin", "from_description", "load_description",
           "parse_description"]

BUILTIN_DIR = Path(__file__).resolve().parent.parent  # the built-in description files sit beside the modules


def builtin(name: str) -> DescribedMechanism:
    """The mechanism of the built-in description file ``<name>.yaml`` in scalesynth/mechanisms/."""
    return from_description(load_description(BUILTIN_DIR / f"{name}.yaml"))
