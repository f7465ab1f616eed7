"""The mechanism of a validated description, by its motion (the one place that knows every motion's module)."""

from __future__ import annotations

from scalesynth.mechanisms.describe.mechanism import DescribedMechanism, from_description_3t
from scalesynth.mechanisms.describe.planar import from_description_2t
from scalesynth.mechanisms.describe.schema import Description
from scalesynth.mechanisms.describe.sixdof import from_description_6dof


def from_description(desc: Description) -> DescribedMechanism:
    """The registered mechanism of a validated description (motion 3T: mechanism.py's, 6DOF: sixdof.py's, 2T:
    planar.py's)."""
    if desc.motion == "2T":
        return from_description_2t(desc)
    if desc.motion == "6DOF":
        return from_description_6dof(desc)
    return from_description_3t(desc)
