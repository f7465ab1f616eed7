"""The stiffness frame of a described 6-DOF mechanism (``scalesynth stiffness``), derived from its description.

Per leg i, with B the base point, Q = P + R r the platform joint at the options' orientation R, f = Q - E (RUS, E
the elbow) or Q - B (UPS) and a pair of unit axes (a1, a2) normal to f (a1 = unit(n x f), n the arm's axis or, for a
UPS leg, the base joint's cone axis; a2 = unit(f) x a1):

* RUS / R-SS: the arm, a beam B -> E of group ``upper_arm`` on a revolute actuator about the arm's axis at B (a
  torsional spring to the base); the rod, a beam E -> Q of group ``rod``, on a universal joint (a1, a2) at the elbow
  and a spherical joint at the platform. The universal joint holds the rod's spin (a rod between two spherical
  joints could spin freely: no stiffness about its own axis), and with no moment passed at either end the rod is
  a bar: it carries only its axial force.
* UPS / SPS: the leg as two collinear beams of group ``leg``, the cylinder B -> M and the piston M -> Q (M the
  leg's midpoint), joined at M by a prismatic actuator along f (a linear spring), with a universal joint (a1, a2)
  to the base at B and a spherical joint to the platform at Q: a bar whose axial compliance is
  1/k + L / EA (L the leg's length, k the actuator stiffness).
* a rigid platform with reference point P, where the load (a force) acts; its DOFs x, y, z, rx, ry, rz.

For the hexapod this is the classical Gough-Stewart stiffness K = J^T diag(k_i) J (Gosselin 1990), J the rows
[n_i, rho_i x n_i] of the unit legs n_i, rho_i = R r_i, with 1/k_i = 1/k + L_i / EA (tests/test_sixdof_stiffness.py
asserts it). Sections: the shared stiffness options (round tubes of one material, ``sections`` by group).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np


def _normal_axes(f: np.ndarray, n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two orthogonal unit axes normal to f: a1 = unit(n x f) (another direction where n is along f), a2 = f x a1."""
    from scalesynth.stiffness.builder import unit

    fu = unit(f)
    a1 = np.cross(n, fu)
    if np.linalg.norm(a1) < 1e-6:
        a1 = np.cross((1.0, 0.0, 0.0) if abs(fu[0]) < 0.9 else (0.0, 1.0, 0.0), fu)
    a1 = unit(a1)
    return a1, np.cross(fu, a1)


def stiffness_model(mech, design: Mapping[str, float], opts: Mapping[str, Any], pose, joints: str = "ideal"):
    """The FrameModel at platform centre ``pose`` (the options' orientation) in the kernel's branch (module
    docstring); InvalidPose outside the workspace."""
    from scalesynth.errors import InvalidPose
    from scalesynth.mechanisms.describe.frame import link_groups
    from scalesynth.stiffness.builder import FrameBuilder
    from scalesynth.stiffness.model import Body
    from scalesynth.stiffness.sections import tube_section

    p = mech.check_vector("pose", pose, 3)
    if mech.point_kernel(mech.pack(design, opts), *p) < 0.0:
        raise InvalidPose(f"pose: ({p[0]:g}, {p[1]:g}, {p[2]:g}) is outside the workspace (branch "
                          f"{mech.kernel_branch(opts)}, orientation {opts['orientation']}, limits included)")
    label = mech.kernel_branch(opts)
    (q,) = [s.values for s in mech.inverse_kinematics(design, opts, p) if s.label == label]
    legs = mech.legs(design, opts)
    rot = mech.rotation(opts)
    unit_name = mech.default_length_unit
    fb = FrameBuilder({g: tube_section(opts, g, unit_name) for g in link_groups(legs[0].type.code)}, joints)
    k = opts["actuator_stiffness"]
    for i, (leg, qi) in enumerate(zip(legs, q, strict=True), 1):
        jq = p + rot @ leg.r
        if leg.rus:
            e = leg.actuated_point(float(qi))
            fb.link(f"upper_arm{i}", "upper_arm", leg.base, e)
            fb.joint(f"actuator{i}", "revolute", leg.base, f"upper_arm{i}.a", "base", (leg.axis,), k)
            fb.link(f"rod{i}", "rod", e, jq)
            fb.joint(f"U_elbow{i}", "universal", e, f"upper_arm{i}.b", f"rod{i}.a", _normal_axes(jq - e, leg.axis))
            fb.joint(f"S_platform{i}", "spherical", jq, f"rod{i}.b", "platform")
        else:
            m = 0.5 * (leg.base + jq)
            fb.link(f"cylinder{i}", "leg", leg.base, m)
            fb.link(f"piston{i}", "leg", m, jq)
            fb.joint(f"U_base{i}", "universal", leg.base, f"cylinder{i}.a", "base", _normal_axes(jq - leg.base,
                                                                                                 leg.axis))
            fb.joint(f"actuator{i}", "prismatic", m, f"cylinder{i}.b", f"piston{i}.a", (jq - leg.base,), k)
            fb.joint(f"S_platform{i}", "spherical", jq, f"piston{i}.b", "platform")
    bodies = [Body("base", np.zeros(3)), Body("platform", p.copy())]
    legs_note = ("each arm on its actuator spring, each rod a bar on a universal joint at the elbow and a spherical "
                 "joint at the platform (RUS)" if legs[0].rus else
                 "each leg a cylinder and a piston joined by the prismatic actuator's spring, on a universal joint "
                 "at the base and a spherical joint at the platform (UPS)")
    notes = [f"described mechanism {mech.name}: {legs_note}; rigid platform with reference point P where the load "
             "acts; its DOFs x, y, z, rx, ry, rz",
             f"orientation [roll, pitch, yaw] {list(opts['orientation'])} rad; branch {label}"]
    return fb.model(unit_name, bodies, opts["load"], notes)
