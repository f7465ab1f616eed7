"""The kinetostatic model of one mechanism at one pose: elastic links, joints, actuator springs, rigid bodies.

A :class:`FrameModel` is what a mechanism's ``stiffness_model`` method returns and what the ``stiffness`` command
prints (``to_dict``), so that anyone can rebuild the same frame in another solver. Idealisation (docs/stiffness.md):
links are straight Euler-Bernoulli beams between joint centres; passive joints are ideal (no force or moment along
their free directions); an actuated joint is a passive joint plus a spring along its free direction (torsional for a
revolute, linear for a prismatic actuator) to the body on its other side; bodies other than the links (base,
platform, hinge plates) are rigid; deflections are small and linear-elastic.

Units: lengths in the mechanism's length unit (mm or m), forces in N, so EA in N, EI and GJ in N * length^2,
revolute actuator stiffness in N * length / rad, prismatic actuator stiffness in N / length.

A part of a joint is named ``"base"``, a body name (``"platform"``, ``"plate1"``) or a link end ``"<link>.a"`` /
``"<link>.b"`` (``a`` is the link's ``start`` point, ``b`` its ``end`` point).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

JOINT_KINDS = ("fixed", "revolute", "spherical", "universal", "prismatic")


@dataclass(frozen=True)
class Link:
    """A straight beam from ``start`` to ``end`` (points, 2 or 3 coordinates) of group ``group`` (arm, forearm...).

    Planar models use EA and EI (bending in the plane); spatial ones EA, EIy, EIz (bending about the section's local
    y and z axes; local y is ``up`` made orthogonal to the beam) and GJ."""

    name: str
    group: str
    start: np.ndarray
    end: np.ndarray
    EA: float
    EIy: float
    EIz: float
    GJ: float
    up: np.ndarray | None = None

    @property
    def length(self) -> float:
        return float(np.linalg.norm(self.end - self.start))


@dataclass(frozen=True)
class Joint:
    """A joint at point ``at`` between two parts (see module docstring).

    ``axes``: unit vectors of the free directions: rotation axes for revolute (1) and universal (2) joints, the
    sliding axis for a prismatic joint, none for fixed and spherical joints (a spherical joint frees every
    rotation). In a planar model every revolute axis is the plane normal (0, 0, 1). ``stiffness`` > 0 makes it an
    actuated joint: a spring along its single free direction; None for a passive joint."""

    name: str
    kind: str
    at: np.ndarray
    parts: tuple[str, str]
    axes: tuple[np.ndarray, ...] = ()
    stiffness: float | None = None


@dataclass(frozen=True)
class Body:
    """A rigid body with reference point ``ref``; ``kind`` 'rigid' (translations and rotations) or 'point' (a pin
    carrying forces only: every joint to it is at ``ref`` and transmits no moment)."""

    name: str
    ref: np.ndarray
    kind: str = "rigid"


@dataclass(frozen=True)
class FrameModel:
    """Links, joints and bodies of one mechanism at one pose; ``dim`` 2 (planar, in the xy plane) or 3.

    ``platform`` names the body whose compliance is wanted (its reference point is the mechanism's task point);
    ``load`` is the force (N, ``dim`` entries) applied there; ``length_unit`` is 'mm' or 'm'."""

    dim: int
    length_unit: str
    links: tuple[Link, ...]
    joints: tuple[Joint, ...]
    bodies: tuple[Body, ...]
    platform: str
    load: np.ndarray
    notes: tuple[str, ...] = field(default_factory=tuple)

    def body(self, name: str) -> Body:
        for b in self.bodies:
            if b.name == name:
                return b
        raise KeyError(name)

    @property
    def actuators(self) -> tuple[Joint, ...]:
        return tuple(j for j in self.joints if j.stiffness is not None)

    def to_dict(self) -> dict:
        """JSON-ready description (every unit stated), the ``model`` of the ``stiffness`` command."""
        u = self.length_unit

        def pt(v):
            return [float(c) for c in v]

        links = []
        for link in self.links:
            row = {"name": link.name, "group": link.group, "from": pt(link.start), "to": pt(link.end),
                   "length": link.length, "EA": link.EA}
            if self.dim == 2:
                row["EI"] = link.EIz
            else:
                row.update({"EIy": link.EIy, "EIz": link.EIz, "GJ": link.GJ, "up": pt(link.up)})
            links.append(row)
        joints = [{"name": j.name, "kind": j.kind, "at": pt(j.at), "parts": list(j.parts),
                   "axes": [pt(a) for a in j.axes]} for j in self.joints]
        actuators = []
        for j in self.actuators:
            rot = j.kind == "revolute"
            actuators.append({"joint": j.name, "at": pt(j.at), "axis": pt(j.axes[0]), "kind": j.kind,
                              "between": list(j.parts), "stiffness": j.stiffness,
                              "stiffness_unit": f"N*{u}/rad" if rot else f"N/{u}"})
        return {
            "dim": self.dim,
            "units": {"length": u, "force": "N", "EA": "N", "EI": f"N*{u}^2", "GJ": f"N*{u}^2",
                      "compliance": f"{u}/N", "stiffness": f"N/{u}"},
            "links": links,
            "joints": joints,
            "actuators": actuators,
            "bodies": [{"name": b.name, "ref": pt(b.ref), "kind": b.kind} for b in self.bodies],
            "platform": {"body": self.platform, "point": pt(self.body(self.platform).ref),
                         "kind": self.body(self.platform).kind},
            "load": {"force": pt(self.load), "unit": "N", "at": pt(self.body(self.platform).ref)},
            "notes": list(self.notes),
        }
