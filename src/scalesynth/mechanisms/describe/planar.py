"""Described 2T (planar) mechanisms: two RR or PR legs in the plane z = 0, NumPy kinematics, packing for kernel2.py,
link geometry and the Mechanism.

The task axes are x, y; the platform translates (a single point where the links meet, or a body whose orientation
parallelograms hold, as on the seed-004 five-bar). Description points and directions are 3-vectors with z = 0
(schema.py checks it); here they are 2-vectors. Forward kinematics intersects the two circles (RR: radius l about
the elbow minus the platform offset; PR alike about the carriage). docs/describing.md ("Planar legs") states it for
users; the kernel's docstring gives the closed forms.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from scalesynth.errors import InvalidParameter, InvalidPose
from scalesynth.mechanisms import links
from scalesynth.mechanisms.base import (
    DesignMetric,
    Field,
    Option,
    Parameter,
    Solution,
    base_fields,
    check_magnitude,
    parse_range,
    svd_lci,
    wrap_angle,
)
from scalesynth.mechanisms.describe import bodies, expressions, frame, frame2
from scalesynth.mechanisms.describe import kernel2 as _k
from scalesynth.mechanisms.describe.legs import LEG_TYPES, LegType
from scalesynth.mechanisms.describe.mechanism import (
    CLEARANCE,
    CLEARANCE_METRICS_OPTION,
    INTERFERENCE_FREE_OPTION,
    STIFFNESS_METRICS_OPTION,
    DescribedMechanism,
    _footprint,
    _plans,
    _turn,
    _unit,
    pack_clearance,
)
from scalesynth.mechanisms.describe.schema import Description
from scalesynth.stiffness import legs as _sl
from scalesynth.stiffness.sections import check_stiffness_options

# capsule radii (m) when link_radius does not give them: the seed-004 five-bar's illustrative ones (25, 20, 15, 40 mm)
PLANAR_RADII_M = {"base": 0.025, "arm": 0.02, "forearm": 0.015, "platform": 0.04, "rail": 0.02, "carriage": 0.03}
LINK_RADIUS_DOC = ("capsule radius of every body, or {group or body: radius} (groups arm, forearm, rail, carriage, "
                   "base, platform); null = defaults (docs/describing.md)")
# the per-voxel stiffness fields of kernel2._stiffness (frame2.py's frame, ideal joints): the 3T ones' contract with
# a planar load and a platform that only translates
STIFFNESS_FIELDS_2T = (
    Field("stiffness_min", "N/{length}", "smallest eigenvalue of the platform pin's 2 x 2 stiffness (ideal joints, "
          "Euler-Bernoulli links, actuator springs; the frame of `stiffness`); 0 at a singular pose; its metrics need "
          "options.stiffness_metrics", "max", needs_options=("stiffness_metrics",)),
    Field("deflection", "{length}", "magnitude of the deflection of P under options.load (default 150 N along -y); "
          f"{_sl.DEFLECTION_CAP:g} at a singular pose; its metrics need options.stiffness_metrics", "min",
          (0.0, _sl.DEFLECTION_CAP), needs_options=("stiffness_metrics",)),
)


@dataclass(frozen=True)
class PlanarLeg:
    """One RR or PR leg of a resolved design, in the plane: base point B, platform offset r_p (Q - P), u (RR: the
    crank at q = 0; PR: the rail), w (RR: the direction the crank turns to; PR: the rail's normal), crank length
    (RR), link length, branch sigma (+1/-1) and actuator limits (None or (lo, hi))."""

    type: LegType
    base: np.ndarray
    platform: np.ndarray
    u: np.ndarray
    w: np.ndarray
    arm: float
    forearm: float
    branch: float
    limits: tuple[float, float] | None

    @property
    def rotary(self) -> bool:
        return self.type.code == _k.RR

    def actuated_point(self, q: float) -> np.ndarray:
        """The elbow (RR) or carriage (PR) at joint value q."""
        if self.rotary:
            return self.base + self.arm * (math.cos(q) * self.u + math.sin(q) * self.w)
        return self.base + q * self.u

    def actuated_velocity(self, q: float) -> np.ndarray:
        """d(actuated point)/dq."""
        if self.rotary:
            return self.arm * (-math.sin(q) * self.u + math.cos(q) * self.w)
        return self.u.copy()

    def roots(self, pose) -> dict[float, float]:
        """Both IK roots {sigma: q} at platform point ``pose`` (limits not applied); {} out of reach. RR:
        q = atan2(b, a) + sigma acos(K / (2 L rho)) in (-pi, pi], (a, b) = (D.u, D.w), D = Q - B; PR:
        q = D.e + sigma sqrt(l^2 - (D.n)^2). A pose on the reach boundary (within 1e-12) is a double root."""
        d = np.asarray(pose, dtype=float) + self.platform - self.base
        if self.rotary:
            a, b = float(d @ self.u), float(d @ self.w)
            rho = math.hypot(a, b)
            if rho == 0.0:
                return {}
            k = (rho * rho + self.arm ** 2 - self.forearm ** 2) / (2.0 * self.arm * rho)
            if abs(k) > 1.0 + 1e-12:
                return {}
            g = math.acos(min(1.0, max(-1.0, k)))
            phi = math.atan2(b, a)
            return {1.0: wrap_angle(phi + g), -1.0: wrap_angle(phi - g)}
        de, dn = float(d @ self.u), float(d @ self.w)
        h = self.forearm ** 2 - dn * dn
        if h < -1e-12 * self.forearm ** 2:
            return {}
        s = math.sqrt(max(h, 0.0))
        return {1.0: de + s, -1.0: de - s}

    def within_limits(self, q: float) -> bool:
        """Whether q lies in the actuator range (RR: modulo 2 pi)."""
        if self.limits is None:
            return True
        lo, hi = self.limits
        if self.rotary:
            return (q - lo) % (2.0 * math.pi) <= hi - lo
        return lo <= q <= hi


class PlanarMechanism(DescribedMechanism):
    """A described 2T mechanism (module docstring); poses are (x, y)."""

    link_endpoints = None  # no vectorised twin of the Pa legs' (the dynamics takes link_geometry per pose)

    # ----- options, legs and packing ----------------------------------------------------------------------
    def check_options(self, options: dict[str, Any]) -> None:
        bodies.check_link_radius(options, self._codes())
        check_stiffness_options(options, 2, frame.link_groups(self._codes()[0]))
        for flag in ("stiffness_metrics", "clearance_metrics", "interference_free"):
            links.check_flag_option(options, flag)
        for name, spec in self.description.options.items():
            if spec.kind == "range":
                options[name] = parse_range(name, options[name])
            elif options[name] is not None:
                raise InvalidParameter(f"options.{name}: a 2T leg has no ball-joint cone; give null")
        for plan in self.plans:
            if plan.type == "PR" and (plan.limits is None or options[plan.limits] is None):
                raise InvalidParameter(f"options.{plan.limits or 'limits'}: a PR leg needs a stroke range [lo, hi] "
                                       "(its rail is otherwise endless)")

    def legs(self, design: Mapping[str, float], options: Mapping[str, Any]) -> list[PlanarLeg]:
        """The legs of a resolved design and options, in the plane."""
        out = []
        for i, plan in enumerate(self.plans):
            lt = LEG_TYPES[plan.type]
            try:
                base = _turn(plan.phi, [e.value(design) for e in plan.base])[:2]
                platform = _turn(plan.phi, [e.value(design) for e in plan.platform])[:2]
                lengths = {k: e.value(design) for k, e in plan.links.items()}
            except expressions.ExpressionError as err:
                raise InvalidParameter(f"design: leg {i + 1}: {err}") from None
            for k, v in lengths.items():
                if not v > 0.0:
                    raise InvalidParameter(f"design: leg {i + 1} {k} = {v:g}, must be > 0")
                check_magnitude(f"design: leg {i + 1} {k}", v)
            if lt.code == _k.RR:
                u = _unit(_turn(plan.phi, plan.frame["arm_zero"])[:2])
                w = _unit(_turn(plan.phi, plan.frame["arm_positive"])[:2])
            else:
                u = _unit(_turn(plan.phi, plan.frame["rail"])[:2])
                w = np.array([-u[1], u[0]])
            limits = options[plan.limits] if plan.limits else None
            out.append(PlanarLeg(lt, base, platform, u, w, lengths.get("arm", 0.0), lengths["forearm"],
                                 lt.branches[plan.branch], tuple(limits) if limits is not None else None))
        return out

    def pack(self, design: Mapping[str, float], options: Mapping[str, Any]) -> np.ndarray:
        """The packed vector of kernel2.py: the legs, then (options.stiffness_metrics) the stiffness block
        (frame2.pack_stiffness) and (clearance_metrics or interference_free) the capsules of bodies.capsules2."""
        p = np.zeros(_k.N_PACKED)
        p[0] = len(self.plans)
        legs = self.legs(design, options)
        if options.get("stiffness_metrics"):
            frame2.pack_stiffness(self, design, options, p)
        if options.get("clearance_metrics") or options.get("interference_free"):
            caps, pairs = bodies.capsules2(legs, bodies.radii(options, self._codes(), self.default_length_unit,
                                                              PLANAR_RADII_M))
            pack_clearance(p, (_k.CLEAR, _k.FREE, _k.UNIFORM, _k.CAPS), options, caps, pairs)
        for i, leg in enumerate(legs):
            k = _k.HEAD + i * _k.STRIDE
            p[k + _k.TYPE] = leg.type.code
            p[k + _k.BASE : k + _k.BASE + 2] = leg.base
            p[k + _k.PLAT : k + _k.PLAT + 2] = leg.platform
            p[k + _k.U : k + _k.U + 2] = leg.u
            p[k + _k.W : k + _k.W + 2] = leg.w
            p[k + _k.ARM] = leg.arm
            p[k + _k.LINK] = leg.forearm
            p[k + _k.BRANCH] = leg.branch
            if leg.limits is None or (leg.rotary and leg.limits[1] - leg.limits[0] >= 2.0 * math.pi):
                continue  # a full turn or more restricts nothing
            lo, hi = leg.limits
            p[k + _k.HAS_LIMITS] = 1.0
            p[k + _k.LO], p[k + _k.HI] = lo, hi
            p[k + _k.COS_LO], p[k + _k.SIN_LO] = math.cos(lo), math.sin(lo)
            p[k + _k.COS_HI], p[k + _k.SIN_HI] = math.cos(hi), math.sin(hi)
            p[k + _k.WIDE] = 1.0 if hi - lo > math.pi else 0.0
        return p

    @property
    def field_kernel(self):
        return _k.point_fields

    @property
    def lci_kernel(self):
        """point_fields without the stiffness and clearance stages (slots 0-2 bit for bit): kernel2.point_lci."""
        return _k.point_lci

    def stats_kernel(self, packed: np.ndarray, lci_only: bool = False):
        """point_lci unless a design of ``packed`` sets the stiffness or clearance flag (options.stiffness_metrics,
        clearance_metrics, interference_free): then point_fields. With the flags off both give slots 0-2 bit for bit
        and 0 in slots 3-5, and an evaluation without the fields compiles neither stage."""
        needs = np.any(packed[..., _k.STIFF] > 0.0) or np.any(packed[..., _k.CLEAR] > 0.0)
        return _k.point_fields if needs and not lci_only else _k.point_lci

    @property
    def reach_kernel(self):
        return _k.point_reach

    def bounding_box(self, design, options):
        """Box of the set both legs reach: RR, the disk of radius L + l about B - r_p; PR, the stroke segment swept
        by the disk of radius l, minus r_p (its box). Two RR legs: the exact box of the two disks' lens (extreme
        points of a disk inside the other, and the circles' crossings); otherwise the boxes' intersection. The third
        entry is unused (0); an empty set gives a zero-size box at the origin."""
        legs = self.legs(design, options)
        lo, hi = np.full(2, -math.inf), np.full(2, math.inf)
        for leg in legs:
            if leg.rotary:
                c0 = c1 = leg.base - leg.platform
                reach = leg.arm + leg.forearm
            else:
                c0 = leg.base + leg.limits[0] * leg.u - leg.platform
                c1 = leg.base + leg.limits[1] * leg.u - leg.platform
                reach = leg.forearm
            lo = np.maximum(lo, np.minimum(c0, c1) - reach)
            hi = np.minimum(hi, np.maximum(c0, c1) + reach)
        if all(leg.rotary for leg in legs) and np.all(lo < hi):
            lens = _lens_box([leg.base - leg.platform for leg in legs], [leg.arm + leg.forearm for leg in legs])
            if lens is None:
                return np.zeros(3), np.zeros(3)
            lo, hi = np.maximum(lo, lens[0]), np.minimum(hi, lens[1])
        if np.any(lo >= hi):
            return np.zeros(3), np.zeros(3)
        return np.append(lo, 0.0), np.append(hi, 0.0)

    # ----- bodies ----------------------------------------------------------------------------------------
    def link_geometry(self, design, options, pose, q) -> links.LinkGeometry:
        """Capsules in the plane z = 0 at platform point ``pose`` with joint values ``q``: per leg i ``arm<i>``
        B -> E and ``forearm<i>`` E -> Q (RR), or ``rail<i>`` over the stroke, ``carriage<i>`` a ball at C and
        ``forearm<i>`` C -> Q (PR); ``base`` through the B_i, ``platform`` through the Q_i (a ball at P where they
        meet). Adjacent: base-arm, arm-forearm, base-rail, rail-carriage, carriage-forearm, rail-forearm,
        forearm-platform, and the two forearms when their joints coincide (pinned together at P)."""
        p = self.check_vector("pose", pose, 2)
        qv = self.check_vector("inputs", q, len(self.joints))
        rad = bodies.radii(options, self._codes(), self.default_length_unit, PLANAR_RADII_M)
        legs = self.legs(design, options)
        segs: list[links.Segment] = []
        pairs: list[tuple[str, str]] = []

        def seg(name, a, b):
            segs.append(links.Segment(name, name, links.point(*a), links.point(*b), rad[name]))

        joints = []
        for i, (leg, qi) in enumerate(zip(legs, qv, strict=True), 1):
            e = leg.actuated_point(float(qi))
            j = p + leg.platform
            joints.append(j)
            if leg.rotary:
                seg(f"arm{i}", leg.base, e)
                pairs += [("base", f"arm{i}"), (f"arm{i}", f"forearm{i}")]
            else:
                lo, hi = leg.limits
                seg(f"rail{i}", leg.base + lo * leg.u, leg.base + hi * leg.u)
                seg(f"carriage{i}", e, e)
                pairs += [("base", f"rail{i}"), (f"rail{i}", f"carriage{i}"), (f"carriage{i}", f"forearm{i}"),
                          (f"rail{i}", f"forearm{i}")]
            seg(f"forearm{i}", e, j)
            pairs.append((f"forearm{i}", "platform"))
        if bodies.joints_coincide(legs):
            pairs.append(("forearm1", "forearm2"))
        base_a, base_b = legs[1].base, legs[0].base
        segs.insert(0, links.Segment("base", "base", links.point(*base_a), links.point(*base_b), rad["base"]))
        segs.append(links.Segment("platform", "platform", links.point(*joints[0]), links.point(*joints[1]),
                                  rad["platform"]))
        return links.LinkGeometry(tuple(segs), links.adjacency(pairs))

    def stiffness_model(self, design, options, pose, joints: str = "ideal"):
        """The planar stiffness frame (scalesynth.stiffness.FrameModel) at platform point ``pose`` in the kernel's
        branch: cranks or carriages on their actuator springs, links pinned to them and to the platform pin
        (frame2.py); ``joints`` 'bonded' welds the passive revolute joints."""
        return frame2.stiffness_model(self, design, options, pose, joints)

    # ----- NumPy kinematics ----------------------------------------------------------------------------------
    def inverse_kinematics(self, design, options, pose) -> list[Solution]:
        """Every branch combination whose legs both reach the platform point ``pose`` (limits not applied),
        labelled by the legs' branch names joined by '/' (e.g. '+/-', the described five-bar's)."""
        p = self.check_vector("pose", pose, 2)
        roots = [leg.roots(p) for leg in self.legs(design, options)]
        if any(not r for r in roots):
            return []
        out = []
        for combo in itertools.product(*self._labels()):
            label = "/".join(name for name, _ in combo)
            out.append(Solution(label, np.array([r[sign] for r, (_, sign) in zip(roots, combo, strict=True)])))
        return out

    def forward_kinematics(self, design, options, inputs) -> list[Solution]:
        """Both intersections of the circles |P - (A_i - r_p,i)| = l_i (A_i the actuated point): '+' the one to the
        left of c1 -> c2 (c_i the centres), '-' the other; one 'double' when they touch; [] when they do not meet
        or coincide."""
        q = self.check_vector("inputs", inputs, len(self.joints))
        legs = self.legs(design, options)
        c1, c2 = (leg.actuated_point(qi) - leg.platform for leg, qi in zip(legs, q, strict=True))
        r1, r2 = legs[0].forearm, legs[1].forearm
        scale = max(r1, r2, float(np.abs(c1).max()), float(np.abs(c2).max()))
        u = c2 - c1
        d = float(np.hypot(*u))
        if d <= 1e-14 * scale:
            return []
        a = (r1 * r1 - r2 * r2 + d * d) / (2.0 * d)
        h2 = r1 * r1 - a * a
        if h2 < -1e-12 * scale * scale:
            return []
        mid = c1 + a * u / d
        if h2 <= 1e-12 * scale * scale:
            return [Solution("double", mid)]
        perp = np.array([-u[1], u[0]]) / d * math.sqrt(h2)
        return [Solution("+", mid + perp), Solution("-", mid - perp)]

    def jacobians(self, design, options, pose, q) -> dict[str, Any]:
        """Jx (rows f_i, the links Q_i - A_i), Jq = diag(f_i . dA_i/dq_i) and J = dx/dq = Jx^-1 Jq (None where Jx
        is singular). Raises InvalidPose when q does not assemble at the pose (a link off its length by more than
        1e-6 relative)."""
        p = self.check_vector("pose", pose, 2)
        qv = self.check_vector("inputs", q, len(self.joints))
        jx, jq = np.zeros((2, 2)), np.zeros((2, 2))
        for i, (leg, qi) in enumerate(zip(self.legs(design, options), qv, strict=True)):
            f = p + leg.platform - leg.actuated_point(qi)
            if abs(float(np.linalg.norm(f)) - leg.forearm) > 1e-6 * max(leg.forearm, leg.arm):
                raise InvalidPose(f"inputs: joint values do not assemble at the pose (link {i + 1} would be "
                                  f"{float(np.linalg.norm(f)):g} long, not {leg.forearm:g})")
            jx[i] = f
            jq[i, i] = float(f @ leg.actuated_velocity(qi))
        try:
            j = np.linalg.solve(jx, jq)
        except np.linalg.LinAlgError:
            j = None
        return {"Jx": jx, "Jq": jq, "J": j}

    def lci(self, design, options, pose, q) -> float:
        """sigma_min / sigma_max of J = dx/dq by NumPy's SVD; 0 at any singularity."""
        jac = self.jacobians(design, options, pose, q)
        if jac["J"] is None or self.singularity(design, options, pose, q, tol=0.0) != "none":
            return 0.0
        return svd_lci(jac["J"])


def _lens_box(centres, radii) -> tuple[np.ndarray, np.ndarray] | None:
    """(lo, hi) of the intersection of two disks, or None where it is empty or a single point."""
    (c1, c2), (r1, r2) = centres, radii
    pts = []
    for c, r in ((c1, r1), (c2, r2)):
        pts += [c + r * np.array(v) for v in ((1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0))]
    u = c2 - c1
    d = float(np.hypot(*u))
    if 0.0 < d < r1 + r2 and d > abs(r1 - r2):
        a = (r1 * r1 - r2 * r2 + d * d) / (2.0 * d)
        h = math.sqrt(max(r1 * r1 - a * a, 0.0))
        mid, perp = c1 + a * u / d, np.array([-u[1], u[0]]) / d * h
        pts += [mid + perp, mid - perp]
    inside = [v for v in pts if all(np.hypot(*(v - c)) <= r * (1.0 + 1e-12) for c, r in zip(centres, radii,
                                                                                           strict=True))]
    if not inside:
        return None
    arr = np.array(inside)
    return arr.min(axis=0), arr.max(axis=0)


def from_description_2t(desc: Description) -> PlanarMechanism:
    """The registered mechanism of a validated 2T description: the description's options, then ``link_radius``."""
    plans = _plans(desc)
    rotary = LEG_TYPES[plans[0].type].joint_unit == "angle"
    options = tuple(Option(name, spec.default, spec.doc) for name, spec in desc.options.items()) + (
        Option("link_radius", None, LINK_RADIUS_DOC), *frame.options(desc.stiffness, desc.length_unit, rotary, True),
        STIFFNESS_METRICS_OPTION, CLEARANCE_METRICS_OPTION, INTERFERENCE_FREE_OPTION)
    sigma_unit = "{length}/rad" if rotary else "1"
    jac = ("J = dx/dq (platform motion per rad of crank rotation)" if rotary else
           "J = dx/dq (platform motion per unit carriage motion)")
    return PlanarMechanism(
        name=desc.name,
        title=desc.title,
        seed="",
        motion=desc.motion,
        task_axes=("x", "y"),
        task_units=("length", "length"),
        joints=tuple(f"{plan.joint}{i + 1}" for i, plan in enumerate(plans)),
        joint_units=tuple(LEG_TYPES[plan.type].joint_unit for plan in plans),
        parameters=tuple(Parameter(name, spec.default, spec.doc, spec.unit, spec.positive)
                         for name, spec in desc.parameters.items()),
        options=options,
        default_length_unit=desc.length_unit,
        fields=(*base_fields(sigma_unit, jac), *STIFFNESS_FIELDS_2T, CLEARANCE),
        design_metrics=(
            DesignMetric("link_length_sum", "{length}", "every link length of every leg, summed (crank and link; "
                         "a parallelogram counted once)",
                         lambda d, o, _p=plans: float(sum(e.value(d) for pl in _p for e in pl.links.values()))),
            DesignMetric("footprint_radius", "{length}", "radius of the smallest circle in the plane holding the "
                         "legs' base points", lambda d, o, _p=plans: _footprint(_p, d)),
        ),
        description=desc,
        plans=plans,
    )
