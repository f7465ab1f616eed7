"""The stiffness frame of a described 2T (planar) mechanism (``scalesynth stiffness``), derived from its description.

A planar frame (FrameModel dim 2, the xy plane, revolute axes along z). Per leg i, with B the base point, Q = P + r_p
the platform joint and E the elbow (RR) or C the carriage (PR) at the pose's joint value:

* RR: the crank, a beam B -> E of group ``arm``, on a revolute actuator at B (a torsional spring to the base); the
  link, a beam E -> Q of group ``forearm``, pinned to the crank at E (revolute ``elbow<i>``);
* PR: a rigid carriage body (reference C) on a prismatic actuator along the rail (a linear spring to the base; the
  rail is part of the rigid base, and the slide holds the carriage's rotation); the link, a beam C -> Q of group
  ``forearm``, pinned to the carriage at C;
* the platform: the pin where the links meet (a point body at Q carrying forces only), each link pinned to it
  (revolute ``wrist<i>``). The load acts there.

This is the seed-004 five-bar's frame with ``forearm: single`` (planar_fivebar.py, the 5R of paper Fig. 7a): the
described five-bar gives the same model. ``joints: bonded`` welds every passive revolute joint (actuators stay
springs) and makes the platform a rigid body, as the hand-written frame does.

The frame needs the legs' platform joints to coincide (one pin): a description whose platform offsets differ relies
on parallelograms to hold the platform's orientation, which this frame does not model (it would leave the platform
free to turn), so ``stiffness`` is refused with one line naming the leg's ``platform``. With equal offsets r_p the
pin is Q = P + r_p and the platform translates, so P deflects as Q.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

Z_AXIS = np.array([0.0, 0.0, 1.0])


def stiffness_model(mech, design: Mapping[str, float], opts: Mapping[str, Any], pose, joints: str = "ideal"):
    """The planar FrameModel at platform point ``pose`` = (x, y) in the kernel's branch (module docstring);
    InvalidPose outside the workspace (out of reach in that branch or outside the actuator ranges),
    InvalidParameter when the legs' platform joints do not coincide."""
    from scalesynth.errors import InvalidParameter, InvalidPose
    from scalesynth.mechanisms.describe.frame import link_groups
    from scalesynth.stiffness.model import Body, FrameModel, Joint, Link
    from scalesynth.stiffness.sections import tube_section

    p = mech.check_vector("pose", pose, 2)
    label = mech.kernel_branch(opts)
    legs = mech.legs(design, opts)
    scale = max(1.0, *(float(np.abs(leg.base).max()) + leg.arm + leg.forearm for leg in legs))
    for i, leg in enumerate(legs[1:], 1):
        if np.abs(leg.platform - legs[0].platform).max() > 1e-12 * scale:
            k = mech.plans[i].leg_index
            raise InvalidParameter(f"legs[{k}] ({mech.description.legs[k].name}).platform: the planar stiffness "
                                   "frame needs every link pinned at one platform point (equal platform offsets)")
    q = {s.label: s.values for s in mech.inverse_kinematics(design, opts, p)}.get(label)
    if q is None or not all(leg.within_limits(float(qi)) for leg, qi in zip(legs, q, strict=True)):
        raise InvalidPose(f"pose: ({p[0]:g}, {p[1]:g}) is outside the workspace (branch {label}, limits included)")
    unit_name = mech.default_length_unit
    sec = {g: tube_section(opts, g, unit_name) for g in link_groups(legs[0].type.code)}
    k_act = opts["actuator_stiffness"]
    bonded = joints == "bonded"
    pin = p + legs[0].platform
    links: list[Link] = []
    frame_joints: list[Joint] = []
    bodies = [Body("base", np.zeros(2))]

    def link(name, group, a, b):
        s = sec[group]
        links.append(Link(name, group, np.array(a, dtype=float), np.array(b, dtype=float), s.EA, s.EI, s.EI, s.GJ))

    def joint(name, kind, at, a, b, axis=Z_AXIS, stiffness=None):
        if bonded and stiffness is None and kind == "revolute":  # a passive joint welded shut (moment-carrying)
            kind, axes = "fixed", ()
        else:
            axes = (np.asarray(axis, dtype=float),)
        frame_joints.append(Joint(name, kind, np.array(at, dtype=float), (a, b), axes, stiffness))

    for i, (leg, qi) in enumerate(zip(legs, q, strict=True), 1):
        e = leg.actuated_point(float(qi))
        if leg.rotary:
            link(f"arm{i}", "arm", leg.base, e)
            joint(f"actuator{i}", "revolute", leg.base, f"arm{i}.a", "base", stiffness=k_act)
            holder = f"arm{i}.b"
            link(f"forearm{i}", "forearm", e, pin)
            joint(f"elbow{i}", "revolute", e, holder, f"forearm{i}.a")
        else:
            holder = f"carriage{i}"
            bodies.append(Body(holder, e.copy()))
            joint(f"actuator{i}", "prismatic", e, holder, "base", axis=(*leg.u, 0.0), stiffness=k_act)
            link(f"forearm{i}", "forearm", e, pin)
            joint(f"pin{i}", "revolute", e, holder, f"forearm{i}.a")
        joint(f"wrist{i}", "revolute", pin, f"forearm{i}.b", "platform")
    bodies.append(Body("platform", pin.copy(), "rigid" if bonded else "point"))
    kind = "crank" if legs[0].rotary else "carriage"
    notes = [f"described mechanism {mech.name}: planar frame in the xy plane, revolute axes along z; each leg's "
             f"{kind} on its actuator spring, its link pinned to it and to the platform pin where the load acts",
             f"branch {label}"]
    if np.abs(legs[0].platform).max() > 0.0:
        notes.append("platform offsets r_p = (" + ", ".join(f"{v:g}" for v in legs[0].platform) + f") {unit_name}: "
                     "the pin is P + r_p, and the translating platform deflects as it")
    if bonded:
        notes.append("joints bonded: every passive joint welded (carries moments), actuators stay springs")
    return FrameModel(2, unit_name, tuple(links), tuple(frame_joints), tuple(bodies), "platform",
                      np.asarray(opts["load"], dtype=float), tuple(notes))


def pack_stiffness(mech, design: Mapping[str, float], opts: Mapping[str, Any], p: np.ndarray) -> None:
    """Fill the stiffness block of a packed vector (kernel2.py: flag, load, per leg the crank's EA and EI, the
    link's EA and the actuator spring) from the same sections and options as stiffness_model; the legs' kinematic
    slots are already packed. InvalidParameter where the legs' platform joints do not coincide (as there)."""
    from scalesynth.errors import InvalidParameter
    from scalesynth.mechanisms.describe import kernel2 as _k
    from scalesynth.mechanisms.describe.bodies import joints_coincide
    from scalesynth.mechanisms.describe.frame import link_groups
    from scalesynth.stiffness.sections import tube_section

    legs = mech.legs(design, opts)
    if not joints_coincide(legs):
        k = mech.plans[1].leg_index
        raise InvalidParameter(f"legs[{k}] ({mech.description.legs[k].name}).platform: the per-voxel stiffness "
                               "fields need every link pinned at one platform point (equal platform offsets)")
    groups = {g: tube_section(opts, g, mech.default_length_unit) for g in link_groups(legs[0].type.code)}
    bar = groups["forearm"]
    arm = groups.get("arm", bar)  # PR: no crank (slots unused)
    for i in range(len(legs)):
        s = _k.SLEGS + i * _k.SSTRIDE
        p[s + _k.EA_ARM], p[s + _k.EI_ARM] = arm.EA, arm.EI
        p[s + _k.EA_BAR] = bar.EA
        p[s + _k.K_ACT] = opts["actuator_stiffness"]
    p[_k.STIFF] = 1.0
    p[_k.LOAD : _k.LOAD + 2] = opts["load"]
