"""Mechanisms as data: a description (schema), a leg library with closed-form IK (legs), the Numba field-kernel
template (kernel) and the Mechanism they make (mechanism). docs/describing.md is the user's guide."""

from __future__ import annotations

from pathlib import Path

from scalesynth.mechanisms.describe import mobility_check, schema
from scalesynth.mechanisms.describe.build import from_description
from scalesynth.mechanisms.describe.mechanism import DescribedMechanism
from scalesynth.mechanisms.describe.schema import Description, load_description, parse_description

# looked up at each call, so that a test may switch it off (monkeypatch mobility_check.check_mobility)
schema.MOBILITY_CHECK = lambda desc: mobility_check.check_mobility(desc)

__all__ = ["Description", "DescribedMechanism", "builtin", "builtin_names", "builtin_path", "from_description",
           "load_description", "parse_description"]

BUILTIN_DIR = Path(__file__).resolve().parent.parent  # the built-in description files sit beside the modules



def builtin_path(name: str) -> Path:
    """The built-in description file of mechanism ``name`` (it may not exist)."""
    return BUILTIN_DIR / f"{name}.yaml"


def builtin_names() -> list[str]:
    """Names of the built-in description files in scalesynth/mechanisms/, sorted."""
    return sorted(p.stem for p in BUILTIN_DIR.glob("*.yaml"))


def builtin(name: str) -> DescribedMechanism:
    """The mechanism of the built-in description file ``<name>.yaml`` in scalesynth/mechanisms/."""
    return from_description(load_description(builtin_path(name)))
