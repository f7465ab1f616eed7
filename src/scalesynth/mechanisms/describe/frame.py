"""The stiffness frame of a described mechanism (``scalesynth stiffness``), derived from its description.

Per leg i, with B the base point, E the elbow (R-Pa) or carriage point (P-Pa), Q = P + r_p the platform joint,
n the normal of the leg's plane (R-Pa: the actuated axis), h half the parallelogram's ``width`` and
t = unit(n x f), f = Q - E the forearm:

* R-Pa: the upper arm, a beam B -> E of group ``upper_arm``, on a revolute actuator about n at B (a torsional
  spring to the base); a rigid elbow body (reference E) welded to its end, carrying the parallelogram's short side;
* P-Pa: a rigid carriage body (reference E) on a prismatic actuator along the rail (a linear spring to the base;
  the rail is part of the rigid base);
* the parallelogram: two beams of group ``forearm``, E +- h n -> Q +- h n, each on universal joints (t, n) at the
  elbow or carriage and at the platform (t turns with the bar, n is fixed in the other part): the RUU Delta. The
  joints hold each bar's spin, and the two bars together hold the platform's rotations about t and n x t;
* a rigid platform with reference point P, where the load (a force) acts.

The platform keeps all six DOFs (its rotations are held elastically by the parallelograms' bending, not rigidly),
the deflection is that of P. Sections: the shared stiffness options (round tubes of one material,
``stiffness.sections``), whose defaults a description's ``stiffness:`` block sets (StiffnessSpec); a leg needs a
width > 0 (one bar on the centre line would leave the platform free to turn).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

# actuator stiffness defaults in SI (assumptions, as the seed mechanisms'): a geared servo arm, a ball-screw carriage
ROTARY_STIFFNESS_NM_PER_RAD = 1e5  # N m / rad
LINEAR_STIFFNESS_N_PER_M = 2e7  # N / m
LOAD_N = [0.0, 0.0, -150.0]  # N: 150 N down -z (z up in the Delta conventions)
LOAD_2T_N = [0.0, -150.0]  # N: motion 2T, 150 N along -y (the seed-004 five-bar's: its workspace below the base)
STIFFNESS_OPTIONS = ("youngs_modulus", "poisson_ratio", "tube", "sections", "actuator_stiffness", "load")


class StiffnessSpec(BaseModel):
    """A description's ``stiffness:`` block: the defaults of the stiffness options (null = the shared default:
    aluminium 70 GPa, nu 0.33, a 40 x 3 mm tube; actuators 1e5 N m/rad rotary, 2e7 N/m linear). Lengths in the
    description's length unit; ``sections`` by link group (upper_arm, forearm; 6-DOF: upper_arm, rod or leg; 2T: arm,
    forearm)."""

    model_config = ConfigDict(extra="forbid")

    youngs_modulus: float | None = Field(None, description="GPa")
    poisson_ratio: float | None = None
    tube: list[float] | None = Field(None, description="[outer diameter, wall], length unit")
    sections: dict[str, list[float]] = {}
    actuator_stiffness: float | None = Field(None, description="N length/rad (rotary) or N/length (linear)")


def link_groups(code: float) -> tuple[str, ...]:
    """The elastic link groups of the frame of a mechanism whose legs have type code ``code`` (kernel codes)."""
    from scalesynth.mechanisms.describe import kernel as _k
    from scalesynth.mechanisms.describe import kernel2 as _k2
    from scalesynth.mechanisms.describe import kernel6 as _k6

    return {_k.R_PA: ("upper_arm", "forearm"), _k.P_PA: ("forearm",), _k6.RUS: ("upper_arm", "rod"),
            _k6.UPS: ("leg",), _k2.RR: ("arm", "forearm"), _k2.PR: ("forearm",)}[code]


def load_dim(code: float) -> int:
    """Force components of the load of a mechanism whose legs have type code ``code``: 2 for a planar (2T) one."""
    from scalesynth.mechanisms.describe import kernel2 as _k2

    return 2 if code in (_k2.RR, _k2.PR) else 3


def options(spec: StiffnessSpec | None, length_unit: str, rotary: bool, planar: bool = False):
    """The stiffness Options of a described mechanism: the shared ones (sections.stiffness_options) with the
    description's defaults laid over them; ``planar`` (motion 2T): a load in the plane."""
    from scalesynth.mechanisms.base import Option
    from scalesynth.mechanisms.describe.bodies import UNITS_PER_M
    from scalesynth.stiffness.sections import stiffness_options

    per_m = UNITS_PER_M[length_unit]
    if rotary:
        k, doc = ROTARY_STIFFNESS_NM_PER_RAD * per_m, f"torsional stiffness of each arm actuator, N {length_unit}/rad"
    else:
        k, doc = LINEAR_STIFFNESS_N_PER_M / per_m, f"axial stiffness of each carriage actuator, N/{length_unit}"
    load, where = (LOAD_2T_N, "default 150 N along -y at P") if planar else (LOAD_N, "default 150 N down -z at P")
    shared = stiffness_options(length_unit, k, doc + " (an assumption)", load, where)
    given = {} if spec is None else {k: v for k, v in spec.model_dump().items() if v is not None and v != {}}
    return tuple(Option(o.name, given.get(o.name, o.default), o.doc) for o in shared)


def stiffness_model(mech, design: Mapping[str, float], opts: Mapping[str, Any], pose, joints: str = "ideal"):
    """The FrameModel at platform centre ``pose`` in the kernel's branch (module docstring); InvalidPose outside
    the workspace, InvalidParameter for a leg without a parallelogram width."""
    from scalesynth.errors import InvalidParameter, InvalidPose
    from scalesynth.mechanisms.describe import kernel as _k
    from scalesynth.mechanisms.describe.bodies import widths
    from scalesynth.stiffness.builder import FrameBuilder, unit
    from scalesynth.stiffness.model import Body
    from scalesynth.stiffness.sections import tube_section

    p = mech.check_vector("pose", pose, 3)
    if mech.point_kernel(mech.pack(design, opts), *p) < 0.0:
        raise InvalidPose(f"pose: ({p[0]:g}, {p[1]:g}, {p[2]:g}) is outside the workspace (branch "
                          f"{mech.kernel_branch(opts)}, limits included)")
    label = mech.kernel_branch(opts)
    (q,) = [s.values for s in mech.inverse_kinematics(design, opts, p) if s.label == label]
    legs = mech.legs(design, opts)
    ws = widths(mech.plans, design)
    for plan, w in zip(mech.plans, ws, strict=True):
        if not w > 0.0:
            leg = mech.description.legs[plan.leg_index]
            raise InvalidParameter(f"legs[{plan.leg_index}] ({leg.name}).width: the stiffness frame needs the "
                                   "parallelogram's width > 0 (one bar would leave the platform free to turn)")
    rotary = legs[0].type.code == _k.R_PA
    unit_name = mech.default_length_unit
    fb = FrameBuilder({g: tube_section(opts, g, unit_name) for g in link_groups(legs[0].type.code)}, joints)
    k = opts["actuator_stiffness"]
    bodies = [Body("base", np.zeros(3))]
    for i, (leg, qi, w) in enumerate(zip(legs, q, ws, strict=True), 1):
        e = leg.actuated_point(float(qi))
        jq = p + leg.platform
        n = leg.normal
        side = 0.5 * w * n
        t = unit(np.cross(n, jq - e))
        if leg.type.code == _k.R_PA:
            holder = f"elbow{i}"
            fb.link(f"upper_arm{i}", "upper_arm", leg.base, e)
            fb.joint(f"actuator{i}", "revolute", leg.base, f"upper_arm{i}.a", "base", (n,), k)
            bodies.append(Body(holder, e.copy()))
            fb.joint(f"elbow_weld{i}", "fixed", e, f"upper_arm{i}.b", holder)
        else:
            holder = f"carriage{i}"
            bodies.append(Body(holder, e.copy()))
            fb.joint(f"actuator{i}", "prismatic", e, holder, "base", (leg.u,), k)
        for tag, s in (("a", 1.0), ("b", -1.0)):
            bar = f"forearm{i}{tag}"
            fb.link(bar, "forearm", e + s * side, jq + s * side)
            # axes in the order of the parts: t turns with the bar, n is fixed in the elbow/carriage and platform
            fb.joint(f"U_{holder}{tag}", "universal", e + s * side, f"{bar}.a", holder, (t, n))
            fb.joint(f"U_platform{i}{tag}", "universal", jq + s * side, f"{bar}.b", "platform", (t, n))
    bodies.append(Body("platform", p.copy()))
    kind = "arm" if rotary else "carriage"
    notes = [f"described mechanism {mech.name}: each leg's {kind} on its actuator spring, the parallelogram as two "
             "bars on universal joints (RUU), rigid platform with reference point P where the load acts; the "
             "parallelograms hold the platform's rotations elastically, so its DOFs are x, y, z, rx, ry, rz",
             f"parallelogram widths {', '.join(f'{w:g}' for w in ws)} {unit_name}; branch {label}"]
    return fb.model(unit_name, bodies, opts["load"], notes)


def pack_stiffness(mech, design: Mapping[str, float], opts: Mapping[str, Any], p: np.ndarray) -> None:
    """Fill the stiffness block of a packed vector (kernel.py: flag, load, characteristic length, per leg the
    sections, actuator spring and half width) from the same sections and options as stiffness_model; the legs'
    kinematic slots are already packed. InvalidParameter for a leg without a parallelogram width (as there)."""
    from scalesynth.errors import InvalidParameter
    from scalesynth.mechanisms.describe import kernel as _k
    from scalesynth.mechanisms.describe.bodies import widths
    from scalesynth.stiffness.sections import tube_section

    unit_name = mech.default_length_unit
    groups = {g: tube_section(opts, g, unit_name) for g in link_groups(p[_k.HEAD + _k.TYPE])}
    bar = groups["forearm"]
    arm = groups.get("upper_arm", bar)  # P-Pa: no upper arm (slots unused)
    longest = 0.0
    for i, (plan, w) in enumerate(zip(mech.plans, widths(mech.plans, design), strict=True)):
        if not w > 0.0:
            leg = mech.description.legs[plan.leg_index]
            raise InvalidParameter(f"legs[{plan.leg_index}] ({leg.name}).width: the stiffness fields need the "
                                   "parallelogram's width > 0 (one bar would leave the platform free to turn)")
        k = _k.HEAD + i * _k.STRIDE
        s = _k.SLEGS + i * _k.SSTRIDE
        p[s + _k.EA_ARM], p[s + _k.EI_ARM], p[s + _k.GJ_ARM] = arm.EA, arm.EI, arm.GJ
        p[s + _k.EA_BAR], p[s + _k.EI_BAR], p[s + _k.GJ_BAR] = bar.EA, bar.EI, bar.GJ
        p[s + _k.K_ACT] = opts["actuator_stiffness"]
        p[s + _k.HALF_WIDTH] = 0.5 * w
        rotary = p[k + _k.TYPE] == _k.R_PA
        longest = max(longest, p[k + _k.FOREARM], p[k + _k.ARM] if rotary else 0.0)
    p[_k.STIFF] = 1.0
    p[_k.LOAD : _k.LOAD + 3] = opts["load"]
    p[_k.CHAR_LEN] = longest  # the reference solver's: its longest link (solve.solve)


def check_spec(spec: StiffnessSpec | None, length_unit: str, code: float) -> None:
    """A description's ``stiffness:`` block checked as the options it sets; ConfigError 'stiffness.<field>: ...'."""
    from scalesynth.errors import ConfigError, InvalidParameter
    from scalesynth.stiffness.sections import check_stiffness_options

    if spec is None:
        return
    from scalesynth.mechanisms.describe.legs import LEG_TYPES

    rotary = next(lt for lt in LEG_TYPES.values() if lt.code == code).joint_unit == "angle"
    values = {o.name: o.default for o in options(spec, length_unit, rotary, load_dim(code) == 2)}
    try:
        check_stiffness_options(values, load_dim(code), link_groups(code))
    except InvalidParameter as err:
        raise ConfigError(str(err).replace("options.", "stiffness.", 1)) from None
