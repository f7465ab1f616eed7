"""2-RPS-UPU parallel mechanism with two rotations and one translation (2R1T, seed 002), spec
``mechanisms_001_003.md`` §2.

Geometry (mm, rad): base joints A1 = (0, -g, 0), A2 = (0, g, 0), A3 = (e, 0, 0) with O the midpoint of A1A2
(erratum F1); platform points B1' = (0, -h, 0), B2' = (0, h, 0), B3' = (c, 0, 0). Inputs are the three leg
lengths q_i = |A_i B_i| (mm); the task coordinates are (z, theta, psi): the height of the platform origin O' and
the Euler angles about y and x.

Two models (spec §2.3):

* ``P`` (default) reproduces the paper's numbers: p = (0, 0, z), R = Ry(theta) Rx(psi). It violates the RPS
  joint constraints (B1 and B2 leave the plane x = 0), but it is what the paper computed with.
* ``C`` is constraint-consistent: x0 = 0 and R[0, 1] = 0, which adds a parasitic yaw
  phi = atan2(sin theta sin psi, cos psi), R = Rz(phi) Ry(theta) Rx(psi), and a parasitic y0 that depends on the
  chain-3 variant: ``plane`` keeps B3 in y = 0 (y0 = -c R[1, 0]); ``upu`` has the fixed U axis parallel to x
  through A3 and the platform U axis parallel to w (y0 = R[1, 2] (z + c R[2, 0]) / R[2, 2] - c R[1, 0]).

The LCI is 1/kappa_2 of the homogenised Jacobian dq/d(z, L theta, L psi): the angle columns of dq/d(z, theta, psi)
(mm/rad) are divided by the characteristic length L (option ``characteristic_length``, default h), which is the
same as measuring angular rates by the tangential speed L omega; the homogenised matrix is dimensionless.

Singularities: ``inverse`` when a leg length vanishes (q_i = 0: the leg direction is undefined), ``forward``
when the rows of the constraint Jacobian become dependent (det dq/dx = 0: assembly modes merge). A zero leg
also zeroes its constraint row, so q_i = 0 is always ``both``.

``TOOL_MECHANISM`` (``rps-upu-tool``) is the optional second workspace of spec §2.8: the position workspace of
the tool point T = O' + R (0, 0, -d) over (x, y, z), P-model, through the closed-form inverse T -> (z, theta, psi).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numba import njit

from scalesynth.errors import InvalidParameter, InvalidPose
from scalesynth.evaluation.plans import ColumnPlan
from scalesynth.kernels import grid as _grid
from scalesynth.kernels.clearance import min_capsule_gap, put_segment
from scalesynth.kernels.conditioning import inverse_singular_values, sv_3x3
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
    enclosing_circle_radius,
    parse_range,
    singularity_label,
    svd_lci,
    wrap_angle,
)
from scalesynth.stiffness import legs as _legs_k
from scalesynth.stiffness.sections import check_stiffness_options, stiffness_options, tube_section

MODELS = ("P", "C")
C3_VARIANTS = ("plane", "upu")
BRANCH = "+++"  # the only IK branch: every leg length is the positive root q_i = |A_i B_i|

# packed-parameter layout (see RpsUpu.pack); _RAD: capsule radii of base, leg1, leg2, leg3, platform (LINK_RADII
# order); _FREE_ONLY 1: poses whose capsules overlap are unreachable; stiffness: EA (N), EI, GJ (N mm^2) of the
# 'leg' group, the actuators' compliance 1/k (mm/N) and the load (N)
_G, _H, _C, _E, _MODEL_C, _UPU, _QLO, _QHI, _INV_L = range(9)
_RAD = 9
_FREE_ONLY = 14
_EA, _EI, _GJ, _CK, _FX = 15, 16, 17, 18, 19
N_PACKED = 22
_F_CLEARANCE = 3  # slot of the clearance field in the field kernels' out (its index in ``fields``), both workspaces
_F_STIFFNESS_MIN, _F_DEFLECTION = 4, 5  # slots of the stiffness fields, both workspaces
# the tool kernel's Newton solve for the C-model pose placing the tool at T: tolerance relative to max(g, h, c) + d
# and an iteration cap (it converges in 3-5 steps from the P-model pose; a failure is reported as singular)
_TOOL_NEWTON_RTOL = 1e-13
_TOOL_NEWTON_ITERS = 50

# capsules of the clearance field in link_geometry's order (base12, base23, base31, leg1..3, platform12, 23, 31,
# then the tool of rps-upu-tool) and their bodies (index into TOOL_RADII: base, leg1..3, platform, tool)
_SEGMENT_BODY = np.array([0, 0, 0, 1, 2, 3, 4, 4, 4, 5], dtype=np.int64)
_BODY_NAMES = ("base", "leg1", "leg2", "leg3", "platform", "tool")
_ADJACENT = links.adjacency([("base", "leg1"), ("base", "leg2"), ("base", "leg3"), ("leg1", "platform"),
                             ("leg2", "platform"), ("leg3", "platform"), ("tool", "platform")])
_PAIRS = links.kernel_pairs([_BODY_NAMES[b] for b in _SEGMENT_BODY[:9]], _ADJACENT)
_PAIRS_TOOL = links.kernel_pairs([_BODY_NAMES[b] for b in _SEGMENT_BODY], _ADJACENT)

# a parametrisation is degenerate below these (dimensionless) values: yaw undefined (cos psi = 0 with
# sin theta sin psi = 0), or, for the upu variant, R[2, 2] = cos theta cos psi = 0 (y0 unbounded)
_YAW_EPS2 = 1e-24
_R22_EPS = 1e-12


# ----- point kernel ---------------------------------------------------------------------------------------
@njit(cache=True, fastmath=FASTMATH)
def _p_model_rows(g, h, c, e, z, st, ct, sp, cp):
    """Squared leg lengths and the rows of q_i dq_i/d(z, theta, psi) of the P-model, spec §2.3 and §2.5."""
    a = g * g + h * h + z * z - 2.0 * g * h * cp
    b = 2.0 * h * z * ct * sp
    q1s = a - b
    q2s = a + b
    q3s = c * c + e * e + z * z - 2.0 * c * e * ct - 2.0 * c * z * st
    hz = h * z
    r11 = z - h * ct * sp
    r12 = hz * st * sp
    r13 = g * h * sp - hz * ct * cp
    r21 = z + h * ct * sp
    r23 = g * h * sp + hz * ct * cp
    r31 = z - c * st
    r32 = c * e * st - c * z * ct
    return True, q1s, q2s, q3s, r11, r12, r13, r21, -r12, r23, r31, r32, 0.0


@njit(cache=True, fastmath=FASTMATH)
def _yaw(st, ct, sp, cp):
    """The C-model's parasitic yaw phi = atan2(N, M), N = sin theta sin psi, M = cos psi: (ok, n = |(N, M)|, its sine
    sf = N/n and cosine cf = M/n, and the derivatives of n, sf, cf with respect to theta (_t) and psi (_p)); ok False
    where the yaw is undefined (n = 0)."""
    nn = st * sp
    mm = cp
    n2 = nn * nn + mm * mm
    if n2 < _YAW_EPS2:
        return False, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    n = math.sqrt(n2)
    n_t = nn * ct * sp / n
    n_p = -sp * cp * ct * ct / n
    return (True, n, nn / n, mm / n, n_t, n_p, (ct * sp * n - nn * n_t) / n2, (st * cp * n - nn * n_p) / n2,
            -mm * n_t / n2, (-sp * n - mm * n_p) / n2)


@njit(cache=True, fastmath=FASTMATH)
def _c_model_rows(g, h, c, e, upu, z, st, ct, sp, cp):
    """Squared leg lengths and the rows of q_i dq_i/d(z, theta, psi) of the C-model (spec §2.3).

    Every leg vector d_i = B_i - A_i is differentiated by the chain rule through the parasitic yaw (its sine
    and cosine sf = N/n, cf = M/n with N = sin theta sin psi, M = cos psi, n = |(N, M)| = R[1, 1]) and y0; the
    row is d_i . dB_i/dx. Returns ok = False where the parametrisation is degenerate; then y0, sin and cos of the
    yaw (for the platform's placement).
    """
    ok, n, sf, cf, n_t, n_p, sf_t, sf_p, cf_t, cf_p = _yaw(st, ct, sp, cp)
    if not ok:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0
    r10 = sf * ct
    r10_t = sf_t * ct - sf * st
    r10_p = sf_p * ct
    if upu:
        r22 = ct * cp
        if abs(r22) < _R22_EPS:
            return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0
        r12 = sf * st * cp - cf * sp
        r12_t = sf_t * st * cp + sf * ct * cp - cf_t * sp
        r12_p = sf_p * st * cp - sf * st * sp - cf_p * sp - cf * cp
        r22_t = -st * cp
        r22_p = -ct * sp
        w = z - c * st  # z + c R[2, 0]
        w_t = -c * ct
        y0 = r12 * w / r22 - c * r10
        y0_z = r12 / r22
        y0_t = (r12_t * w + r12 * w_t) / r22 - r12 * w * r22_t / (r22 * r22) - c * r10_t
        y0_p = r12_p * w / r22 - r12 * w * r22_p / (r22 * r22) - c * r10_p
    else:
        y0 = -c * r10
        y0_z = 0.0
        y0_t = -c * r10_t
        y0_p = -c * r10_p
    # chains 1 and 2: B_i stays in x = 0, d = (0, y0 -+ h n +- g, z -+ h cos theta sin psi)
    d1y = y0 - h * n + g
    d1z = z - h * ct * sp
    d2y = y0 + h * n - g
    d2z = z + h * ct * sp
    # chain 3: d3 = (c cf cos theta - e, y0 + c R[1, 0], z - c sin theta)
    d3x = c * cf * ct - e
    d3y = y0 + c * r10
    d3z = z - c * st
    q1s = d1y * d1y + d1z * d1z
    q2s = d2y * d2y + d2z * d2z
    q3s = d3x * d3x + d3y * d3y + d3z * d3z
    r11 = d1y * y0_z + d1z
    r12_ = d1y * (y0_t - h * n_t) + d1z * (h * st * sp)
    r13 = d1y * (y0_p - h * n_p) + d1z * (-h * ct * cp)
    r21 = d2y * y0_z + d2z
    r22_ = d2y * (y0_t + h * n_t) + d2z * (-h * st * sp)
    r23 = d2y * (y0_p + h * n_p) + d2z * (h * ct * cp)
    r31 = d3y * y0_z + d3z
    r32 = d3x * c * (cf_t * ct - cf * st) + d3y * (y0_t + c * r10_t) + d3z * (-c * ct)
    r33 = d3x * c * cf_p * ct + d3y * (y0_p + c * r10_p)
    return True, q1s, q2s, q3s, r11, r12_, r13, r21, r22_, r23, r31, r32, r33, y0, sf, cf


@njit(cache=True, fastmath=FASTMATH)
def _clearance(p, y0, z, st, ct, sp, cp, sf, cf, pairs, tx, ty, tz, r_tool):
    """Smallest gap (mm) between the capsules of link_geometry that share no joint, at the platform pose
    p = (0, y0, z), R = Rz(phi) Ry(theta) Rx(psi) (sf, cf: sine and cosine of the yaw phi; P-model 0, 1). With the
    tool pairs (rps-upu-tool) the 10th capsule is the tool O' -> T = (tx, ty, tz) of radius r_tool."""
    g = p[_G]
    h = p[_H]
    c = p[_C]
    e = p[_E]
    ux = cf * ct  # R x
    uy = sf * ct
    uz = -st
    vx = cf * st * sp - sf * cp  # R y
    vy = sf * st * sp + cf * cp
    vz = ct * sp
    b1x, b1y, b1z = -h * vx, y0 - h * vy, z - h * vz
    b2x, b2y, b2z = h * vx, y0 + h * vy, z + h * vz
    b3x, b3y, b3z = c * ux, y0 + c * uy, z + c * uz
    seg = np.empty((10, 6))
    put_segment(seg, 0, 0.0, -g, 0.0, 0.0, g, 0.0)
    put_segment(seg, 1, 0.0, g, 0.0, e, 0.0, 0.0)
    put_segment(seg, 2, e, 0.0, 0.0, 0.0, -g, 0.0)
    put_segment(seg, 3, 0.0, -g, 0.0, b1x, b1y, b1z)
    put_segment(seg, 4, 0.0, g, 0.0, b2x, b2y, b2z)
    put_segment(seg, 5, e, 0.0, 0.0, b3x, b3y, b3z)
    put_segment(seg, 6, b1x, b1y, b1z, b2x, b2y, b2z)
    put_segment(seg, 7, b2x, b2y, b2z, b3x, b3y, b3z)
    put_segment(seg, 8, b3x, b3y, b3z, b1x, b1y, b1z)
    put_segment(seg, 9, 0.0, y0, z, tx, ty, tz)
    radius = np.empty(10)
    for i in range(9):
        radius[i] = p[_RAD + _SEGMENT_BODY[i]]
    radius[9] = r_tool
    return min_capsule_gap(seg, pairs, radius)


@njit(cache=True, fastmath=FASTMATH)
def _leg_ok(qs, lo, hi):
    """(within limits, q) for a squared leg length; tiny negative round-off of a squared norm is clamped."""
    q = math.sqrt(qs) if qs > 0.0 else 0.0
    return lo <= q <= hi, q


@njit(cache=True, fastmath=FASTMATH)
def _singular_response(p):
    """(stiffness_min, deflection) at a singular or degenerate pose: 0 and the 1e12 cap (0 under no load)."""
    return 0.0, 0.0 if (p[_FX] == 0.0 and p[_FX + 1] == 0.0 and p[_FX + 2] == 0.0) else _legs_k.DEFLECTION_CAP


@njit(cache=True, fastmath=FASTMATH)
def _chain_columns(p, kk, ax, ay, az, bx, by, bz, f2x, f2y, f2z, m2x, m2y, m2z, rx, ry, rz):
    """K += W Phi^-1 W^T for one leg A -> B (ideal joints, the frame of stiffness_model): its two constraint
    wrenches at B are w1 = the force along the leg (it also loads the actuator spring) and w2 = (f2, m2) (N, N mm
    about B), reciprocal to the leg's passive joints; Phi (2x2) is their flexibility on the leg clamped at A
    (cylinder and rod: one straight round-section beam, legs.tip_bilinear) plus the spring's 1/k (F . e)^2. The
    columns W L^-T (Phi = L L^T) are carried to the reference point (rx, ry, rz): moment M + (B - ref) x F.
    Returns (ok, kk); ok False for a leg of zero length or a flexibility that is not positive definite."""
    dx, dy, dz = bx - ax, by - ay, bz - az
    length = math.sqrt(dx * dx + dy * dy + dz * dz)
    if not length > 0.0:
        return False, kk
    ex, ey, ez = dx / length, dy / length, dz / length
    ea, ei, gj, ck = p[_EA], p[_EI], p[_GJ], p[_CK]
    f2e = f2x * ex + f2y * ey + f2z * ez
    p11 = _legs_k.tip_bilinear(length, ea, ei, gj, ex, ey, ez, ex, ey, ez, 0.0, 0.0, 0.0, ex, ey, ez, 0.0, 0.0,
                               0.0) + ck
    p12 = _legs_k.tip_bilinear(length, ea, ei, gj, ex, ey, ez, ex, ey, ez, 0.0, 0.0, 0.0, f2x, f2y, f2z, m2x, m2y,
                               m2z) + ck * f2e
    p22 = _legs_k.tip_bilinear(length, ea, ei, gj, ex, ey, ez, f2x, f2y, f2z, m2x, m2y, m2z, f2x, f2y, f2z, m2x,
                               m2y, m2z) + ck * f2e * f2e
    if not p11 > 0.0:
        return False, kk
    l11 = math.sqrt(p11)
    l21 = p12 / l11
    q22 = p22 - l21 * l21
    if not q22 > 0.0:
        return False, kk
    i11 = 1.0 / l11
    i22 = 1.0 / math.sqrt(q22)
    sx, sy, sz = bx - rx, by - ry, bz - rz  # ref -> B
    # column 1: w1 / l11; column 2: (w2 - l21 w1 / l11) / l22
    ux, uy, uz = ex * i11, ey * i11, ez * i11
    kk = _legs_k.outer_add(kk, ux, uy, uz, sy * uz - sz * uy, sz * ux - sx * uz, sx * uy - sy * ux)
    t = l21 * i11
    vx, vy, vz = (f2x - t * ex) * i22, (f2y - t * ey) * i22, (f2z - t * ez) * i22
    kk = _legs_k.outer_add(kk, vx, vy, vz, m2x * i22 + sy * vz - sz * vy, m2y * i22 + sz * vx - sx * vz,
                           m2z * i22 + sx * vy - sy * vx)
    return True, kk


@njit(cache=True, fastmath=FASTMATH)
def _stiffness(p, upu, y0, z, st, ct, sp, cp, sf, cf, rx, ry, rz):
    """(stiffness_min N/mm, deflection mm) of the reference point (rx, ry, rz) under the packed load, ideal joints,
    the frame of stiffness_model at the constraint-consistent (C-model) pose: O' = (0, y0, z), R = Rz(phi) Ry(theta)
    Rx(psi) (sf, cf: sine and cosine of the yaw phi). Per leg two constraint wrenches (_chain_columns): RPS_1, RPS_2
    (revolute about x at A_i, spherical at B_i) and chain 3 'plane' (revolute about y at A3) pass forces through B_i
    along the leg and along the revolute axis; chain 3 'upu' (universal joints (x, m) at A3 and (m, w) at B3,
    m = x X w) passes the force along the leg and a force along m through the point Q where the x axis through A3
    meets the w axis through B3 (both lie in the plane normal to m that holds the leg). Six wrench columns; the
    platform response from the 21 entries of K (legs.response_upper, characteristic length the longest beam, half
    a leg). (0, 1e12) where a leg has zero length or the wrenches degenerate (w along x: Q at infinity)."""
    g = p[_G]
    h = p[_H]
    c = p[_C]
    e = p[_E]
    ux, uy, uz = cf * ct, sf * ct, -st  # R x
    vx, vy, vz = cf * st * sp - sf * cp, sf * st * sp + cf * cp, ct * sp  # R y
    b1x, b1y, b1z = -h * vx, y0 - h * vy, z - h * vz
    b2x, b2y, b2z = h * vx, y0 + h * vy, z + h * vz
    b3x, b3y, b3z = c * ux, y0 + c * uy, z + c * uz
    kk = (0.0,) * 21
    ok1, kk = _chain_columns(p, kk, 0.0, -g, 0.0, b1x, b1y, b1z, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, rx, ry, rz)
    ok2, kk = _chain_columns(p, kk, 0.0, g, 0.0, b2x, b2y, b2z, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, rx, ry, rz)
    if upu:
        wx, wy, wz = cf * st * cp + sf * sp, sf * st * cp - cf * sp, ct * cp  # R z
        my, mz = -wz, wy  # x X w = (0, -wz, wy)
        mn = math.sqrt(my * my + mz * mz)
        if not mn > 1e-12:
            return _singular_response(p)
        my, mz = my / mn, mz / mn
        # Q = A3 + s x = B3 + t w (the lines are coplanar): t = (d.x (x.w) - d.w) / (1 - (x.w)^2), d = B3 - A3;
        # with x.w = wx the x components cancel: t = -(d_y w_y + d_z w_z) / |m|^2, |m|^2 = 1 - wx^2 (A3 has y = z = 0)
        t = -(b3y * wy + b3z * wz) / (mn * mn)
        # the force along m through Q, about B3: (Q - B3) x m = t w x m
        ok3, kk = _chain_columns(p, kk, e, 0.0, 0.0, b3x, b3y, b3z, 0.0, my, mz, t * (wy * mz - wz * my),
                                 t * (-wx * mz), t * (wx * my), rx, ry, rz)
    else:
        ok3, kk = _chain_columns(p, kk, e, 0.0, 0.0, b3x, b3y, b3z, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, rx, ry, rz)
    if not (ok1 and ok2 and ok3):
        return _singular_response(p)
    l1 = math.sqrt(b1x * b1x + (b1y + g) * (b1y + g) + b1z * b1z)
    l2 = math.sqrt(b2x * b2x + (b2y - g) * (b2y - g) + b2z * b2z)
    l3 = math.sqrt((b3x - e) * (b3x - e) + b3y * b3y + b3z * b3z)
    return _legs_k.response_upper(kk, p[_FX], p[_FX + 1], p[_FX + 2], 0.5 * max(l1, l2, l3))


@njit(cache=True, fastmath=FASTMATH)
def point_fields(p, x, y, z, out):
    """Every field at task point (z, theta, psi) = (x, y, z) (see _fields): LCI, sigma_min, sigma_max, clearance,
    stiffness_min, deflection."""
    _fields(p, x, y, z, out, True)


@njit(cache=True, fastmath=FASTMATH)
def kinematic_fields(p, x, y, z, out):
    """Slots 0-3 only (LCI, sigma_min, sigma_max, clearance), for benchmarks (the cost without stiffness)."""
    _fields(p, x, y, z, out, False)


@njit(cache=True, fastmath=FASTMATH)
def lci_fields(p, x, y, z, out):
    """Slot 0 of point_fields alone, computed as there (the LCI or -1; with interference_free the clearance still
    decides reachability), the other slots not written: the search's kernel when it needs only the LCI's metrics
    (Mechanism.lci_kernel)."""
    _fields(p, x, y, z, out, False, True, False)


@njit(cache=True, fastmath=FASTMATH)
def point_reach(p, x, y, z, out):
    """Slot 0 of point_fields up to its value: >= 0 exactly where point_fields' LCI is (the same leg checks and,
    with interference_free, the same clearance), -1 elsewhere; no conditioning, stiffness or (without
    interference_free) clearance. The adaptive evaluator's nodes and bisections (Mechanism.reach_kernel)."""
    _fields(p, x, y, z, out, False, False)


@njit(cache=True, fastmath=FASTMATH)
def _placement_stiffness(p, y0, z, st, ct, sp, cp, sf, cf, placed, at_origin, rx, ry, rz):
    """(stiffness_min, deflection) at the constraint-consistent placement of (z, theta, psi): the configured
    C-model pose itself when ``placed`` (y0, sf, cf given), else the C-model pose with the configured chain-3
    variant computed here (the P-model violates the RPS joint constraints; docs/stiffness.md). The reference point
    is O' = (0, y0, z) when ``at_origin``, else (rx, ry, rz). A degenerate C-model parametrisation gives (0, 1e12)."""
    upu = p[_UPU] > 0.0
    if not placed:
        ok, _, _, _, _, _, _, _, _, _, _, _, _, y0, sf, cf = _c_model_rows(p[_G], p[_H], p[_C], p[_E], upu, z, st,
                                                                         ct, sp, cp)
        if not ok:
            return _singular_response(p)
    if at_origin:
        rx, ry, rz = 0.0, y0, z
    return _stiffness(p, upu, y0, z, st, ct, sp, cp, sf, cf, rx, ry, rz)


@njit(cache=True, fastmath=FASTMATH)
def _fields(p, x, y, z, out, stiffness, every=True, others=True):
    """LCI of the homogenised dq/d(z, L theta, L psi) at task point (x, y, z) = (z, theta, psi), or -1 when a leg
    length leaves the stroke limits or the parametrisation is degenerate (C-model). ``others`` False (a constant,
    lci_fields): slot 0 alone, the LCI as with True. Fields (kernels.grid contract):
    LCI, sigma_min, sigma_max of J = its inverse, dx/dq (dimensionless); 3 clearance (mm) of the link capsules
    (with interference_free, overlapping capsules make the pose unreachable); with ``stiffness``, 4 stiffness_min
    (N/mm) and 5 deflection (mm) of O' under the packed load on the frame at the constraint-consistent placement
    of the pose (ideal joints; _stiffness), computed at every reachable pose whether or not that placement's own
    legs are within the stroke limits (docs/stiffness.md). ``every`` False (a constant, point_reach): slot 0 alone,
    0 where reachable, -1 elsewhere."""
    g = p[_G]
    h = p[_H]
    c = p[_C]
    e = p[_E]
    st = math.sin(y)
    ct = math.cos(y)
    sp = math.sin(z)
    cp = math.cos(z)
    y0, sf, cf = 0.0, 0.0, 1.0  # P-model: O' on the z axis, no yaw
    if p[_MODEL_C] > 0.0:
        ok, q1s, q2s, q3s, a11, a12, a13, a21, a22, a23, a31, a32, a33, y0, sf, cf = _c_model_rows(
            g, h, c, e, p[_UPU] > 0.0, x, st, ct, sp, cp
        )
        if not ok:
            _grid.write_unreachable(out)
            return
    else:
        ok, q1s, q2s, q3s, a11, a12, a13, a21, a22, a23, a31, a32, a33 = _p_model_rows(g, h, c, e, x, st, ct, sp, cp)
    lo = p[_QLO]
    hi = p[_QHI]
    ok1, q1 = _leg_ok(q1s, lo, hi)
    ok2, q2 = _leg_ok(q2s, lo, hi)
    ok3, q3 = _leg_ok(q3s, lo, hi)
    if not (ok1 and ok2 and ok3):
        _grid.write_unreachable(out)
        return
    if not every:
        out[0] = 0.0
        if p[_FREE_ONLY] > 0.0 and _clearance(p, y0, x, st, ct, sp, cp, sf, cf, _PAIRS, 0.0, 0.0, 0.0, 0.0) < 0.0:
            out[0] = -1.0
        return
    gap = 0.0
    if others or p[_FREE_ONLY] > 0.0:
        gap = _clearance(p, y0, x, st, ct, sp, cp, sf, cf, _PAIRS, 0.0, 0.0, 0.0, 0.0)
        if gap < 0.0 and p[_FREE_ONLY] > 0.0:
            _grid.write_unreachable(out)
            return
    if q1 == 0.0 or q2 == 0.0 or q3 == 0.0:
        _grid.write_singular(out)  # inverse singularity: a leg of zero length has no direction
    else:
        # row i of dq/dx is (q_i dq_i/dx) / q_i; the angle columns are divided by L (homogenisation)
        i1 = 1.0 / q1
        i2 = 1.0 / q2
        i3 = 1.0 / q3
        il = p[_INV_L]
        lci, smin, smax = sv_3x3(
            a11 * i1, a12 * i1 * il, a13 * i1 * il,
            a21 * i2, a22 * i2 * il, a23 * i2 * il,
            a31 * i3, a32 * i3 * il, a33 * i3 * il,
        )  # fmt: skip
        out[0] = lci
        if not others:
            return
        out[1], out[2] = inverse_singular_values(smin, smax)
    if not others:
        return
    out[_F_CLEARANCE] = gap
    if stiffness:
        out[_F_STIFFNESS_MIN], out[_F_DEFLECTION] = _placement_stiffness(
            p, y0, x, st, ct, sp, cp, sf, cf, p[_MODEL_C] > 0.0, True, 0.0, 0.0, 0.0)


# ----- NumPy kinematics (vectorised over poses; CLI, FK and tests) ----------------------------------------
def _rot(axis: str, a: np.ndarray) -> np.ndarray:
    """Stack of active rotation matrices about a fixed axis, shape (n, 3, 3)."""
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    if axis == "x":
        rows = ((o, z, z), (z, c, -s), (z, s, c))
    elif axis == "y":
        rows = ((c, z, s), (z, o, z), (-s, z, c))
    else:
        rows = ((c, -s, z), (s, c, z), (z, z, o))
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


def _skew(w: np.ndarray) -> np.ndarray:
    """[w]x for a stack of vectors (n, 3) -> (n, 3, 3)."""
    z = np.zeros(w.shape[0])
    rows = ([z, -w[:, 2], w[:, 1]], [w[:, 2], z, -w[:, 0]], [-w[:, 1], w[:, 0], z])
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


def _platform(geom: tuple, model: str, variant: str, x: np.ndarray):
    """Platform pose of task points x (n, 3) = (z, theta, psi).

    Returns (valid (n,), p (n, 3), R (n, 3, 3), phi (n,), T (n, 6, 3)) where T = d(v, omega)/d(z, theta, psi)
    maps task rates to the platform twist (v: velocity of O', omega: angular velocity, fixed frame). It carries the
    parasitic yaw rate and y0 rate of the C-model (spec §2.5): omega = phi' z + theta' Rz y + psi' Rz Ry x.
    """
    _, _, c, _ = geom
    z, th, ps = x[:, 0], x[:, 1], x[:, 2]
    n = x.shape[0]
    st, ct, sp, cp = np.sin(th), np.cos(th), np.sin(ps), np.cos(ps)
    valid = np.ones(n, dtype=bool)
    if model == "P":
        phi = np.zeros(n)
        phi_t = phi_p = np.zeros(n)
    else:
        n2 = (st * sp) ** 2 + cp**2
        valid &= n2 >= _YAW_EPS2
        n2 = np.where(valid, n2, 1.0)
        phi = np.arctan2(st * sp, cp)
        phi_t = cp * ct * sp / n2
        phi_p = st / n2
    rz, ry, rx = _rot("z", phi), _rot("y", th), _rot("x", ps)
    rzy = rz @ ry
    R = rzy @ rx
    ez = np.array([0.0, 0.0, 1.0])
    w_t = phi_t[:, None] * ez + rz[:, :, 1]
    w_p = phi_p[:, None] * ez + rzy[:, :, 0]
    dR_t = _skew(w_t) @ R
    dR_p = _skew(w_p) @ R
    y0 = np.zeros(n)
    dy = np.zeros((n, 3))  # d y0 / d(z, theta, psi)
    if model == "C" and variant == "plane":
        y0 = -c * R[:, 1, 0]
        dy[:, 1] = -c * dR_t[:, 1, 0]
        dy[:, 2] = -c * dR_p[:, 1, 0]
    elif model == "C":
        r22 = R[:, 2, 2]
        valid &= np.abs(r22) >= _R22_EPS
        r22 = np.where(valid, r22, 1.0)
        w = z + c * R[:, 2, 0]
        y0 = R[:, 1, 2] * w / r22 - c * R[:, 1, 0]
        dy[:, 0] = R[:, 1, 2] / r22
        for k, dR in ((1, dR_t), (2, dR_p)):
            dw = c * dR[:, 2, 0]  # d(z + c R[2, 0]) for the angles
            quotient = (dR[:, 1, 2] * w + R[:, 1, 2] * dw) / r22 - R[:, 1, 2] * w * dR[:, 2, 2] / r22**2
            dy[:, k] = quotient - c * dR[:, 1, 0]
    p = np.stack([np.zeros(n), y0, z], axis=-1)
    T = np.zeros((n, 6, 3))
    T[:, 1, :] = dy
    T[:, 2, 0] = 1.0
    T[:, 3:, 1] = w_t
    T[:, 3:, 2] = w_p
    return valid, p, R, phi, T


def _legs(geom: tuple, model: str, variant: str, x: np.ndarray):
    """Leg vectors and Jacobians at task points x (n, 3).

    Returns (valid, q (n, 3), jx (n, 3, 3)) with jx[:, i] = q_i dq_i/d(z, theta, psi) from the twist form
    q_i q_i' = d_i . v + (r_i x d_i) . omega (spec §0, §2.5) composed with T; d_i = B_i - A_i, r_i = R b_i'.
    """
    g, h, c, e = geom
    valid, p, R, _, T = _platform(geom, model, variant, x)
    a = np.array([[0.0, -g, 0.0], [0.0, g, 0.0], [e, 0.0, 0.0]])
    b = np.array([[0.0, -h, 0.0], [0.0, h, 0.0], [c, 0.0, 0.0]])
    r = np.einsum("nij,kj->nki", R, b)  # (n, leg, xyz)
    d = p[:, None, :] + r - a[None]
    q = np.sqrt(np.einsum("nki,nki->nk", d, d))
    screw = np.concatenate([d, np.cross(r, d)], axis=-1)  # (n, leg, 6)
    jx = screw @ T
    return valid, q, jx


def _p_leg_lengths(geom: tuple, x: np.ndarray) -> np.ndarray:
    """Leg lengths (n, 3) of the P-model at poses x (n, 3) = (z, theta, psi) in closed form (phi = y0 = 0, so
    B_i = (0, 0, z) + Ry(theta) Rx(psi) b_i'): _legs' q without its Jacobians."""
    g, h, c, e = geom
    z, st, ct, sp, cp = x[:, 0], np.sin(x[:, 1]), np.cos(x[:, 1]), np.sin(x[:, 2]), np.cos(x[:, 2])
    return np.stack([np.sqrt((h * st * sp) ** 2 + (g - h * cp) ** 2 + (z - h * ct * sp) ** 2),
                     np.sqrt((h * st * sp) ** 2 + (h * cp - g) ** 2 + (z + h * ct * sp) ** 2),
                     np.sqrt((c * ct - e) ** 2 + (z - c * st) ** 2)], axis=-1)


# ----- forward kinematics -----------------------------------------------------------------------------------
def _p_angles(geom: tuple, q: np.ndarray, z: np.ndarray, cos_theta: np.ndarray, sin_theta: np.ndarray) -> np.ndarray:
    """Complete P-model candidates (z, theta, psi) from z and theta (spec §2.4): cos psi from q1^2 + q2^2,
    sin psi = D / (h z cos theta). Where h z cos theta vanishes (then D = 0 too) both signs of sin psi are
    returned. Candidates with |cos psi| > 1 are dropped; the caller polishes the rest by Newton."""
    g, h, _, _ = geom
    s = 0.5 * (q[0] ** 2 + q[1] ** 2)
    d = 0.25 * (q[1] ** 2 - q[0] ** 2)
    out = []
    for zi, ct, st in zip(z, cos_theta, sin_theta, strict=True):
        cp = (g * g + h * h + zi * zi - s) / (2.0 * g * h)
        if abs(cp) > 1.0 + 1e-7:
            continue
        cp = min(1.0, max(-1.0, cp))
        den = h * zi * ct
        if abs(den) > 1e-9 * h * max(zi, 1.0):
            sps = [d / den]
        else:
            sps = [math.sqrt(1.0 - cp * cp), -math.sqrt(1.0 - cp * cp)]
        th = math.atan2(st, ct)
        out.extend((zi, th, math.atan2(sp, cp)) for sp in sps)
    return np.array(out, dtype=float).reshape(-1, 3)


def fk_p_quartic(geom: tuple, q) -> np.ndarray:
    """Unpolished P-model FK candidates for e = 0 from the quartic in t = z^2 (spec §2.4):

    (t - S + (g - h)^2)(t - S + (g + h)^2)(t - (c + q3)^2)(t - (c - q3)^2) = 16 g^2 c^2 D^2,
    S = (q1^2 + q2^2)/2, D = (q2^2 - q1^2)/4; then sin theta = (c^2 + t - q3^2)/(2 c z) with both signs of
    cos theta (the theta <-> pi - theta mirror). Only z > 0 is returned: every solution (z, theta, psi) has the
    mirror image (-z, -theta, -psi) through the base plane. Shape (k, 3).
    """
    g, h, c, e = geom
    if e != 0.0:
        raise ValueError("fk_p_quartic: the quartic holds for e = 0 only; use fk_p_bracket")
    q = np.asarray(q, dtype=float)
    s = 0.5 * (q[0] ** 2 + q[1] ** 2)
    d = 0.25 * (q[1] ** 2 - q[0] ** 2)
    # roots of the four factors in u = (t - S) / scale: centring on S keeps long legs (all four roots close to
    # S) from cancelling, scaling makes the coefficients O(1) (t^4 ~ 1e16 mm^8 otherwise)
    factors = np.array([-((g - h) ** 2), -((g + h) ** 2), (c + q[2]) ** 2 - s, (c - q[2]) ** 2 - s])
    scale = max(float(np.abs(factors).max()), 1e-300)
    coef = np.poly(factors / scale)
    coef[-1] -= (4.0 * g * c * d) ** 2 / scale**4
    roots = np.roots(coef)
    real = roots[np.abs(roots.imag) <= 1e-6 * np.maximum(1.0, np.abs(roots))].real
    dcoef = np.polyder(coef)
    for _ in range(3):  # Newton on the polynomial: restores full precision after the eigenvalue solver
        dp = np.polyval(dcoef, real)
        real = real - np.where(dp != 0.0, np.polyval(coef, real) / np.where(dp != 0.0, dp, 1.0), 0.0)
    t = s + real * scale
    t = t[t > 0.0]
    z, st, ct = [], [], []
    for ti in t:
        zi = math.sqrt(ti)
        sth = (c * c + ti - q[2] ** 2) / (2.0 * c * zi)
        if abs(sth) > 1.0 + 1e-7:
            continue
        sth = min(1.0, max(-1.0, sth))
        cth = math.sqrt(1.0 - sth * sth)
        for sign in (1.0, -1.0):
            z.append(zi)
            st.append(sth)
            ct.append(sign * cth)
    return _p_angles(geom, q, np.array(z), np.array(ct), np.array(st))


def _p_branch_residual(geom: tuple, q: np.ndarray, z: np.ndarray, branch: float):
    """F(z) = D^2 - (h z cos theta)^2 (1 - cos^2 psi) on one theta branch of the q3 equation (any e):
    theta = atan2(z, e) + branch * arccos(K / (c r)), K = (c^2 + e^2 + z^2 - q3^2)/2, r = |(e, z)|.
    F = 0 is cos^2 psi + sin^2 psi = 1 with sin psi = D / (h z cos theta), free of poles. Returns (F, theta)."""
    g, h, c, e = geom
    s = 0.5 * (q[0] ** 2 + q[1] ** 2)
    d = 0.25 * (q[1] ** 2 - q[0] ** 2)
    r = np.hypot(e, z)
    k = 0.5 * (c * c + e * e + z * z - q[2] ** 2)
    arg = np.clip(k / (c * np.maximum(r, 1e-300)), -1.0, 1.0)
    theta = np.arctan2(z, e) + branch * np.arccos(arg)
    cp = np.clip((g * g + h * h + z * z - s) / (2.0 * g * h), -1.0, 1.0)
    return d * d - (h * z * np.cos(theta)) ** 2 * (1.0 - cp * cp), theta


def fk_p_bracket(geom: tuple, q, samples: int = 2048) -> np.ndarray:
    """Unpolished P-model FK candidates for any e by root bracketing in z (spec §2.4, ``P_fk_all``).

    On z^2 in [max((c - q3)^2 - e^2, S - (g + h)^2), min((c + q3)^2 - e^2, S - (g - h)^2)] both theta branches of
    the q3 equation and cos psi are real; the ends are where the branches join or |cos psi| = 1. Each branch's
    F(z) (see ``_p_branch_residual``) is sampled at ``samples`` points and every sign change bisected; the
    samples around each local minimum of |F| below 1 % of max |F| are added as candidates, so that a pair of roots
    closer than the sample step (next to a forward singularity) still gets a start for the Newton polish, and so
    do both ends. z > 0 only.
    """
    g, h, c, e = geom
    q = np.asarray(q, dtype=float)
    s = 0.5 * (q[0] ** 2 + q[1] ** 2)
    t_lo = max((c - q[2]) ** 2 - e * e, s - (g + h) ** 2, 0.0)
    t_hi = min((c + q[2]) ** 2 - e * e, s - (g - h) ** 2)
    if not t_hi > t_lo:
        return np.zeros((0, 3))
    zs = np.linspace(math.sqrt(t_lo), math.sqrt(t_hi), samples)
    z_out, th_out = [], []
    for branch in (1.0, -1.0):
        f, theta = _p_branch_residual(geom, q, zs, branch)
        # the ends are candidates too: with q1 = q2 (D = 0, psi = 0) the root sits where |cos psi| = 1, and F
        # touches zero there without changing sign
        z_out.extend(zs[[0, -1]])
        th_out.extend(theta[[0, -1]])
        # a pair of roots closer than the sample step shows as a local minimum of |F| without a sign change:
        # its neighbourhood goes to the Newton polish as extra candidates
        af = np.abs(f)
        small = af[1:-1] <= 1e-2 * af.max()
        dip = np.nonzero(small & (af[1:-1] < af[:-2]) & (af[1:-1] < af[2:]))[0] + 1
        for k in dip:
            near = zs[max(k - 1, 0) : k + 2]
            _, theta = _p_branch_residual(geom, q, near, branch)
            z_out.extend(near)
            th_out.extend(theta)
        idx = np.nonzero(np.sign(f[:-1]) * np.sign(f[1:]) <= 0.0)[0]
        if idx.size == 0:
            continue
        lo, hi = zs[idx], zs[idx + 1]
        f_lo = f[idx]
        for _ in range(80):  # bisection to round-off, all brackets at once
            mid = 0.5 * (lo + hi)
            f_mid, _ = _p_branch_residual(geom, q, mid, branch)
            left = np.sign(f_mid) * np.sign(f_lo) <= 0.0
            hi = np.where(left, mid, hi)
            lo = np.where(left, lo, mid)
            f_lo = np.where(left, f_lo, f_mid)
        root = 0.5 * (lo + hi)
        _, theta = _p_branch_residual(geom, q, root, branch)
        z_out.extend(root)
        th_out.extend(theta)
    z_arr, th_arr = np.array(z_out), np.array(th_out)
    keep = z_arr > 0.0
    return _p_angles(geom, q, z_arr[keep], np.cos(th_arr[keep]), np.sin(th_arr[keep]))


def fk_p_candidates(geom: tuple, q) -> np.ndarray:
    """Unpolished P-model FK candidates: the quartic for e = 0, root bracketing otherwise."""
    return fk_p_quartic(geom, q) if geom[3] == 0.0 else fk_p_bracket(geom, q)


def _newton(geom: tuple, model: str, variant: str, q: np.ndarray, x0: np.ndarray, iters: int = 60):
    """Newton with step halving, x <- x - alpha (dq/dx)^+ (q(x) - q), on all starts at once (spec §0).

    The Newton step is a descent direction of |q(x) - q|_2^2, so a halved step is taken as soon as it lowers that
    sum. A start stops when max|q(x) - q| <= 1e-13 max(1, q), or when no step down to 2^-12 lowers the sum (a root
    to round-off, or a local minimum that is no root). Returns (x (n, 3), max|q(x) - q| (n,) in mm); degenerate
    poses get inf.
    """
    x = np.array(x0, dtype=float).reshape(-1, 3)
    tight = 1e-13 * max(1.0, float(np.max(q)))

    def evaluate(xx):
        valid, qq, jx = _legs(geom, model, variant, xx)
        with np.errstate(invalid="ignore", over="ignore"):
            err = qq - q
            merit = np.where(valid, np.einsum("ni,ni->n", err, err), np.inf)
        return np.where(np.isfinite(merit), merit, np.inf), qq, jx

    merit, qq, jx = evaluate(x)
    alive = np.isfinite(merit)
    for _ in range(iters):
        idx = np.nonzero(alive & (np.abs(qq - q).max(axis=1) > tight))[0]
        if idx.size == 0:
            break
        xa, qa = x[idx], qq[idx]
        with np.errstate(divide="ignore", invalid="ignore"):
            jac = jx[idx] / qa[:, :, None]
        jac = np.where(np.isfinite(jac), jac, 0.0)
        step = np.einsum("nij,nj->ni", np.linalg.pinv(jac), qa - q)
        alpha = np.ones(idx.size)
        pending = np.ones(idx.size, dtype=bool)
        for _ in range(13):  # step halving until the sum of squares drops
            sub = np.nonzero(pending)[0]
            trial = xa[sub] - alpha[sub, None] * step[sub]
            m_trial, q_trial, j_trial = evaluate(trial)
            better = m_trial < merit[idx[sub]]
            took = idx[sub[better]]
            x[took], merit[took], qq[took], jx[took] = trial[better], m_trial[better], q_trial[better], j_trial[better]
            pending[sub[better]] = False
            if not np.any(pending):
                break
            alpha[pending] *= 0.5
        alive[idx[pending]] = False
    with np.errstate(invalid="ignore"):
        res = np.where(np.isfinite(merit), np.abs(qq - q).max(axis=1), np.inf)
    return x, res


def _distinct(x: np.ndarray, res: np.ndarray) -> list[np.ndarray]:
    """Distinct poses (angles wrapped to (-pi, pi]), the smallest residual kept for each."""
    out: list[np.ndarray] = []
    for i in np.argsort(res, kind="stable"):
        xi = np.array([x[i, 0], *wrap_angle(x[i, 1:])])
        if all(
            abs(xi[0] - o[0]) > 1e-7 * max(1.0, abs(o[0]))
            or np.abs(wrap_angle(xi[1:] - o[1:])).max() > 1e-7
            for o in out
        ):
            out.append(xi)
    return out


def _label(sols: list[np.ndarray]) -> list[Solution]:
    """Labels '<k><a><b>': k ranks the distinct z values (1 = highest platform), a and b are the signs of cos theta
    and cos psi ('++': the platform faces up; '-+': the theta <-> pi - theta mirror of the P-model; the C-model
    also has psi <-> pi - psi branches)."""
    groups: list[list[np.ndarray]] = []
    for v in sorted(sols, key=lambda v: -v[0]):
        if groups and abs(v[0] - groups[-1][0][0]) <= 1e-7 * max(1.0, abs(groups[-1][0][0])):
            groups[-1].append(v)
        else:
            groups.append([v])
    out, used = [], set()
    for rank, group in enumerate(groups, start=1):
        for v in sorted(group, key=lambda v: (math.cos(v[1]) < 0.0, math.cos(v[2]) < 0.0)):
            label = f"{rank}{'+' if math.cos(v[1]) >= 0.0 else '-'}{'+' if math.cos(v[2]) >= 0.0 else '-'}"
            base, k = label, 2
            while label in used:
                label = f"{base}{k}"
                k += 1
            used.add(label)
            out.append(Solution(label, v))
    return out


# starts of the C-model multi-start Newton besides the P-model solutions: z as a fraction of the largest
# possible height, theta and psi spread over both mirror families (cos theta > 0 and < 0)
_C_START_Z = (0.05, 0.2, 0.4, 0.65, 0.9)
_C_START_THETA = (-1.0, 0.0, 1.0, math.pi - 1.0, math.pi, 1.0 - math.pi)
_C_START_PSI = (-0.8, 0.0, 0.8)


# default capsule radii (mm), illustrative (the paper gives no cross-sections); the tool only on rps-upu-tool
LINK_RADII = {"base": 6.0, "leg1": 5.0, "leg2": 5.0, "leg3": 5.0, "platform": 6.0}
TOOL_RADII = {**LINK_RADII, "tool": 4.0}
# stiffness (scalesynth.stiffness, docs/stiffness.md): one link group, the three legs (cylinder and rod); the
# linear actuators' stiffness default 2e4 N/mm (a small ball-screw actuator; an assumption, the paper gives none)
LINK_GROUPS = ("leg",)
ACTUATOR_STIFFNESS = 2e4
STIFFNESS_OPTIONS = stiffness_options("mm", ACTUATOR_STIFFNESS, "axial stiffness of each linear actuator (leg), N/mm "
                                      "(an assumption)", [0.0, 0.0, -150.0],
                                      "default 150 N along -z, the gravity direction (z up)")


class RpsUpu(Mechanism):
    """Seed-002 mechanism; see module docstring."""

    # the adaptive evaluator's plans (scalesynth.evaluation.plans). Node plan (psi-columns; since the z-column
    # intervals it runs only for the C-model and interference_free): no cheaper plan of a grid search (870 plans)
    # passes both design sets ((15, 8, 6, 3, beta 3.5): 0.61x on seed 0, 1.4-1.6x on seed-1 designs against N = 192),
    # so (24, 8, 5, 3, beta 3) stays (0.82x / 0.80x on seed 0; 0.56x / 0.75x on seed 1 without the design whose
    # N = 96 reference is 2.45x off N = 192's). Its workspaces are smooth and thick (the benchmark meets the
    # tolerance without z-levels or face columns)
    node_plan = ColumnPlan(24, 8, 5, 3, beta=3.0)
    # interval plan (P-model; its columns run along z, column_axis): (8, 6, 5, 2, beta 3, 2 z-levels confirmed once)
    # is within 0.77x of the tolerance against N = 192 on seeds 0-3 and N = 384 on seed 4 (N = 192 is off there) at
    # 2 988 calls per design (seed 0), 0.44x the time of (8, 8, 5, 2, beta 1, 3 z-levels), which was within 0.58x at
    # 7 186 calls: its 200 x 200 loop had reached 30 s, the goal. The psi-column node plan took 23 958. Without
    # z-levels the fields' Gauss rule along z misses the GCI (16-48 fixed z-cells: 1.1-4.4x; the LCI varies along z
    # more than the coarse cells resolve on some designs); more z-levels are not safer here (3 instead of 2: 2.02x in
    # GCI on seed 0 against N = 384), so only the searched plan is trusted (benchmarks/notes/adaptive_plans.md).
    # Inherited fields (kernels.adaptive step 3b) are not allowed by its GCI (1.19x on seed 1)
    interval_plan = ColumnPlan(8, 6, 5, 2, beta=3.0, zlevels=2, zconfirm=1)

    # ----- options, packing -------------------------------------------------------------------------------
    def check_options(self, options: dict[str, Any]) -> None:
        if options["model"] not in MODELS:
            raise InvalidParameter(f"options.model: must be 'P' or 'C', got {options['model']!r}")
        if options["c3_variant"] not in C3_VARIANTS:
            raise InvalidParameter(f"options.c3_variant: must be 'plane' or 'upu', got {options['c3_variant']!r}")
        check_stiffness_options(options, 3, LINK_GROUPS)
        self._check_limits(options)
        length = options["characteristic_length"]
        if length is not None:
            if isinstance(length, bool) or not isinstance(length, (int, float)) or not math.isfinite(length):
                raise InvalidParameter(f"options.characteristic_length: expected a number > 0 or null, got {length!r}")
            if length <= 0:
                raise InvalidParameter(f"options.characteristic_length: must be > 0, got {length:g}")
            options["characteristic_length"] = float(length)
        links.check_radius_option(options, LINK_RADII)
        links.check_flag_option(options, "interference_free")

    @staticmethod
    def _check_limits(options: dict[str, Any]) -> None:
        """Validate (in place) the stroke limits and the z / theta / psi ranges."""
        stroke = parse_range("stroke_limits", options["stroke_limits"])
        if stroke is not None and stroke[0] < 0.0:
            raise InvalidParameter(f"options.stroke_limits: leg lengths are >= 0, got lower bound {stroke[0]:g}")
        options["stroke_limits"] = stroke
        for name in ("z_range", "theta_range", "psi_range"):
            if options[name] is None:
                raise InvalidParameter(f"options.{name}: required [lo, hi] (the workspace box), got null")
            options[name] = parse_range(name, options[name])

    def characteristic_length(self, design: Mapping[str, float], options: Mapping[str, Any]) -> float:
        """L (mm) dividing the angle columns of dq/d(z, theta, psi); default h, the platform half-width."""
        length = options.get("characteristic_length")
        return float(design["h"]) if length is None else float(length)

    def pack(self, design: Mapping[str, float], options: Mapping[str, Any]) -> np.ndarray:
        p = np.empty(N_PACKED)
        p[_G], p[_H], p[_C], p[_E] = design["g"], design["h"], design["c"], design["e"]
        p[_MODEL_C] = 1.0 if options["model"] == "C" else 0.0
        p[_UPU] = 1.0 if options["c3_variant"] == "upu" else 0.0
        stroke = options.get("stroke_limits")
        p[_QLO], p[_QHI] = stroke if stroke is not None else (-math.inf, math.inf)
        p[_INV_L] = 1.0 / self.characteristic_length(design, options)
        rad = links.radii(options, LINK_RADII)
        p[_RAD : _RAD + 5] = [rad[body] for body in LINK_RADII]
        p[_FREE_ONLY] = 1.0 if options.get("interference_free") else 0.0
        sec = tube_section(options, "leg", "mm")
        p[_EA], p[_EI], p[_GJ] = sec.EA, sec.EI, sec.GJ
        p[_CK] = 1.0 / options["actuator_stiffness"]
        p[_FX : _FX + 3] = options["load"]
        return p

    @property
    def field_kernel(self):
        return point_fields

    @property
    def reach_kernel(self):
        return point_reach

    @property
    def lci_kernel(self):
        return lci_fields

    @property
    def interval_kernel(self):
        """_p_column_intervals(p, theta, psi, zlo, zhi, out) -> k: the reachable intervals of a z-column (column_axis
        0) of the P-model in closed form (-1 for the C-model or with interference_free)."""
        return _p_column_intervals

    def interval_kernel_for(self, options):
        """The interval kernel for the P-model without interference_free, else None (the C-model's legs are not
        quadratics in z, and with interference_free the clearance decides reachability too)."""
        return None if options["model"] == "C" or options.get("interference_free") else _p_column_intervals

    def column_axis(self, options) -> int:
        """z (axis 0) where the interval kernel applies (the P-model's closed-form z-columns), else psi (2)."""
        return 0 if self.interval_kernel_for(options) is not None else 2

    def column_order_kernel(self, kernel, options):
        """The field, LCI or reach kernel with task coordinates in column order: (theta, psi, z) on z-columns."""
        if self.column_axis(options) == 2:
            return kernel
        return {point_fields: z_column_point_fields, lci_fields: z_column_lci_fields,
                point_reach: z_column_point_reach}[kernel]

    def kernel_branch(self, options) -> str:
        return BRANCH

    def mirror_axes(self, options) -> tuple[int, ...]:
        """psi (axis 2): the pose at -psi is the mirror image in y = 0 of the pose at psi (legs 1 and 2 swap; both
        models and chain-3 variants: the yaw and y0 change sign), so with equal leg-1 and leg-2 radii and no load along
        y every field is symmetric."""
        if links.mirrored_radii(options, LINK_RADII, [("leg1", "leg2")]) and options["load"][1] == 0.0:
            return (2,)
        return ()

    def bounding_box(self, design, options):
        """The configured workspace box (z_range, theta_range, psi_range), in mm and rad (spec §2.8)."""
        lo = np.array([options["z_range"][0], options["theta_range"][0], options["psi_range"][0]], dtype=float)
        hi = np.array([options["z_range"][1], options["theta_range"][1], options["psi_range"][1]], dtype=float)
        return lo, hi

    # ----- helpers ------------------------------------------------------------------------------------------
    @staticmethod
    def _geom(design) -> tuple[float, float, float, float]:
        return float(design["g"]), float(design["h"]), float(design["c"]), float(design["e"])

    def platform_pose(self, design, options, pose) -> dict[str, Any]:
        """Platform origin p (mm), rotation R, parasitic yaw phi (rad) and y0 (mm) of a task pose (z, theta, psi).

        In the P-model phi = y0 = 0. Raises InvalidPose where the C-model parametrisation is degenerate.
        """
        x = self.check_vector("pose", pose, 3)
        valid, p, R, phi, _ = _platform(self._geom(design), options["model"], options["c3_variant"], x[None])
        if not valid[0]:
            raise InvalidPose(f"pose: the C-model yaw or y0 is undefined at {list(map(float, x))}")
        return {"p": p[0], "R": R[0], "phi": float(phi[0]), "y0": float(p[0, 1])}

    # ----- IK ---------------------------------------------------------------------------------------------
    def inverse_kinematics(self, design, options, pose) -> list[Solution]:
        """The single IK branch '+++' (q1, q2, q3) in mm, q_i = |A_i B_i| (spec §2.3), for the configured model;
        [] where the C-model parametrisation is degenerate. Stroke limits are not applied here (see the kernel)."""
        x = self.check_vector("pose", pose, 3)
        valid, q, _ = _legs(self._geom(design), options["model"], options["c3_variant"], x[None])
        if not valid[0]:
            return []
        return [Solution(BRANCH, q[0])]

    # ----- FK ---------------------------------------------------------------------------------------------
    def forward_kinematics(self, design, options, inputs) -> list[Solution]:
        """All assembly modes (z, theta, psi) with z > 0 of leg lengths q (mm), polished by Newton to
        max|q(x) - q| ~ 1e-13 q (spec §2.4). Each solution (z, theta, psi) of the P-model has a mirror image
        (-z, -theta, -psi) through the base plane, not listed.

        P-model: closed form (quartic in z^2) for e = 0, root bracketing in z otherwise; all real branches,
        including the theta <-> pi - theta mirror. C-model: Newton from the P-model solutions and a fixed grid of
        starts; distinct converged branches are reported (a multi-start search, so branches far from every
        start can be missed). Labels: see ``_label``.
        """
        q = self.check_vector("inputs", inputs, 3)
        if np.any(q < 0.0):
            raise InvalidPose(f"inputs: leg lengths must be >= 0 mm, got {list(map(float, q))}")
        geom = self._geom(design)
        model, variant = options["model"], options["c3_variant"]
        starts = fk_p_candidates(geom, q)
        if model == "C":
            z_top = float(q.max()) + max(geom[:3]) + abs(geom[3])
            grid = np.array(
                [(f * z_top, t, p) for f in _C_START_Z for t in _C_START_THETA for p in _C_START_PSI], dtype=float
            )
            starts = np.vstack([starts, grid])
        if starts.shape[0] == 0:
            return []
        tol = 1e-9 * max(1.0, float(q.max()))
        x, res = _newton(geom, model, variant, q, starts)
        accept = np.isfinite(res) & (res <= tol) & (x[:, 0] > 0.0)
        if model == "C" and np.any(accept):
            # second pass from the mirror images of the branches found (theta -> pi - theta, psi -> pi - psi):
            # exact symmetries for e = 0, good starts for the nearby branches otherwise
            found = x[accept]
            z, th, ps = found[:, 0], found[:, 1], found[:, 2]
            images = np.vstack([np.stack([z, np.pi - th, -ps], -1), np.stack([z, th, np.pi - ps], -1),
                                np.stack([z, np.pi - th, ps - np.pi], -1)])
            x2, res2 = _newton(geom, model, variant, q, images)
            x, res = np.vstack([x, x2]), np.concatenate([res, res2])
            accept = np.isfinite(res) & (res <= tol) & (x[:, 0] > 0.0)
        return _label(_distinct(x[accept], res[accept]))

    # ----- Jacobians, LCI, singularities -----------------------------------------------------------------
    def jacobians(self, design, options, pose, q) -> dict[str, np.ndarray | None]:
        """Jacobians at a pose with leg lengths q (mm), from the twist form composed with T (spec §2.5):

        Jx (rows q_i dq_i/d(z, theta, psi), mm^2 and mm^2/rad), Jq = diag(q) (mm), dq_dx = Jq^-1 Jx (the spec's
        dq/d(z, theta, psi)), dq_dx_h (dq_dx with its angle columns divided by L, dimensionless) and the forward
        Jacobian J = Jx^-1 Jq = d(z, theta, psi)/dq (None at a forward or inverse singularity).
        """
        x = self.check_vector("pose", pose, 3)
        qv = self.check_vector("inputs", q, 3)
        valid, _, jx = _legs(self._geom(design), options["model"], options["c3_variant"], x[None])
        if not valid[0]:
            raise InvalidPose(f"pose: the C-model yaw or y0 is undefined at {list(map(float, x))}")
        jx = jx[0]
        jq = np.diag(qv)
        dq_dx = dq_dx_h = j = None
        if np.all(qv > 0.0):
            dq_dx = jx / qv[:, None]
            length = self.characteristic_length(design, options)
            dq_dx_h = dq_dx / np.array([1.0, length, length])
            try:
                j = np.linalg.solve(jx, jq)
            except np.linalg.LinAlgError:
                j = None
        return {"Jx": jx, "Jq": jq, "dq_dx": dq_dx, "dq_dx_h": dq_dx_h, "J": j}

    def lci(self, design, options, pose, q) -> float:
        """LCI = sigma_min / sigma_max of dq/d(z, L theta, L psi) with NumPy's SVD (0 at any singularity)."""
        jac = self.jacobians(design, options, pose, q)
        if jac["dq_dx_h"] is None:
            return 0.0
        return svd_lci(jac["dq_dx_h"])

    def singularity(self, design, options, pose, q, tol: float = 1e-7) -> str:
        """'inverse' when a leg length q_i <= tol (g + h + c), 'forward' when the rows of Jx, each normalised and
        with the angle columns divided by L, have sigma_min / sigma_max <= tol; 'both' or 'none'."""
        jac = self.jacobians(design, options, pose, q)
        g, h, c, _ = self._geom(design)
        inverse = bool(np.any(jac["Jq"].diagonal() <= tol * (g + h + c)))
        length = self.characteristic_length(design, options)
        rows = jac["Jx"] / np.array([1.0, length, length])
        norms = np.linalg.norm(rows, axis=1)
        if np.any(norms == 0.0):
            forward = True
        else:
            sv = np.linalg.svd(rows / norms[:, None], compute_uv=False)
            forward = bool(sv[-1] <= tol * sv[0])
        return singularity_label(inverse, forward)

    # ----- link geometry, velocity map (scalesynth.cycle) ----------------------------------------------------
    def _joint_points(self, design, options, pose) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Base joints A_i (3, 3), platform joints B_i = p + R b_i' (3, 3), platform origin p and R at a pose."""
        x = self.check_vector("pose", pose, 3)
        g, h, c, e = self._geom(design)
        valid, p, R, _, _ = _platform(self._geom(design), options["model"], options["c3_variant"], x[None])
        if not valid[0]:
            raise InvalidPose(f"pose: the C-model yaw or y0 is undefined at {list(map(float, x))}")
        a = np.array([[0.0, -g, 0.0], [0.0, g, 0.0], [e, 0.0, 0.0]])
        b = np.array([[0.0, -h, 0.0], [0.0, h, 0.0], [c, 0.0, 0.0]])
        return a, p[0] + b @ R[0].T, p[0], R[0]

    def _capsules(self, design, options, pose, radii):
        a, b, _, _ = self._joint_points(design, options, pose)
        sides = ((1, 2), (2, 3), (3, 1))
        segs = [links.Segment(f"base{i}{j}", "base", a[i - 1], a[j - 1], radii["base"]) for i, j in sides]
        segs += [links.Segment(f"leg{i}", f"leg{i}", a[i - 1], b[i - 1], radii[f"leg{i}"]) for i in (1, 2, 3)]
        segs += [links.Segment(f"platform{i}{j}", "platform", b[i - 1], b[j - 1], radii["platform"])
                 for i, j in sides]
        adjacent = [("base", f"leg{i}") for i in (1, 2, 3)] + [(f"leg{i}", "platform") for i in (1, 2, 3)]
        return segs, adjacent

    def _capsule_ends(self, design, options, x: np.ndarray) -> list:
        """_capsules' segment endpoints at poses x (m, 3), vectorised: [(a, b)] with points (3,) or (m, 3); NaN
        rows where the C-model parametrisation is degenerate."""
        g, h, c, e = self._geom(design)
        valid, p, R, _, _ = _platform(self._geom(design), options["model"], options["c3_variant"], x)
        a = np.array([[0.0, -g, 0.0], [0.0, g, 0.0], [e, 0.0, 0.0]])
        bp = np.array([[0.0, -h, 0.0], [0.0, h, 0.0], [c, 0.0, 0.0]])
        b = p[:, None, :] + np.einsum("kj,mij->mki", bp, R)
        b[~valid] = np.nan
        b = [b[:, i] for i in range(3)]  # one object per joint (links.segment_points)
        sides = ((1, 2), (2, 3), (3, 1))
        return ([(a[i - 1], a[j - 1]) for i, j in sides] + [(a[i], b[i]) for i in range(3)]
                + [(b[i - 1], b[j - 1]) for i, j in sides])

    def link_endpoints(self, design, options, poses, q) -> np.ndarray:
        """Vectorised twin of link_geometry's segment endpoints at poses (m, 3): links.SegmentPoints, segments in
        link_geometry's order; q is not needed."""
        x = np.asarray(poses, dtype=float)
        return links.segment_points(self._capsule_ends(design, options, x), len(x))

    def link_geometry(self, design, options, pose, q) -> links.LinkGeometry:
        """Capsules (mm) at a pose (z, theta, psi): the base triangle A1 A2 A3, each leg A_i -> B_i (cylinder and
        piston as one capsule) and the platform triangle B1 B2 B3 (spec §2.2, the configured model). Adjacent:
        base-leg_i, leg_i-platform. q is not needed (the legs are the segments A_i B_i). Radii: option
        ``link_radius``, defaults LINK_RADII."""
        segs, adjacent = self._capsules(design, options, pose, links.radii(options, LINK_RADII))
        return links.LinkGeometry(tuple(segs), links.adjacency(adjacent))

    def velocity_map(self, design, options, pose, q) -> np.ndarray:
        """dq/d(z, theta, psi) (mm/mm, mm/rad), the spec's dq_dx (§2.5); infinite rows where a leg length is 0."""
        jac = self.jacobians(design, options, pose, q)
        if jac["dq_dx"] is None:
            return np.full((3, 3), np.inf)
        return jac["dq_dx"]

    def cycle_kinematics(self, design, options, poses, label: str) -> tuple[np.ndarray, np.ndarray]:
        """Vectorised twin of Mechanism.cycle_kinematics: leg lengths and dq/d(z, theta, psi) (velocity_map) at
        poses (n, 3) from the vectorised _legs; NaN rows where the branch or the C-model parametrisation fails."""
        x = np.asarray(poses, dtype=float)
        valid, q, jx = _legs(self._geom(design), options["model"], options["c3_variant"], x)
        with np.errstate(divide="ignore", invalid="ignore"):
            a = np.where(np.all(q > 0.0, axis=1)[:, None, None], jx / q[:, :, None], np.inf)
        ok = valid & (label == BRANCH)
        return np.where(ok[:, None], q, np.nan), np.where(ok[:, None, None], a, np.nan)

    def payload_point(self, design, options, pose) -> np.ndarray:
        """The cycle's payload sits at the platform origin O' = (0, y0, z) (mm; y0 = 0 in the P-model)."""
        return self._joint_points(design, options, pose)[2]

    def payload_points(self, design, options, poses) -> np.ndarray:
        """Vectorised payload_point: O' at poses (n, 3) from the vectorised _platform; NaN where the C-model
        parametrisation is degenerate."""
        valid, p, _, _, _ = _platform(self._geom(design), options["model"], options["c3_variant"],
                                      np.asarray(poses, dtype=float))
        return np.where(valid[:, None], p, np.nan)

    # ----- mobility (scalesynth.mobility) -------------------------------------------------------------------
    def topology(self, design, options):
        """Joint list of spec §2.2: chains RPS, RPS and UPU; n = 8 (base, platform, two links per chain),
        g = 9, sum f = 15, classical G-K 6(8 - 9 - 1) + 15 = 3 with no redundant constraint."""
        from scalesynth.mobility import Topology

        return Topology(
            n_links=8,
            chains=(("RPS-1", ("R", "P", "S")), ("RPS-2", ("R", "P", "S")), ("UPU", ("U", "P", "U"))),
            note="spec §2.2 (paper): classical G-K; three coplanar constraint forces. Joint screws at the "
            "C-model placement of the pose (the P-model violates the RPS joint constraints, spec §2.3)",
        )

    def joint_screws(self, design, options, pose, q=None):
        """Joint screws (omega; v) per chain at pose (z, theta, psi), fixed frame O-xyz of spec §2.1 (mm);
        ``q`` is not needed (the legs follow from the pose).

        The P-model violates the RPS joint constraints (spec §2.3: B1, B2 leave the plane x = 0), so the
        joints are placed at the constraint-consistent C-model pose with the same (z, theta, psi) and the
        configured chain-3 variant. RPS_i: revolute about x through A_i, prismatic along A_i -> B_i, S at B_i.
        UPU, variant 'upu': U at A3 about x and then the middle axis m = x x w, prismatic along the leg, U at
        B3 about m and then the platform axis w = R z. Variant 'plane' (B3 held in y = 0, spec §2.3) has no
        stated joint axes: its chain enters as the five twists reciprocal to its constraint force along y
        through B3 (a revolute about y through A3, the leg prismatic, S at B3)."""
        from scalesynth.mobility import Joint, chain_screws

        x = self.check_vector("pose", pose, 3)
        g, h, c, e = self._geom(design)
        variant = options.get("c3_variant", "plane")
        # RpsUpu's own platform_pose: a subclass (the tool workspace) pins its override to the P-model
        plat = RpsUpu.platform_pose(self, design, {**options, "model": "C", "c3_variant": variant}, x)
        rot, p = plat["R"], plat["p"]
        base = np.array([[0.0, -g, 0.0], [0.0, g, 0.0], [e, 0.0, 0.0]])
        top = p + np.array([[0.0, -h, 0.0], [0.0, h, 0.0], [c, 0.0, 0.0]]) @ rot.T
        xhat = np.array([1.0, 0.0, 0.0])
        chains = []
        for i in (0, 1):
            leg_i = Joint("P", axes=(top[i] - base[i],))
            chains.append(chain_screws([Joint("R", base[i], (xhat,)), leg_i, Joint("S", top[i])]))
        leg = Joint("P", axes=(top[2] - base[2],))
        if variant == "upu":
            w = rot[:, 2]
            m = np.cross(xhat, w)
            chains.append(chain_screws([Joint("U", base[2], (xhat, m)), leg, Joint("U", top[2], (m, w))]))
        else:
            chains.append(chain_screws([Joint("R", base[2], ((0.0, 1.0, 0.0),)), leg, Joint("S", top[2])]))
        return chains

    # ----- stiffness (scalesynth.stiffness; pose level) ------------------------------------------------------
    def _in_box(self, options, x) -> bool:
        return all(options[name][0] <= v <= options[name][1]
                   for name, v in zip(("z_range", "theta_range", "psi_range"), x, strict=True))

    def _stiffness_placement(self, design, options, pose) -> tuple[np.ndarray, str, np.ndarray]:
        """(z, theta, psi) of the constraint-consistent (C-model) frame, its chain-3 variant and the platform
        reference point (O'); raises InvalidPose outside the workspace box or the configured model's workspace.
        The frame's own legs may leave the stroke limits (a P-model pose whose placement differs): the model's
        notes say so, and the per-voxel fields use the same frame (docs/stiffness.md)."""
        x = self.check_vector("pose", pose, 3)
        variant = options["c3_variant"]
        c_opts = {**options, "model": "C"}
        if not self._in_box(options, x) or self.point_kernel(self.pack(design, options), *x) < 0.0:
            raise InvalidPose(f"pose: ({', '.join(f'{v:g}' for v in x)}) is outside the workspace (box and stroke "
                              f"limits of the {options['model']}-model)")
        return x, variant, RpsUpu.platform_pose(self, design, c_opts, x)["p"]

    def stiffness_model(self, design, options, pose, joints: str = "ideal"):
        """Frame model (scalesynth.stiffness.FrameModel, spatial, mm, N) at a pose (z, theta, psi) of the
        constraint-consistent placement (the C-model with the configured chain-3 variant: the P-model violates the
        RPS joint constraints, spec §2.3, so its joints would not assemble); raises InvalidPose outside the workspace
        box, the configured model's stroke limits or the C-model's. Joints as in joint_screws: RPS_i (revolute about
        x at A_i, a prismatic actuator spring between cylinder and rod, each half the leg, spherical at B_i); chain 3
        'plane': revolute about y at A3, prismatic actuator, spherical at B3; 'upu': universal (x, m) at A3,
        prismatic actuator, universal (m, w) at B3, m = x X w. The platform B1B2B3 is rigid, reference point O' (6
        DOFs: x, y, z and the small rotations rx, ry, rz about the fixed axes); the load is a force at O'.
        ``joints`` 'bonded' welds the passive joints."""
        x, variant, ref = self._stiffness_placement(design, options, pose)
        return self._frame(design, options, x, variant, ref, joints)

    def _frame(self, design, options, x, variant, ref, joints):
        from scalesynth.stiffness.builder import FrameBuilder, unit
        from scalesynth.stiffness.model import Body
        from scalesynth.stiffness.sections import tube_section

        g, h, c, e = self._geom(design)
        plat = RpsUpu.platform_pose(self, design, {**options, "model": "C", "c3_variant": variant}, x)
        rot, p = plat["R"], plat["p"]
        base = np.array([[0.0, -g, 0.0], [0.0, g, 0.0], [e, 0.0, 0.0]])
        top = p + np.array([[0.0, -h, 0.0], [0.0, h, 0.0], [c, 0.0, 0.0]]) @ rot.T
        k = options["actuator_stiffness"]
        fb = FrameBuilder({"leg": tube_section(options, "leg", "mm")}, joints)
        xhat, yhat = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
        w = rot[:, 2]
        m_axis = unit(np.cross(xhat, w))
        for i in range(3):
            n = i + 1
            a, b = base[i], top[i]
            mid = 0.5 * (a + b)
            fb.link(f"cylinder{n}", "leg", a, mid)
            fb.link(f"rod{n}", "leg", mid, b)
            if n < 3:
                fb.joint(f"R{n}", "revolute", a, f"cylinder{n}.a", "base", (xhat,))
            elif variant == "upu":
                fb.joint("U3_base", "universal", a, "cylinder3.a", "base", (xhat, m_axis))
            else:
                fb.joint("R3", "revolute", a, "cylinder3.a", "base", (yhat,))
            fb.joint(f"P{n}", "prismatic", mid, f"cylinder{n}.b", f"rod{n}.a", (b - a,), k)
            if n == 3 and variant == "upu":
                fb.joint("U3_platform", "universal", b, "rod3.b", "platform", (m_axis, w))
            else:
                fb.joint(f"S{n}", "spherical", b, f"rod{n}.b", "platform")
        bodies = (Body("base", np.zeros(3)), Body("platform", np.asarray(ref, float).copy()))
        notes = [f"spatial frame O-xyz of spec §2.1 (z up, mm) at the constraint-consistent (C-model, chain 3 "
                 f"'{variant}') placement of (z, theta, psi) = ({', '.join(f'{v:g}' for v in x)}): yaw phi = "
                 f"{plat['phi']:.6g} rad, y0 = {plat['y0']:.6g} mm",
                 "rigid platform B1B2B3, DOFs x, y, z, rx, ry, rz (small rotations about the fixed axes) at its "
                 "reference point; the load is a force there"]
        if options.get("model", "P") == "P":
            notes.append("the P-model violates the RPS joint constraints (spec §2.3): the frame uses the C-model "
                         "placement")
        legs = np.linalg.norm(top - base, axis=1)
        stroke = options.get("stroke_limits")
        if stroke is not None and not np.all((legs >= stroke[0]) & (legs <= stroke[1])):
            notes.append(f"the placement's leg lengths ({', '.join(f'{v:.6g}' for v in legs)}) mm leave the stroke "
                         f"limits [{stroke[0]:g}, {stroke[1]:g}]: the frame is the structure at that placement all the "
                         "same (the per-voxel fields use the same rule)")
        if not self._in_box(options, x):
            notes.append("the placement's (z, theta, psi) leaves the pose ranges: the frame is the structure at that "
                         "placement all the same (the per-voxel fields use the same rule)")
        return fb.model("mm", bodies, options["load"], notes)


DESIGN_METRICS = (
    DesignMetric(
        "link_length_sum", "{length}",
        "edges of the moving platform triangle B1B2B3: 2 h + 2 sqrt(h^2 + c^2) (the legs are the prismatic inputs, "
        "their lengths set by the stroke limits, not by the design)",
        lambda d, o: 2.0 * d["h"] + 2.0 * math.hypot(d["h"], d["c"]),
    ),
    DesignMetric(
        "footprint_radius", "{length}",
        "radius of the smallest circle in the base plane holding A1 = (0, -g), A2 = (0, g), A3 = (e, 0)",
        lambda d, o: enclosing_circle_radius([(0.0, -d["g"]), (0.0, d["g"]), (d["e"], 0.0)]),
    ),
)

def _stiffness_fields(point: str) -> tuple[Field, Field]:
    """stiffness_min and deflection (slots 4, 5) of the reference point ``point`` (docs/stiffness.md)."""
    return (
        Field("stiffness_min", "N/{length}", "smallest eigenvalue of the platform's translational stiffness at "
              f"{point} under a pure force (ideal joints, Euler-Bernoulli legs, actuator springs, at the "
              "constraint-consistent C-model placement; docs/stiffness.md)", "max"),
        Field("deflection", "{length}", f"magnitude of the deflection of {point} under options.load (default 150 N "
              "along -z); 1e12 at a singular pose", "min", (0.0, _legs_k.DEFLECTION_CAP)),
    )


FIELDS = (*base_fields("1", "J = dx/dq, x = (z, L theta, L psi) homogenised by the characteristic length L (mm/mm)"),
          links.CLEARANCE_FIELD, *_stiffness_fields("O'"))

MECHANISM = RpsUpu(
    name="rps-upu",
    title="2-RPS-UPU 2R1T parallel mechanism (seed 002)",
    seed="002",
    motion="2R1T",
    task_axes=("z", "theta", "psi"),
    task_units=("length", "angle", "angle"),
    joints=("q1", "q2", "q3"),
    joint_units=("length", "length", "length"),
    parameters=(
        Parameter("g", 80.0, "half distance A1A2 of the base (mm)"),
        Parameter("h", 50.0, "half distance B1B2 of the platform (mm)"),
        Parameter("c", 50.0, "platform offset of B3 along u (mm)"),
        Parameter("e", 0.0, "base offset of A3 along x (mm); 0 reproduces the paper's Table 2", positive=False),
    ),
    options=(
        Option("model", "P", "'P' = paper-reproducing (R = Ry Rx, O' on the z axis), 'C' = constraint-consistent"),
        Option("c3_variant", "plane", "C-model chain 3: 'plane' (B3 stays in y = 0) or 'upu' (U axes x and w)"),
        Option("stroke_limits", [40.0, 90.0], "[lo, hi] mm for all three legs, null = none (ASSUMED default: "
               "the paper gives none; [40, 90] is the Table-2 span used by spec §2.8)"),
        Option("z_range", [-10.0, 90.0], "workspace box in z (mm), the paper's"),
        Option("theta_range", [-0.314, 0.314], "workspace box in theta (rad), the paper's"),
        Option("psi_range", [-0.314, 0.314], "workspace box in psi (rad), the paper's"),
        Option("characteristic_length", None, "L (mm) dividing the angle columns of the Jacobian; null = h"),
        *STIFFNESS_OPTIONS,
        Option("link_radius", None, "capsule radius (mm) of every body, or {body: radius}; null = defaults base 6, "
               "leg1/leg2/leg3 5, platform 6 (illustrative)"),
        Option("interference_free", False, "true: a pose whose link capsules overlap (clearance < 0) is unreachable"),
    ),
    default_length_unit="mm",
    fields=FIELDS,
    design_metrics=DESIGN_METRICS,
)


# ----- optional second workspace: the tool point T = O' + R (0, 0, -d) over (x, y, z) (spec §2.8) ---------
# packed layout of the tool kernel (see RpsUpuTool.pack): the first N_PACKED entries as above, then
_D, _ZLO, _ZHI, _TLO, _THI, _PLO, _PHI, _RAD_TOOL = range(N_PACKED, N_PACKED + 8)
N_PACKED_TOOL = N_PACKED + 8


@njit(cache=True, fastmath=FASTMATH)
def _c_plane_tool(c, d, z, st, ct, sp, cp):
    """Tool point T = O' + R (0, 0, -d) of the C-model pose (z, theta, psi) with chain 3 'plane' (y0 = -c R[1, 0],
    yaw phi = atan2(sin theta sin psi, cos psi)) and its Jacobian dT/d(z, theta, psi) (rows T_x, T_y, T_z), as
    (ok, tx, ty, tz, j01, j02, j11, j12, j21, j22) (column 0 is (0, 0, 1)); ok False where the yaw is undefined."""
    ok, _, sf, cf, _, _, sf_t, sf_p, cf_t, cf_p = _yaw(st, ct, sp, cp)
    if not ok:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    y0 = -c * sf * ct
    y0_t = -c * (sf_t * ct - sf * st)
    y0_p = -c * sf_p * ct
    wx = cf * st * cp + sf * sp  # R z
    wy = sf * st * cp - cf * sp
    wz = ct * cp
    wx_t = cf_t * st * cp + cf * ct * cp + sf_t * sp
    wx_p = cf_p * st * cp - cf * st * sp + sf_p * sp + sf * cp
    wy_t = sf_t * st * cp + sf * ct * cp - cf_t * sp
    wy_p = sf_p * st * cp - sf * st * sp - cf_p * sp - cf * cp
    return (True, -d * wx, y0 - d * wy, z - d * wz, -d * wx_t, -d * wx_p, y0_t - d * wy_t, y0_p - d * wy_p,
            d * st * cp, d * ct * sp)


@njit(cache=True, fastmath=FASTMATH)
def _tool_stiffness(p, tx, ty, tz, z, th, ps):
    """(stiffness_min N/mm, deflection mm) of the tool point T under the packed load: Newton from the P-model pose
    (z, theta, psi) to the C-model pose (chain 3 'plane') that puts the tool at T (as RpsUpuTool's pose level),
    then _stiffness with T as the reference point. (0, 1e12) when Newton does not converge (the pose level
    refuses such a T) or the pose is degenerate."""
    c = p[_C]
    d = p[_D]
    tol = _TOOL_NEWTON_RTOL * (max(p[_G], p[_H], c) + d)
    for _ in range(_TOOL_NEWTON_ITERS):
        st = math.sin(th)
        ct = math.cos(th)
        sp = math.sin(ps)
        cp = math.cos(ps)
        ok, fx, fy, fz, j01, j02, j11, j12, j21, j22 = _c_plane_tool(c, d, z, st, ct, sp, cp)
        if not ok:
            return _singular_response(p)
        rx, ry, rz = fx - tx, fy - ty, fz - tz
        if max(abs(rx), abs(ry), abs(rz)) <= tol:
            _, _, sf, cf, _, _, _, _, _, _ = _yaw(st, ct, sp, cp)
            return _stiffness(p, False, -c * sf * ct, z, st, ct, sp, cp, sf, cf, tx, ty, tz)
        # J = [[0, j01, j02], [0, j11, j12], [1, j21, j22]]: the angles from the first two rows, then z
        det = j01 * j12 - j02 * j11
        if not abs(det) > 0.0:
            return _singular_response(p)
        dth = (rx * j12 - j02 * ry) / det
        dps = (j01 * ry - rx * j11) / det
        th -= dth
        ps -= dps
        z -= rz - j21 * dth - j22 * dps
    return _singular_response(p)


@njit(cache=True, fastmath=FASTMATH)
def tool_point_fields(p, x, y, z, out):
    """Every field at tool point T = (x, y, z) (see _tool_fields)."""
    _tool_fields(p, x, y, z, out, True)


@njit(cache=True, fastmath=FASTMATH)
def tool_kinematic_fields(p, x, y, z, out):
    """Slots 0-3 only (LCI, sigma_min, sigma_max, clearance), for benchmarks (the cost without stiffness)."""
    _tool_fields(p, x, y, z, out, False)


@njit(cache=True, fastmath=FASTMATH)
def tool_lci_fields(p, x, y, z, out):
    """Slot 0 of tool_point_fields alone, computed as there (the LCI or -1; with interference_free the clearance
    still decides reachability), the other slots not written: the search's kernel when it needs only the LCI's
    metrics (Mechanism.lci_kernel); no per-point Newton solve of the stiffness placement."""
    _tool_fields(p, x, y, z, out, False, True, False)


@njit(cache=True, fastmath=FASTMATH)
def tool_point_reach(p, x, y, z, out):
    """Slot 0 of tool_point_fields up to its value: >= 0 exactly where tool_point_fields' LCI is (the same branch,
    pose ranges and leg checks and, with interference_free, the same clearance), -1 elsewhere; no conditioning,
    stiffness (its per-point Newton solve) or (without interference_free) clearance. The adaptive evaluator's nodes
    and bisections (Mechanism.reach_kernel)."""
    _tool_fields(p, x, y, z, out, False, False)


@njit(cache=True, fastmath=FASTMATH)
def _tool_fields(p, x, y, z, out, stiffness, every=True, others=True):
    """LCI of dq/dT (dimensionless) at tool point T = (x, y, z) mm of the P-model, principal branch
    (cos theta > 0, cos psi > 0), or -1 when T is out of reach of that branch, its pose leaves the z/theta/psi
    ranges or a leg leaves the stroke limits.

    Pose from T (spec §2.8): sin psi = T_y/d, sin theta = -T_x/(d cos psi), z0 = T_z + d cos theta cos psi; then
    dq/dT = dq/d(z0, theta, psi) . d(z0, theta, psi)/dT with the closed-form inverse of dT/d(z0, theta, psi).
    Fields (kernels.grid contract): LCI, sigma_min, sigma_max of J = dT/dq (dimensionless); 3 clearance (mm) of the
    link capsules and the tool O' -> T (with interference_free, overlapping capsules make the pose unreachable);
    with ``stiffness``, 4 stiffness_min (N/mm) and 5 deflection (mm) of T under the packed load, on the frame at
    the C-model pose that puts the tool at T (_tool_stiffness), whether or not that pose is within the pose ranges
    and stroke limits (docs/stiffness.md). ``every`` False (a constant, tool_point_reach): slot 0 alone, 0 where
    reachable, -1 elsewhere. ``others`` False (a constant, tool_lci_fields): slot 0 alone, the LCI as with True.
    """
    d = p[_D]
    sp = y / d
    if sp > 1.0 or sp < -1.0:
        _grid.write_unreachable(out)
        return
    cp = math.sqrt(1.0 - sp * sp)
    if cp <= 1e-12:
        _grid.write_unreachable(out)  # psi = +-pi/2: theta is undetermined, the branch is not defined
        return
    st = -x / (d * cp)
    if st > 1.0 or st < -1.0:
        _grid.write_unreachable(out)
        return
    ct = math.sqrt(1.0 - st * st)
    z0 = z + d * ct * cp
    th = math.asin(st)
    ps = math.asin(sp)
    if not (p[_ZLO] <= z0 <= p[_ZHI] and p[_TLO] <= th <= p[_THI] and p[_PLO] <= ps <= p[_PHI]):
        _grid.write_unreachable(out)
        return
    _, q1s, q2s, q3s, a11, a12, a13, a21, a22, a23, a31, a32, a33 = _p_model_rows(
        p[_G], p[_H], p[_C], p[_E], z0, st, ct, sp, cp
    )
    lo = p[_QLO]
    hi = p[_QHI]
    ok1, q1 = _leg_ok(q1s, lo, hi)
    ok2, q2 = _leg_ok(q2s, lo, hi)
    ok3, q3 = _leg_ok(q3s, lo, hi)
    if not (ok1 and ok2 and ok3):
        _grid.write_unreachable(out)
        return
    if not every:
        out[0] = 0.0
        if p[_FREE_ONLY] > 0.0 and _clearance(p, 0.0, z0, st, ct, sp, cp, 0.0, 1.0, _PAIRS_TOOL, x, y, z,
                                              p[_RAD_TOOL]) < 0.0:
            out[0] = -1.0
        return
    gap = 0.0
    if others or p[_FREE_ONLY] > 0.0:
        gap = _clearance(p, 0.0, z0, st, ct, sp, cp, 0.0, 1.0, _PAIRS_TOOL, x, y, z, p[_RAD_TOOL])
        if gap < 0.0 and p[_FREE_ONLY] > 0.0:
            _grid.write_unreachable(out)
            return
    if q1 == 0.0 or q2 == 0.0 or q3 == 0.0 or ct <= 1e-12:
        _grid.write_singular(out)  # a zero leg (inverse singularity) or cos theta = 0 (T no longer fixes theta)
        if not others:
            return
        out[_F_CLEARANCE] = gap
        if stiffness:
            out[_F_STIFFNESS_MIN], out[_F_DEFLECTION] = _tool_stiffness(p, x, y, z, z0, th, ps)
        return
    # d(z0, theta, psi)/dT, rows z0, theta, psi; columns T_x, T_y, T_z
    inv = 1.0 / (d * ct * cp)
    m11 = st / ct
    m12 = -sp / (ct * cp)
    m21 = -inv
    m22 = st * sp * inv / cp
    m32 = 1.0 / (d * cp)
    # row i of dq/dT = (q_i dq_i/dx) M / q_i
    i1 = 1.0 / q1
    i2 = 1.0 / q2
    i3 = 1.0 / q3
    lci, smin, smax = sv_3x3(
        (a11 * m11 + a12 * m21) * i1, (a11 * m12 + a12 * m22 + a13 * m32) * i1, a11 * i1,
        (a21 * m11 + a22 * m21) * i2, (a21 * m12 + a22 * m22 + a23 * m32) * i2, a21 * i2,
        (a31 * m11 + a32 * m21) * i3, (a31 * m12 + a32 * m22 + a33 * m32) * i3, a31 * i3,
    )  # fmt: skip
    out[0] = lci
    if not others:
        return
    out[1], out[2] = inverse_singular_values(smin, smax)
    out[_F_CLEARANCE] = gap
    if stiffness:
        out[_F_STIFFNESS_MIN], out[_F_DEFLECTION] = _tool_stiffness(p, x, y, z, z0, th, ps)


# ----- reachable intervals of a z-column of the tool workspace (closed form) ------------------------------
@njit(cache=True, fastmath=FASTMATH)
def _monic_roots(b, c):
    """(real, r1, r2): the roots r1 <= r2 of z^2 + 2 b z + c, the larger-magnitude one first and the other as
    c / it (no cancellation); real False when there are none."""
    disc = b * b - c
    if not disc >= 0.0:
        return False, 0.0, 0.0
    t = -b - math.sqrt(disc) if b >= 0.0 else -b + math.sqrt(disc)
    if t == 0.0:
        return True, 0.0, 0.0  # b = c = 0: a double root at 0
    r = c / t
    return True, min(t, r), max(t, r)


@njit(cache=True, fastmath=FASTMATH)
def _leg_window(b, c, lo, hi, shift, lower, upper):
    """One leg whose squared length is z0^2 + 2 b z0 + c (mm^2) at platform height z0 = z + shift (mm), stroke
    [lo, hi] (mm, +-inf = no limit), as _leg_ok decides it: (lower, upper, ex_lo, ex_hi), the window
    [lower, upper] on the tool height z narrowed to q <= hi (lower > upper when empty) and the open interval
    (ex_lo, ex_hi) of z where q < lo ((inf, inf) when none)."""
    if hi < math.inf:
        if hi < 0.0:
            return math.inf, -math.inf, math.inf, math.inf  # q >= 0 > hi everywhere
        real, r1, r2 = _monic_roots(b, c - hi * hi)
        if not real:
            return math.inf, -math.inf, math.inf, math.inf  # the leg is longer than hi on the whole column
        lower = max(lower, r1 - shift)
        upper = min(upper, r2 - shift)
    if lo > 0.0:  # lo <= 0 holds for every q >= 0 (the kernel clamps round-off q^2 < 0 to q = 0)
        real, s1, s2 = _monic_roots(b, c - lo * lo)
        if real and s1 - shift < s2 - shift:  # the roots themselves have q = lo: reachable, the interval is open
            return lower, upper, s1 - shift, s2 - shift
    return lower, upper, math.inf, math.inf


@njit(cache=True, fastmath=FASTMATH)
def _tool_column_intervals(p, x, y, zlo, zhi, out):
    """Reachable set of the column (x, y, z in [zlo, zhi]) of the tool workspace (mm) in closed form: writes its
    closed intervals [out[i, 0], out[i, 1]] (mm, i < k, sorted, disjoint, inside [zlo, zhi]; a degenerate
    [a, a] is a single reachable height) into out (float64, (K, 2)) and returns k >= 0: z is in one exactly where
    tool_point_reach(p, x, y, z) >= 0, to rounding at the ends. -1 (out undefined) when reachability is not in
    closed form (interference_free: the clearance decides too) or out has fewer rows than the column needs (4 at
    most: the z-range window minus one open interval per leg where it is shorter than its lower stroke limit).

    Along the column the pose's angles are fixed (sin psi = y / d, sin theta = -x / (d cos psi), computed and
    checked as in _tool_fields) and z0 = z + d cos theta cos psi, so each squared leg length is a monic quadratic
    in z0 (_p_model_rows) and every condition is an interval or the complement of an open one."""
    if p[_FREE_ONLY] > 0.0:
        return -1
    # the column's pose angles and their checks, as _tool_fields computes them
    d = p[_D]
    sp = y / d
    if not (-1.0 <= sp <= 1.0) or not zlo <= zhi:  # also NaN
        return 0
    cp = math.sqrt(1.0 - sp * sp)
    if cp <= 1e-12:
        return 0
    st = -x / (d * cp)
    if not -1.0 <= st <= 1.0:
        return 0
    ct = math.sqrt(1.0 - st * st)
    if not (p[_TLO] <= math.asin(st) <= p[_THI] and p[_PLO] <= math.asin(sp) <= p[_PHI]):
        return 0
    shift = d * ct * cp  # z0 - z (mm)
    g, h, c, e = p[_G], p[_H], p[_C], p[_E]
    lo, hi = p[_QLO], p[_QHI]
    # q1^2, q2^2 = z0^2 -+ 2 h cos(theta) sin(psi) z0 + g^2 + h^2 - 2 g h cos(psi); q3^2 = z0^2 - 2 c sin(theta) z0
    # + c^2 + e^2 - 2 c e cos(theta) (_p_model_rows)
    lower = max(zlo, p[_ZLO] - shift)
    upper = min(zhi, p[_ZHI] - shift)
    c12 = g * g + h * h - 2.0 * g * h * cp
    lower, upper, a1, b1 = _leg_window(-h * ct * sp, c12, lo, hi, shift, lower, upper)
    lower, upper, a2, b2 = _leg_window(h * ct * sp, c12, lo, hi, shift, lower, upper)
    lower, upper, a3, b3 = _leg_window(-c * st, c * c + e * e - 2.0 * c * e * ct, lo, hi, shift, lower, upper)
    if not lower <= upper:
        return 0
    return _sweep_window(lower, upper, a1, b1, a2, b2, a3, b3, out)


@njit(cache=True, fastmath=FASTMATH)
def _sweep_window(lower, upper, a1, b1, a2, b2, a3, b3, out):
    """The window [lower, upper] minus the open intervals (a_i, b_i) ((inf, inf): none) as sorted closed intervals
    in out[:k]; returns k, or -1 when out has too few rows."""
    # sort the three excluded open intervals by their start (none: (inf, inf), last), then sweep the window
    if a2 < a1:
        a1, b1, a2, b2 = a2, b2, a1, b1
    if a3 < a2:
        a2, b2, a3, b3 = a3, b3, a2, b2
    if a2 < a1:
        a1, b1, a2, b2 = a2, b2, a1, b1
    k = 0
    cur = lower  # start of the reachable piece being built
    for a, b in ((a1, b1), (a2, b2), (a3, b3)):
        if a >= upper:
            break  # this and the later exclusions start past the window (an end a = upper is itself reachable)
        if b <= cur:
            continue
        if a >= cur:
            if k == out.shape[0]:
                return -1
            out[k, 0] = cur
            out[k, 1] = a
            k += 1
        cur = b
    if cur <= upper:
        if k == out.shape[0]:
            return -1
        out[k, 0] = cur
        out[k, 1] = upper
        k += 1
    return k


# ----- z-columns of the P-model workspace: kernels in column order (theta, psi, z), closed-form intervals -----------
# RpsUpu.column_axis is z (axis 0) where its interval kernel applies: at fixed (theta, psi) the platform orientation
# is fixed and each squared leg length a monic quadratic in z, so a z-column's reachable set comes in closed form. The
# adaptive evaluator passes task coordinates in column order (Mechanism.column_order_kernel): these wrappers call
# point_fields, lci_fields and point_reach with the coordinates put back in task order (calls, not the inlined
# _fields: with _fields inlined into the wrapper the search's columns ran 1.6x slower, measured on 20 designs)
@njit(cache=True, fastmath=FASTMATH)
def z_column_point_fields(p, theta, psi, z, out):
    """point_fields(p, z, theta, psi, out): every field, task coordinates in z-column order."""
    point_fields(p, z, theta, psi, out)


@njit(cache=True, fastmath=FASTMATH)
def z_column_lci_fields(p, theta, psi, z, out):
    """lci_fields(p, z, theta, psi, out): slot 0 alone, task coordinates in z-column order."""
    lci_fields(p, z, theta, psi, out)


@njit(cache=True, fastmath=FASTMATH)
def z_column_point_reach(p, theta, psi, z, out):
    """point_reach(p, z, theta, psi, out): reachability alone, task coordinates in z-column order."""
    point_reach(p, z, theta, psi, out)


@njit(cache=True, fastmath=FASTMATH)
def _p_column_intervals(p, theta, psi, zlo, zhi, out):
    """Reachable set of the z-column (z in [zlo, zhi] mm, theta, psi rad) of the P-model workspace in closed form:
    writes its closed intervals [out[i, 0], out[i, 1]] (mm, i < k, sorted, disjoint, inside [zlo, zhi]) into out
    (float64, (K, 2)) and returns k >= 0: z is in one exactly where point_reach(p, z, theta, psi) >= 0, to rounding
    at the ends. -1 (out undefined) for the C-model or with interference_free (reachability not in closed form), or
    when out has fewer rows than the column needs (4 at most: [zlo, zhi] minus one open interval per leg where it is
    shorter than its lower stroke limit).

    q1^2, q2^2 = z^2 -+ 2 h cos(theta) sin(psi) z + g^2 + h^2 - 2 g h cos(psi); q3^2 = z^2 - 2 c sin(theta) z + c^2
    + e^2 - 2 c e cos(theta) (_p_model_rows): each leg's stroke [lo, hi] is a window of z minus an open interval
    (_leg_window, as for the tool's columns with shift 0)."""
    if p[_FREE_ONLY] > 0.0 or p[_MODEL_C] > 0.0:
        return -1
    if not zlo <= zhi:  # also NaN
        return 0
    st = math.sin(theta)
    ct = math.cos(theta)
    sp = math.sin(psi)
    cp = math.cos(psi)
    g, h, c, e = p[_G], p[_H], p[_C], p[_E]
    lo, hi = p[_QLO], p[_QHI]
    c12 = g * g + h * h - 2.0 * g * h * cp
    lower, upper, a1, b1 = _leg_window(-h * ct * sp, c12, lo, hi, 0.0, zlo, zhi)
    lower, upper, a2, b2 = _leg_window(h * ct * sp, c12, lo, hi, 0.0, lower, upper)
    lower, upper, a3, b3 = _leg_window(-c * st, c * c + e * e - 2.0 * c * e * ct, lo, hi, 0.0, lower, upper)
    if not lower <= upper:
        return 0
    return _sweep_window(lower, upper, a1, b1, a2, b2, a3, b3, out)


def _sin_cos_range(lo: float, hi: float) -> tuple[tuple[float, float], tuple[float, float]]:
    """([min, max] of sin, [min, max] of cos) over the angle interval [lo, hi]: the ends and every multiple of
    pi/2 inside."""
    if hi - lo >= 2 * math.pi:  # a whole turn: both reach [-1, 1] (and a wide range must not list its multiples)
        return (-1.0, 1.0), (-1.0, 1.0)
    pts = [lo, hi] + [k * math.pi / 2 for k in range(math.ceil(lo / (math.pi / 2)), math.floor(hi / (math.pi / 2)) + 1)]
    s = [math.sin(a) for a in pts]
    c = [math.cos(a) for a in pts]
    return (min(s), max(s)), (min(c), max(c))


def _interval_product(a: tuple[float, float], b: tuple[float, float]) -> tuple[float, float]:
    corners = [a[0] * b[0], a[0] * b[1], a[1] * b[0], a[1] * b[1]]
    return min(corners), max(corners)


class RpsUpuTool(RpsUpu):
    """Position workspace of the tool point T = O' + R (0, 0, -d) of the P-model (spec §2.8), task axes (x, y, z).

    The pose ranges (z_range of O', theta_range, psi_range) act as limits on the pose that places T; the kernel
    uses the principal branch (cos theta > 0, cos psi > 0). The Jacobian dq/dT is in mm/mm, so the LCI needs no
    characteristic length. Only the P-model has the closed-form inverse, so there is no ``model`` option.
    """

    # node plan (with interference_free; else the interval plan): from benchmarks/plan_search.py's 1926 plans (LCI
    # kernel; benchmarks/notes/adaptive_plans.md), the one with the widest margin against the better reference
    # N = 192 (N = 96 is 0.2-0.6x the volume tolerance off it on most designs) among the cheap ones: 10 x 10 columns
    # of 8 z-cells (up to 3 doublings, confirmed twice), 5 bisections, 2 levels, face columns: 122 299 calls/design,
    # 4.4x fewer than the 3-D default's 533 892. Errors x tolerance (volume, GCI) against N = 192, seeds 0 / 1 / 2:
    # 0.50, 0.73 / 0.46, 0.47 / 0.43, 0.40. The cheapest plan passing the rule, (12, 12, 4, 2, beta 1, 2 z-levels
    # confirmed once): 93 874 calls, but 0.80x in GCI on seed 1. Both are more accurate at 2 levels than at 3
    # (0.82-1.02x: a third level refines part of the boundary and loses a cancellation), so the margin, not the level
    # count, is the safety here. Their own estimates stop above the tolerance (the reported error_volume is
    # conservative, up to 4.6x, as ups-sspr's). Without face columns or z-levels no plan passes seed 0 (the task
    # box's wall and thin slabs)
    node_plan = ColumnPlan(10, 8, 5, 2, beta=1.0, zlevels=3, zconfirm=2, faces=True)
    # interval plan (columns in closed form: no z-levels needed to find thin shells; the z-cells only serve the Gauss
    # rule of the fields): benchmarks/plan_search.py's 14 plans against N = 192 on seeds 0, 1, 2
    # (benchmarks/notes/adaptive_plans.md): (10, 16, 5, 2, beta 1, faces) is within 0.60x (volume) and 0.52x (GCI) of
    # the tolerance on all three at 7 320 calls per design, against its node plan's 19 512 (with intervals) or 61 150
    # (without); 8 columns or 12 z-cells miss (8.5x the volume tolerance on a seed-0 design; 1.65x in GCI), and 8
    # z-cells with no z-levels are 12x off in GCI (the fields' Gauss rule needs the 16). With inherited fields
    # (kernels.adaptive step 3b) on the same plan: 3 132 calls per design against 7 320, 0.43x the time
    # (plan_search.py --ab), with the same worst errors against N = 192 on seeds 0-4 (volume 0.60 / 0.91x, GCI
    # 0.50 / 0.46x; before 0.60 / 0.91x, 0.52 / 0.62x)
    interval_plan = ColumnPlan(10, 16, 5, 2, beta=1.0, faces=True, field_levels=0)

    def check_options(self, options: dict[str, Any]) -> None:
        self._check_limits(options)
        check_stiffness_options(options, 3, LINK_GROUPS)
        d = options["tool_offset"]
        if isinstance(d, bool) or not isinstance(d, (int, float)) or not math.isfinite(d) or d <= 0:
            raise InvalidParameter(f"options.tool_offset: expected a length > 0 (mm), got {d!r}")
        options["tool_offset"] = float(d)
        links.check_radius_option(options, TOOL_RADII)
        links.check_flag_option(options, "interference_free")

    @staticmethod
    def _p(options: Mapping[str, Any]) -> dict[str, Any]:
        """The options with the P-model settings that the inherited (z, theta, psi) kinematics read."""
        return {**options, "model": "P", "c3_variant": "plane", "characteristic_length": None}

    def pack(self, design: Mapping[str, float], options: Mapping[str, Any]) -> np.ndarray:
        p = np.empty(N_PACKED_TOOL)
        p[:N_PACKED] = super().pack(design, self._p(options))
        p[_RAD_TOOL] = links.radii(options, TOOL_RADII)["tool"]
        p[_D] = options["tool_offset"]
        p[_ZLO], p[_ZHI] = options["z_range"]
        p[_TLO], p[_THI] = options["theta_range"]
        p[_PLO], p[_PHI] = options["psi_range"]
        return p

    @property
    def field_kernel(self):
        return tool_point_fields

    @property
    def reach_kernel(self):
        return tool_point_reach

    @property
    def lci_kernel(self):
        return tool_lci_fields

    @property
    def interval_kernel(self):
        """_tool_column_intervals(p, x, y, zlo, zhi, out) -> k: the reachable intervals of a z-column in closed
        form (-1: not handled, evaluate points with reach_kernel instead)."""
        return _tool_column_intervals

    def interval_kernel_for(self, options):
        """None with interference_free (the clearance then decides reachability too: _tool_column_intervals returns
        -1 on every column), else the interval kernel."""
        return None if options["interference_free"] else _tool_column_intervals

    def column_axis(self, options) -> int:
        """z (axis 2), the last: the tool's columns (RpsUpu's z-columns are those of the platform height)."""
        return 2

    def column_order_kernel(self, kernel, options):
        return kernel

    def kernel_branch(self, options) -> str:
        return "++"

    def mirror_axes(self, options) -> tuple[int, ...]:
        """y (axis 1): T at -y is reached by the mirror image (psi -> -psi, RpsUpu.mirror_axes) of the pose reaching
        T at y, so a psi range symmetric about 0 is needed as well."""
        lo, hi = options["psi_range"]
        if lo == -hi and links.mirrored_radii(options, TOOL_RADII, [("leg1", "leg2")]) and options["load"][1] == 0.0:
            return (1,)
        return ()

    def bounding_box(self, design, options):
        """Interval bound of T = (-d sin(theta) cos(psi), d sin(psi), z0 - d cos(theta) cos(psi)) over the pose
        ranges (mm)."""
        d = options["tool_offset"]
        (s_t, c_t), (s_p, c_p) = _sin_cos_range(*options["theta_range"]), _sin_cos_range(*options["psi_range"])
        tx = _interval_product(s_t, c_p)
        tz = _interval_product(c_t, c_p)
        z_lo, z_hi = options["z_range"]
        lo = np.array([-d * tx[1], d * s_p[0], z_lo - d * tz[1]])
        hi = np.array([-d * tx[0], d * s_p[1], z_hi - d * tz[0]])
        return lo, hi

    # ----- tool point <-> pose ----------------------------------------------------------------------------
    def platform_pose(self, design, options, pose) -> dict[str, Any]:
        """As RpsUpu.platform_pose for a pose (z, theta, psi) of the P-model."""
        return super().platform_pose(design, self._p(options), pose)

    def tool_point(self, design, options, pose) -> np.ndarray:
        """T (mm) of a pose (z, theta, psi) of the P-model."""
        z, th, ps = self.check_vector("pose", pose, 3)
        d = options["tool_offset"]
        return np.array([-d * math.sin(th) * math.cos(ps), d * math.sin(ps), z - d * math.cos(th) * math.cos(ps)])

    def poses_of_tool_point(self, design, options, point) -> list[Solution]:
        """Every pose (z, theta, psi) that puts the tool at T (spec §2.8), labelled by the signs of cos theta and
        cos psi ('++' is the kernel's); the pose ranges are not applied. [] when |T_y| > d or |T_x| > d |cos psi|."""
        tx, ty, tz = self.check_vector("pose", point, 3)
        d = options["tool_offset"]
        if abs(ty) > d:
            return []
        out = []
        ps0 = math.asin(ty / d)
        for lp, ps in (("+", ps0), ("-", math.pi - ps0)):
            cp = math.cos(ps)
            if abs(cp) <= 1e-12 or abs(tx) > d * abs(cp):
                continue
            th0 = math.asin(-tx / (d * cp))
            for lt, th in (("+", th0), ("-", math.pi - th0)):
                z = tz + d * math.cos(th) * cp
                out.append(Solution(lt + lp, np.array([z, *wrap_angle(np.array([th, ps]))])))
        return out

    # ----- IK, FK -----------------------------------------------------------------------------------------
    def inverse_kinematics(self, design, options, pose) -> list[Solution]:
        """Leg lengths (mm) of every pose that places the tool at T = pose (labels as poses_of_tool_point)."""
        out = []
        for sol in self.poses_of_tool_point(design, options, pose):
            (legs,) = super().inverse_kinematics(design, self._p(options), sol.values)
            out.append(Solution(sol.label, legs.values))
        return out

    def forward_kinematics(self, design, options, inputs) -> list[Solution]:
        """T (mm) of every P-model assembly mode with z > 0 (labels as RpsUpu.forward_kinematics)."""
        return [
            Solution(s.label, self.tool_point(design, options, s.values))
            for s in super().forward_kinematics(design, self._p(options), inputs)
        ]

    # ----- Jacobians --------------------------------------------------------------------------------------
    def _pose_for(self, design, options, point, q) -> np.ndarray:
        """The pose placing the tool at T whose leg lengths are closest to q."""
        poses = self.poses_of_tool_point(design, options, point)
        if not poses:
            raise InvalidPose(f"pose: tool point {list(map(float, point))} is out of reach (|T_y| or |T_x| > d)")
        qv = self.check_vector("inputs", q, 3)
        legs = [RpsUpu.inverse_kinematics(self, design, self._p(options), s.values)[0].values for s in poses]
        return poses[int(np.argmin([np.abs(lv - qv).max() for lv in legs]))].values

    def jacobians(self, design, options, pose, q) -> dict[str, np.ndarray | None]:
        """At tool point T with leg lengths q: dq_dT = dq/d(z0, theta, psi) . d(z0, theta, psi)/dT (dimensionless),
        Jx = diag(q) dq_dT, Jq = diag(q) and the forward Jacobian J = dT/dq (None at a singularity). The pose is
        the one (of up to four) whose legs are closest to q."""
        x = self._pose_for(design, options, pose, q)
        base = super().jacobians(design, self._p(options), x, q)
        _, th, ps = x
        d = options["tool_offset"]
        st, ct, sp, cp = math.sin(th), math.cos(th), math.sin(ps), math.cos(ps)
        dT_dx = np.array([[0.0, -d * ct * cp, d * st * sp], [0.0, 0.0, d * cp], [1.0, d * st * cp, d * ct * sp]])
        jx = np.linalg.solve(dT_dx.T, base["Jx"].T).T if abs(ct * cp) > 0.0 else None
        out: dict[str, np.ndarray | None] = {"Jx": jx, "Jq": base["Jq"], "dT_dx": dT_dx, "dq_dT": None, "J": None}
        if jx is not None and base["dq_dx"] is not None:
            out["dq_dT"] = jx / base["Jq"].diagonal()[:, None]
            try:
                out["J"] = np.linalg.solve(jx, base["Jq"])
            except np.linalg.LinAlgError:
                out["J"] = None
        return out

    def link_geometry(self, design, options, pose, q) -> links.LinkGeometry:
        """As RpsUpu.link_geometry for the pose placing the tool at T = pose (legs closest to q), plus the tool
        O' -> T (body 'tool', adjacent to the platform only, so it is checked against the base and the legs)."""
        x = self._pose_for(design, options, pose, q)
        radii = links.radii(options, TOOL_RADII)
        segs, adjacent = self._capsules(design, self._p(options), x, radii)
        _, _, origin, _ = self._joint_points(design, self._p(options), x)
        segs.append(links.Segment("tool", "tool", origin, self.tool_point(design, options, x), radii["tool"]))
        return links.LinkGeometry(tuple(segs), links.adjacency([*adjacent, ("tool", "platform")]))

    def link_endpoints(self, design, options, poses, q) -> np.ndarray:
        """Vectorised twin of link_geometry's segment endpoints at tool points (m, 3) with legs q (m, 3):
        links.SegmentPoints. The pose of each point as _pose_for picks it: of the (up to four)
        poses placing the tool there, in poses_of_tool_point's order, the first whose legs are closest to q."""
        t, q = np.asarray(poses, dtype=float), np.asarray(q, dtype=float)
        d = options["tool_offset"]
        geom = self._geom(design)
        with np.errstate(invalid="ignore"):
            ps0 = np.arcsin(np.clip(t[:, 1] / d, -1.0, 1.0))
            best, x = np.full(len(t), np.inf), np.full((len(t), 3), np.nan)
            for ps in (ps0, math.pi - ps0):
                cp = np.cos(ps)
                ok = (np.abs(t[:, 1]) <= d) & (np.abs(cp) > 1e-12) & (np.abs(t[:, 0]) <= d * np.abs(cp))
                th0 = np.arcsin(np.clip(-t[:, 0] / np.where(ok, d * cp, 1.0), -1.0, 1.0))
                for th in (th0, math.pi - th0):
                    cand = np.column_stack([t[:, 2] + d * np.cos(th) * cp, wrap_angle(th), wrap_angle(ps)])
                    miss = np.where(ok, np.abs(_p_leg_lengths(geom, cand) - q).max(axis=1), np.inf)
                    closer = miss < best
                    best, x = np.where(closer, miss, best), np.where(closer[:, None], cand, x)
        # the P-model's joints in closed form: phi = y0 = 0, p = (0, 0, z), R = Ry(theta) Rx(psi), so R (0, +-h, 0)
        # = +-h (st sp, cp, ct sp) and R (c, 0, 0) = c (ct, 0, -st)
        g, h, c, e = geom
        z, st, ct, sp, cp = x[:, 0], np.sin(x[:, 1]), np.cos(x[:, 1]), np.sin(x[:, 2]), np.cos(x[:, 2])
        a = [(0.0, -g, 0.0), (0.0, g, 0.0), (e, 0.0, 0.0)]
        b = [(-h * st * sp, -h * cp, z - h * ct * sp), (h * st * sp, h * cp, z + h * ct * sp),
             (c * ct, 0.0, z - c * st)]
        sides = ((0, 1), (1, 2), (2, 0))
        tool = (-d * st * cp, d * sp, z - d * ct * cp)
        return links.segment_points([(a[i], a[j]) for i, j in sides] + [(a[i], b[i]) for i in range(3)]
                                     + [(b[i], b[j]) for i, j in sides] + [((0.0, 0.0, z), tool)], len(t))

    def velocity_map(self, design, options, pose, q) -> np.ndarray:
        """dq/dT (mm/mm) of the tool point; infinite where cos theta cos psi = 0 or a leg length is 0."""
        jac = self.jacobians(design, options, pose, q)
        return np.full((3, 3), np.inf) if jac["dq_dT"] is None else jac["dq_dT"]

    def cycle_kinematics(self, design, options, poses, label: str) -> tuple[np.ndarray, np.ndarray]:
        """Vectorised twin of Mechanism.cycle_kinematics for the kernel's branch '++' (cos theta, cos psi > 0):
        the pose of each tool point in closed form (poses_of_tool_point), its legs and dq/dT = dq/dx (dT/dx)^-1
        (velocity_map); other branches take the per-pose loop."""
        if label != "++":
            return Mechanism.cycle_kinematics(self, design, options, poses, label)
        t = np.asarray(poses, dtype=float)
        d = options["tool_offset"]
        with np.errstate(divide="ignore", invalid="ignore"):
            ps = np.arcsin(np.clip(t[:, 1] / d, -1.0, 1.0))
            cp = np.cos(ps)
            ok = (np.abs(t[:, 1]) <= d) & (np.abs(cp) > 1e-12) & (np.abs(t[:, 0]) <= d * np.abs(cp))
            th = np.arcsin(np.clip(-t[:, 0] / (d * cp), -1.0, 1.0))
            ct, st, sp = np.cos(th), np.sin(th), np.sin(ps)
            x = np.column_stack([t[:, 2] + d * ct * cp, wrap_angle(th), wrap_angle(ps)])
            _, q, jx = _legs(self._geom(design), "P", "plane", np.where(ok[:, None], x, 0.0))
            dt_dx = np.zeros((len(t), 3, 3))
            dt_dx[:, 0, 1], dt_dx[:, 0, 2] = -d * ct * cp, d * st * sp
            dt_dx[:, 1, 2] = d * cp
            dt_dx[:, 2, 0], dt_dx[:, 2, 1], dt_dx[:, 2, 2] = 1.0, d * st * cp, d * ct * sp
            regular = ok & (np.abs(ct * cp) > 0.0)
            safe = np.where(regular[:, None, None], dt_dx, np.eye(3))
            jx_t = np.transpose(np.linalg.solve(np.transpose(safe, (0, 2, 1)), np.transpose(jx, (0, 2, 1))), (0, 2, 1))
            a = np.where((regular & np.all(q > 0.0, axis=1))[:, None, None], jx_t / q[:, :, None], np.inf)
        return np.where(ok[:, None], q, np.nan), np.where(ok[:, None, None], a, np.nan)

    def payload_point(self, design, options, pose) -> np.ndarray:
        """The payload sits at the tool point T = pose (mm)."""
        return self.check_vector("pose", pose, 3)

    def payload_points(self, design, options, poses) -> np.ndarray:
        return np.asarray(poses, dtype=float).reshape(-1, 3)

    def lci(self, design, options, pose, q) -> float:
        """LCI = sigma_min / sigma_max of dq/dT with NumPy's SVD (0 at any singularity)."""
        jac = self.jacobians(design, options, pose, q)
        if jac["dq_dT"] is None:
            return 0.0
        return svd_lci(jac["dq_dT"])

    def singularity(self, design, options, pose, q, tol: float = 1e-7) -> str:
        """'inverse' when a leg length q_i <= tol (g + h + c); 'forward' when the normalised rows of q_i dq_i/dT are
        dependent (sigma ratio <= tol) or |cos theta cos psi| <= tol (T no longer fixes the pose)."""
        jac = self.jacobians(design, options, pose, q)
        g, h, c, _ = self._geom(design)
        inverse = bool(np.any(jac["Jq"].diagonal() <= tol * (g + h + c)))
        if jac["Jx"] is None:
            forward = True
        else:
            norms = np.linalg.norm(jac["Jx"], axis=1)
            forward = bool(np.any(norms == 0.0))
            if not forward:
                sv = np.linalg.svd(jac["Jx"] / norms[:, None], compute_uv=False)
                forward = bool(sv[-1] <= tol * sv[0])
            x = self._pose_for(design, options, pose, q)
            forward = forward or abs(math.cos(x[1]) * math.cos(x[2])) <= tol
        return singularity_label(inverse, forward)

    # ----- stiffness (scalesynth.stiffness; pose level) ------------------------------------------------------
    def _stiffness_placement(self, design, options, pose) -> tuple[np.ndarray, str, np.ndarray]:
        """The C-model pose (z, theta, psi), chain 3 'plane', that puts the tool at T = pose (Newton from the
        P-model's principal pose '++'), and T; raises InvalidPose when T is outside the tool workspace or Newton
        fails. That pose may leave the pose ranges or its legs the stroke limits: the model's notes say so, and the
        per-voxel fields use the same frame (docs/stiffness.md)."""
        t = self.check_vector("pose", pose, 3)
        where = f"pose: tool point ({', '.join(f'{v:g}' for v in t)})"
        if self.point_kernel(self.pack(design, options), *t) < 0.0:
            raise InvalidPose(f"{where} is outside the workspace (pose ranges and stroke limits, P-model)")
        (x,) = [s.values for s in self.poses_of_tool_point(design, options, t) if s.label == "++"]
        geom, d = self._geom(design), options["tool_offset"]
        scale = max(geom[:3]) + d
        for _ in range(50):
            _, p, rot, _, tm = _platform(geom, "C", "plane", x[None])
            r = rot[0] @ np.array([0.0, 0.0, -d])
            res = p[0] + r - t
            if np.max(np.abs(res)) <= 1e-13 * scale:
                break
            jac = tm[0, :3] - _skew(r[None])[0] @ tm[0, 3:]
            x = x - np.linalg.solve(jac, res)
        else:
            raise InvalidPose(f"{where}: no constraint-consistent (C-model) pose places the tool there")
        return x, "plane", t

    def stiffness_model(self, design, options, pose, joints: str = "ideal"):
        """As RpsUpu.stiffness_model, at the constraint-consistent pose (C-model, chain 3 'plane') that puts the
        tool at T = pose; the rigid platform's reference point (load, deflection) is the tool point T."""
        x, variant, ref = self._stiffness_placement(design, options, pose)
        return self._frame(design, self._p(options), x, variant, ref, joints)

    # ----- mobility (scalesynth.mobility) -------------------------------------------------------------------
    def joint_screws(self, design, options, pose, q):
        """RpsUpu.joint_screws at the pose (of up to four) that places the tool at T = pose with legs closest
        to q (as in ``jacobians``)."""
        x = self._pose_for(design, options, pose, q)
        return super().joint_screws(design, self._p(options), x, q)


TOOL_MECHANISM = RpsUpuTool(
    name="rps-upu-tool",
    title="2-RPS-UPU tool-point position workspace (seed 002, P-model)",
    seed="002",
    motion="2R1T",
    task_axes=("x", "y", "z"),
    task_units=("length", "length", "length"),
    joints=("q1", "q2", "q3"),
    joint_units=("length", "length", "length"),
    parameters=MECHANISM.parameters,
    options=(
        Option("tool_offset", 50.0, "d (mm): T = O' + R (0, 0, -d); illustrative default, the paper has no tool"),
        *(o for o in MECHANISM.options if o.name in ("stroke_limits", "z_range", "theta_range", "psi_range")),
        *STIFFNESS_OPTIONS,
        Option("link_radius", None, "capsule radius (mm) of every body, or {body: radius}; null = defaults base 6, "
               "leg1/leg2/leg3 5, platform 6, tool 4 (illustrative)"),
        Option("interference_free", False, "true: a pose whose link capsules overlap (clearance < 0) is unreachable"),
    ),
    default_length_unit="mm",
    fields=(*base_fields("1", "J = dT/dq of the tool point (mm/mm)"), links.CLEARANCE_FIELD,
            *_stiffness_fields("the tool point T")),
    design_metrics=DESIGN_METRICS,
)
