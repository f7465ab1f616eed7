"""DescribedMechanism: a registered Mechanism built from a Description, with no kinematics code of its own.

Parameters, options, joints and fields come from the description; the field kernel is the template of kernel.py
reading the packed legs; the NumPy kinematics (IK of every branch, FK, Jacobians, LCI, singularity) are generic
over the legs of ``legs.py``. FK of a 3T mechanism of Pa legs is closed form: the platform centre lies on a sphere
of radius l_i about each actuated point minus the platform offset, so FK intersects three spheres.
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from scalesynth.errors import InvalidParameter, InvalidPose
from scalesynth.mechanisms.base import (
    DesignMetric,
    Field,
    Mechanism,
    Option,
    Parameter,
    Solution,
    base_fields,
    check_magnitude,
    enclosing_circle_radius,
    parse_range,
    singularity_label,
    svd_lci,
)
from scalesynth.mechanisms.describe import bodies, expressions, frame, symmetry
from scalesynth.mechanisms.describe import kernel as _k
from scalesynth.mechanisms.describe import sector as _sector
from scalesynth.mechanisms.describe.legs import LEG_TYPES, Leg
from scalesynth.mechanisms.describe.schema import Description, leg_frame
from scalesynth.mechanisms.links import check_flag_option
from scalesynth.stiffness import legs as _sl
from scalesynth.stiffness.sections import check_stiffness_options


def _turn(phi: float, v) -> np.ndarray:
    """Vector v turned by phi (rad) about z."""
    c, s = math.cos(phi), math.sin(phi)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]], dtype=float)


@dataclass(frozen=True)
class _LegPlan:
    """A leg of the description with its expressions parsed and its turn about z fixed."""

    type: str
    joint: str
    phi: float
    base: tuple[expressions.Expression, ...]
    platform: tuple[expressions.Expression, ...]
    links: dict[str, expressions.Expression]
    branch: str
    limits: str | None
    cone: str | None
    frame: dict[str, tuple[float, float, float]]
    width: expressions.Expression | None = None  # the parallelogram's width (bodies.py); None = 0
    leg_index: int = 0  # index of the description's leg this one comes from (error lines name it)


def _plans(desc: Description) -> tuple[_LegPlan, ...]:
    names = list(desc.parameters)
    out = []
    for index, leg in enumerate(desc.legs):
        lt = LEG_TYPES[leg.type]
        if leg.pattern:
            degrees = [leg.pattern.start_deg + 360.0 * k / leg.pattern.count for k in range(leg.pattern.count)]
        else:
            degrees = [leg.angle_deg]
        # in [-180, 180] (math.remainder is exact): legs at +-a then turn by exactly mirrored cos and sin (sin is
        # odd, cos even), so a mirror-symmetric pattern packs exactly symmetric and its box is symmetric about 0
        # to the bit (the adaptive evaluator's half box, mirror_axes)
        phis = [math.radians(math.remainder(d, 360.0)) for d in degrees]
        for phi in phis:
            out.append(_LegPlan(
                leg.type, leg.joint or lt.joint, phi,
                tuple(expressions.parse(v, names) for v in leg.base),
                tuple(expressions.parse(v, names) for v in leg.platform),
                {k: expressions.parse(v, names) for k, v in leg.links.items()},
                leg.branch or next(iter(lt.branches)), leg.limits, leg.cone, leg_frame(leg),
                expressions.parse(leg.width, names), index))
    return tuple(out)


@dataclass(frozen=True)
class DescribedMechanism(Mechanism):
    """A mechanism from a description (module docstring)."""

    description: Description | None = field(default=None, compare=False, hash=False, repr=False)
    plans: tuple = field(default=(), compare=False, hash=False, repr=False)

    # ----- options and packing ------------------------------------------------------------------
    def check_options(self, options: dict[str, Any]) -> None:
        bodies.check_link_radius(options, self._codes())
        check_stiffness_options(options, 3, frame.link_groups(self._codes()[0]))
        check_flag_option(options, "stiffness_metrics")
        check_flag_option(options, "clearance_metrics")
        check_flag_option(options, "interference_free")
        for name, spec in self.description.options.items():
            value = options[name]
            if spec.kind == "range":
                options[name] = parse_range(name, value)
            elif value is not None:
                if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 < value <= math.pi / 2:
                    raise InvalidParameter(f"options.{name}: expected null or a cone half-angle in (0, pi/2] rad, "
                                           f"got {value!r}")
                options[name] = float(value)
        for plan in self.plans:
            if plan.type == "P-Pa" and (plan.limits is None or options[plan.limits] is None):
                raise InvalidParameter(f"options.{plan.limits or 'limits'}: a P-Pa leg needs a stroke range "
                                       "[lo, hi] (its rail is otherwise endless)")

    def legs(self, design: Mapping[str, float], options: Mapping[str, Any]) -> list[Leg]:
        """The legs of a resolved design and options, in the mechanism frame."""
        out = []
        for i, plan in enumerate(self.plans):
            lt = LEG_TYPES[plan.type]
            try:
                base = _turn(plan.phi, [e.value(design) for e in plan.base])
                platform = _turn(plan.phi, [e.value(design) for e in plan.platform])
                links = {k: e.value(design) for k, e in plan.links.items()}
            except expressions.ExpressionError as err:
                raise InvalidParameter(f"design: leg {i + 1}: {err}") from None
            for k, v in links.items():
                if not v > 0.0:
                    raise InvalidParameter(f"design: leg {i + 1} {k} = {v:g}, must be > 0")
                check_magnitude(f"design: leg {i + 1} {k}", v)
            u, w, normal = _leg_directions(lt.code, plan.phi, tuple(sorted(plan.frame.items())))
            cone = options[plan.cone] if plan.cone else None
            out.append(Leg(lt, base, platform, u, w, normal, links.get("upper_arm", 0.0), links["forearm"],
                           lt.branches[plan.branch], options[plan.limits] if plan.limits else None,
                           math.sin(cone) if cone is not None else None))
        return out

    def pack(self, design: Mapping[str, float], options: Mapping[str, Any]) -> np.ndarray:
        p = np.zeros(_k.N_PACKED)
        p[0] = len(self.plans)
        legs = self.legs(design, options)
        for i, leg in enumerate(legs):
            k = _k.HEAD + i * _k.STRIDE
            p[k + _k.TYPE] = leg.type.code
            p[k + _k.BASE : k + _k.BASE + 3] = leg.base
            p[k + _k.PLAT : k + _k.PLAT + 3] = leg.platform
            p[k + _k.U : k + _k.U + 3] = leg.u
            p[k + _k.W : k + _k.W + 3] = leg.w
            p[k + _k.AXIS : k + _k.AXIS + 3] = leg.normal
            p[k + _k.ARM] = leg.arm
            p[k + _k.FOREARM] = leg.forearm
            p[k + _k.BRANCH] = leg.branch
            if leg.limits is not None and not (leg.type.code == _k.R_PA and leg.limits[1] - leg.limits[0]
                                               >= 2.0 * math.pi):
                p[k + _k.HAS_LIMITS] = 1.0
                p[k + _k.LO], p[k + _k.HI] = leg.limits
            if leg.sin_cone is not None:
                p[k + _k.HAS_CONE] = 1.0
                p[k + _k.SIN_CONE] = leg.sin_cone
        if options.get("stiffness_metrics"):
            frame.pack_stiffness(self, design, options, p)
        if options.get("clearance_metrics") or options.get("interference_free"):
            w = bodies.widths(self.plans, design)
            caps, pairs = bodies.capsules(legs, w, bodies.radii(options, self._codes(), self.default_length_unit))
            pack_clearance(p, (_k.CLEAR, _k.FREE, _k.UNIFORM, _k.CAPS), options, caps, pairs, w)
        return p

    @property
    def calibrated_plans(self) -> tuple:
        """The description's evaluation block as evaluation.plans.CalibratedPlan entries (none without one)."""
        from scalesynth.evaluation.plans import CalibratedPlan, ColumnPlan, Tolerance

        spec = self.description.evaluation if self.description is not None else None
        if spec is None:
            return ()
        return tuple(CalibratedPlan(Tolerance(p.tolerance["volume"], p.tolerance["gci"]),
                                    ColumnPlan(p.columns, p.cells, p.bisections, p.levels, p.beta, p.zlevels,
                                               p.zconfirm, p.faces, p.field_levels, p.gauss_points))
                     for p in spec.plans)

    @property
    def sector_plans(self) -> tuple:
        """The description's sector plans (evaluation.sector) as (Tolerance, SectorPlan) pairs (none without)."""
        from scalesynth.evaluation.plans import Tolerance
        from scalesynth.evaluation.sector import SectorPlan

        spec = self.description.evaluation if self.description is not None else None
        if spec is None:
            return ()
        return tuple((Tolerance(p.tolerance["volume"], p.tolerance["gci"]),
                      SectorPlan(p.angles, p.radii, p.z_points, p.min_z_points, p.scan, p.bisections))
                     for p in spec.sector)

    def sector_angle(self, packed: np.ndarray) -> float | None:
        """The fundamental sector (rad) about z shared by every design of ``packed`` ((n, N_PACKED): rotational
        symmetry of the legs, halved by a mirror; symmetry.fundamental_sectors), None where there is none or the
        fields are not the 3T template's (the sector evaluator, evaluation/sector.py)."""
        if self.motion != "3T" or self.n_fields != _sector.N_FIELDS:
            return None
        angles = symmetry.fundamental_sectors(packed)
        if not (np.all(np.isfinite(angles)) and np.all(angles == angles[0])):
            return None
        return float(angles[0])

    @property
    def sector_kernel(self):
        """The sector evaluator's Numba population kernel (describe/sector.population_sector_stats)."""
        return _sector.population_sector_stats

    @property
    def field_kernel(self):
        return _k.point_fields

    @property
    def lci_kernel(self):
        """point_fields without the stiffness stage (slot 0 bit for bit): a search on the LCI's metrics alone (a
        subclass with a kernel of its own, e.g. the planar one, keeps the default: its field kernel)."""
        return _k.point_lci if self.field_kernel is _k.point_fields else self.field_kernel

    @property
    def point_kernel(self):
        """The scalar LCI kernel (Mechanism.point_kernel) over ``lci_kernel`` instead of the field kernel: the same
        LCI bit for bit, and a cycle or a single point never compiles the stiffness stage."""
        from scalesynth.kernels.grid import lci_kernel

        return lci_kernel(self.lci_kernel, self.n_fields)

    @property
    def reach_kernel(self):
        return _k.point_reach

    @property
    def interval_kernel(self):
        """The z-columns' reachable intervals in closed form (kernel.column_intervals; -1 for a leg it does not
        handle, e.g. a tilted rotary axis); 3T only (6-DOF: nodes and bisection)."""
        return _k.column_intervals if self.motion == "3T" else None

    def kernel_branch(self, options) -> str:
        return "/".join(plan.branch for plan in self.plans)

    def kernel_clearance(self, options) -> bool:
        """The clearance slot is computed only where options.clearance_metrics or interference_free packs it."""
        return "clearance" in self.field_names and bool(options.get("clearance_metrics")
                                                         or options.get("interference_free"))

    def mirror_axes(self, options) -> tuple[int, ...]:
        """x (0) and/or y (1) where the packed legs are a mirror image of themselves in that plane: every leg has a
        partner (itself, on the plane) of the same type, lengths, branch, limits and cone whose base, platform and
        arm/rail directions are its own reflected (the plane normal of the cone check up to sign: the kernel reads
        only |f . axis|; with the stiffness fields on, equal sections and springs and a load in the plane). The
        kernel's fields (reach, LCI, sigma_min, sigma_max, stiffness_min, deflection) depend on nothing else, and a
        reflection keeps singular values and eigenvalues, so each such plane is a symmetry of every field.
        Checked on the packed legs of the default design and of two designs with every parameter scaled and shifted
        apart (a description symmetric only at its defaults, e.g. through an offset whose default is 0, is not
        declared).
        3T only."""
        if self.motion != "3T":
            return ()
        base = self.resolve_design({})
        scale = max([abs(v) for v in base.values()] + [1e-3])
        designs = [base] + [{n: v * (1.0 + 0.07 * (k + 1) * (1 + i % 3)) + 0.013 * scale * (k + 1) * (1 + i % 5)
                             for i, (n, v) in enumerate(base.items())} for k in range(2)]
        try:
            packed = [self.pack(self.resolve_design(d), options) for d in designs]
        except InvalidParameter:  # a scaled design the legs reject: declare nothing
            return ()
        return tuple(a for a in (0, 1) if all(symmetry.mirrored_legs(p, a) for p in packed))

    def bounding_box(self, design, options):
        """Intersection over the legs of the box of the set each leg can reach: R-Pa, a ball of radius L + l about
        B - r_p; P-Pa, the stroke segment of the rail swept by the half ball of radius l on its branch's side
        (f . e >= 0 for 'near', <= 0 for 'far', f the forearm: the platform joint lies beyond the carriage along
        the rail, or before it), minus r_p. An empty intersection gives a zero-size box at the origin."""
        lo, hi = np.full(3, -math.inf), np.full(3, math.inf)
        for leg in self.legs(design, options):
            if leg.type.code == _k.R_PA:
                c0 = c1 = leg.base - leg.platform
                down = up = np.full(3, leg.arm + leg.forearm)
            else:
                c0 = leg.base + leg.limits[0] * leg.u - leg.platform
                c1 = leg.base + leg.limits[1] * leg.u - leg.platform
                # extent of the half ball {|f| <= l, f . n >= 0}, n = -branch e, along each axis: l where the axis
                # points into the half (or along its face), else l sqrt(1 - n_k^2), its rim's
                n = -leg.branch * leg.u
                rim = leg.forearm * np.sqrt(np.maximum(0.0, 1.0 - n * n))
                up = np.where(n >= 0.0, leg.forearm, rim)
                down = np.where(n <= 0.0, leg.forearm, rim)
            lo = np.maximum(lo, np.minimum(c0, c1) - down)
            hi = np.minimum(hi, np.maximum(c0, c1) + up)
        if np.any(lo >= hi):
            return np.zeros(3), np.zeros(3)
        return lo, hi

    # ----- bodies (bodies.py) -------------------------------------------------------------------
    def _codes(self) -> list[float]:
        return [LEG_TYPES[plan.type].code for plan in self.plans]

    def link_geometry(self, design, options, pose, q):
        """Capsules of every body at platform centre ``pose`` with joint values ``q`` (bodies.py: upper_arm<i>,
        rail<i>, carriage<i>, forearm<i> as its parallelogram's bars, base, platform); radii from link_radius."""
        p = self.check_vector("pose", pose, 3)
        qv = self.check_vector("inputs", q, len(self.joints))
        rad = bodies.radii(options, self._codes(), self.default_length_unit)
        return bodies.link_geometry(self.legs(design, options), bodies.widths(self.plans, design), rad, p, qv)

    def link_endpoints(self, design, options, poses, q) -> np.ndarray:
        """Vectorised twin of link_geometry's segment endpoints at platform centres (m, 3) with joint values (m, 3):
        links.SegmentPoints (bodies.link_endpoints)."""
        return bodies.link_endpoints(self.legs(design, options), bodies.widths(self.plans, design), poses, q)

    def stiffness_model(self, design, options, pose, joints: str = "ideal"):
        """The stiffness frame (scalesynth.stiffness.FrameModel) at platform centre ``pose`` in the kernel's
        branch: arms or carriages on actuator springs, each parallelogram as two bars on universal joints, a rigid
        platform (frame.py); ``joints`` 'bonded' welds the passive universal joints."""
        return frame.stiffness_model(self, design, options, pose, joints)

    # ----- NumPy kinematics ---------------------------------------------------------------------
    def _labels(self) -> list[list[tuple[str, float]]]:
        return [list(LEG_TYPES[plan.type].branches.items()) for plan in self.plans]

    def inverse_kinematics(self, design, options, pose) -> list[Solution]:
        """Every branch combination whose legs all reach the pose (limits not applied), labelled by the legs' branch
        names joined by '/' (e.g. 'out/out/out', the kernel's for the rotary Delta)."""
        p = self.check_vector("pose", pose, 3)
        roots = [leg.roots(p) for leg in self.legs(design, options)]
        if any(not r for r in roots):
            return []
        out = []
        for combo in itertools.product(*self._labels()):
            label = "/".join(name for name, _ in combo)
            out.append(Solution(label, np.array([r[sign] for r, (_, sign) in zip(roots, combo, strict=True)])))
        return out

    def forward_kinematics(self, design, options, inputs) -> list[Solution]:
        """Both intersections of the three spheres |P - (A_i - r_p,i)| = l_i (A_i the actuated point), labelled
        'low' and 'high' by z (a Delta works 'low'); one 'double' when they touch; [] when they do not meet or when
        two centres coincide (no isolated assembly)."""
        q = self.check_vector("inputs", inputs, len(self.joints))
        legs = self.legs(design, options)
        centres = [leg.actuated_point(qi) - leg.platform for leg, qi in zip(legs, q, strict=True)]
        radii = [leg.forearm for leg in legs]
        return _three_spheres(centres, radii)

    def jacobians(self, design, options, pose, q) -> dict[str, Any]:
        """Jx (rows f_i, the forearm vectors Q_i - A_i), Jq = diag(f_i . dA_i/dq_i) and J = dx/dq = Jx^-1 Jq (None
        where Jx is singular). Raises InvalidPose when q does not assemble at the pose (a forearm off its length by
        more than 1e-6 relative)."""
        p = self.check_vector("pose", pose, 3)
        q = self.check_vector("inputs", q, len(self.joints))
        jx, jq = np.zeros((3, 3)), np.zeros((3, 3))
        for i, (leg, qi) in enumerate(zip(self.legs(design, options), q, strict=True)):
            f = p + leg.platform - leg.actuated_point(qi)
            if abs(float(np.linalg.norm(f)) - leg.forearm) > 1e-6 * max(leg.forearm, leg.arm):
                raise InvalidPose(f"inputs: joint values do not assemble at the pose (forearm {i + 1} would be "
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

    def singularity(self, design, options, pose, q, tol: float = 1e-7) -> str:
        """'inverse' (some |f_i . dA_i/dq_i| <= tol |f_i| |dA_i/dq_i|: a forearm square to its actuated point's
        motion), 'forward' (|det| of the unit forearm rows <= tol), 'both' or 'none'."""
        jac = self.jacobians(design, options, pose, q)
        legs = self.legs(design, options)
        qv = self.check_vector("inputs", q, len(self.joints))
        inverse = False
        for i, (leg, qi) in enumerate(zip(legs, qv, strict=True)):
            scale = float(np.linalg.norm(jac["Jx"][i]) * np.linalg.norm(leg.actuated_velocity(qi)))
            inverse |= abs(jac["Jq"][i, i]) <= tol * scale
        unit = jac["Jx"] / np.linalg.norm(jac["Jx"], axis=1)[:, None]
        forward = abs(float(np.linalg.det(unit))) <= tol
        return singularity_label(inverse, forward)

    def velocity_map(self, design, options, pose, q) -> np.ndarray:
        """A = Jq^-1 Jx: q_dot = A P_dot; rows at an inverse singularity (Jq_ii = 0) infinite."""
        jac = self.jacobians(design, options, pose, q)
        with np.errstate(divide="ignore", invalid="ignore"):
            return jac["Jx"] / np.diag(jac["Jq"])[:, None]


@functools.lru_cache(maxsize=256)
def _leg_directions(code: float, phi: float, frame: tuple) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(u, w, normal) of a leg in the mechanism frame: they depend on its type, turn and frame directions only, not
    on the design, so they are computed once per leg (the NSGA-II loop packs every design). Read-only arrays."""
    vec = dict(frame)
    if code == _k.R_PA:
        u = _unit(_turn(phi, vec["arm_zero"]))
        w = _unit(_turn(phi, vec["arm_positive"]))
        normal = np.cross(u, w)
    else:
        u = _unit(_turn(phi, vec["rail"]))
        w = np.zeros(3)
        radial = _turn(phi, (1.0, 0.0, 0.0))
        normal = np.cross(u, radial)
        if np.linalg.norm(normal) < 1e-9:  # a radial rail: the leg's plane is vertical
            normal = np.cross(u, (0.0, 0.0, 1.0))
        normal = _unit(normal)
    for a in (u, w, normal):
        a.flags.writeable = False
    return u, w, normal


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


def _three_spheres(centres, radii) -> list[Solution]:
    c1, c2, c3 = (np.asarray(c, dtype=float) for c in centres)
    r1, r2, r3 = radii
    scale = max(r1, r2, r3, float(np.abs(np.array(centres)).max()))
    ex = c2 - c1
    d = float(np.linalg.norm(ex))
    if d <= 1e-12 * scale:
        return []
    ex /= d
    t = c3 - c1
    i = float(ex @ t)
    ey = t - i * ex
    j = float(np.linalg.norm(ey))
    if j <= 1e-12 * scale:
        return []
    ey /= j
    ez = np.cross(ex, ey)
    x = (r1 * r1 - r2 * r2 + d * d) / (2.0 * d)
    y = (r1 * r1 - r3 * r3 + i * i + j * j) / (2.0 * j) - i * x / j
    h2 = r1 * r1 - x * x - y * y
    if h2 < -1e-12 * scale * scale:
        return []
    mid = c1 + x * ex + y * ey
    if h2 <= 1e-12 * scale * scale:
        return [Solution("double", mid)]
    h = math.sqrt(h2)
    a, b = mid + h * ez, mid - h * ez
    low, high = (a, b) if a[2] <= b[2] else (b, a)
    return [Solution("low", low), Solution("high", high)]


def _link_length_sum(plans, d: Mapping[str, float]) -> float:
    return float(sum(e.value(d) for plan in plans for e in plan.links.values()))


def _footprint(desc_mech_plans, d: Mapping[str, float]) -> float:
    pts = [_turn(plan.phi, [e.value(d) for e in plan.base])[:2] for plan in desc_mech_plans]
    return enclosing_circle_radius(pts)


# The per-voxel stiffness fields (kernel._stiffness: frame.py's idealisation condensed per leg). Opt-in, as seed 000's:
# their stage costs many times the kinematic fields, so a search whose metrics do not read them must not pay it.
STIFFNESS_METRICS_OPTION = Option(
    "stiffness_metrics", False, "true: compute the per-voxel fields stiffness_min and deflection (the frame of "
    "`stiffness`, ideal joints) and enable their metrics; false: they are 0 and their metrics unavailable")
STIFFNESS_FIELDS = (
    Field("stiffness_min", "N/{length}", "smallest eigenvalue of the platform's translational stiffness at P felt by "
          "a pure force (ideal joints, Euler-Bernoulli links, actuator springs; the frame of `stiffness`); 0 at a "
          "singular pose; its metrics need options.stiffness_metrics", "max", needs_options=("stiffness_metrics",)),
    Field("deflection", "{length}", "magnitude of the deflection of P under options.load (default 150 N down -z); "
          f"{_sl.DEFLECTION_CAP:g} at a singular pose; its metrics need options.stiffness_metrics", "min",
          (0.0, _sl.DEFLECTION_CAP), needs_options=("stiffness_metrics",)),
)


# The per-voxel clearance field (kernels.clearance.packed_capsule_gap over bodies.py's capsules), opt-in like the
# stiffness fields: a Delta has 120 capsule pairs, about ten times the kinematic fields' cost per voxel.
CLEARANCE_METRICS_OPTION = Option(
    "clearance_metrics", False, "true: compute the per-voxel field clearance (the link capsules of `show` and "
    "`cycle`, radii from link_radius) and enable its metrics; false: it is 0 and its metrics unavailable")
INTERFERENCE_FREE_OPTION = Option(
    "interference_free", False, "true: a pose whose link capsules overlap (clearance < 0) is unreachable")
CLEARANCE = Field(
    "clearance", "{length}", "smallest distance between the capsules of links that share no joint, minus their radii "
    "(< 0: the links interfere; bodies and radii of `show` and `cycle`, options.link_radius); its metrics need "
    "options.clearance_metrics", "max", (-math.inf, math.inf), needs_options=("clearance_metrics",))


def pack_clearance(p: np.ndarray, slots: tuple[int, int, int, int], options: Mapping[str, Any], caps, pairs,
                   widths=()) -> None:
    """The clearance block (flag, interference_free, uniform legs, capsules at ``slots``) of a 3T or 6-DOF
    template's packed vector from bodies.capsules / capsules6."""
    clear, free, uniform, at = slots
    p[clear] = 1.0
    p[free] = 1.0 if options.get("interference_free") else 0.0
    p[uniform] = 1.0 if bodies.uniform_legs(caps, widths) else 0.0
    bodies.pack_capsules(p, at, caps, pairs)


def from_description_3t(desc: Description) -> DescribedMechanism:
    """The registered mechanism of a validated 3T description (build.from_description dispatches by motion)."""
    plans = _plans(desc)
    lt0 = LEG_TYPES[plans[0].type]
    rotary = lt0.joint_unit == "angle"
    joints = tuple(f"{plan.joint}{i + 1}" for i, plan in enumerate(plans))
    options = tuple(Option(name, spec.default, spec.doc) for name, spec in desc.options.items())
    options += (Option("link_radius", None, bodies.LINK_RADIUS_DOC),
                *frame.options(desc.stiffness, desc.length_unit, rotary), STIFFNESS_METRICS_OPTION,
                CLEARANCE_METRICS_OPTION, INTERFERENCE_FREE_OPTION)
    sigma_unit = "{length}/rad" if rotary else "1"
    jac = "J = dx/dq (platform motion per rad of arm rotation)" if rotary else \
        "J = dx/dq (platform motion per unit carriage motion)"
    return DescribedMechanism(
        name=desc.name,
        title=desc.title,
        seed="",
        motion=desc.motion,
        task_axes=("x", "y", "z"),
        task_units=("length", "length", "length"),
        joints=joints,
        joint_units=tuple(LEG_TYPES[plan.type].joint_unit for plan in plans),
        parameters=tuple(Parameter(name, spec.default, spec.doc, spec.unit, spec.positive)
                         for name, spec in desc.parameters.items()),
        options=options,
        default_length_unit=desc.length_unit,
        fields=(*base_fields(sigma_unit, jac), *STIFFNESS_FIELDS, CLEARANCE),
        design_metrics=(
            DesignMetric("link_length_sum", "{length}", "every link length of every leg, summed (a parallelogram "
                         "counted once)", lambda d, o, _p=plans: _link_length_sum(_p, d)),
            DesignMetric("footprint_radius", "{length}", "radius of the smallest circle in the xy plane holding the "
                         "legs' base attachment points", lambda d, o, _p=plans: _footprint(_p, d)),
        ),
        description=desc,
        plans=plans,
    )
