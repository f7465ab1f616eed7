"""Planar five-bar packing robot with parallelograms (seed 004), spec mechanisms_000_004.md §2.

The parallelograms only keep the platform's orientation fixed, so the kinematics are those of a symmetric
five-bar (spec §2.1), all lengths in mm:

* active pivots B1 = (r, 0) (right arm) and B2 = (-r, 0) (left arm);
* arm angles alpha_i (rad) from +x, counter-clockwise; elbows Q_i = B_i + l1 (cos alpha_i, sin alpha_i);
* platform P = (x, y) = Q_i + l2 (cos beta_i, sin beta_i); the packing workspace is below the base (y < 0).

Design parameters r (half the pivot distance), l1 (arm), l2 (forearm). The defaults r = 200, l1 = 475,
l2 = 875 mm are the spec's ILLUSTRATIVE lengths (§2.7): the paper does not give its dimensions (§2.5-2.6).
Inputs q = (alpha1, alpha2) in rad; the operating (elbows-out) working mode is sigma1 = +1, sigma2 = -1 ("+-").
Both task axes are lengths, so LCI needs no characteristic length: LCI = sigma_min / sigma_max of the
forward Jacobian J = Jx^-1 Jq (mm/rad), which the paper states with the spectral norm (§2.4).

Arm limits are [lo, hi] intervals in rad taken modulo 2 pi, so an interval may extend past pi: the spec's
corrected limits are alpha1 in [-4 pi/9, 7 pi/36] and alpha2 in [29 pi/36, 13 pi/9] (§2.5).

The point kernel calls no trigonometric function, limits included (cross products against the limit
directions): cos/sin of the arm angles come from the law of cosines in algebraic form.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numba import njit

from scalesynth.errors import InvalidParameter, InvalidPose
from scalesynth.kernels import grid as _grid
from scalesynth.kernels.clearance import planar_capsule_gap
from scalesynth.kernels.conditioning import SIGMA_CAP, sv_2x2
from scalesynth.kernels.flags import FASTMATH
from scalesynth.mechanisms import links
from scalesynth.mechanisms.base import (
    DesignMetric,
    Field,
    Mechanism,
    Option,
    Parameter,
    Solution,
    base_fields,
    parse_range,
    singularity_label,
    svd_lci,
    wrap_angle,
)
from scalesynth.stiffness.sections import check_stiffness_options, stiffness_options

MODES = ("++", "+-", "-+", "--")
FOREARMS = ("single", "parallelogram")
LINK_GROUPS = ("arm", "forearm", "arm_link", "forearm_link")
# default actuator stiffness: 1e5 N m/rad (a servo with a stiff precision reducer), in N mm/rad
ACTUATOR_STIFFNESS = 1e8
# default capsule radii (mm) of the bodies, illustrative like the lengths: the platform ball carries the gripper
LINK_RADII = {"base": 25.0, "arm1": 20.0, "arm2": 20.0, "forearm1": 15.0, "forearm2": 15.0, "platform": 40.0}
TWO_PI = 2.0 * math.pi

# packed-parameter layout (see PlanarFivebar.pack); arm limit i occupies 6 slots from _LIM[i]:
# has, cos lo, sin lo, cos hi, sin hi, wide (1 if hi - lo > pi)
_R, _L1, _L2, _S1, _S2 = 0, 1, 2, 3, 4
_LIM1, _LIM2 = 5, 11
# stiffness slots (point_fields slots 3, 4): arm EA (N), arm EI (N mm^2), forearm EA (N), actuator stiffness (N mm/rad),
# load Fx, Fy (N)
_EA1, _EI1, _EA2, _KACT, _FX, _FY = 17, 18, 19, 20, 21, 22
# eigenvalue ratio (smallest / largest) at or below which the platform stiffness is singular (as stiffness.solve)
SINGULAR_RTOL = 1e-11
DEFLECTION_CAP = SIGMA_CAP  # mm: the per-voxel deflection at a singular pose (the field contract has no inf)
# capsule radii of base, arm1, arm2, forearm1, forearm2, platform (order of LINK_RADII); 1 = interference-free only
_RAD = 23
_FREE_ONLY = 29
_F_CLEARANCE = 5  # slot of the clearance field in the field kernel's out (its index in ``fields``)
N_PACKED = 30


@njit(cache=True, fastmath=FASTMATH)
def _arm(u, y, l1, l2, sigma):
    """cos(alpha), sin(alpha) of one chain's IK root sigma, without transcendental calls, and
    S = sqrt(D^2 + E^2 - F^2), the discriminant of spec §2.2.

    (u, y) = P - B_i. With rho^2 = u^2 + y^2 and K = rho^2 + l1^2 - l2^2 (law of cosines),
    alpha = atan2(y, u) + sigma * arccos(K / (2 l1 rho)); expanding cos/sin of that sum gives
    cos(alpha) = (u K - sigma y S) / (2 l1 rho^2), sin(alpha) = (y K + sigma u S) / (2 l1 rho^2), where
    S^2 = 4 l1^2 rho^2 - K^2 = ((l1 + l2)^2 - rho^2) (rho^2 - (l1 - l2)^2) is written in factored form so that
    it keeps its relative accuracy near the reach boundary. S = 2 l1 l2 |sin(beta - alpha)| vanishes exactly at
    the chain's inverse singularity. Returns (ok, cos, sin, S); ok is False when P is out of the chain's reach.
    """
    rho2 = u * u + y * y
    if rho2 <= 0.0:
        return False, 0.0, 0.0, 0.0  # P on the pivot: alpha undetermined (measure-zero set)
    h = ((l1 + l2) * (l1 + l2) - rho2) * (rho2 - (l1 - l2) * (l1 - l2))
    if h < 0.0:
        return False, 0.0, 0.0, 0.0
    s = math.sqrt(h)
    k = rho2 + l1 * l1 - l2 * l2
    inv = 1.0 / (2.0 * l1 * rho2)
    return True, (u * k - sigma * y * s) * inv, (y * k + sigma * u * s) * inv, s


@njit(cache=True, fastmath=FASTMATH)
def _arc_ok(p, k, c, s):
    """True if the angle with cosine c and sine s lies in arm limit k (slots p[k:k+6]), modulo 2 pi.

    No atan2: with a = the angle, sin(a - lo) >= 0 and sin(hi - a) >= 0 (two cross products) select [lo, hi] when
    hi - lo <= pi; a wider interval is the complement of an arc narrower than pi, so either test suffices.
    """
    if p[k] <= 0.0:
        return True
    after_lo = p[k + 1] * s - p[k + 2] * c >= 0.0
    before_hi = c * p[k + 4] - s * p[k + 3] >= 0.0
    if p[k + 5] > 0.0:
        return after_lo or before_hi
    return after_lo and before_hi


@njit(cache=True, fastmath=FASTMATH)
def _kinematics(p, x, y, out, conditioning=True):
    """Slots 0-2 at P = (x, y) in the packed working mode: LCI (sigma_min/sigma_max of J), sigma_min and sigma_max
    of J = dx/dq (mm/rad); unreachable: write_unreachable. Returns (ok, cos, sin of alpha1, cos, sin of alpha2).
    ``conditioning`` (a constant): False stops after the reach and arm-limit checks with slot 0 = 0 where they
    pass (point_reach)."""
    r = p[_R]
    l1 = p[_L1]
    l2 = p[_L2]
    u1 = x - r
    u2 = x + r
    ok1, c1, s1, g1 = _arm(u1, y, l1, l2, p[_S1])
    ok2, c2, s2, g2 = _arm(u2, y, l1, l2, p[_S2])
    if not ok1 or not ok2 or not _arc_ok(p, _LIM1, c1, s1) or not _arc_ok(p, _LIM2, c2, s2):
        _grid.write_unreachable(out)
        return False, 0.0, 0.0, 0.0, 0.0
    if not conditioning:
        out[0] = 0.0  # reachable (point_reach): slots 1-2 not computed
        return True, c1, s1, c2, s2
    # forearm vectors w_i = P - Q_i = l2 (cos beta_i, sin beta_i)
    w1x = u1 - l1 * c1
    w1y = y - l1 * s1
    w2x = u2 - l1 * c2
    w2y = y - l1 * s2
    # J = Jx^-1 Jq = adj(Jx) Jq / det(Jx) with Jx rows w_i / l2 and Jq = diag(-sigma_i g_i) / (2 l2) (spec §2.4).
    # LCI ignores the common scale and the column signs, so adj(Jx) diag(g1, g2) suffices; it stays finite at a
    # forward singularity (det Jx = 0), where its rank drops to 1 and the LCI is 0, the limit of J's.
    # With W the matrix of rows w_i, J = adj(W) diag(-sigma_i g_i) / (2 det W): sigma(J) = sigma(B) / (2 |det W|).
    lci, smin, smax = sv_2x2(w2y * g1, -w1y * g2, -w2x * g1, w1x * g2)
    out[0] = lci
    det2 = 2.0 * abs(w1x * w2y - w1y * w2x)
    if not det2 * SIGMA_CAP > smax:  # forward singularity: J unbounded
        out[1] = 0.0
        out[2] = SIGMA_CAP
    else:
        out[1] = smin / det2
        out[2] = smax / det2
    return True, c1, s1, c2, s2


@njit(cache=True, fastmath=FASTMATH)
def kinematic_fields(p, x, y, z, out):
    """point_fields without the stiffness (slots 3, 4 left 0): LCI, sigma_min, sigma_max and the clearance, for
    benchmarks (the cost of the stiffness fields against the rest)."""
    _fields(p, x, y, out, False)


@njit(cache=True, fastmath=FASTMATH)
def _leg_compliance(p, u, y, c, s):
    """Compliance (mm/N) of one RRR chain along its forearm, ideal joints: the forearm (a pinned bar) stretches,
    and the arm tip Q moves as a cantilever on a torsional actuator spring under the forearm force. Returns the
    forearm unit vector (ex, ey) and the compliance. (u, y) = P - B_i, (c, s) = cos, sin of the arm angle."""
    l1 = p[_L1]
    l2 = p[_L2]
    ex = (u - l1 * c) / l2
    ey = (y - l1 * s) / l2
    along = ex * c + ey * s  # forearm direction . arm direction
    across = ey * c - ex * s  # forearm direction . arm normal
    bend = l1 * l1 * l1 / (3.0 * p[_EI1]) + l1 * l1 / p[_KACT]
    return ex, ey, l2 / p[_EA2] + along * along * l1 / p[_EA1] + across * across * bend


@njit(cache=True, fastmath=FASTMATH)
def _stiffness(p, x, y, c1, s1, c2, s2):
    """(stiffness_min N/mm, deflection mm) at a reachable P, ideal joints: platform stiffness
    K = sum_i u_i u_i^T / c_i (u_i forearm unit vector, c_i its chain's compliance: a per-leg condensation), its
    smallest eigenvalue and |K^-1 F| under the packed load F. Under ideal joints the parallelograms carry no force
    from a load at P (moment balance about P), so this holds for both forearm options. At a singular pose
    (lambda_min(K) <= 1e-11 lambda_max(K)): (0, DEFLECTION_CAP) for a non-zero load (the field contract has no inf)."""
    r = p[_R]
    e1x, e1y, cc1 = _leg_compliance(p, x - r, y, c1, s1)
    e2x, e2y, cc2 = _leg_compliance(p, x + r, y, c2, s2)
    kxx = e1x * e1x / cc1 + e2x * e2x / cc2
    kxy = e1x * e1y / cc1 + e2x * e2y / cc2
    kyy = e1y * e1y / cc1 + e2y * e2y / cc2
    det = kxx * kyy - kxy * kxy
    half = 0.5 * (kxx + kyy)
    diff = 0.5 * (kxx - kyy)
    kmax = half + math.sqrt(diff * diff + kxy * kxy)
    kmin = det / kmax  # = lambda_min, without cancellation
    if not kmin > SINGULAR_RTOL * kmax:
        return 0.0, DEFLECTION_CAP if (p[_FX] != 0.0 or p[_FY] != 0.0) else 0.0
    dx = (kyy * p[_FX] - kxy * p[_FY]) / det
    dy = (kxx * p[_FY] - kxy * p[_FX]) / det
    return kmin, min(math.sqrt(dx * dx + dy * dy), DEFLECTION_CAP)


@njit(cache=True, fastmath=FASTMATH)
def _clearance(p, x, y, c1, s1, c2, s2):
    """Smallest gap (mm) between the link capsules that share no joint (as in link_geometry): base B2-B1,
    arm_i B_i-Q_i, forearm_i Q_i-P and the platform ball at P; negative where two of them overlap."""
    r = p[_R]
    l1 = p[_L1]
    q1x = r + l1 * c1
    q1y = l1 * s1
    q2x = -r + l1 * c2
    q2y = l1 * s2
    rb, ra1, ra2, rf1, rf2, rp = p[_RAD], p[_RAD + 1], p[_RAD + 2], p[_RAD + 3], p[_RAD + 4], p[_RAD + 5]
    gap = planar_capsule_gap(-r, 0.0, r, 0.0, rb, q1x, q1y, x, y, rf1)
    gap = min(gap, planar_capsule_gap(-r, 0.0, r, 0.0, rb, q2x, q2y, x, y, rf2))
    gap = min(gap, planar_capsule_gap(-r, 0.0, r, 0.0, rb, x, y, x, y, rp))
    gap = min(gap, planar_capsule_gap(r, 0.0, q1x, q1y, ra1, -r, 0.0, q2x, q2y, ra2))
    gap = min(gap, planar_capsule_gap(r, 0.0, q1x, q1y, ra1, q2x, q2y, x, y, rf2))
    gap = min(gap, planar_capsule_gap(r, 0.0, q1x, q1y, ra1, x, y, x, y, rp))
    gap = min(gap, planar_capsule_gap(-r, 0.0, q2x, q2y, ra2, q1x, q1y, x, y, rf1))
    gap = min(gap, planar_capsule_gap(-r, 0.0, q2x, q2y, ra2, x, y, x, y, rp))
    return gap


@njit(cache=True, fastmath=FASTMATH)
def point_fields(p, x, y, z, out):
    """Fields at P = (x, y) in the packed working mode (kernels.grid contract): slots 0-2 LCI, sigma_min,
    sigma_max of J = dx/dq (mm/rad); 3 stiffness_min (N/mm), 4 deflection (mm) under the packed load (ideal
    joints, docs/stiffness.md); 5 clearance (mm) of the link capsules; LCI -1 (and zeros) if unreachable (or, with
    interference_free, where the capsules overlap); z unused."""
    _fields(p, x, y, out, True)


@njit(cache=True, fastmath=FASTMATH)
def point_reach(p, x, y, z, out):
    """Slot 0 of point_fields up to its value: >= 0 exactly where point_fields' LCI is (the same working mode and
    arm limits and, with interference_free, the same clearance), -1 elsewhere; no conditioning, stiffness or
    (without interference_free) clearance. The adaptive evaluator's nodes and bisections (Mechanism.reach_kernel)."""
    ok, c1, s1, c2, s2 = _kinematics(p, x, y, out, False)
    if ok and p[_FREE_ONLY] > 0.0 and _clearance(p, x, y, c1, s1, c2, s2) < 0.0:
        out[0] = -1.0


@njit(cache=True, fastmath=FASTMATH)
def _fields(p, x, y, out, stiffness):
    """point_fields, with the stiffness slots only when ``stiffness`` (a constant: each caller's copy keeps its
    branch)."""
    ok, c1, s1, c2, s2 = _kinematics(p, x, y, out)
    if ok:
        gap = _clearance(p, x, y, c1, s1, c2, s2)
        if gap < 0.0 and p[_FREE_ONLY] > 0.0:
            _grid.write_unreachable(out)
            return
        if stiffness:
            out[3], out[4] = _stiffness(p, x, y, c1, s1, c2, s2)
        else:
            out[3], out[4] = 0.0, 0.0
        out[_F_CLEARANCE] = gap


DESIGN_METRICS = (
    DesignMetric(
        "link_length_sum", "{length}",
        "arms and forearms of both chains: 2 (l1 + l2) (the parallelograms' second bars only keep the platform's "
        "orientation and are not counted)",
        lambda d, o: 2.0 * (d["l1"] + d["l2"]),
    ),
    DesignMetric(
        "footprint_radius", "{length}",
        "radius of the smallest circle in the base plane holding the active pivots B1, B2 = (+-r, 0): r",
        lambda d, o: d["r"],
    ),
)


def check_fivebar_stiffness_options(options: dict[str, Any]) -> None:
    if options["forearm"] not in FOREARMS:
        raise InvalidParameter(f"options.forearm: must be one of {', '.join(FOREARMS)}, got {options['forearm']!r}")
    d = options["parallelogram_spacing"]
    if isinstance(d, bool) or not isinstance(d, (int, float)) or not (math.isfinite(d) and d > 0):
        raise InvalidParameter(f"options.parallelogram_spacing: must be a finite number > 0 (mm), got {d!r}")
    options["parallelogram_spacing"] = float(d)
    offs = options["parallelogram_offsets"]
    if (not isinstance(offs, (list, tuple)) or len(offs) != 2
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in offs)):
        raise InvalidParameter(f"options.parallelogram_offsets: expected [angle arm link, angle forearm link] rad, "
                               f"got {offs!r}")
    options["parallelogram_offsets"] = [float(v) for v in offs]
    check_stiffness_options(options, 2, LINK_GROUPS)


class PlanarFivebar(Mechanism):
    """Seed-004 mechanism; see module docstring."""

    def check_options(self, options: dict[str, Any]) -> None:
        if options["mode"] not in MODES:
            raise InvalidParameter(f"options.mode: must be one of {', '.join(MODES)}, got {options['mode']!r}")
        for name in ("alpha1_limits", "alpha2_limits"):
            options[name] = parse_range(name, options[name])
        check_fivebar_stiffness_options(options)
        links.check_radius_option(options, LINK_RADII)
        links.check_flag_option(options, "interference_free")

    def pack(self, design: Mapping[str, float], options: Mapping[str, Any]) -> np.ndarray:
        p = np.zeros(N_PACKED)
        p[_R] = design["r"]
        p[_L1] = design["l1"]
        p[_L2] = design["l2"]
        mode = options["mode"]
        p[_S1] = 1.0 if mode[0] == "+" else -1.0
        p[_S2] = 1.0 if mode[1] == "+" else -1.0
        for name, k in (("alpha1_limits", _LIM1), ("alpha2_limits", _LIM2)):
            lim = options.get(name)
            if lim is not None and lim[1] - lim[0] < TWO_PI:  # a full turn or more restricts nothing
                lo, hi = lim
                p[k : k + 6] = (1.0, math.cos(lo), math.sin(lo), math.cos(hi), math.sin(hi), hi - lo > math.pi)
        from scalesynth.stiffness.sections import tube_section

        arm, fore = tube_section(options, "arm", "mm"), tube_section(options, "forearm", "mm")
        p[_EA1], p[_EI1], p[_EA2] = arm.EA, arm.EI, fore.EA
        p[_KACT] = options["actuator_stiffness"]
        p[_FX], p[_FY] = options["load"]
        p[_RAD : _RAD + 6] = list(links.radii(options, LINK_RADII).values())
        p[_FREE_ONLY] = 1.0 if options["interference_free"] else 0.0
        return p

    @property
    def field_kernel(self):
        return point_fields

    @property
    def reach_kernel(self):
        return point_reach

    def kernel_branch(self, options) -> str:
        return options["mode"]

    def mirror_axes(self, options) -> tuple[int, ...]:
        """x (axis 0): the mirror image in x = 0 swaps the two chains (alpha2 = pi - alpha1), so with a working mode
        whose two chains mirror each other ('+-' or '-+'), alpha2 limits that mirror the alpha1 limits (both null,
        or equal packed bounds to rounding), equal radii of the swapped bodies and no load along x every field is
        symmetric (the parallelograms carry no load: point_fields)."""
        if options["mode"] not in ("+-", "-+") or options["load"][0] != 0.0:
            return ()
        if not links.mirrored_radii(options, LINK_RADII, [("arm1", "arm2"), ("forearm1", "forearm2")]):
            return ()
        p = self.pack(self.default_design(), options)
        one, two = p[_LIM1 : _LIM1 + 6], p[_LIM2 : _LIM2 + 6]
        # the mirror of [lo, hi] is [pi - hi, pi - lo]: cos changes sign, sin stays
        mirrored = np.array([one[0], -one[3], one[4], -one[1], one[2], one[5]])
        if not np.allclose(two, mirrored, rtol=0.0, atol=1e-12):
            return ()
        return (0,)

    def bounding_box(self, design, options):
        """Box of the reachable set: P lies in both disks of radius L = l1 + l2 around (+-r, 0), so
        |x| <= L - r and |y| <= sqrt(L^2 - r^2) (both attained at a fully stretched chain); the third entry is
        unused (0). An empty lens (L <= r) gives a zero-size box at the origin, which is unreachable."""
        r, reach = design["r"], design["l1"] + design["l2"]
        xr = max(reach - r, 0.0)
        yr = math.sqrt(max(reach * reach - r * r, 0.0))
        return np.array([-xr, -yr, 0.0]), np.array([xr, yr, 0.0])

    # ----- NumPy kinematics (CLI, tests) ----------------------------------------------------------
    def inverse_kinematics(self, design, options, pose) -> list[Solution]:
        """All four IK branches (sigma1 sigma2) as (alpha1, alpha2) in rad, each in (-pi, pi]; [] if unreachable.

        Spec §2.2: D cos(alpha) + E sin(alpha) + F = 0 with D = -2 l1 u, E = -2 l1 y, F = u^2 + y^2 + l1^2 - l2^2
        (u = x - r for chain 1, x + r for chain 2), alpha(sigma) = atan2(E, D) - sigma arccos(-F / |(D, E)|).
        A pose on a reach boundary (within 1e-12 in the arccos argument) is accepted as a double root.
        """
        x, y = self.check_vector("pose", pose, 2)
        r, l1, l2 = design["r"], design["l1"], design["l2"]
        roots = []
        for u in (x - r, x + r):
            dd, ee = -2.0 * l1 * u, -2.0 * l1 * y
            f = u * u + y * y + l1 * l1 - l2 * l2
            norm = math.hypot(dd, ee)
            if norm == 0.0:
                return []
            k = -f / norm
            if abs(k) > 1.0 + 1e-12:
                return []
            g = math.acos(min(1.0, max(-1.0, k)))
            base = math.atan2(ee, dd)
            roots.append({1: wrap_angle(base - g), -1: wrap_angle(base + g)})
        return [
            Solution(s1 + s2, np.array([roots[0][1 if s1 == "+" else -1], roots[1][1 if s2 == "+" else -1]]))
            for s1 in "+-"
            for s2 in "+-"
        ]

    def elbows(self, design, q) -> tuple[np.ndarray, np.ndarray]:
        """Elbow points Q1, Q2 (mm) of arm angles q = (alpha1, alpha2)."""
        a1, a2 = self.check_vector("inputs", q, 2)
        r, l1 = design["r"], design["l1"]
        return (
            np.array([r + l1 * math.cos(a1), l1 * math.sin(a1)]),
            np.array([-r + l1 * math.cos(a2), l1 * math.sin(a2)]),
        )

    def forward_kinematics(self, design, options, inputs) -> list[Solution]:
        """Both assembly modes of arm angles (alpha1, alpha2): the intersections of the circles of radius l2
        around the two elbows (spec §2.3). Label '+' is P = M + h R90(Q2 - Q1)/|Q2 - Q1| (M the midpoint,
        R90 a quarter turn counter-clockwise), '-' the mirror image; with the left elbow Q2 to the left of Q1,
        '+' is the lower solution (the packing side). A double root 'double' when the circles are tangent
        (forward singularity); [] when they do not meet or coincide (Q1 = Q2: infinitely many solutions)."""
        q1, q2 = self.elbows(design, inputs)
        l2 = design["l2"]
        u = q2 - q1
        dist = float(np.hypot(*u))
        scale = max(l2, design["l1"], design["r"])
        if dist <= 1e-14 * scale:
            return []
        h2 = l2 * l2 - dist * dist / 4.0
        if h2 < -1e-12 * scale * scale:
            return []
        mid = 0.5 * (q1 + q2)
        if h2 <= 1e-12 * scale * scale:
            return [Solution("double", mid)]
        h = math.sqrt(h2)
        perp = np.array([-u[1], u[0]]) / dist
        return [Solution("+", mid + h * perp), Solution("-", mid - h * perp)]

    def forearm_angles(self, design, pose, q) -> np.ndarray:
        """(beta1, beta2) in rad, (-pi, pi]: directions of the forearms Q_i -> P. Raises InvalidPose when the
        arm angles q do not assemble at the pose (a forearm length off l2 by more than 1e-6 relative)."""
        p = self.check_vector("pose", pose, 2)
        l2 = design["l2"]
        betas = []
        for i, qi in enumerate(self.elbows(design, q), start=1):
            w = p - qi
            length = float(np.hypot(*w))
            if abs(length - l2) > 1e-6 * max(l2, design["l1"], design["r"]):
                raise InvalidPose(
                    f"inputs: arm angles do not assemble at the pose (forearm {i} would be {length:g} long, "
                    f"l2 = {l2:g})"
                )
            betas.append(math.atan2(w[1], w[0]))
        return np.array(betas)

    def jacobians(self, design, options, pose, q) -> dict[str, np.ndarray]:
        """Jx (rows (cos beta_i, sin beta_i)), Jq = l1 diag(sin(beta_i - alpha_i)) (mm) and the forward Jacobian
        J = Jx^-1 Jq (mm/rad, dP = J dalpha; None at an exact forward singularity), spec §2.4."""
        a1, a2 = self.check_vector("inputs", q, 2)
        b1, b2 = self.forearm_angles(design, pose, q)
        l1 = design["l1"]
        jx = np.array([[math.cos(b1), math.sin(b1)], [math.cos(b2), math.sin(b2)]])
        jq = l1 * np.diag([math.sin(b1 - a1), math.sin(b2 - a2)])
        try:
            j = np.linalg.solve(jx, jq)
        except np.linalg.LinAlgError:
            j = None
        return {"Jx": jx, "Jq": jq, "J": j}

    def singularity(self, design, options, pose, q, tol: float = 1e-7) -> str:
        """'inverse' (|sin(beta_i - alpha_i)| <= tol: arm and forearm collinear), 'forward'
        (|sin(beta1 - beta2)| <= tol: forearms collinear), 'both' or 'none'; tol is scale-free."""
        a1, a2 = self.check_vector("inputs", q, 2)
        b1, b2 = self.forearm_angles(design, pose, q)
        inverse = abs(math.sin(b1 - a1)) <= tol or abs(math.sin(b2 - a2)) <= tol
        forward = abs(math.sin(b1 - b2)) <= tol
        return singularity_label(inverse, forward)

    def lci(self, design, options, pose, q) -> float:
        """LCI = sigma_min / sigma_max of J with NumPy's SVD (0 at any singularity)."""
        jac = self.jacobians(design, options, pose, q)
        if jac["J"] is None or self.singularity(design, options, pose, q, tol=0.0) != "none":
            return 0.0
        return svd_lci(jac["J"])

    def link_geometry(self, design, options, pose, q) -> links.LinkGeometry:
        """Capsules in the plane z = 0 (mm): base B2 -> B1, arm_i B_i -> Q_i, forearm_i Q_i -> P, and the
        platform as a ball at P. Adjacent (a joint between them): base-arm_i, arm_i-forearm_i, the two forearms
        (they meet at P), forearm_i-platform. Radii: option ``link_radius``, defaults LINK_RADII."""
        x, y = self.check_vector("pose", pose, 2)
        q1, q2 = self.elbows(design, q)
        rad = links.radii(options, LINK_RADII)
        r = design["r"]
        b1, b2, p = links.point(r, 0.0), links.point(-r, 0.0), links.point(x, y)
        e1, e2 = links.point(*q1), links.point(*q2)
        ends = {"base": (b2, b1), "arm1": (b1, e1), "arm2": (b2, e2), "forearm1": (e1, p), "forearm2": (e2, p),
                "platform": (p, p)}
        segments = tuple(links.Segment(name, name, a, b, rad[name]) for name, (a, b) in ends.items())
        return links.LinkGeometry(segments, links.adjacency([
            ("base", "arm1"), ("base", "arm2"), ("arm1", "forearm1"), ("arm2", "forearm2"),
            ("forearm1", "forearm2"), ("forearm1", "platform"), ("forearm2", "platform"),
        ]))

    def link_endpoints(self, design, options, poses, q) -> np.ndarray:
        """Vectorised twin of link_geometry's segment endpoints at poses (m, 2) with arm angles q (m, 2):
        links.SegmentPoints (mm), segments in link_geometry's order."""
        pts, q = np.asarray(poses, dtype=float), np.asarray(q, dtype=float)
        r, l1 = design["r"], design["l1"]
        b1, b2, p = (r, 0.0, 0.0), (-r, 0.0, 0.0), (pts[:, 0], pts[:, 1], 0.0)
        e1 = (r + l1 * np.cos(q[:, 0]), l1 * np.sin(q[:, 0]), 0.0)
        e2 = (-r + l1 * np.cos(q[:, 1]), l1 * np.sin(q[:, 1]), 0.0)
        return links.segment_points([(b2, b1), (b1, e1), (b2, e2), (e1, p), (e2, p), (p, p)], len(pts))

    def velocity_map(self, design, options, pose, q) -> np.ndarray:
        """A = Jq^-1 Jx (rad/mm): alpha_dot = A P_dot, the inverse of J (spec §2.4); rows with an inverse
        singularity (Jq_ii = 0) are infinite."""
        jac = self.jacobians(design, options, pose, q)
        with np.errstate(divide="ignore", invalid="ignore"):
            return jac["Jx"] / np.diag(jac["Jq"])[:, None]

    def cycle_kinematics(self, design, options, poses, label: str) -> tuple[np.ndarray, np.ndarray]:
        """Vectorised twin of Mechanism.cycle_kinematics: the closed-form IK of inverse_kinematics in branch
        ``label`` and A = Jq^-1 Jx of velocity_map at poses (n, 2) in NumPy; NaN rows out of reach."""
        pts = np.asarray(poses, dtype=float)
        return _cycle_kinematics(pts[:, 0], pts[:, 1], design["r"], design["l1"], design["l2"], label)

    def population_cycle_kinematics(self, designs, options, poses, label: str) -> tuple[np.ndarray, np.ndarray]:
        """cycle_kinematics of many designs at once (the same element-wise NumPy over designs x poses): poses
        (D, n, 2) -> q (D, n, 2), A (D, n, 2, 2)."""
        pts = np.asarray(poses, dtype=float)
        r, l1, l2 = (np.array([[d[name]] for d in designs], dtype=float) for name in ("r", "l1", "l2"))
        return _cycle_kinematics(pts[..., 0], pts[..., 1], r, l1, l2, label)

    def resolution_index(self, design, options, pose, dalpha=(1.0, 1.0)) -> float:
        """Kinematic resolution |J dalpha| (mm per the arm increments dalpha in rad; spec §2.4, paper eq. 18) in
        the working mode options['mode']. Infinite at an exact forward singularity (J unbounded); raises
        InvalidPose when the pose is out of reach."""
        dq = self.check_vector("dalpha", dalpha, 2)
        branches = {s.label: s.values for s in self.inverse_kinematics(design, options, pose)}
        if not branches:
            raise InvalidPose(f"pose: {tuple(float(v) for v in pose)} is out of reach")
        j = self.jacobians(design, options, pose, branches[self.kernel_branch(options)])["J"]
        return math.inf if j is None else float(np.linalg.norm(j @ dq))

    # ----- stiffness (scalesynth.stiffness) -------------------------------------------------------
    def stiffness_model(self, design, options, pose, joints: str = "ideal"):
        """Frame model (scalesynth.stiffness.FrameModel, planar, mm, N) at pose P = (x, y) in the kernel's working
        mode; raises InvalidPose when P is outside the workspace (out of reach or outside the arm limits).
        ``joints``: 'ideal' (the per-voxel fields' idealisation) or 'bonded' (every passive joint welded, as in an FE
        model with bonded contacts; actuators stay springs).

        forearm 'single': the symmetric five-bar 5R (paper Fig. 7a, parallelograms removed); the platform is the pin
        P. 'parallelogram': the right chain as built (paper §1): arm parallelogram (arm + arm link, offset
        parallelogram_spacing along the fixed direction parallelogram_offsets[0]) carrying a rigid hinge plate, then
        the forearm parallelogram (forearm + forearm link, offset along parallelogram_offsets[1]) carrying the rigid
        platform; the left chain stays arm + forearm. Actuators: torsional springs at B1, B2 between arm and base."""
        from scalesynth.stiffness.model import Body, FrameModel, Joint, Link
        from scalesynth.stiffness.sections import tube_section

        p = self.check_vector("pose", pose, 2)
        branches = {s.label: s.values for s in self.inverse_kinematics(design, options, p)}
        q = branches.get(self.kernel_branch(options))
        packed = self.pack(design, options)
        if q is None or self.point_kernel(packed, p[0], p[1], 0.0) < 0.0:
            raise InvalidPose(f"pose: ({p[0]:g}, {p[1]:g}) is outside the workspace (mode {options['mode']}, "
                              "arm limits included)")
        r = design["r"]
        q1, q2 = self.elbows(design, q)
        b1, b2 = np.array([r, 0.0]), np.array([-r, 0.0])
        z = np.array([0.0, 0.0, 1.0])
        k = options["actuator_stiffness"]
        sec = {g: tube_section(options, g, "mm") for g in LINK_GROUPS}

        def link(name, group, a, b):
            s = sec[group]
            return Link(name, group, np.asarray(a, float), np.asarray(b, float), s.EA, s.EI, s.EI, s.GJ)

        bonded = joints == "bonded"

        def rev(name, at, a, b, stiffness=None):
            if bonded and stiffness is None:  # a passive joint welded shut (moment-carrying)
                return Joint(name, "fixed", np.asarray(at, float), (a, b))
            return Joint(name, "revolute", np.asarray(at, float), (a, b), (z,), stiffness)

        links = [link("arm1", "arm", b1, q1), link("forearm1", "forearm", q1, p),
                 link("arm2", "arm", b2, q2), link("forearm2", "forearm", q2, p)]
        joints = [rev("actuator1", b1, "arm1.a", "base", k), rev("elbow1", q1, "arm1.b", "forearm1.a"),
                  rev("actuator2", b2, "arm2.a", "base", k), rev("elbow2", q2, "arm2.b", "forearm2.a"),
                  rev("wrist2", p, "forearm2.b", "platform")]
        notes = ["planar frame in the xy plane; revolute axes along z; the load acts at P"]
        if bonded:
            notes.append("joints bonded: every passive joint welded (carries moments), actuators stay springs")
        if options["forearm"] == "single":
            joints.append(rev("wrist1", p, "forearm1.b", "platform"))
            bodies = [Body("base", np.zeros(2)), Body("platform", p.copy(), "rigid" if bonded else "point")]
        else:
            d = options["parallelogram_spacing"]
            phi_a, phi_f = options["parallelogram_offsets"]
            na = d * np.array([math.cos(phi_a), math.sin(phi_a)])
            nf = d * np.array([math.cos(phi_f), math.sin(phi_f)])
            links += [link("arm_link1", "arm_link", b1 + na, q1 + na),
                      link("forearm_link1", "forearm_link", q1 + nf, p + nf)]
            joints = [j for j in joints if j.name != "elbow1"]
            joints += [rev("elbow1", q1, "arm1.b", "plate1"), rev("plate_forearm1", q1, "forearm1.a", "plate1"),
                       rev("arm_link_base1", b1 + na, "arm_link1.a", "base"),
                       rev("arm_link_plate1", q1 + na, "arm_link1.b", "plate1"),
                       rev("forearm_link_plate1", q1 + nf, "forearm_link1.a", "plate1"),
                       rev("wrist1", p, "forearm1.b", "platform"),
                       rev("forearm_link_platform1", p + nf, "forearm_link1.b", "platform")]
            bodies = [Body("base", np.zeros(2)), Body("plate1", q1.copy()), Body("platform", p.copy())]
            notes.append("right chain: arm and forearm parallelograms (paper §1); hinge plate and platform rigid")
        return FrameModel(2, "mm", tuple(links), tuple(joints), tuple(bodies), "platform",
                          np.asarray(options["load"], float), tuple(notes))

    # ----- mobility (scalesynth.mobility) ---------------------------------------------------------
    def topology(self, design, options):
        """Joint list of paper §1 (planar, each parallelogram counted as one 1-DOF joint): the right chain
        is two parallelograms in series (active arm + arm link, then forearm + forearm link, joined by the
        hinge plate), the left chain a revolute arm and a forearm (its two rods act as one link): n = 5
        (base, platform, hinge plate, left arm, left forearm), g = 5, sum f = 5: planar G-K
        3(5 - 5 - 1) + 5 = 2."""
        from scalesynth.mobility import Topology

        return Topology(
            n_links=5,
            chains=(("PaPa (right)", ("Pa", "Pa")), ("RRR (left)", ("R", "R", "R"))),
            order=3,
            note="paper §1: planar G-K; the parallelograms only keep the platform from turning",
        )

    def joint_screws(self, design, options, pose, q):
        """Unit joint screws (omega; v) per chain at pose P = (x, y) with arm angles q, the plane z = 0
        embedded in space (mm). Chain 1 (right, pivot B1): the hinge plate translates along dQ1/dalpha1 ~
        (-sin alpha1, cos alpha1, 0), the platform relative to it along (-sin beta1, cos beta1, 0). Chain 2
        (left): revolutes about z at B2, Q2 and P."""
        from scalesynth.mobility import Joint, chain_screws

        x, y = self.check_vector("pose", pose, 2)
        a1, _ = self.check_vector("inputs", q, 2)
        b1, _ = self.forearm_angles(design, pose, q)
        _, q2 = self.elbows(design, q)
        zhat = (0.0, 0.0, 1.0)
        right = chain_screws([
            Joint("Pa", axes=((-math.sin(a1), math.cos(a1), 0.0),)),
            Joint("Pa", axes=((-math.sin(b1), math.cos(b1), 0.0),)),
        ])
        left = chain_screws([
            Joint("R", (-design["r"], 0.0, 0.0), (zhat,)),
            Joint("R", (q2[0], q2[1], 0.0), (zhat,)),
            Joint("R", (x, y, 0.0), (zhat,)),
        ])
        return [right, left]


MECHANISM = PlanarFivebar(
    name="planar-fivebar",
    title="2-DOF planar five-bar packing robot with parallelograms (seed 004)",
    seed="004",
    motion="2T",
    task_axes=("x", "y"),
    task_units=("length", "length"),
    joints=("alpha1", "alpha2"),
    joint_units=("angle", "angle"),
    parameters=(
        Parameter("r", 200.0, "half the distance between the active pivots (illustrative default, spec §2.7)"),
        Parameter("l1", 475.0, "active arm length (illustrative default, spec §2.7)"),
        Parameter("l2", 875.0, "forearm length (illustrative default, spec §2.7)"),
    ),
    options=(
        Option("mode", "+-", "working mode sigma1 sigma2: '+-' = elbows out (operating mode), '++', '-+', '--'"),
        Option("alpha1_limits", None, "[lo, hi] rad for alpha1 modulo 2 pi, null = none (spec: [-4pi/9, 7pi/36])"),
        Option("alpha2_limits", None, "[lo, hi] rad for alpha2 modulo 2 pi, null = none (spec: [29pi/36, 13pi/9])"),
        Option("forearm", "single", "stiffness: 'single' (five-bar 5R) or 'parallelogram' (right chain PaPa, §1)"),
        Option("parallelogram_spacing", 60.0, "stiffness: bar spacing of the parallelograms, mm"),
        Option("parallelogram_offsets", [1.1780972450961724, -0.75],
               "stiffness: directions (rad from +x) of the arm-link and forearm-link offsets: perpendicular to the "
               "arm and forearm at mid-range over the packing rectangle (67.5 deg, -43 deg)"),
        *stiffness_options("mm", ACTUATOR_STIFFNESS, "torsional stiffness of each arm actuator, N mm/rad (1e5 N m/rad)",
                           [0.0, -150.0], "default 150 N along -y, the gravity direction (the workspace is below "
                           "the base)"),
        Option("link_radius", None, "capsule radius (mm) of every body, or {body: radius}; null = defaults "
               "base 25, arm1/arm2 20, forearm1/forearm2 15, platform 40 (illustrative)"),
        Option("interference_free", False, "true: a pose whose link capsules overlap (clearance < 0) is unreachable"),
    ),
    default_length_unit="mm",
    fields=(
        *base_fields("{length}/rad", "J = dx/dq (mm per rad of arm rotation)"),
        Field("stiffness_min", "N/{length}", "smallest eigenvalue of the platform's translational stiffness under a "
              "pure force (ideal joints, Euler-Bernoulli links, actuator springs; docs/stiffness.md)", "max"),
        Field("deflection", "{length}", "magnitude of the platform's deflection under options.load (default 150 N "
              "along -y); 1e12 at a singular pose", "min", (0.0, SIGMA_CAP)),
        links.CLEARANCE_FIELD,
    ),
    design_metrics=DESIGN_METRICS,
)


def _cycle_kinematics(x, y, r, l1, l2, label: str) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form IK in branch ``label`` and A = Jq^-1 Jx at P = (x, y) (any shape S; r, l1, l2 broadcast to it,
    mm) -> q (*S, 2) rad with NaN where out of reach, A (*S, 2, 2) rad/mm (NaN there)."""
    shape = np.broadcast(x, r).shape
    q = np.empty((*shape, 2))
    ok = np.ones(shape, dtype=bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        for i, (u, sign) in enumerate(((x - r, label[0]), (x + r, label[1]))):
            dd, ee = -2.0 * l1 * u, -2.0 * l1 * y
            norm = np.hypot(dd, ee)
            k = -(u * u + y * y + l1 * l1 - l2 * l2) / norm
            ok &= (norm != 0.0) & (np.abs(k) <= 1.0 + 1e-12)
            g = np.arccos(np.clip(k, -1.0, 1.0))
            q[..., i] = wrap_angle(np.arctan2(ee, dd) + (-g if sign == "+" else g))
        l1e = np.asarray(l1)[..., None]  # broadcast against the arm axis
        elbow_x = np.stack([r + l1 * np.cos(q[..., 0]), -r + l1 * np.cos(q[..., 1])], axis=-1)
        elbow_y = l1e * np.sin(q)
        beta = np.arctan2(y[..., None] - elbow_y, x[..., None] - elbow_x)
        jq = l1e * np.sin(beta - q)
        a = np.stack([np.cos(beta), np.sin(beta)], axis=-1) / jq[..., None]
    q[~ok] = np.nan
    a[~ok] = np.nan
    return q, a
