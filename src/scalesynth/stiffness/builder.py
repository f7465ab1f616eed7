"""Assembling a spatial :class:`~scalesynth.stiffness.model.FrameModel` in a mechanism's ``stiffness_model``: round-tube
links by group, joints with unit axes, and the 'bonded' variant (passive rotational joints welded)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from scalesynth.stiffness.model import Body, FrameModel, Joint, Link
from scalesynth.stiffness.sections import Section

WELDABLE = ("revolute", "universal", "spherical")  # passive joints that 'bonded' welds; slides stay slides


def unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


class FrameBuilder:
    """Links and joints of one spatial frame. ``sections``: {group: Section}; ``joints``: 'ideal' or 'bonded'
    (every passive revolute, universal and spherical joint welded; actuators and passive slides kept)."""

    def __init__(self, sections: Mapping[str, Section], joints: str = "ideal"):
        self.sections = sections
        self.bonded = joints == "bonded"
        self.links: list[Link] = []
        self.joints: list[Joint] = []

    def link(self, name: str, group: str, start, end) -> None:
        """A beam of group ``group`` from ``start`` to ``end``; its section's local y axis is z made normal to the
        beam (x for a beam within ~25 deg of vertical): a round tube, so only for the record."""
        s = self.sections[group]
        start, end = np.array(start, dtype=float), np.array(end, dtype=float)
        up = np.array([0.0, 0.0, 1.0]) if abs(unit(end - start)[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
        self.links.append(Link(name, group, start, end, s.EA, s.EI, s.EI, s.GJ, up))

    def joint(self, name: str, kind: str, at, part_a: str, part_b: str, axes: Sequence = (),
              stiffness: float | None = None) -> None:
        """A joint (model.Joint) with its axes normalised; welded when bonded and passive and rotational."""
        if self.bonded and stiffness is None and kind in WELDABLE:
            kind, axes = "fixed", ()
        self.joints.append(Joint(name, kind, np.array(at, dtype=float), (part_a, part_b),
                                 tuple(unit(a) for a in axes), stiffness))

    def model(self, length_unit: str, bodies: Sequence[Body], load, notes: Sequence[str]) -> FrameModel:
        """The FrameModel (spatial, platform body 'platform'); a note records the bonded variant."""
        notes = list(notes)
        if self.bonded:
            notes.append("joints bonded: every passive revolute, universal and spherical joint welded (carries "
                         "moments), actuators and slides kept")
        return FrameModel(3, length_unit, tuple(self.links), tuple(self.joints), tuple(bodies), "platform",
                          np.asarray(load, dtype=float), tuple(notes))
