"""2PaUU-PPaP three-translation parallel mechanism (seed 000), convention T of the spec (§1).

Design parameters m, n, l1, l2, c (lengths); inputs q = (theta1, theta2, d); output P = (x, y, z).
The chain geometry depends on m and n only through delta = m - n (spec §1.1). Default vertical offset
e = 2c: only this value reproduces the paper's Tables 2 and 3 (spec §1.8); without z-limits e only
translates the workspace.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numba import njit, prange

from scalesynth.errors import InvalidParameter, InvalidPose
from scalesynth.evaluation.plans import ColumnPlan, UniformPlan
from scalesynth.kernels import grid as _grid
from scalesynth.kernels.clearance import min_capsule_gap, put_segment
from scalesynth.kernels.conditioning import SIGMA_CAP, cos_third_acos, inverse_singular_values, sv_3x3
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
from scalesynth.stiffness import legs as _legs_k
from scalesynth.stiffness.sections import (
    check_positive_option,
    check_stiffness_options,
    stiffness_options,
    tube_section,
)

MODES = ("++", "+-", "-+", "--")
# stiffness (scalesynth.stiffness, docs/stiffness.md): link groups, the actuated long links of the parallelograms
# (arm), their second long links (arm_link) and the U-U links (link); actuator stiffness defaults (assumptions, the
# paper gives none): 1e5 N m/rad for theta1, theta2 (a servo with a stiff precision reducer), 2e7 N/m (2e4 N/mm, a
# ball-screw axis) for the stroke d
LINK_GROUPS = ("arm", "arm_link", "link")
ACTUATOR_STIFFNESS = 1e5
STROKE_STIFFNESS = 2e7
# default capsule radii (m), illustrative (the paper gives no cross-sections)
LINK_RADII = {"base": 0.05, "arm1": 0.03, "arm2": 0.03, "link1": 0.02, "link2": 0.02, "platform": 0.05}

# packed-parameter layout (see PauuPpap.pack)
_DELTA, _L1, _L2, _E, _S1, _S2 = 0, 1, 2, 3, 4, 5
_T1LO, _T1HI, _T2LO, _T2HI, _DLO, _DHI, _ZMIN, _HAS_THETA = 6, 7, 8, 9, 10, 11, 12, 13
_M = 14  # m itself (the kinematics need only m - n; the capsules need both)
_RAD = 15  # capsule radii of the 6 bodies, in LINK_RADII order
_FREE_ONLY = 21  # 1: poses whose capsules overlap are unreachable
_CLEARANCE_STATS = 22  # 1: the config asks for clearance statistics (or interference_free): the generic kernel
# stiffness (slots _F_STIFFNESS_MIN, _F_DEFLECTION): EA (N), EI (N m^2), GJ (N m^2) of the groups arm, arm_link and
# link (3 each, LINK_GROUPS order), the actuator stiffness of theta1, theta2 (N m/rad) and of d (N/m), the load (N),
# the short link c (m) and 1 when the config asks for the stiffness statistics (options.stiffness_metrics)
_EA_ARM, _EA_ARM_LINK, _EA_LINK = 23, 26, 29
_KACT, _KD, _FX, _C, _STIFFNESS_STATS = 32, 33, 34, 37, 38
N_PACKED = 39
N_FIELDS = 3  # fields of the fast path population_stats_fast: lci, sigma_min, sigma_max (MECHANISM.fields[:3])
_F_CLEARANCE = 3  # slot of the clearance field in the field kernel's out (its index in ``fields``)
_F_STIFFNESS_MIN, _F_DEFLECTION = 4, 5  # slots of the stiffness fields
N_KERNEL_FIELDS = 6  # fields of point_fields (MECHANISM.fields)

# capsules of the clearance field, in link_geometry's order: one segment per body, so segment i is body i
_BODIES = tuple(LINK_RADII)
_ADJACENT = links.adjacency([("base", "arm1"), ("base", "arm2"), ("arm1", "link1"), ("arm2", "link2"),
                             ("link1", "platform"), ("link2", "platform")])
_PAIRS = links.kernel_pairs(_BODIES, _ADJACENT)


@njit(cache=True, fastmath=FASTMATH)
def _chain(a, b, yy, l1, l2, sigma):
    """One chain's IK root sigma in algebraic form: (ok, cos theta, sin theta, Jq entry), no transcendental calls.

    With r^2 = a^2 + b^2 and K = (r^2 + y^2 + l1^2 - l2^2) / (2 l1) (= r cos of the arccos term of spec §1.2),
    S = sqrt(r^2 - K^2) (= r sin of it): cos theta = (a K + sigma b S) / r^2, sin theta = (-b K + sigma a S) / r^2
    and Jq_ii = -l1 (a sin theta + b cos theta) = -sigma l1 S. ok is False when the pose is out of reach (K^2 > r^2).
    """
    r2 = a * a + b * b
    kk = (r2 + yy + l1 * l1 - l2 * l2) / (2.0 * l1)
    s2 = r2 - kk * kk
    if s2 < 0.0 or r2 <= 1e-300:
        return False, 0.0, 0.0, 0.0
    sq = math.sqrt(s2)
    inv = 1.0 / r2
    return True, (a * kk + sigma * b * sq) * inv, (-b * kk + sigma * a * sq) * inv, -sigma * l1 * sq


@njit(cache=True, fastmath=FASTMATH)
def _angle_in(c, s, lo, hi):
    t = math.atan2(s, c)
    two_pi = 2.0 * math.pi
    return (lo <= t <= hi) or (lo <= t - two_pi <= hi) or (lo <= t + two_pi <= hi)


@njit(cache=True, fastmath=FASTMATH)
def _clearance(p, x, y, z, c1, s1, c2, s2):
    """Clearance of link_geometry's capsules at P = (x, y, z) with cos/sin of theta1, theta2: the smallest distance
    between the axes of non-adjacent bodies minus their radii (length unit). A_i = (+-m, 0, e),
    C_1 = (m + l1 cos theta1, 0, e - l1 sin theta1), C_2 = (-(m + l1 cos theta2), 0, e - l1 sin theta2),
    D_i = (x +- n, y, z); segments base A2-A1, arm_i A_i-C_i, link_i C_i-D_i, platform D2-D1."""
    m = p[_M]
    n = m - p[_DELTA]
    l1 = p[_L1]
    e = p[_E]
    seg = np.empty((6, 6))
    put_segment(seg, 0, -m, 0.0, e, m, 0.0, e)
    put_segment(seg, 1, m, 0.0, e, m + l1 * c1, 0.0, e - l1 * s1)
    put_segment(seg, 2, -m, 0.0, e, -(m + l1 * c2), 0.0, e - l1 * s2)
    put_segment(seg, 3, m + l1 * c1, 0.0, e - l1 * s1, x + n, y, z)
    put_segment(seg, 4, -(m + l1 * c2), 0.0, e - l1 * s2, x - n, y, z)
    put_segment(seg, 5, x - n, y, z, x + n, y, z)
    return min_capsule_gap(seg, _PAIRS, p[_RAD : _RAD + 6])


@njit(cache=True, fastmath=FASTMATH)
def _chain_stiffness(p, wx, wy, wz, ex, ez):
    """(ok, kappa, u) of one PaUU chain, ideal joints, the frame of stiffness_model: with the platform's rotations
    held (by the PPaP chain) the chain adds kappa u u^T to the platform's translational stiffness (N/m), u the unit
    vector of w = D_i - C_i (the link), e = (ex, 0, ez) the unit vector A_i -> C_i of the arm.

    The U-link-U part passes two wrenches: the force along the link's line (through C_i and D_i) and the couple
    along n = the xz-projection of u (normal to both U axes y, t_i). Their 2x2 flexibility Phi adds (complementary
    energy, the joints' free motions do no work on them) the link (a cantilever clamped at C_i: axial l2 / EA,
    the couple's torsion and bending) and the parallelogram plate at C_i. The parallelogram lies in the xz plane
    with joint axes along y, so its in-plane and out-of-plane responses decouple: in plane the force at C_i loads
    the arm alone (the arm link, pinned at both ends, would only carry a moment about y, which U_C releases):
    axial l1 / EA and transverse l1^3 / 3 EI + l1^2 / k (the actuator spring at A_i); out of plane (force along y,
    moments about x and z) both bars are clamped at the base and at the plate (their revolutes turn about y only),
    two cantilevers in parallel, the arm link's tip C_i - c z transported to C_i, inverted in scalars. The platform
    cannot rotate, so the couple is a reaction and kappa = (Phi^-1)_11 = Phi_22 / det Phi."""
    ll = math.sqrt(wx * wx + wy * wy + wz * wz)
    hxz = math.sqrt(wx * wx + wz * wz)
    if not (ll > 0.0 and hxz > 0.0):
        return False, 0.0, 0.0, 0.0, 0.0
    ux, uy, uz = wx / ll, wy / ll, wz / ll
    nx, nz = wx / hxz, wz / hxz
    px, pz = -ez, ex  # p = e x y, in plane, normal to the arm
    l1 = p[_L1]
    l2 = p[_L2]
    c = p[_C]
    ea_a, ei_a, gj_a = p[_EA_ARM], p[_EA_ARM + 1], p[_EA_ARM + 2]
    ei_b, gj_b = p[_EA_ARM_LINK + 1], p[_EA_ARM_LINK + 2]
    ea_l, ei_l, gj_l = p[_EA_LINK], p[_EA_LINK + 1], p[_EA_LINK + 2]
    # out-of-plane stiffness of the plate at C_i in (v along y, rotation about e, rotation about p); a cantilever
    # tip (v, phi_p) has [[12 EI / L^3, -6 EI / L^2], [-6 EI / L^2, 4 EI / L]], torsion GJ / L; the arm link's tip
    # moves by v + c phi_x along y (phi_x = e_x phi_e + p_x phi_p)
    il = 1.0 / l1
    avv, avp, aee, app = 12.0 * ei_a * il * il * il, -6.0 * ei_a * il * il, gj_a * il, 4.0 * ei_a * il
    bvv, bvp, bee, bpp = 12.0 * ei_b * il * il * il, -6.0 * ei_b * il * il, gj_b * il, 4.0 * ei_b * il
    al = c * ex
    be = c * px
    ok, c00, c01, c02, c11, c12, c22 = _legs_k.sym3_inverse(
        avv + bvv, bvv * al, avp + bvv * be + bvp, aee + bvv * al * al + bee, al * (bvv * be + bvp),
        app + bvv * be * be + 2.0 * bvp * be + bpp)
    if not ok:
        return False, 0.0, 0.0, 0.0, 0.0
    ue = ux * ex + uz * ez
    up = ux * px + uz * pz
    ne = nx * ex + nz * ez
    np_ = nx * px + nz * pz
    un = ux * nx + uz * nz
    phi11 = (l2 / ea_l + ue * ue * l1 / ea_a + up * up * (l1 * l1 * l1 / (3.0 * ei_a) + l1 * l1 / p[_KACT])
             + uy * uy * c00)
    phi12 = uy * (c01 * ne + c02 * np_)
    phi22 = l2 / ei_l + (l2 / gj_l - l2 / ei_l) * un * un + c11 * ne * ne + 2.0 * c12 * ne * np_ + c22 * np_ * np_
    det = phi11 * phi22 - phi12 * phi12
    if not (det > 0.0 and phi22 > 0.0):
        return False, 0.0, 0.0, 0.0, 0.0
    return True, phi22 / det, ux, uy, uz


@njit(cache=True, fastmath=FASTMATH)
def _stiffness(p, w1x, w1y, w1z, c1, s1, w2x, w2y, w2z, c2, s2):
    """(stiffness_min N/m, deflection m) at P under the packed load, ideal joints, the frame of stiffness_model:
    the platform only translates (the PPaP chain holds its rotations), so its stiffness is the 3x3
    K = sum_i kappa_i u_i u_i^T + k_d y y^T (the two PaUU chains, _chain_stiffness, and the stroke spring: the
    PPaP chain's other slides leave x and z free), singular where u_1, u_2 and y are coplanar (a forward
    singularity); legs.response_translational. Arms: e_1 = (cos theta1, 0, -sin theta1),
    e_2 = (-cos theta2, 0, -sin theta2)."""
    zero = 0.0 if (p[_FX] == 0.0 and p[_FX + 1] == 0.0 and p[_FX + 2] == 0.0) else _legs_k.DEFLECTION_CAP
    ok1, k1, ax, ay, az = _chain_stiffness(p, w1x, w1y, w1z, c1, -s1)
    ok2, k2, bx, by, bz = _chain_stiffness(p, w2x, w2y, w2z, -c2, -s2)
    if not (ok1 and ok2):
        return 0.0, zero
    return _legs_k.response_translational(
        k1 * ax * ax + k2 * bx * bx, k1 * ax * ay + k2 * bx * by, k1 * ax * az + k2 * bx * bz,
        k1 * ay * ay + k2 * by * by + p[_KD], k1 * ay * az + k2 * by * bz, k1 * az * az + k2 * bz * bz,
        p[_FX], p[_FX + 1], p[_FX + 2])


@njit(cache=True, fastmath=FASTMATH)
def _put_stiffness(p, out, w1x, w1y, w1z, c1, s1, w2x, w2y, w2z, c2, s2):
    """Slots _F_STIFFNESS_MIN, _F_DEFLECTION of a reachable pose: _stiffness when the packed options ask for it
    (options.stiffness_metrics), else 0 (written: the grid kernels reuse ``out``)."""
    if p[_STIFFNESS_STATS] > 0.0:
        out[_F_STIFFNESS_MIN], out[_F_DEFLECTION] = _stiffness(p, w1x, w1y, w1z, c1, s1, w2x, w2y, w2z, c2, s2)
    else:
        out[_F_STIFFNESS_MIN] = 0.0
        out[_F_DEFLECTION] = 0.0


@njit(cache=True, fastmath=FASTMATH)
def point_fields(p, x, y, z, out):
    """Fields at P = (x, y, z) in the packed working mode (kernels.grid contract): LCI (1/kappa_2 of J), sigma_min
    and sigma_max of J = dx/dq, clearance of the link capsules (length unit), stiffness_min (N/m) and deflection
    (m) under the packed load (ideal joints, docs/stiffness.md; _stiffness; 0 unless options.stiffness_metrics);
    LCI -1 (and zeros) if unreachable
    (or, with interference_free, where the capsules overlap)."""
    _fields(p, x, y, z, out, True, True)


@njit(cache=True, fastmath=FASTMATH)
def kinematic_fields(p, x, y, z, out):
    """Slots 0-2 of point_fields (LCI, sigma_min, sigma_max) without the clearance and stiffness: the fast path's
    kernel for the cells it does not vectorise (theta limits); ``out`` needs N_FIELDS slots."""
    _fields(p, x, y, z, out, False, False)


@njit(cache=True, fastmath=FASTMATH)
def point_reach(p, x, y, z, out):
    """Slot 0 of point_fields up to its value: >= 0 exactly where point_fields' LCI is (the same working mode,
    stroke and theta checks and, with interference_free, the same clearance), -1 elsewhere; no conditioning,
    stiffness or (without interference_free) clearance. The adaptive evaluator's nodes and bisections
    (Mechanism.reach_kernel)."""
    _fields(p, x, y, z, out, False, False, False)


@njit(cache=True, fastmath=FASTMATH)
def _fields(p, x, y, z, out, with_clearance, with_stiffness, every=True):
    """point_fields (both True) or kinematic_fields (both False; constants, so each copy keeps its branches). The
    stiffness fields are computed only when the packed options ask for them (options.stiffness_metrics), so that
    the generic kernel run for the clearance metrics alone does not pay for them (they stay 0 otherwise).
    ``every`` False (a constant, point_reach): slot 0 alone, 0 where point_fields' is >= 0, -1 elsewhere."""
    if z < p[_ZMIN] or y < p[_DLO] or y > p[_DHI]:
        _grid.write_unreachable(out)
        return
    delta = p[_DELTA]
    l1 = p[_L1]
    l2 = p[_L2]
    b = z - p[_E]
    yy = y * y
    if yy >= l2 * l2:
        _grid.write_unreachable(out)
        return
    a1 = x - delta
    a2 = -x - delta
    ok1, c1, s1, q1 = _chain(a1, b, yy, l1, l2, p[_S1])
    if not ok1:
        _grid.write_unreachable(out)
        return
    ok2, c2, s2, q2 = _chain(a2, b, yy, l1, l2, p[_S2])
    if not ok2:
        _grid.write_unreachable(out)
        return
    if p[_HAS_THETA] > 0.0:
        if not _angle_in(c1, s1, p[_T1LO], p[_T1HI]) or not _angle_in(c2, s2, p[_T2LO], p[_T2HI]):
            _grid.write_unreachable(out)
            return
    if not every:
        out[0] = 0.0
        if p[_FREE_ONLY] > 0.0 and _clearance(p, x, y, z, c1, s1, c2, s2) < 0.0:
            out[0] = -1.0
        return
    gap = _clearance(p, x, y, z, c1, s1, c2, s2) if with_clearance else 0.0
    if gap < 0.0 and p[_FREE_ONLY] > 0.0:
        _grid.write_unreachable(out)
        return
    # w_i = D_i - C_i; chain 2 mirrored in x
    w1x = a1 - l1 * c1
    w1z = b + l1 * s1
    w2x = -(a2 - l1 * c2)
    w2z = b + l1 * s2
    if q1 == 0.0 or q2 == 0.0:
        _grid.write_singular(out)  # inverse (type-1) singularity; the structure's stiffness stays finite
        if with_clearance:
            out[_F_CLEARANCE] = gap
        if with_stiffness:
            _put_stiffness(p, out, w1x, y, w1z, c1, s1, w2x, y, w2z, c2, s2)
        return
    # M = J^-1 = Jq^-1 Jx has rows w1/q1, w2/q2, (0, 1, 0); kappa(M) = kappa(J), sigma(J) = 1 / sigma(M)
    iq1 = 1.0 / q1
    iq2 = 1.0 / q2
    lci, smin, smax = sv_3x3(w1x * iq1, y * iq1, w1z * iq1, w2x * iq2, y * iq2, w2z * iq2, 0.0, 1.0, 0.0)
    out[0] = lci
    out[1], out[2] = inverse_singular_values(smin, smax)
    if with_clearance:
        out[_F_CLEARANCE] = gap
    if with_stiffness:
        _put_stiffness(p, out, w1x, y, w1z, c1, s1, w2x, y, w2z, c2, s2)


@njit(cache=True, fastmath=FASTMATH)
def _k_range(zlo, zhi, lo, step, nz):
    """Indices k (inclusive range, widened by one cell each side) whose cell centres may lie in [zlo, zhi]."""
    k0 = int(math.floor((zlo - lo) / step - 0.5)) - 1
    k1 = int(math.ceil((zhi - lo) / step - 0.5)) + 1
    if k0 < 0:
        k0 = 0
    if k1 > nz - 1:
        k1 = nz - 1
    return k0, k1


@njit(cache=True, fastmath=FASTMATH)
def _mirror_plan(lo, step, n):
    """(first index to visit, weight of visited indices, index of the unmirrored middle cell or -1) for an axis.

    When the grid is symmetric about 0 (lo = -n * step / 2), cell j and cell n - 1 - j are mirror images: visit
    the upper half only and count each cell twice (an odd n leaves a middle cell counted once)."""
    centre = lo + 0.5 * n * step
    if abs(centre) <= 1e-12 * (abs(lo) + n * step) and n > 1:
        return n // 2, 2.0, (n // 2 if n % 2 == 1 else -1)
    return 0, 1.0, -1


@njit(cache=True, fastmath=FASTMATH)
def _column_pass1(x, y, k0, k1, lo_z, step_z, p, flag, targ, tq, tp, tc2, td2):
    """Cells k0..k1 of column (x, y), no theta limits: everything of point_fields up to the trigonometric step of
    lci_3x3, written branch-free into scratch arrays so that the compiler can vectorise the loop.

    flag: 1 reachable, 0 reachable but inverse-singular (LCI 0), -1 unreachable; targ: argument of acos; tq, tp: the
    centre and scale of the eigenvalue problem; tc2: sum of the squared 2x2 minors; td2: det^2 (see lci_3x3).
    """
    delta = p[_DELTA]
    l1 = p[_L1]
    l2 = p[_L2]
    e = p[_E]
    s1 = p[_S1]
    s2 = p[_S2]
    zmin = p[_ZMIN]
    yy = y * y
    a1 = x - delta
    a2 = -x - delta
    a1s = a1 * a1
    a2s = a2 * a2
    cst = yy + l1 * l1 - l2 * l2
    inv2l1 = 1.0 / (2.0 * l1)
    for k in range(k0, k1 + 1):
        z = lo_z + (k + 0.5) * step_z
        b = z - e
        bb = b * b
        r2a = a1s + bb
        r2b = a2s + bb
        kka = (r2a + cst) * inv2l1
        kkb = (r2b + cst) * inv2l1
        s2a = r2a - kka * kka
        s2b = r2b - kkb * kkb
        ok = (s2a >= 0.0) & (s2b >= 0.0) & (r2a > 1e-300) & (r2b > 1e-300) & (z >= zmin)
        sqa = math.sqrt(max(s2a, 0.0))
        sqb = math.sqrt(max(s2b, 0.0))
        ia = 1.0 / max(r2a, 1e-300)
        ib = 1.0 / max(r2b, 1e-300)
        ca = (a1 * kka + s1 * b * sqa) * ia
        sa = (-b * kka + s1 * a1 * sqa) * ia
        cb = (a2 * kkb + s2 * b * sqb) * ib
        sb = (-b * kkb + s2 * a2 * sqb) * ib
        q1 = -s1 * l1 * sqa
        q2 = -s2 * l1 * sqb
        sing = (q1 == 0.0) | (q2 == 0.0)
        iq1 = 1.0 / (q1 if q1 != 0.0 else 1.0)
        iq2 = 1.0 / (q2 if q2 != 0.0 else 1.0)
        u1 = (a1 - l1 * ca) * iq1
        u2 = y * iq1
        u3 = (b + l1 * sa) * iq1
        v1 = -(a2 - l1 * cb) * iq2
        v2 = y * iq2
        v3 = (b + l1 * sb) * iq2
        g11 = u1 * u1 + u2 * u2 + u3 * u3
        g22 = v1 * v1 + v2 * v2 + v3 * v3
        g12 = u1 * v1 + u2 * v2 + u3 * v3
        cx = u2 * v3 - u3 * v2
        cy = u3 * v1 - u1 * v3
        cz = u1 * v2 - u2 * v1
        c2 = cx * cx + cy * cy + cz * cz + u3 * u3 + u1 * u1 + v3 * v3 + v1 * v1
        det = u3 * v1 - u1 * v3
        tr = g11 + g22 + 1.0
        q = tr / 3.0
        b11 = g11 - q
        b22 = g22 - q
        b33 = 1.0 - q
        p2 = b11 * b11 + b22 * b22 + b33 * b33 + 2.0 * (g12 * g12 + u2 * u2 + v2 * v2)
        pp_ = math.sqrt(p2 / 6.0)
        ip = 1.0 / max(pp_, 1e-300)
        b11 *= ip
        b22 *= ip
        b33 *= ip
        b12 = g12 * ip
        b13 = u2 * ip
        b23 = v2 * ip
        r = 0.5 * (b11 * (b22 * b33 - b23 * b23) - b12 * (b12 * b33 - b23 * b13) + b13 * (b12 * b23 - b22 * b13))
        targ[k] = min(max(r, -1.0), 1.0)
        tq[k] = q
        tp[k] = pp_
        tc2[k] = c2
        td2[k] = det * det
        flag[k] = -1.0 if not ok else (0.0 if sing else 1.0)

@njit(cache=True, fastmath=FASTMATH)
def _column_pass2(k0, k1, targ):
    """The trigonometric step of the eigenvalue solution, cos(acos(r) / 3), in a loop of its own: by
    conditioning.cos_third_acos (two Halley steps on the triple-angle cubic), which vectorises where libm's acos and
    cos ran one cell at a time (the largest share of this path's time: 0.66 of 1.6 ms per design at N = 72)."""
    ta = targ[k0 : k1 + 1]
    for i in range(k1 - k0 + 1):
        ta[i] = cos_third_acos(ta[i])

@njit(cache=True, fastmath=FASTMATH)
def _column_pass3(k0, k1, flag, targ, tq, tp, tc2, td2, buf, wbuf, m, w):
    """Fields of cells k0..k1 into the slab buffers from index m (as kernels.grid.gather_column: weight w if
    reachable, else 0), as point_fields: LCI from the largest eigenvalue and the sum/product of the other two (as
    in sv_3x3); of J = M^-1, sigma_min = 1/sqrt(lmax) and sigma_max = 1/(LCI sqrt(lmax)) (= 1/sigma_min(M)),
    capped at SIGMA_CAP; LCI -1 if unreachable.

    Loops over slices from 0 (no index wraparound) and is branch-free so that the compiler vectorises it: every
    value is computed for every cell, and the flag (1 regular, 0 singular, -1 unreachable) selects by arithmetic
    (min, products with 0 or 1, exact), because a conditional expression becomes a branch that the vectoriser
    gives up on. Unreachable cells may carry garbage (even NaN): the clamps put the constant first, which Python's
    and Numba's min/max return when the other argument is NaN, so every output is finite."""
    n = k1 - k0 + 1
    fl = flag[k0 : k1 + 1]
    ta = targ[k0 : k1 + 1]
    q_ = tq[k0 : k1 + 1]
    p_ = tp[k0 : k1 + 1]
    c2 = tc2[k0 : k1 + 1]
    d2 = td2[k0 : k1 + 1]
    out_lci = buf[0, m : m + n]
    out_lo = buf[1, m : m + n]
    out_hi = buf[2, m : m + n]
    out_w = wbuf[m : m + n]
    for i in range(n):
        lmax = q_[i] + 2.0 * p_[i] * ta[i]
        il = 1.0 / max(1e-300, lmax)
        prod = d2[i] * il
        s = (c2[i] - prod) * il
        disc = max(0.0, s * s - 4.0 * prod)
        lmid = max(1e-300, 0.5 * (s + math.sqrt(disc)))
        ratio = min(1.0, max(0.0, prod / lmid * il))
        v = math.sqrt(ratio)
        v = v if (s > 0.0) & (prod > 0.0) else 0.0
        sig_lo = min(SIGMA_CAP, math.sqrt(il))
        sig_hi = min(SIGMA_CAP, sig_lo / max(1e-300, v))
        f = fl[i]
        ok = max(0.0, f)  # 1 regular, else 0
        reach = min(1.0, f + 1.0)  # 1 reachable, else 0
        out_lci[i] = min(v, f)
        out_lo[i] = sig_lo * ok
        out_hi[i] = sig_hi * ok + SIGMA_CAP * (reach - ok)
        out_w[i] = w * reach


@njit(cache=True, parallel=True, fastmath=FASTMATH)
def population_stats_fast(params, lo, step, shape, edges):
    """Same statistics as kernels.grid.population_stats(point_fields, ...) for the first N_FIELDS fields (LCI,
    sigma_min, sigma_max; no clearance, no interference_free), computed faster and fed to the same accumulator
    (kernels.grid.gather_column, accumulate_cells).

    Three savings: (1) for each (x, y) column the reachable z are the intersection of the two chains' annuli
    (spec §1.9), so only the cells of (at most two) z-intervals are visited, widened by one cell and then tested
    cell by cell, so the counted cells are the pointwise ones; (2) LCI is even in y, and in x for the
    mirror-symmetric modes (++, --) with equal theta limits, so a symmetric grid is visited over a half or a
    quarter and weighted; (3) without theta limits the cells of a column go through branch-free passes that the
    compiler vectorises, with acos/cos alone in a scalar loop (designs with theta limits use kinematic_fields per
    cell).
    Every field is invariant under both mirror symmetries (they permute rows and flip signs of columns of J).
    """
    n_designs = params.shape[0]
    nx, ny, nz = shape[0], shape[1], shape[2]
    nb = edges.shape[0] - 1
    ncol = _grid.stat_columns(N_FIELDS, nb)
    partial = np.zeros((n_designs * nx, ncol))
    for task in prange(n_designs * nx):
        d = task // nx
        i = task - d * nx
        p = params[d]
        row = partial[task]
        _grid.init_row(row, N_FIELDS)
        x_sym = p[_S1] == p[_S2] and p[_T1LO] == p[_T2LO] and p[_T1HI] == p[_T2HI]
        i0, wx, _ = _mirror_plan(lo[d, 0], step[d, 0], nx)
        if not x_sym:
            i0, wx = 0, 1.0
        if i < i0:
            continue
        if wx == 2.0 and i == nx // 2 and nx % 2 == 1:
            wx = 1.0
        y_sym = p[_DLO] == -p[_DHI]
        j0, wy_half, j_mid = _mirror_plan(lo[d, 1], step[d, 1], ny)
        if not y_sym:
            j0, wy_half, j_mid = 0, 1.0, -1
        scalar = p[_HAS_THETA] > 0.0
        flag = np.empty(nz)
        targ = np.empty(nz)
        tq = np.empty(nz)
        tp = np.empty(nz)
        tc2 = np.empty(nz)
        td2 = np.empty(nz)
        vals = np.empty((N_FIELDS, nz))
        cell = np.empty(N_FIELDS)
        buf = np.empty((N_FIELDS, ny * nz))
        wbuf = np.empty(ny * nz)
        m = 0
        x = lo[d, 0] + (i + 0.5) * step[d, 0]
        l1 = p[_L1]
        l2 = p[_L2]
        e = p[_E]
        a1 = x - p[_DELTA]
        a2 = -x - p[_DELTA]
        a1s = a1 * a1
        a2s = a2 * a2
        amax = a1s if a1s > a2s else a2s
        amin = a1s if a1s < a2s else a2s
        for j in range(j0, ny):
            w = wx * (1.0 if j == j_mid else wy_half)
            y = lo[d, 1] + (j + 0.5) * step[d, 1]
            yy = y * y
            if yy >= l2 * l2 or y < p[_DLO] or y > p[_DHI]:
                continue
            rho = math.sqrt(l2 * l2 - yy)
            ro = l1 + rho
            ri = l1 - rho
            b_hi2 = ro * ro - amax
            if b_hi2 < 0.0:
                continue
            b_lo2 = ri * ri - amin
            if b_lo2 > b_hi2:
                continue
            b_hi = math.sqrt(b_hi2)
            b_lo = math.sqrt(b_lo2) if b_lo2 > 0.0 else 0.0
            # upper interval e + [b_lo, b_hi], lower interval e - [b_hi, b_lo]; merged when they touch
            ku0, ku1 = _k_range(e + b_lo, e + b_hi, lo[d, 2], step[d, 2], nz)
            kl0, kl1 = _k_range(e - b_hi, e - b_lo, lo[d, 2], step[d, 2], nz)
            if kl1 >= ku0 - 1:
                kl1 = ku1
                ku0 = 1
                ku1 = 0
            for part in range(2):
                k0 = kl0 if part == 0 else ku0
                k1 = kl1 if part == 0 else ku1
                if k1 < k0:
                    continue
                if scalar:
                    for k in range(k0, k1 + 1):
                        kinematic_fields(p, x, y, lo[d, 2] + (k + 0.5) * step[d, 2], cell)
                        for fi in range(N_FIELDS):
                            vals[fi, k] = cell[fi]
                    m = _grid.gather_column(buf, wbuf, m, vals, k0, k1, w)
                else:
                    _column_pass1(x, y, k0, k1, lo[d, 2], step[d, 2], p, flag, targ, tq, tp, tc2, td2)
                    _column_pass2(k0, k1, targ)
                    _column_pass3(k0, k1, flag, targ, tq, tp, tc2, td2, buf, wbuf, m, w)
                    m += k1 - k0 + 1
        _grid.accumulate_cells(row, buf, wbuf, m, edges)
    return _grid.reduce_partials(partial, n_designs, nx, N_FIELDS)


def widen_rows(stats: np.ndarray, n_from: int, n_to: int) -> np.ndarray:
    """Statistics rows of ``n_from`` fields in the layout of ``n_to`` fields (kernels.grid): the extra fields'
    columns empty (sum, sum of squares 0, min +inf, max -inf), the band counts moved after them."""
    n_bands = stats.shape[1] - _grid.stat_columns(n_from, 0)
    out = np.zeros((stats.shape[0], _grid.stat_columns(n_to, n_bands)))
    head = _grid.band_column(n_from, 0)
    out[:, :head] = stats[:, :head]
    for f in range(n_from, n_to):
        out[:, _grid.field_column(f, _grid.STAT_MIN)] = math.inf
        out[:, _grid.field_column(f, _grid.STAT_MAX)] = -math.inf
    out[:, _grid.band_column(n_to, 0):] = stats[:, head:]
    return out


def _stroke_d(design: Mapping[str, float], options: Mapping[str, Any]) -> float:
    """Stroke the prismatic input d = y needs: the reachable |y| < l2 within the stroke limits."""
    lo, hi = -design["l2"], design["l2"]
    limits = options.get("stroke_limits")
    if limits is not None:
        lo, hi = max(lo, limits[0]), min(hi, limits[1])
    return max(hi - lo, 0.0)


DESIGN_METRICS = (
    DesignMetric(
        "link_length_sum", "{length}",
        "moving links of the two PaUU chains: 2 (2 l1 + c + l2), each chain's two parallelogram bars l1, its moving "
        "short bar c and the link l2 (the PPaP chain is not dimensioned in the paper)",
        lambda d, o: 2.0 * (2.0 * d["l1"] + d["c"] + d["l2"]),
    ),
    DesignMetric(
        "footprint_radius", "{length}",
        "radius of the smallest base-plane circle holding the base joints: m (the PaUU pivots at x = +-m)",
        lambda d, o: d["m"],
    ),
    DesignMetric("stroke_d", "{length}", "stroke of the input d = y: 2 l2, clipped by stroke_limits", _stroke_d),
)


# The clearance field (slot 3). Its statistics cost the generic grid kernel (9 segment distances per voxel, no column
# intervals or symmetry), several times slower than population_stats_fast, so its metrics are evaluated only for
# configs that state the link radii (the defaults are illustrative: the paper gives no cross-sections).
CLEARANCE = dataclasses.replace(
    links.CLEARANCE_FIELD, needs_options=("link_radius",),
    description=links.CLEARANCE_FIELD.description + "; its metrics need options.link_radius (the default radii are "
    "illustrative)",
)

# The stiffness fields (slots 4, 5). Like the clearance they need the generic grid kernel, so they are computed and
# their metrics evaluated only for configs that ask for them (options.stiffness_metrics: true; else they are 0).
STIFFNESS_FIELDS = (
    Field("stiffness_min", "N/{length}", "smallest eigenvalue of the platform's translational stiffness at P (ideal "
          "joints, Euler-Bernoulli links, actuator springs, the PPaP chain rigid; docs/stiffness.md); its metrics "
          "need options.stiffness_metrics", "max", needs_options=("stiffness_metrics",)),
    Field("deflection", "{length}", "magnitude of the deflection of P under options.load (default 150 N along -z); "
          "1e12 at a singular pose; its metrics need options.stiffness_metrics", "min",
          (0.0, _legs_k.DEFLECTION_CAP), needs_options=("stiffness_metrics",)),
)


class PauuPpap(Mechanism):
    """Seed-000 mechanism; see module docstring."""

    # the adaptive evaluator's plan (scalesynth.evaluation.plans): the 3-D default with beta 3 (its lobe tips are
    # shells thinner than the 8 coarse z-cells, hence z-levels confirmed twice and box-face columns)
    node_plan = ColumnPlan(24, 8, 5, 3, beta=3.0, zlevels=5, zconfirm=2, faces=True)
    # the tolerance form on its uniform grid: its uniform fast path (column intervals, mirror symmetries) costs about
    # 1/15 of the adaptive evaluator at (0.2 %, 5e-4) (N = 72: 0.96 ms against 15 ms per design on the quarter box of
    # its symmetries, one thread). Ladders on the config's bounds (paper_2pauu_ppap.yaml; quick.yaml has the same),
    # worst volume / GCI error as multiples of the tolerance on seed 0 | seed 1 (benchmarks/notes/uniform_plans.md):
    # N = 72 at (0.2 %, 5e-4): 0.41, 0.44 | 0.50, 0.48 (N = 56: 0.67, 0.70 | 1.06, 1.04; N = 64: 1.04 on seed 0);
    # N = 32 at (1 %, 2.5e-3): 0.68, 0.32 | 0.51, 0.52; N = 24 at (3 %, 5e-3): 0.57, 0.46 | 0.50, 0.74 (N = 20: 0.85,
    # 0.88 on seed 0). Tighter steps, against N = 448 (`uniform_ladder.py 2pauu-ppap SEED ... --ref 448`): N = 112 at
    # (0.1 %, 2.5e-4): 0.53, 0.60 | 0.58, 0.76 (N = 96: 0.88x in GCI on seed 1); N = 144 at (0.05 %, 1e-4): 0.28,
    # 0.59 | 0.60, 0.72 (N = 128: 0.93x on seed 1). Without them such a tolerance ran the adaptive evaluator: 0.12 s
    # per design at (0.05 %, 1e-4), where N = 144 takes about 4 ms
    uniform_plan = UniformPlan(((0.0005, 1.0e-4, 144), (0.001, 2.5e-4, 112), (0.002, 5.0e-4, 72), (0.01, 2.5e-3, 32),
                                (0.03, 5.0e-3, 24)))

    def check_options(self, options: dict[str, Any]) -> None:
        check_stiffness_options(options, 3, LINK_GROUPS)
        check_positive_option(options, "stroke_stiffness")
        if options["mode"] not in MODES:
            raise InvalidParameter(f"options.mode: must be one of {', '.join(MODES)}, got {options['mode']!r}")
        for name in ("theta1_limits", "theta2_limits", "stroke_limits"):
            options[name] = parse_range(name, options[name])
        for name in ("e", "z_min"):
            value = options[name]
            if value is not None:
                if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                    raise InvalidParameter(f"options.{name}: expected a finite number or null, got {value!r}")
                options[name] = float(value)
        links.check_radius_option(options, LINK_RADII)
        links.check_flag_option(options, "interference_free")
        links.check_flag_option(options, "stiffness_metrics")

    def offset_e(self, design: Mapping[str, float], options: Mapping[str, Any]) -> float:
        e = options.get("e")
        return 2.0 * design["c"] if e is None else float(e)

    def pack(self, design: Mapping[str, float], options: Mapping[str, Any]) -> np.ndarray:
        p = np.empty(N_PACKED)
        p[_DELTA] = design["m"] - design["n"]
        p[_L1] = design["l1"]
        p[_L2] = design["l2"]
        p[_E] = self.offset_e(design, options)
        mode = options["mode"]
        p[_S1] = 1.0 if mode[0] == "+" else -1.0
        p[_S2] = 1.0 if mode[1] == "+" else -1.0
        t1 = options.get("theta1_limits")
        t2 = options.get("theta2_limits")
        p[_HAS_THETA] = 1.0 if (t1 is not None or t2 is not None) else 0.0
        p[_T1LO], p[_T1HI] = t1 if t1 is not None else (-4.0 * math.pi, 4.0 * math.pi)
        p[_T2LO], p[_T2HI] = t2 if t2 is not None else (-4.0 * math.pi, 4.0 * math.pi)
        d = options.get("stroke_limits")
        p[_DLO], p[_DHI] = d if d is not None else (-math.inf, math.inf)
        z_min = options.get("z_min")
        p[_ZMIN] = -math.inf if z_min is None else z_min
        p[_M] = design["m"]
        p[_RAD : _RAD + len(LINK_RADII)] = list(links.radii(options, LINK_RADII).values())
        free = bool(options.get("interference_free"))
        p[_FREE_ONLY] = 1.0 if free else 0.0
        p[_CLEARANCE_STATS] = 1.0 if (free or options.get("link_radius") is not None) else 0.0
        for o, group in zip((_EA_ARM, _EA_ARM_LINK, _EA_LINK), LINK_GROUPS, strict=True):
            sec = tube_section(options, group, "m")
            p[o], p[o + 1], p[o + 2] = sec.EA, sec.EI, sec.GJ
        p[_KACT], p[_KD] = options["actuator_stiffness"], options["stroke_stiffness"]
        p[_FX : _FX + 3] = options["load"]
        p[_C] = design["c"]
        p[_STIFFNESS_STATS] = 1.0 if options.get("stiffness_metrics") else 0.0
        return p

    @property
    def field_kernel(self):
        return point_fields

    @property
    def reach_kernel(self):
        return point_reach

    def kernel_branch(self, options) -> str:
        return options["mode"]

    def grid_stats(self, packed, lo, step, shape, edges, lci_only=False):
        """The column-interval and symmetry evaluator (population_stats_fast; the same numbers as the generic one)
        when no design needs the statistics of the clearance or stiffness fields (or ``lci_only``): its rows then
        carry empty columns for them (sums 0, min +inf, max -inf), which no metric reads because their metrics need
        options.link_radius (CLEARANCE) or options.stiffness_metrics (STIFFNESS_FIELDS). With link_radius,
        interference_free or stiffness_metrics: the generic kernel over point_fields."""
        needs_fields = np.any(packed[:, _CLEARANCE_STATS] > 0.0) or np.any(packed[:, _STIFFNESS_STATS] > 0.0)
        if needs_fields and not (lci_only and not np.any(packed[:, _FREE_ONLY] > 0.0)):
            return _grid.population_stats(point_fields, N_KERNEL_FIELDS, packed, lo, step, shape, edges)
        return widen_rows(population_stats_fast(packed, lo, step, shape, edges), N_FIELDS, N_KERNEL_FIELDS)

    def derived_columns(self, design):
        """The model depends on m and n only through m - n (spec §1.1)."""
        return {"m_minus_n": design["m"] - design["n"]}

    def canonical_vectors(self, names, X):
        """Replace (m, n) by (m - n, 0): designs with equal m - n are the same model (spec §1.1)."""
        X = np.array(X, dtype=float)
        if "m" in names and "n" in names:
            i, j = names.index("m"), names.index("n")
            X[:, i] = X[:, i] - X[:, j]
            X[:, j] = 0.0
        return X

    def mirror_axes(self, options) -> tuple[int, ...]:
        """y (axis 1): the two PaUU chains lie in planes y = const and the PPaP stroke is d = y, so the pose at -y is
        the mirror image in y = 0 of the pose at y, given symmetric stroke limits and no load along y. x (axis 0):
        the mirror image in x = 0 swaps the two PaUU chains, given one working mode for both ('++' or '--'), equal
        theta1 and theta2 limits, equal radii of the swapped bodies and no load along x."""
        axes = []
        stroke = options.get("stroke_limits")
        if options["load"][0] == 0.0 and options["mode"][0] == options["mode"][1] \
                and options.get("theta1_limits") == options.get("theta2_limits") \
                and links.mirrored_radii(options, LINK_RADII, [("arm1", "arm2"), ("link1", "link2")]):
            axes.append(0)
        if options["load"][1] == 0.0 and (stroke is None or stroke[0] == -stroke[1]):
            axes.append(1)
        return tuple(axes)

    def bounding_box(self, design, options):
        """Tight box of the reachable set: |x| <= l1 + l2 - |m - n| (both annuli), |y| < l2, |z - e| <= l1 + l2,
        clipped by the stroke limits and z_min (spec §1.9/§1.10; the spec's box uses l1 + l2 + |m - n| in x)."""
        delta = abs(design["m"] - design["n"])
        l1, l2 = design["l1"], design["l2"]
        e = self.offset_e(design, options)
        reach = l1 + l2
        xr = max(reach - delta, 0.0)
        lo = np.array([-xr, -l2, e - reach])
        hi = np.array([xr, l2, e + reach])
        d = options.get("stroke_limits")
        if d is not None:
            lo[1], hi[1] = max(lo[1], d[0]), min(hi[1], d[1])
        if options.get("z_min") is not None:
            lo[2] = max(lo[2], options["z_min"])
        hi = np.maximum(hi, lo)
        return lo, hi

    # ----- NumPy kinematics (CLI, tests) ----------------------------------------------------------
    def _chains(self, design, options):
        delta = design["m"] - design["n"]
        return delta, design["l1"], design["l2"], self.offset_e(design, options)

    def inverse_kinematics(self, design, options, pose) -> list[Solution]:
        """All four IK branches (sigma1, sigma2) as (theta1, theta2, d) in rad and length units; [] if unreachable.

        A pose on a reach boundary (within 1e-12 in the arccos argument) is accepted as a double root.
        """
        x, y, z = self.check_vector("pose", pose, 3)
        delta, l1, l2, e = self._chains(design, options)
        b = z - e
        roots = []
        for a in (x - delta, -x - delta):
            r = math.hypot(a, b)
            if r == 0.0:
                return []
            k = (r * r + y * y + l1 * l1 - l2 * l2) / (2.0 * l1 * r)
            if abs(k) > 1.0 + 1e-12:
                return []
            g = math.acos(min(1.0, max(-1.0, k)))
            base = math.atan2(-b, a)
            roots.append({+1: wrap_angle(base + g), -1: wrap_angle(base - g)})
        return [
            Solution(s1 + s2, np.array([roots[0][1 if s1 == "+" else -1], roots[1][1 if s2 == "+" else -1], y]))
            for s1 in "+-"
            for s2 in "+-"
        ]

    def forward_kinematics(self, design, options, inputs) -> list[Solution]:
        """Both assembly modes (kappa = +1, -1) of inputs (theta1, theta2, d); a double root when the circles are
        tangent; [] when out of reach or when the circles coincide (infinitely many solutions)."""
        t1, t2, d = self.check_vector("inputs", inputs, 3)
        delta, l1, l2, e = self._chains(design, options)
        if abs(d) > l2:
            return []
        rho = math.sqrt(l2 * l2 - d * d)
        o1 = np.array([delta + l1 * math.cos(t1), e - l1 * math.sin(t1)])
        o2 = np.array([-(delta + l1 * math.cos(t2)), e - l1 * math.sin(t2)])
        u = o2 - o1
        dist = float(np.hypot(*u))
        scale = max(rho, l1, 1e-300)
        if dist <= 1e-14 * scale:
            return []
        h2 = rho * rho - dist * dist / 4.0
        if h2 < -1e-12 * scale * scale:
            return []
        mid = 0.5 * (o1 + o2)
        if h2 <= 1e-12 * scale * scale:
            return [Solution("double", np.array([mid[0], d, mid[1]]))]
        h = math.sqrt(h2)
        perp = np.array([-u[1], u[0]]) / dist
        out = []
        for label, kappa in (("+", 1.0), ("-", -1.0)):
            xz = mid + kappa * h * perp
            out.append(Solution(label, np.array([xz[0], d, xz[1]])))
        return out

    def jacobians(self, design, options, pose, q) -> dict[str, np.ndarray]:
        """Jx, Jq and the forward Jacobian J = Jx^-1 Jq (J is None at a forward singularity)."""
        x, y, z = self.check_vector("pose", pose, 3)
        t1, t2, _ = self.check_vector("inputs", q, 3)
        delta, l1, _, e = self._chains(design, options)
        b = z - e
        rows, diag = [], []
        for s, t in ((1.0, t1), (-1.0, t2)):
            a = s * x - delta
            rows.append([s * (a - l1 * math.cos(t)), y, b + l1 * math.sin(t)])
            diag.append(-l1 * (a * math.sin(t) + b * math.cos(t)))
        jx = np.array([rows[0], rows[1], [0.0, 1.0, 0.0]])
        jq = np.diag([diag[0], diag[1], 1.0])
        try:
            j = np.linalg.solve(jx, jq)
        except np.linalg.LinAlgError:
            j = None
        return {"Jx": jx, "Jq": jq, "J": j}

    def singularity(self, design, options, pose, q, tol: float = 1e-7) -> str:
        """'inverse' (det Jq = 0), 'forward' (det Jx = 0), 'both' or 'none', with scale-free tolerances:
        |sin| of the angle between link l1 and the xz-projection of l2 (inverse), and between the two
        xz-projections of the l2 links (forward)."""
        jac = self.jacobians(design, options, pose, q)
        x, _, z = pose
        delta, l1, _, e = self._chains(design, options)
        b = z - e
        inverse = False
        for s, qi in ((1.0, jac["Jq"][0, 0]), (-1.0, jac["Jq"][1, 1])):
            r = math.hypot(s * x - delta, b)
            # r = 0: D_i's projection on the C-circle centre with l1 = rho, theta_i undetermined (folded leg)
            if r <= tol * l1 or abs(qi) <= tol * l1 * r:
                inverse = True
        w1 = jac["Jx"][0, [0, 2]]
        w2 = jac["Jx"][1, [0, 2]]
        n1, n2 = np.hypot(*w1), np.hypot(*w2)
        cross = w1[0] * w2[1] - w1[1] * w2[0]
        forward = n1 == 0.0 or n2 == 0.0 or abs(cross) <= tol * n1 * n2
        return singularity_label(inverse, forward)

    def lci(self, design, options, pose, q) -> float:
        """LCI = 1/kappa_2(J) with NumPy's SVD (0 at any singularity)."""
        jac = self.jacobians(design, options, pose, q)
        if jac["J"] is None or self.singularity(design, options, pose, q, tol=0.0) != "none":
            return 0.0
        return svd_lci(jac["J"])

    def link_geometry(self, design, options, pose, q) -> links.LinkGeometry:
        """Capsules (design length unit) at P = (x, y, z) with inputs q = (theta1, theta2, d), frame of spec §1.1
        as in ``joint_screws``: base A2 -> A1 with A_i = (+-m, 0, e); arm_i (the parallelogram's long link l1)
        A_i -> C_i = (+-(m + l1 cos theta_i), 0, e - l1 sin theta_i); link_i (l2, between the U joints)
        C_i -> D_i = (x +- n, y, z); platform D2 -> D1. Each parallelogram is drawn as its one long link and the
        PPaP chain is not modelled (the paper gives none of its dimensions). Adjacent: base-arm_i, arm_i-link_i,
        link_i-platform. Radii: option ``link_radius``, defaults LINK_RADII (m)."""
        x, y, z = self.check_vector("pose", pose, 3)
        t1, t2, _ = self.check_vector("inputs", q, 3)
        m, n, l1 = design["m"], design["n"], design["l1"]
        e = self.offset_e(design, options)
        rad = links.radii(options, LINK_RADII)
        a = {1: links.point(m, 0.0, e), -1: links.point(-m, 0.0, e)}
        c = {s: links.point(s * (m + l1 * math.cos(t)), 0.0, e - l1 * math.sin(t)) for s, t in ((1, t1), (-1, t2))}
        d = {s: links.point(x + s * n, y, z) for s in (1, -1)}
        ends = {"base": (a[-1], a[1]), "arm1": (a[1], c[1]), "arm2": (a[-1], c[-1]), "link1": (c[1], d[1]),
                "link2": (c[-1], d[-1]), "platform": (d[-1], d[1])}
        segments = tuple(links.Segment(k, k, u, v, rad[k]) for k, (u, v) in ends.items())
        return links.LinkGeometry(segments, links.adjacency([
            ("base", "arm1"), ("base", "arm2"), ("arm1", "link1"), ("arm2", "link2"), ("link1", "platform"),
            ("link2", "platform"),
        ]))

    def link_endpoints(self, design, options, poses, q) -> np.ndarray:
        """Vectorised twin of link_geometry's segment endpoints at poses (m, 3) with inputs q (m, 3):
        links.SegmentPoints, segments in link_geometry's order."""
        pts, q = np.asarray(poses, dtype=float), np.asarray(q, dtype=float)
        m, n, l1 = design["m"], design["n"], design["l1"]
        e = self.offset_e(design, options)
        a = {1: (m, 0.0, e), -1: (-m, 0.0, e)}
        c = {s: (s * (m + l1 * np.cos(t)), 0.0, e - l1 * np.sin(t)) for s, t in ((1, q[:, 0]), (-1, q[:, 1]))}
        d = {s: (pts[:, 0] + s * n, pts[:, 1], pts[:, 2]) for s in (1, -1)}
        return links.segment_points([(a[-1], a[1]), (a[1], c[1]), (a[-1], c[-1]), (c[1], d[1]), (c[-1], d[-1]),
                                      (d[-1], d[1])], len(pts))

    def velocity_map(self, design, options, pose, q) -> np.ndarray:
        """A = Jq^-1 Jx: q_dot = A P_dot (rad and length per unit time), the inverse of J = Jx^-1 Jq; rows with an
        inverse singularity (Jq_ii = 0) are infinite."""
        jac = self.jacobians(design, options, pose, q)
        with np.errstate(divide="ignore", invalid="ignore"):
            return jac["Jx"] / np.diag(jac["Jq"])[:, None]

    def cycle_kinematics(self, design, options, poses, label: str) -> tuple[np.ndarray, np.ndarray]:
        """Vectorised twin of Mechanism.cycle_kinematics: inverse_kinematics' closed form in branch ``label`` and
        velocity_map's A = Jq^-1 Jx at poses (n, 3) in NumPy; NaN rows out of reach."""
        pts = np.asarray(poses, dtype=float)
        x, y, z = pts[:, 0], pts[:, 1], pts[:, 2]
        delta, l1, l2, e = self._chains(design, options)
        b = z - e
        n = len(pts)
        q = np.empty((n, 3))
        a = np.zeros((n, 3, 3))
        ok = np.ones(n, dtype=bool)
        with np.errstate(divide="ignore", invalid="ignore"):
            for i, (side, sign) in enumerate(((1.0, label[0]), (-1.0, label[1]))):
                u = side * x - delta
                r = np.hypot(u, b)
                k = (r * r + y * y + l1 * l1 - l2 * l2) / (2.0 * l1 * r)
                ok &= (r != 0.0) & (np.abs(k) <= 1.0 + 1e-12)
                g = np.arccos(np.clip(k, -1.0, 1.0))
                t = wrap_angle(np.arctan2(-b, u) + (g if sign == "+" else -g))
                q[:, i] = t
                jq = -l1 * (u * np.sin(t) + b * np.cos(t))
                a[:, i, 0] = side * (u - l1 * np.cos(t)) / jq
                a[:, i, 1] = y / jq
                a[:, i, 2] = (b + l1 * np.sin(t)) / jq
            q[:, 2] = y
            a[:, 2, 1] = 1.0
        q[~ok] = np.nan
        a[~ok] = np.nan
        return q, a

    # ----- mobility (scalesynth.mobility) ---------------------------------------------------------
    def topology(self, design, options):
        """Joint list of paper §1 for the G-K counts, each parallelogram Pa counted as one 1-DOF joint:
        chains PaUU, PaUU and PPaP; n = 8 (base, platform, two links per chain), g = 9, sum f = 13. The
        classical count 6(8 - 9 - 1) + 13 = 1 misses nu = 2 redundant constraints: each PaUU chain exerts
        one couple and PPaP three, and together they span only the three couples: the modified count is 3."""
        from scalesynth.mobility import Topology

        return Topology(
            n_links=8,
            chains=(("PaUU-1", ("Pa", "U", "U")), ("PaUU-2", ("Pa", "U", "U")), ("PPaP", ("P", "Pa", "P"))),
            redundant=2,
            note="the paper (§1.2, POC sets) counts F = sum f - sum xi_L = 13 - (6 + 4) = 3; as a modified "
            "G-K count the chains' 1 + 1 + 3 constraint couples span 3: nu = 2",
        )

    def joint_screws(self, design, options, pose, q):
        """Unit joint screws (omega; v) per chain at pose P = (x, y, z) with inputs q = (theta1, theta2, d),
        in the fixed frame of spec §1.1 (design length units).

        PaUU_i: the parallelogram's moving link translates along dC_i/dtheta_i, direction
        (-s_i sin theta_i, 0, -cos theta_i); the U at C_i turns about y (parallel to the parallelogram's axes)
        then about t_i = y x w_i / |y x w_i| (w_i = D_i - C_i: t_i is normal to the link), the U at D_i about
        t_i then y, so the chain's one constraint is a couple along the xz-projection of w_i.

        PPaP: the paper gives no dimensions, only three translations in different directions (its eq. 4);
        taken as the stroke d along y, a parallelogram in the xz-plane with long links L = l1 + l2 pivoted at
        x = 0 (so every |x| of the workspace is reachable; its moving link translates along
        (-sin phi, 0, cos phi), cos phi = x / L) and a slide along z."""
        from scalesynth.mobility import Joint, chain_screws

        x, y, z = self.check_vector("pose", pose, 3)
        t1, t2, _ = self.check_vector("inputs", q, 3)
        m, n, l1 = design["m"], design["n"], design["l1"]
        e = self.offset_e(design, options)
        yhat = (0.0, 1.0, 0.0)
        chains = []
        for s, t in ((1.0, t1), (-1.0, t2)):
            c = np.array([s * (m + l1 * math.cos(t)), 0.0, e - l1 * math.sin(t)])
            d = np.array([x + s * n, y, z])
            axis_t = np.cross(yhat, d - c)
            chains.append(chain_screws([
                Joint("Pa", axes=((-s * math.sin(t), 0.0, -math.cos(t)),)),
                Joint("U", c, (yhat, axis_t)),
                Joint("U", d, (axis_t, yhat)),
            ]))
        cos_phi = min(1.0, max(-1.0, x / (design["l1"] + design["l2"])))
        sin_phi = math.sqrt(1.0 - cos_phi * cos_phi)
        chains.append(chain_screws([
            Joint("P", axes=(yhat,)),
            Joint("Pa", axes=((-sin_phi, 0.0, cos_phi),)),
            Joint("P", axes=((0.0, 0.0, 1.0),)),
        ]))
        return chains

    # ----- stiffness (scalesynth.stiffness; pose level) ------------------------------------------------------
    def stiffness_model(self, design, options, pose, joints: str = "ideal"):
        """Frame model (scalesynth.stiffness.FrameModel, spatial, m, N) at P = (x, y, z) in the working mode
        ``options.mode``; raises InvalidPose outside the workspace. Frame of joint_screws / link_geometry.

        PaUU_i: the parallelogram as two bars with a rigid hinge plate (its moving short side), the actuated arm
        A_i -> C_i (A_i = (+-m, 0, e), a torsional actuator spring about y at A_i) and the arm link
        A_i - c z -> C_i - c z (revolutes about y at both ends; the paper gives the short side's length c, not its
        side: below the arm is assumed), the plate (reference C_i) joined to both bars by revolutes about y; the
        link C_i -> D_i = P +- (n, 0, 0) on universal joints (y, t_i) at C_i and (t_i, y) at D_i,
        t_i = y x w_i / |y x w_i|, w_i = D_i - C_i. PPaP: not dimensioned in the paper, so not elastic: rigid
        bodies at P joined by the actuated slide d along y (a linear spring, stroke_stiffness), the parallelogram's
        translation (-sin phi, 0, cos phi), cos phi = x / (l1 + l2), and the slide along z (joint_screws' model);
        it holds the platform's rotations rigidly, so the platform DOFs are x, y, z. The platform is rigid with
        reference point P; the load is a force at P. ``joints`` 'bonded' welds the passive revolute and universal
        joints (the slides stay slides)."""
        from scalesynth.stiffness.builder import FrameBuilder, unit
        from scalesynth.stiffness.model import Body
        from scalesynth.stiffness.sections import tube_section

        x, y, z = self.check_vector("pose", pose, 3)
        if self.point_kernel(self.pack(design, options), x, y, z) < 0.0:
            raise InvalidPose(f"pose: ({x:g}, {y:g}, {z:g}) is outside the workspace (mode {options['mode']}, "
                              "limits included)")
        (q,) = [sol.values for sol in self.inverse_kinematics(design, options, (x, y, z))
                if sol.label == options["mode"]]
        m, n, l1, c = design["m"], design["n"], design["l1"], design["c"]
        e = self.offset_e(design, options)
        yhat, zhat = np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0])
        k, k_d = options["actuator_stiffness"], options["stroke_stiffness"]
        fb = FrameBuilder({g: tube_section(options, g, "m") for g in LINK_GROUPS}, joints)
        p = np.array([x, y, z])
        bodies = [Body("base", np.zeros(3))]
        for i, (sgn, t) in enumerate(((1.0, q[0]), (-1.0, q[1])), 1):
            a = np.array([sgn * m, 0.0, e])
            ci = np.array([sgn * (m + l1 * math.cos(t)), 0.0, e - l1 * math.sin(t)])
            di = p + np.array([sgn * n, 0.0, 0.0])
            ti = unit(np.cross(yhat, di - ci))
            fb.link(f"arm{i}", "arm", a, ci)
            fb.link(f"arm_link{i}", "arm_link", a - c * zhat, ci - c * zhat)
            fb.link(f"link{i}", "link", ci, di)
            bodies.append(Body(f"plate{i}", ci.copy()))
            fb.joint(f"actuator{i}", "revolute", a, f"arm{i}.a", "base", (yhat,), k)
            fb.joint(f"elbow{i}", "revolute", ci, f"arm{i}.b", f"plate{i}", (yhat,))
            fb.joint(f"arm_link_base{i}", "revolute", a - c * zhat, f"arm_link{i}.a", "base", (yhat,))
            fb.joint(f"arm_link_plate{i}", "revolute", ci - c * zhat, f"arm_link{i}.b", f"plate{i}", (yhat,))
            fb.joint(f"U_C{i}", "universal", ci, f"link{i}.a", f"plate{i}", (yhat, ti))
            fb.joint(f"U_D{i}", "universal", di, f"link{i}.b", "platform", (ti, yhat))
        cos_phi = min(1.0, max(-1.0, x / (design["l1"] + design["l2"])))
        sin_phi = math.sqrt(1.0 - cos_phi * cos_phi)
        bodies += [Body("ppap_carriage", p.copy()), Body("ppap_slide", p.copy()), Body("platform", p.copy())]
        fb.joint("P_d", "prismatic", p, "ppap_carriage", "base", (yhat,), k_d)
        fb.joint("Pa_ppap", "prismatic", p, "ppap_slide", "ppap_carriage", ((-sin_phi, 0.0, cos_phi),))
        fb.joint("P_z", "prismatic", p, "platform", "ppap_slide", (zhat,))
        notes = ["spatial frame of spec §1.1 (z up, m); rigid platform with reference point P; the PPaP chain (rigid "
                 "bodies, slides d along y, the parallelogram's translation and z) holds the platform's rotations, so "
                 "its DOFs are x, y, z; the load is a force at P",
                 f"parallelograms: arm and arm link (offset -c z, c = {c:g}) with a rigid hinge plate; working mode "
                 f"{options['mode']}"]
        return fb.model("m", bodies, options["load"], notes)


MECHANISM = PauuPpap(
    name="2pauu-ppap",
    title="2PaUU-PPaP three-translation parallel mechanism (packaging, seed 000)",
    seed="000",
    motion="3T",
    task_axes=("x", "y", "z"),
    task_units=("length", "length", "length"),
    joints=("theta1", "theta2", "d"),
    joint_units=("angle", "angle", "length"),
    parameters=(
        Parameter("m", 0.857, "inscribed radius of the base square"),
        Parameter("n", 0.706, "platform radius"),
        Parameter("l1", 1.499, "long link of the parallelogram Pa"),
        Parameter("l2", 1.5, "link between the two U joints"),
        Parameter("c", 0.1, "short link of the parallelogram Pa"),
    ),
    options=(
        Option("mode", "++", "working mode sigma1 sigma2: '++', '+-', '-+' or '--'"),
        Option("e", None, "vertical offset of the C-circle centres; null = 2c (reproduces Tables 2-3)"),
        Option("theta1_limits", None, "[lo, hi] rad for theta1 (convention T), null = none"),
        Option("theta2_limits", None, "[lo, hi] rad for theta2 (convention T), null = none"),
        Option("stroke_limits", None, "[lo, hi] for the stroke d = y, null = none"),
        Option("z_min", None, "keep only z >= z_min, null = none"),
        *stiffness_options("m", ACTUATOR_STIFFNESS, "torsional stiffness of each parallelogram actuator theta1, "
                           "theta2, N m/rad (an assumption)", [0.0, 0.0, -150.0],
                           "default 150 N along -z, the gravity direction (z up), at P"),
        Option("stroke_stiffness", STROKE_STIFFNESS, "stiffness: axial stiffness of the PPaP chain's linear actuator "
               "d, N/m (2e4 N/mm, an assumption)"),
        Option("link_radius", None, "capsule radius of every body, or {body: radius}; null = defaults base 0.05, "
               "arm1/arm2 0.03, link1/link2 0.02, platform 0.05 (m, illustrative); setting it enables the "
               "clearance metrics"),
        Option("interference_free", False, "true: a pose whose link capsules overlap (clearance < 0) is unreachable"),
        Option("stiffness_metrics", False, "stiffness: true computes the per-voxel fields stiffness_min and "
               "deflection (0 otherwise) and enables their metrics; grid statistics then use the generic kernel, "
               "slower than the fast path"),
    ),
    default_length_unit="m",
    fields=(*base_fields("{length}/rad", "J = dx/dq (q = theta1, theta2 in rad and d: the d column is "
                         "dimensionless; not rescaled, as in the LCI)"), CLEARANCE, *STIFFNESS_FIELDS),
    design_metrics=DESIGN_METRICS,
    derived_units=(("m_minus_n", "length"),),
)
assert MECHANISM.n_fields == N_KERNEL_FIELDS and MECHANISM.field_names[_F_CLEARANCE] == "clearance"
assert MECHANISM.field_names[_F_STIFFNESS_MIN :] == ("stiffness_min", "deflection")
