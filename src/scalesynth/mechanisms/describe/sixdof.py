"""Described 6-DOF mechanisms (six RUS or UPS legs): NumPy kinematics, packing for kernel6.py, and the Mechanism.

The workspace is the constant-orientation workspace: the platform's orientation is the option ``orientation``
[roll, pitch, yaw] (rad; R = Rz(yaw) Ry(pitch) Rx(roll), default the identity) and the task axes are the platform
centre's x, y, z. Platform joint offsets r_i are given in the platform's frame (the mechanism's frame at the
identity) and turned by R. The Jacobian is homogenised with a characteristic length L (option
``characteristic_length``, default the platform radius: the largest distance of a platform joint from the platform
centre): dx/dq maps joint rates to (v, L omega). Forward kinematics solves the six closures by Newton from several
starts (``forward_kinematics``). docs/describing.md states all of it for users.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from scalesynth.errors import InvalidParameter, InvalidPose
from scalesynth.mechanisms.base import (
    MAX_MAGNITUDE,
    DesignMetric,
    Option,
    Parameter,
    Solution,
    base_fields,
    check_magnitude,
    singularity_label,
    svd_lci,
)
from scalesynth.mechanisms.describe import bodies, expressions, frame
from scalesynth.mechanisms.describe import kernel6 as _k
from scalesynth.mechanisms.describe.legs import LEG_TYPES, LegType
from scalesynth.mechanisms.describe.mechanism import (
    CLEARANCE,
    CLEARANCE_METRICS_OPTION,
    INTERFERENCE_FREE_OPTION,
    STIFFNESS_FIELDS,
    STIFFNESS_METRICS_OPTION,
    DescribedMechanism,
    _footprint,
    _plans,
    _turn,
    _unit,
    pack_clearance,
)
from scalesynth.mechanisms.describe.schema import Description
from scalesynth.mechanisms.links import segment_ends

ORIENTATION = "orientation"
CHARACTERISTIC_LENGTH = "characteristic_length"
POSE_AXES = ("x", "y", "z", "roll", "pitch", "yaw")
FK_STARTS = 9  # Newton starts of the forward kinematics along the bounding box's vertical axis
FK_ITERATIONS = 60


def rotation(rpy) -> np.ndarray:
    """R = Rz(yaw) Ry(pitch) Rx(roll) of [roll, pitch, yaw] (rad): the platform frame in the mechanism frame."""
    a, b, c = (float(v) for v in rpy)
    ca, sa, cb, sb, cc, sc = math.cos(a), math.sin(a), math.cos(b), math.sin(b), math.cos(c), math.sin(c)
    return np.array([[cc * cb, cc * sb * sa - sc * ca, cc * sb * ca + sc * sa],
                     [sc * cb, sc * sb * sa + cc * ca, sc * sb * ca - cc * sa],
                     [-sb, cb * sa, cb * ca]])


def roll_pitch_yaw(r: np.ndarray) -> np.ndarray:
    """[roll, pitch, yaw] of a rotation matrix (the inverse of ``rotation``; pitch in [-pi/2, pi/2])."""
    pitch = math.asin(max(-1.0, min(1.0, -float(r[2, 0]))))
    return np.array([math.atan2(r[2, 1], r[2, 2]), pitch, math.atan2(r[1, 0], r[0, 0])])


def _rodrigues(w: np.ndarray) -> np.ndarray:
    """The rotation by angle |w| about w (rad)."""
    t = float(np.linalg.norm(w))
    if t == 0.0:
        return np.eye(3)
    k = w / t
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(t) * kx + (1.0 - math.cos(t)) * kx @ kx


@dataclass(frozen=True)
class Leg6:
    """One RUS or UPS leg of a resolved design, mechanism frame: base point B, platform joint offset r (platform
    frame), RUS arm directions u (q = 0) and w (positive turn), axis (RUS: u x w; UPS: the base joint's cone axis),
    axis_p (UPS: the platform joint's cone axis, platform frame), RUS arm and rod lengths, branch (+1/-1), actuator
    limits (None or (lo, hi)) and the cone half-angle (None = off)."""

    type: LegType
    base: np.ndarray
    r: np.ndarray
    u: np.ndarray
    w: np.ndarray
    axis: np.ndarray
    axis_p: np.ndarray
    arm: float
    rod: float
    branch: float
    limits: tuple[float, float] | None
    cone: float | None

    @property
    def rus(self) -> bool:
        return self.type.code == _k.RUS

    def actuated_point(self, q: float) -> np.ndarray:
        """RUS: the elbow E at arm angle q; UPS: the base joint B (the leg's fixed end)."""
        if self.rus:
            return self.base + self.arm * (math.cos(q) * self.u + math.sin(q) * self.w)
        return self.base.copy()

    def actuated_velocity(self, q: float) -> np.ndarray:
        """RUS: dE/dq; UPS: zero (the leg's length is the joint; see ``closure_rate``)."""
        if self.rus:
            return self.arm * (-math.sin(q) * self.u + math.cos(q) * self.w)
        return np.zeros(3)

    def roots(self, pose, rot: np.ndarray) -> dict[float, float]:
        """Every IK root {branch: q} at platform centre ``pose`` and orientation ``rot`` (limits not applied); {} out
        of reach. RUS: q = atan2(B, A) -+ acos(K / sqrt(A^2 + B^2)), branch +1 the one with the larger cos q; UPS:
        q = |Q - B| (0 counts as out of reach: no direction; so does a leg longer than MAX_MAGNITUDE, which no
        joint value may be)."""
        d = np.asarray(pose, dtype=float) + rot @ self.r - self.base
        if not self.rus:
            q = float(np.linalg.norm(d))
            return {1.0: q} if 0.0 < q <= MAX_MAGNITUDE else {}
        a = 2.0 * self.arm * float(d @ self.u)
        b = 2.0 * self.arm * float(d @ self.w)
        k = float(d @ d) + self.arm ** 2 - self.rod ** 2
        n = math.hypot(a, b)
        if n == 0.0 or abs(k) > n:
            return {}
        base, g = math.atan2(b, a), math.acos(k / n)
        one, two = _wrap(base - g), _wrap(base + g)
        out_, in_ = (one, two) if math.cos(one) >= math.cos(two) else (two, one)
        return {1.0: out_, -1.0: in_}

    def rod_vector(self, pose, rot: np.ndarray, q: float) -> np.ndarray:
        """f = Q - E (RUS, the rod) or Q - B (UPS, the leg), Q = P + R r the platform joint."""
        return np.asarray(pose, dtype=float) + rot @ self.r - self.actuated_point(q)

    def within_limits(self, q: float, pose, rot: np.ndarray) -> bool:
        """Whether q lies in the actuator range (RUS: modulo 2 pi) and the rod or leg in its joints' cones."""
        if self.limits is not None:
            lo, hi = self.limits
            if self.rus:
                if (q - lo) % (2.0 * math.pi) > hi - lo:
                    return False
            elif not lo <= q <= hi:
                return False
        if self.cone is not None:
            f = self.rod_vector(pose, rot, q)
            if self.rus:
                return abs(float(f @ self.axis)) <= self.rod * math.sin(self.cone)
            n = f / np.linalg.norm(f)
            c = math.cos(self.cone)
            return float(n @ self.axis) >= c and float(n @ (rot @ self.axis_p)) >= c
        return True


def _wrap(a: float) -> float:
    w = math.atan2(math.sin(a), math.cos(a))
    return math.pi if w == -math.pi else w


class SixDofMechanism(DescribedMechanism):
    """A described 6-DOF mechanism (module docstring). Poses given to IK, jacobians, lci are the platform centre
    (x, y, z) at the orientation of the option ``orientation``; FK returns full poses (x, y, z, roll, pitch, yaw)."""

    link_endpoints = None  # no vectorised twin of the Pa legs' (the dynamics takes link_geometry per pose)

    @property
    def pose_axes(self) -> tuple[str, ...]:
        return POSE_AXES

    # ----- options, legs and packing -----------------------------------------------------------------------
    def check_options(self, options: dict[str, Any]) -> None:
        value = options[ORIENTATION]
        if not isinstance(value, (list, tuple)) or len(value) != 3 or any(
                isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) for v in value):
            raise InvalidParameter(f"options.{ORIENTATION}: expected [roll, pitch, yaw] in rad (3 finite numbers), "
                                   f"got {value!r}")
        options[ORIENTATION] = [float(v) for v in value]
        for i, v in enumerate(options[ORIENTATION]):
            check_magnitude(f"options.{ORIENTATION}[{i}]", v)
        length = options[CHARACTERISTIC_LENGTH]
        if length is not None:
            if isinstance(length, bool) or not isinstance(length, (int, float)) or not (
                    math.isfinite(length) and length > 0.0):
                raise InvalidParameter(f"options.{CHARACTERISTIC_LENGTH}: expected null (the platform radius) or a "
                                       f"length > 0, got {length!r}")
            options[CHARACTERISTIC_LENGTH] = check_magnitude(f"options.{CHARACTERISTIC_LENGTH}", float(length))
        own = {k: v for k, v in options.items() if k not in (ORIENTATION, CHARACTERISTIC_LENGTH)}
        super().check_options(own)
        options.update(own)
        for plan in self.plans:
            if LEG_TYPES[plan.type].code == _k.UPS and (plan.limits is None or options[plan.limits] is None):
                raise InvalidParameter(f"options.{plan.limits or 'limits'}: a {plan.type} leg needs a length range "
                                       "[lo, hi] (its reach is otherwise endless)")

    def legs(self, design: Mapping[str, float], options: Mapping[str, Any]) -> list[Leg6]:
        """The legs of a resolved design and options, mechanism frame (platform offsets in the platform frame)."""
        out = []
        for i, plan in enumerate(self.plans):
            lt = LEG_TYPES[plan.type]
            try:
                base = _turn(plan.phi, [e.value(design) for e in plan.base])
                r = _turn(plan.phi, [e.value(design) for e in plan.platform])
                links = {k: e.value(design) for k, e in plan.links.items()}
            except expressions.ExpressionError as err:
                raise InvalidParameter(f"design: leg {i + 1}: {err}") from None
            for k, v in links.items():
                if not v > 0.0:
                    raise InvalidParameter(f"design: leg {i + 1} {k} = {v:g}, must be > 0")
                check_magnitude(f"design: leg {i + 1} {k}", v)
            if lt.code == _k.RUS:
                u = _unit(_turn(plan.phi, plan.frame["arm_zero"]))
                w = _unit(_turn(plan.phi, plan.frame["arm_positive"]))
                axis = np.cross(u, w)
                axis_p = np.zeros(3)
            else:
                u = w = np.zeros(3)
                axis = axis_p = _unit(_turn(plan.phi, plan.frame["cone_axis"]))
            limits = options[plan.limits] if plan.limits else None
            out.append(Leg6(lt, base, r, u, w, axis, axis_p, links.get("arm", 0.0), links.get("rod", 0.0),
                            lt.branches[plan.branch], tuple(limits) if limits is not None else None,
                            options[plan.cone] if plan.cone else None))
        return out

    def characteristic_length(self, design: Mapping[str, float], options: Mapping[str, Any]) -> float:
        """L: the option, or the platform radius (largest |r_i|); 1 where every platform joint is at the centre."""
        if options.get(CHARACTERISTIC_LENGTH) is not None:
            return float(options[CHARACTERISTIC_LENGTH])
        radius = max(float(np.linalg.norm(leg.r)) for leg in self.legs(design, options))
        return radius if radius > 0.0 else 1.0

    def rotation(self, options: Mapping[str, Any]) -> np.ndarray:
        return rotation(options[ORIENTATION])

    def pack(self, design: Mapping[str, float], options: Mapping[str, Any]) -> np.ndarray:
        p = np.zeros(_k.N_PACKED)
        p[0] = len(self.plans)
        p[_k.INV_L] = 1.0 / self.characteristic_length(design, options)
        rot = self.rotation(options)
        for i, leg in enumerate(self.legs(design, options)):
            k = _k.HEAD + i * _k.STRIDE
            p[k + _k.TYPE] = leg.type.code
            p[k + _k.BASE : k + _k.BASE + 3] = leg.base
            p[k + _k.RHO : k + _k.RHO + 3] = rot @ leg.r
            p[k + _k.U : k + _k.U + 3] = leg.u
            p[k + _k.W : k + _k.W + 3] = leg.w
            p[k + _k.AXIS : k + _k.AXIS + 3] = leg.axis
            p[k + _k.AXIS_P : k + _k.AXIS_P + 3] = rot @ leg.axis_p
            p[k + _k.ARM] = leg.arm
            p[k + _k.ROD] = leg.rod
            p[k + _k.BRANCH] = leg.branch
            if leg.limits is not None and not (leg.rus and leg.limits[1] - leg.limits[0] >= 2.0 * math.pi):
                p[k + _k.HAS_LIMITS] = 1.0
                p[k + _k.LO], p[k + _k.HI] = leg.limits
            if leg.cone is not None:
                p[k + _k.HAS_CONE] = 1.0
                p[k + _k.CONE] = math.sin(leg.cone) if leg.rus else math.cos(leg.cone)
        if options.get("stiffness_metrics"):
            self._pack_stiffness(options, p)
        if options.get("clearance_metrics") or options.get("interference_free"):
            rad = bodies.radii(options, self._codes(), self.default_length_unit)
            caps, pairs = bodies.capsules6(self.legs(design, options), rad, rot)
            pack_clearance(p, (_k.CLEAR, _k.FREE, _k.UNIFORM, _k.CAPS), options, caps, pairs)
        return p

    def _pack_stiffness(self, options: Mapping[str, Any], p: np.ndarray) -> None:
        """The stiffness block of kernel6 (flag, load, per leg the sections and the actuator's spring) from the
        sections and options of the stiffness frame (frame6.py)."""
        from scalesynth.stiffness.sections import tube_section

        codes = self._codes()
        groups = {g: tube_section(options, g, self.default_length_unit) for g in frame.link_groups(codes[0])}
        for i, code in enumerate(codes):
            s = _k.SLEGS + i * _k.SSTRIDE
            if code == _k.RUS:
                arm, link = groups["upper_arm"], groups["rod"]
                p[s + _k.EA_ARM], p[s + _k.EI_ARM], p[s + _k.GJ_ARM] = arm.EA, arm.EI, arm.GJ
            else:
                link = groups["leg"]
            p[s + _k.EA_LINK] = link.EA
            p[s + _k.K_ACT] = options["actuator_stiffness"]
        p[_k.STIFF] = 1.0
        p[_k.LOAD : _k.LOAD + 3] = options["load"]

    @property
    def field_kernel(self):
        return _k.point_fields

    @property
    def lci_kernel(self):
        """point_fields without the stiffness stage (slot 0 bit for bit): a search on the LCI's metrics alone."""
        return _k.point_lci

    @property
    def reach_kernel(self):
        return _k.point_reach

    def bounding_box(self, design, options):
        """Intersection over the legs of the box of the ball each reaches, about B - R r: RUS radius a + l, UPS its
        longest length. An empty intersection gives a zero-size box at the origin."""
        rot = self.rotation(options)
        lo, hi = np.full(3, -math.inf), np.full(3, math.inf)
        for leg in self.legs(design, options):
            centre = leg.base - rot @ leg.r
            reach = leg.arm + leg.rod if leg.rus else leg.limits[1]
            lo = np.maximum(lo, centre - reach)
            hi = np.minimum(hi, centre + reach)
        if np.any(lo >= hi):
            return np.zeros(3), np.zeros(3)
        return lo, hi

    # ----- bodies, stiffness frame and cycles (bodies.py, frame6.py) ----------------------------------------
    def link_geometry(self, design, options, pose, q):
        """Capsules of every body at platform centre ``pose`` (the options' orientation) with joint values ``q``
        (bodies.py: upper_arm<i> and rod<i> of a RUS leg, leg<i> of a UPS leg, base, platform)."""
        p = self.check_vector("pose", pose, 3)
        qv = self.check_vector("inputs", q, len(self.joints))
        rad = bodies.radii(options, self._codes(), self.default_length_unit)
        return bodies.link_geometry6(self.legs(design, options), rad, p, self.rotation(options), qv)

    def stiffness_model(self, design, options, pose, joints: str = "ideal"):
        """The stiffness frame (scalesynth.stiffness.FrameModel) at platform centre ``pose`` in the kernel's
        branch (frame6.py): arms on actuator springs with rods as bars, or legs as bars with axial actuator
        springs; a rigid platform. ``joints`` 'bonded' welds the passive universal and spherical joints."""
        from scalesynth.mechanisms.describe import frame6

        return frame6.stiffness_model(self, design, options, pose, joints)

    def _branch_signs(self, label: str) -> list[float] | None:
        names = label.split("/")
        if len(names) != len(self.plans):
            return None
        out = []
        for plan, name in zip(self.plans, names, strict=True):
            sign = LEG_TYPES[plan.type].branches.get(name)
            if sign is None:
                return None
            out.append(sign)
        return out

    def cycle_kinematics(self, design, options, poses, label: str) -> tuple[np.ndarray, np.ndarray]:
        """IK in branch ``label`` and velocity_map at many poses (n, 3); the base class's loop with the legs
        resolved once and only the branch asked for solved (equal to it: tests/test_sixdof_bodies.py)."""
        n, nj = len(poses), len(self.joints)
        q = np.full((n, nj), np.nan)
        a = np.full((n, nj, nj), np.nan)
        signs = self._branch_signs(label)
        if signs is None:
            return q, a
        legs = self.legs(design, options)
        rot = self.rotation(options)
        for s, pose in enumerate(poses):
            p = self.check_vector("pose", pose, 3)
            roots = [leg.roots(p, rot) for leg in legs]
            if any(sign not in r for r, sign in zip(roots, signs, strict=True)):
                continue
            q[s] = [r[sign] for r, sign in zip(roots, signs, strict=True)]
            rows, _ = self._closure_rows(legs, p, rot, q[s])
            jq = np.array([float(rows[i, :3] @ leg.actuated_velocity(qi)) if leg.rus else qi
                           for i, (leg, qi) in enumerate(zip(legs, q[s], strict=True))])
            with np.errstate(divide="ignore", invalid="ignore"):
                a[s] = rows / jq[:, None]
        return q, a

    def held_link_jacobian(self, design, options, poses, label: str, step: float = 1e-5) -> np.ndarray:
        """d(segment endpoints)/d(theta_j) (n, 3, s, 2, 3), length unit per rad: the link_geometry endpoints as
        the platform turns by a small angle theta_j about the mechanism frame's axis j at fixed position (R ->
        Rod(theta_j e_j) R, the omega of velocity_map's last three columns), by central differences of ``step``
        rad. The inverse dynamics needs it for the moments the actuators apply to hold the orientation
        (dynamics.inverse); NaN where the branch does not reach."""
        rot = self.rotation(options)
        sides = []
        for j in range(3):
            for sign in (1.0, -1.0):
                w = np.zeros(3)
                w[j] = sign * step
                turned = dict(options, **{ORIENTATION: list(roll_pitch_yaw(_rodrigues(w) @ rot))})
                sides.append(self._segment_ends(design, turned, poses, label))
        e = np.stack(sides, axis=1)  # (n, 6, s, 2, 3)
        return (e[:, 0::2] - e[:, 1::2]) / (2.0 * step)

    def _segment_ends(self, design, options, poses, label: str) -> np.ndarray:
        """link_geometry's segment endpoints (n, s, 2, 3) at poses (n, 3) in branch ``label``; NaN where it does
        not reach."""
        q, _ = self.cycle_kinematics(design, options, poses, label)
        out = segment_ends(self, design, options, poses, q)
        return np.full((len(poses), 0, 2, 3), np.nan) if out is None else out

    # ----- NumPy kinematics --------------------------------------------------------------------------------
    def inverse_kinematics(self, design, options, pose) -> list[Solution]:
        """Every branch combination whose legs all reach the platform centre ``pose`` at the options' orientation
        (limits not applied), labelled by the legs' branch names joined by '/'."""
        p = self.check_vector("pose", pose, 3)
        rot = self.rotation(options)
        roots = [leg.roots(p, rot) for leg in self.legs(design, options)]
        if any(not r for r in roots):
            return []
        out = []
        for combo in itertools.product(*self._labels()):
            label = "/".join(name for name, _ in combo)
            out.append(Solution(label, np.array([r[sign] for r, (_, sign) in zip(roots, combo, strict=True)])))
        return out

    def _closure_rows(self, legs, pose, rot, q):
        """Rows [f_i, rho_i x f_i] (f_i the rod or leg vector, rho_i = R r_i) and closure errors |f_i| - l_i."""
        rows, err = np.zeros((6, 6)), np.zeros(6)
        for i, (leg, qi) in enumerate(zip(legs, q, strict=True)):
            f = leg.rod_vector(pose, rot, qi)
            rows[i, :3] = f
            rows[i, 3:] = np.cross(rot @ leg.r, f)
            err[i] = float(np.linalg.norm(f)) - (leg.rod if leg.rus else qi)
        return rows, err

    def jacobians(self, design, options, pose, q) -> dict[str, Any]:
        """Jx (rows [f_i, rho_i x f_i], f_i the rod Q_i - E_i or the unit leg direction), Jq = diag(f_i . dE_i/dq_i)
        (UPS: 1), J = Jx^-1 Jq (q_dot -> (v, omega); None where Jx is singular) and H = diag(1, 1, 1, L, L, L) J,
        the homogenised dx/dq whose conditioning the kernel reports. Raises InvalidPose when q does not assemble at
        the pose (a rod or leg off its length by more than 1e-6 relative)."""
        p = self.check_vector("pose", pose, 3)
        q = self.check_vector("inputs", q, len(self.joints))
        rot = self.rotation(options)
        legs = self.legs(design, options)
        jx, err = self._closure_rows(legs, p, rot, q)
        jq = np.eye(6)
        for i, (leg, qi) in enumerate(zip(legs, q, strict=True)):
            length = leg.rod if leg.rus else qi
            if abs(err[i]) > 1e-6 * max(length, leg.arm, 1e-300):
                raise InvalidPose(f"inputs: joint values do not assemble at the pose (leg {i + 1} would be "
                                  f"{err[i] + length:g} long, not {length:g})")
            if leg.rus:
                jq[i, i] = float(jx[i, :3] @ leg.actuated_velocity(qi))
            else:
                jx[i] /= qi
        try:
            j = np.linalg.solve(jx, jq)
        except np.linalg.LinAlgError:
            j = None
        length = self.characteristic_length(design, options)
        h = None if j is None else np.vstack([j[:3], length * j[3:]])
        return {"Jx": jx, "Jq": jq, "J": j, "H": h, "L": length}

    def lci(self, design, options, pose, q) -> float:
        """sigma_min / sigma_max of the homogenised H by NumPy's SVD; 0 at any singularity."""
        jac = self.jacobians(design, options, pose, q)
        if jac["H"] is None or self.singularity(design, options, pose, q, tol=0.0) != "none":
            return 0.0
        return svd_lci(jac["H"])

    def singularity(self, design, options, pose, q, tol: float = 1e-7) -> str:
        """'inverse' (some RUS |f_i . dE_i/dq_i| <= tol |f_i| |dE_i/dq_i|: a rod square to its arm), 'forward'
        (|det| of the homogenised unit rows [f_i, rho_i x f_i / L] / |f_i| <= tol), 'both' or 'none'."""
        jac = self.jacobians(design, options, pose, q)
        legs = self.legs(design, options)
        qv = self.check_vector("inputs", q, len(self.joints))
        inverse = False
        for i, (leg, qi) in enumerate(zip(legs, qv, strict=True)):
            if leg.rus:
                scale = float(np.linalg.norm(jac["Jx"][i, :3]) * np.linalg.norm(leg.actuated_velocity(qi)))
                inverse |= abs(jac["Jq"][i, i]) <= tol * scale
        rows = jac["Jx"] / np.linalg.norm(jac["Jx"][:, :3], axis=1)[:, None]
        rows[:, 3:] /= jac["L"]
        forward = abs(float(np.linalg.det(rows))) <= tol
        return singularity_label(inverse, forward)

    def velocity_map(self, design, options, pose, q) -> np.ndarray:
        """A = Jq^-1 Jx: q_dot = A [v; omega] (v the platform centre's velocity, omega the platform's angular
        velocity: the constant-orientation task holds it 0); rows at an inverse singularity infinite."""
        jac = self.jacobians(design, options, pose, q)
        with np.errstate(divide="ignore", invalid="ignore"):
            return jac["Jx"] / np.diag(jac["Jq"])[:, None]

    def forward_kinematics(self, design, options, inputs) -> list[Solution]:
        """Assembly modes of the joint values by Newton on the six closures |f_i|^2 = l_i^2 (f_i as in
        ``jacobians``), from FK_STARTS starts at the options' orientation spread along the vertical axis of the
        bounding box (its centre's x, y). Each converged pose (closures within 1e-12 relative) is returned once,
        as (x, y, z, roll, pitch, yaw), labelled 'a1', 'a2', ... by increasing z; [] if none converges. A 6-DOF
        platform has up to 40 assembly modes: these are the ones near the working orientation, not all."""
        q = self.check_vector("inputs", inputs, len(self.joints))
        legs = self.legs(design, options)
        rot0 = self.rotation(options)
        lo, hi = self.bounding_box(design, options)
        scale = max(max(leg.arm + leg.rod for leg in legs), float(np.abs(q).max()), float(np.abs(hi - lo).max()),
                    max(float(np.linalg.norm(leg.base)) for leg in legs), 1e-300)
        centre = 0.5 * (lo + hi)
        found: list[np.ndarray] = []
        for t in np.linspace(0.0, 1.0, FK_STARTS):
            start = np.array([centre[0], centre[1], lo[2] + t * (hi[2] - lo[2])])
            pose = self._newton(legs, q, start, rot0, scale)
            if pose is not None and not any(np.abs(pose - f).max() <= 1e-8 * scale for f in found):
                found.append(pose)
        found.sort(key=lambda v: v[2])
        return [Solution(f"a{i + 1}", v) for i, v in enumerate(found)]

    def _newton(self, legs, q, p, rot, scale) -> np.ndarray | None:
        """One Newton solve of the closures from (p, rot), halving a step that does not lower the residual."""
        def residual(p, rot):
            rows, _ = self._closure_rows(legs, p, rot, q)
            target = np.array([leg.rod if leg.rus else qi for leg, qi in zip(legs, q, strict=True)])
            return rows, 0.5 * (np.sum(rows[:, :3] ** 2, axis=1) - target ** 2)

        rows, c = residual(p, rot)
        for _ in range(FK_ITERATIONS):
            size = float(np.abs(c).max())
            if size <= 1e-13 * scale * scale:
                return np.concatenate([p, roll_pitch_yaw(rot)])
            try:
                step = np.linalg.solve(rows, -c)
            except np.linalg.LinAlgError:
                return None
            if not np.all(np.isfinite(step)):
                return None
            for _ in range(30):
                p1, rot1 = p + step[:3], _rodrigues(step[3:]) @ rot
                rows1, c1 = residual(p1, rot1)
                if float(np.abs(c1).max()) < size:
                    break
                step = 0.5 * step
            else:
                return None
            p, rot, rows, c = p1, rot1, rows1, c1
        return None


def _link_length_sum(mech: SixDofMechanism, d: Mapping[str, float], o: Mapping[str, Any]) -> float:
    """RUS: arm + rod per leg; UPS: the leg's longest length (its range's hi)."""
    total = 0.0
    for plan in mech.plans:
        if LEG_TYPES[plan.type].code == _k.RUS:
            total += sum(e.value(d) for e in plan.links.values())
        else:
            limits = o.get(plan.limits) if plan.limits else None
            total += float(limits[1]) if limits is not None else 0.0
    return total


def from_description_6dof(desc: Description) -> SixDofMechanism:
    """The registered mechanism of a validated 6DOF description: the description's options, then ``orientation``
    and ``characteristic_length``."""
    plans = _plans(desc)
    rotary = LEG_TYPES[plans[0].type].joint_unit == "angle"
    options = tuple(Option(name, spec.default, spec.doc) for name, spec in desc.options.items()) + (
        Option("link_radius", None, bodies.LINK_RADIUS_DOC),
        *frame.options(desc.stiffness, desc.length_unit, rotary), STIFFNESS_METRICS_OPTION,
        CLEARANCE_METRICS_OPTION, INTERFERENCE_FREE_OPTION,
        Option(ORIENTATION, [0.0, 0.0, 0.0], "[roll, pitch, yaw] rad of the platform over the whole (constant-"
               "orientation) workspace, R = Rz(yaw) Ry(pitch) Rx(roll)"),
        Option(CHARACTERISTIC_LENGTH, None, "length L of the homogenised Jacobian dx/dq = (v, L omega) per joint "
               "rate; null = the platform radius (largest distance of a platform joint from the platform centre)"),
    )
    sigma_unit = "{length}/rad" if rotary else "1"
    jac = ("H = (v, L omega) per joint rate (platform motion per rad of arm rotation)" if rotary else
           "H = (v, L omega) per joint rate (platform motion per unit leg extension)")
    holder: list[SixDofMechanism] = []
    mech = SixDofMechanism(
        name=desc.name,
        title=desc.title,
        seed="",
        motion=desc.motion,
        task_axes=("x", "y", "z"),
        task_units=("length", "length", "length"),
        joints=tuple(f"{plan.joint}{i + 1}" for i, plan in enumerate(plans)),
        joint_units=tuple(LEG_TYPES[plan.type].joint_unit for plan in plans),
        parameters=tuple(Parameter(name, spec.default, spec.doc, spec.unit, spec.positive)
                         for name, spec in desc.parameters.items()),
        options=options,
        default_length_unit=desc.length_unit,
        fields=(*base_fields(sigma_unit, jac), *STIFFNESS_FIELDS, CLEARANCE),
        design_metrics=(
            DesignMetric("link_length_sum", "{length}", "every link length of every leg, summed (RUS: arm + rod; "
                         "UPS: its longest length)", lambda d, o, _h=holder: _link_length_sum(_h[0], d, o)),
            DesignMetric("footprint_radius", "{length}", "radius of the smallest circle in the xy plane holding the "
                         "legs' base attachment points", lambda d, o, _p=plans: _footprint(_p, d)),
        ),
        description=desc,
        plans=plans,
    )
    holder.append(mech)
    return mech
