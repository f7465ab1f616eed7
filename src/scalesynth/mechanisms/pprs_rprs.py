"""6-DOF 2PPRS-RPRS parallel mechanism (seed 001), primary model of spec mechanisms_001_003.md §1.

Three chains carry a moving triangle C1C2C3 (circumradius r). Chains 1 and 2 (P-P-R-S): a carriage slides
along the horizontal rail u_i (input w_i, measured from O: "conv O", erratum E5), a vertical slider on it
(input s_i) carries D_i, and a link |D_iC_i| = L_i turns about u_i. Chain 3 (R-P-R-S): an actuated revolute
at the fixed point B3 = R u3 (input beta) tilts a prismatic (input s3) in the vertical plane of u3; the link
|D3C3| = L3 turns about the normal of that plane. Pose X = (x, y, z, phi, theta, psi), R = Rz(phi) Ry(theta)
Rx(psi); lengths in mm, angles in rad. The six joints are (w1, w2, beta, s1, s2, s3).

Task space: the constant-orientation position workspace of O1 (spec §1.8). The orientation is an option;
task axes are (x, y, z), so the point kernel and the CLI's ``ik --pose x,y,z`` use that orientation, while the
NumPy kinematics also accept full 6-vector poses. FK solutions are full 6-vector poses.

Dexterity: LCI = 1/kappa_2 of the twist Jacobian J_t (q_dot = J_t [v; omega], spec §1.5), homogenised with
two characteristic lengths because its columns mix translations and rotations and its beta row is an angle
rate: the beta row is multiplied by ``beta_length`` (default R) and the three angular-velocity columns are
divided by ``angle_length`` (default r), which makes every entry dimensionless (spec §1.5: cond = 6.68 at
home). The twist Jacobian is used rather than the Euler-rate Jacobian J = J_t T because it is independent of
the Euler parametrisation (no artificial singularity at theta = +-90 deg); at the default zero orientation
T's angular block is a permutation, so both give the same LCI.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numba import njit

from scalesynth.errors import InvalidParameter, InvalidPose
from scalesynth.evaluation.plans import ColumnPlan
from scalesynth.kernels import grid as _grid
from scalesynth.kernels.clearance import put_segment as _put_seg
from scalesynth.kernels.clearance import segment_distance
from scalesynth.kernels.conditioning import inverse_singular_values
from scalesynth.kernels.flags import FASTMATH
from scalesynth.kernels.intervals import add_piece, sort_span
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
    wrap_angle,
)
from scalesynth.stiffness import legs as _legs_k
from scalesynth.stiffness.sections import check_positive_option, check_stiffness_options, stiffness_options

SQRT3_2 = math.sqrt(3.0) / 2.0
# fraction of the y span added on each side of bounding_box's y range where both y faces come from the w2 limits
# (irrational: see bounding_box)
Y_PAD = (math.sqrt(5.0) - 1.0) / 40.0
BRANCHES = tuple(a + b + c for a in "+-" for b in "+-" for c in "+-")
CONVENTIONS = ("O", "R")
JOINTS = ("w1", "w2", "beta", "s1", "s2", "s3")
CHAIN_OF_JOINT = (0, 1, 2, 0, 1, 2)
# default capsule radii (mm), illustrative (the paper gives no cross-sections)
LINK_RADII = {"base": 5.0, "slider1": 8.0, "slider2": 8.0, "leg3": 8.0, "link1": 5.0, "link2": 5.0, "link3": 5.0,
              "platform": 5.0}

# packed-parameter layout (see PprsRprs.pack)
_R1, _R2, _R3 = 0, 3, 6  # rotated sphere-centre offsets r_k = R c_k' (3 each)
_U3X, _U3Y, _RAIL, _L1, _L2, _L3 = 9, 10, 11, 12, 13, 14
_SG1, _SG2, _SG3, _CONV = 15, 16, 17, 18
_WLO, _WHI, _SLO, _SHI, _BLO, _BHI = 19, 20, 21, 22, 23, 24
_BLEN, _ALEN = 25, 26
_RAD = 27  # capsule radii of the 8 bodies, in LINK_RADII order
_FREE_ONLY = 35  # 1: poses whose capsules overlap are unreachable
_F_CLEARANCE = 3  # slot of the clearance field in the field kernel's out (its index in ``fields``)
# stiffness (slots _F_STIFFNESS_MIN, _F_DEFLECTION): EA (N), EI (N mm^2), GJ (N mm^2) of the 'column' and 'link'
# groups, linear actuator stiffness (N/mm), beta stiffness (N mm/rad), load (N)
_EA_COL, _EA_LINK, _KACT, _KBETA, _FX = 36, 39, 42, 43, 44
_F_STIFFNESS_MIN, _F_DEFLECTION = 4, 5
N_PACKED = 47

# stiffness (scalesynth.stiffness, docs/stiffness.md): link groups, the columns B_i D_i (the vertical sliders and
# chain 3's tilting prismatic) and the links D_i C_i; actuator stiffness defaults (assumptions, the paper gives none):
# 2e4 N/mm for the five linear actuators (a small ball-screw axis), 1e8 N mm/rad (1e5 N m/rad, a servo with a stiff
# precision reducer) for chain 3's revolute input beta
LINK_GROUPS = ("column", "link")
ACTUATOR_STIFFNESS = 2e4
BETA_STIFFNESS = 1e8

# capsules of the clearance field, in link_geometry's order, with their body (index into LINK_RADII)
_SEGMENT_BODY = np.array([0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 7, 7], dtype=np.int64)
_BODIES = tuple(LINK_RADII)
_ADJACENT = {frozenset(p) for p in (("base", "slider1"), ("base", "slider2"), ("base", "leg3"), ("slider1", "link1"),
                                    ("slider2", "link2"), ("leg3", "link3"), ("link1", "platform"),
                                    ("link2", "platform"), ("link3", "platform"))}
# segment pairs whose clearance counts: different bodies sharing no joint (the same rule as LinkGeometry)
_PAIRS = np.array([(i, j) for i in range(12) for j in range(i + 1, 12)
                   if _SEGMENT_BODY[i] != _SEGMENT_BODY[j]
                   and frozenset((_BODIES[_SEGMENT_BODY[i]], _BODIES[_SEGMENT_BODY[j]])) not in _ADJACENT],
                  dtype=np.int64)


# ----- Numba kernels -----------------------------------------------------------------------------------------
# the Gram fast path of _sv_work is trusted where lambda_min / lambda_max of A^T A is at least GRAM_MIN_RATIO (LCI >=
# 1e-3): its relative error in lambda_min is then about eps * kappa^2 <= 1e-10 (measured up to 6e-11 on random
# matrices); below it, the Jacobi fallback works on A itself
GRAM_MIN_RATIO = 1e-6
# relative half-width of the Sturm brackets that certify the Laguerre limits (see _sv_work)
GRAM_BRACKET = 1e-9
GRAM_MAX_ITERATIONS = 12
# rows of the (16, 6) workspace of _sv_work: A, then B = A^T A, then d, e^2 of the tridiagonal T, then two vectors
_WS_ROWS = 16


@njit(cache=True, fastmath=FASTMATH)
def _jacobi_6x6(a):
    """(sigma_min / sigma_max, sigma_min, sigma_max) of the 6x6 matrix ``a`` (overwritten), by one-sided
    (Hestenes) Jacobi.

    Plane rotations orthogonalise the columns; the singular values are then the column norms. Working on A
    itself, not on A^T A, keeps small singular values accurate relative to the large ones. About 4x the cost of
    _sv_work's Gram path (5-6 sweeps of 15 rotations); its fallback.
    """
    n = 6
    for _sweep in range(40):
        rotated = False
        for i in range(n - 1):
            for j in range(i + 1, n):
                alpha = 0.0
                beta = 0.0
                gamma = 0.0
                for k in range(n):
                    alpha += a[k, i] * a[k, i]
                    beta += a[k, j] * a[k, j]
                    gamma += a[k, i] * a[k, j]
                if gamma == 0.0 or abs(gamma) <= 1e-15 * math.sqrt(alpha * beta):
                    continue
                rotated = True
                zeta = (beta - alpha) / (2.0 * gamma)
                t = 1.0 / (abs(zeta) + math.sqrt(1.0 + zeta * zeta))
                if zeta < 0.0:
                    t = -t
                c = 1.0 / math.sqrt(1.0 + t * t)
                s = c * t
                for k in range(n):
                    ai = a[k, i]
                    aj = a[k, j]
                    a[k, i] = c * ai - s * aj
                    a[k, j] = s * ai + c * aj
        if not rotated:
            break
    smax = 0.0
    smin = math.inf
    for j in range(n):
        norm = 0.0
        for k in range(n):
            norm += a[k, j] * a[k, j]
        norm = math.sqrt(norm)
        smax = max(smax, norm)
        smin = min(smin, norm)
    if not smax > 0.0:
        return 0.0, 0.0, 0.0
    return min(smin / smax, 1.0), smin, smax


@njit(cache=True, fastmath=FASTMATH)
def _laguerre_step(w, x):
    """Laguerre step on p(x) = det(x I - T) (T: d = w[12], e^2 = w[13]), from p, p', p'' of the division-free
    three-term recurrence; 0 at a root (p == 0) or where the step is undefined."""
    p0 = 1.0
    p1 = x - w[12, 0]
    dp0 = 0.0
    dp1 = 1.0
    q0 = 0.0
    q1 = 0.0
    for i in range(1, 6):
        c = x - w[12, i]
        e = w[13, i - 1]
        p2 = c * p1 - e * p0
        dp2 = p1 + c * dp1 - e * dp0
        q2 = 2.0 * dp1 + c * q1 - e * q0
        p0, p1 = p1, p2
        dp0, dp1 = dp1, dp2
        q0, q1 = q1, q2
    if p1 == 0.0:
        return 0.0
    g = dp1 / p1
    h = g * g - q1 / p1
    disc = 5.0 * (6.0 * h - g * g)
    sq = math.sqrt(disc) if disc > 0.0 else 0.0
    den = g + sq if g >= 0.0 else g - sq
    if den == 0.0:
        return 0.0
    return 6.0 / den


@njit(cache=True, fastmath=FASTMATH)
def _above(w, x):
    """Number of eigenvalues of T greater than x: the sign changes of the Sturm sequence det(x I_k - T_k), k = 0..6
    (the negative pivots of x I - T = L D L^T); -1 where a term is zero (or its product underflows), which fails
    every bracket test of _sv_work."""
    p0 = 1.0
    p1 = x - w[12, 0]
    if p1 == 0.0:
        return -1
    n = 1 if p1 < 0.0 else 0
    for i in range(1, 6):
        p2 = (x - w[12, i]) * p1 - w[13, i - 1] * p0
        pp = p2 * p1
        if pp == 0.0 or pp != pp:  # a zero, an underflow or a NaN: no count
            return -1
        if pp < 0.0:
            n += 1
        p0, p1 = p1, p2
    return n


@njit(cache=True, fastmath=FASTMATH)
def _sv_work(w):
    """(sigma_min / sigma_max, sigma_min, sigma_max) of the 6x6 matrix A in rows 0-5 of the workspace ``w`` (float,
    shape (16, 6); rows 6-15 are overwritten, and A too where the fallback runs).

    Fast path: B = A^T A, Householder tridiagonalisation T = Q^T B Q (scaled by 1 / trace B, so its eigenvalues lie in
    [0, 1]), then Laguerre iterations on det(x I - T), which converge monotonically (cubically for a simple root)
    from outside the spectrum: from x = 0 to lambda_min and from the Frobenius norm of T to lambda_max. Each limit
    x is certified by two Sturm counts: no eigenvalue below x (1 - GRAM_BRACKET) and one below x (1 + GRAM_BRACKET)
    for lambda_min, likewise above for lambda_max, so a stalled or overshooting iteration (clustered eigenvalues)
    cannot return a wrong value. Squaring A squares its condition number: the relative error of lambda_min is
    about eps * kappa^2, so the Gram result is kept only where lambda_min / lambda_max >= GRAM_MIN_RATIO
    (LCI >= 1e-3, error <= 1e-10). Otherwise (ill-conditioned, B overflowing, no certificate, no convergence within
    GRAM_MAX_ITERATIONS) one-sided Jacobi on A (_jacobi_6x6) gives the result; a zero (or NaN) trace gives zeros.
    The fast path's relative LCI error is thus at most about GRAM_BRACKET + eps kappa^2 (<= 2e-9; clusters of
    singular values narrower than the bracket give up to 1e-9), the fallback's that of Jacobi. About 0.4 us
    against 1.9 us for Jacobi alone (benchmarks/notes/pprs_rprs.md).
    """
    n = 6
    tr = 0.0
    for i in range(n):
        for j in range(i, n):
            s = 0.0
            for k in range(n):
                s += w[k, i] * w[k, j]
            w[6 + i, j] = s
            w[6 + j, i] = s
        tr += w[6 + i, i]
    if not tr > 0.0:
        return 0.0, 0.0, 0.0
    if not tr < math.inf:  # B overflows: Jacobi on A as before
        return _jacobi_6x6(w[:6])
    inv_tr = 1.0 / tr
    for i in range(n):
        for j in range(n):
            w[6 + i, j] *= inv_tr
    # Householder reduction of B (rows 6-11) to T: diagonal d in row 12, squared off-diagonal in row 13; the
    # reflector v in row 14, p = tau B v - k v in row 15
    for k in range(n - 2):
        tail = 0.0
        for i in range(k + 2, n):
            tail += w[6 + i, k] * w[6 + i, k]
        x0 = w[6 + k + 1, k]
        w[12, k] = w[6 + k, k]
        if not tail > 0.0:  # column already reduced (the reflector would divide by zero)
            w[13, k] = x0 * x0
            continue
        sig = tail + x0 * x0
        alpha = -math.sqrt(sig) if x0 >= 0.0 else math.sqrt(sig)
        for i in range(k + 1, n):
            w[14, i] = w[6 + i, k]
        w[14, k + 1] -= alpha
        tau = 2.0 / (tail + w[14, k + 1] * w[14, k + 1])
        for i in range(k + 1, n):
            s = 0.0
            for j in range(k + 1, n):
                s += w[6 + i, j] * w[14, j]
            w[15, i] = tau * s
        kk = 0.0
        for i in range(k + 1, n):
            kk += w[14, i] * w[15, i]
        kk *= 0.5 * tau
        for i in range(k + 1, n):
            w[15, i] -= kk * w[14, i]
        for i in range(k + 1, n):
            for j in range(k + 1, n):
                w[6 + i, j] -= w[14, i] * w[15, j] + w[15, i] * w[14, j]
        w[13, k] = sig
    w[12, n - 2] = w[6 + n - 2, n - 2]
    w[12, n - 1] = w[6 + n - 1, n - 1]
    w[13, n - 2] = w[6 + n - 1, n - 2] * w[6 + n - 1, n - 2]
    fro = 0.0
    for i in range(n):
        fro += w[12, i] * w[12, i]
    for i in range(n - 1):
        fro += 2.0 * w[13, i]
    hi = math.sqrt(fro)
    lo = 0.0
    hi_done = False
    lo_done = False
    # both iterations in one loop: independent dependency chains that the CPU overlaps
    for _ in range(GRAM_MAX_ITERATIONS):
        if not hi_done:
            step = _laguerre_step(w, hi)
            hi -= step
            hi_done = abs(step) <= 1e-8 * hi
        if not lo_done:
            step = _laguerre_step(w, lo)
            lo -= step
            lo_done = abs(step) <= 1e-8 * lo
        if hi_done and lo_done:
            break
    if (hi_done and lo_done and lo >= GRAM_MIN_RATIO * hi
            and _above(w, lo * (1.0 - GRAM_BRACKET)) == n and 0 <= _above(w, lo * (1.0 + GRAM_BRACKET)) < n
            and _above(w, hi * (1.0 + GRAM_BRACKET)) == 0 and _above(w, hi * (1.0 - GRAM_BRACKET)) > 0):
        smax = math.sqrt(hi * tr)
        smin = math.sqrt(lo * tr)
        return min(smin / smax, 1.0), smin, smax
    return _jacobi_6x6(w[:6])


@njit(cache=True, fastmath=FASTMATH)
def _sv_6x6(a):
    """(sigma_min / sigma_max, sigma_min, sigma_max) of the 6x6 matrix ``a`` (not modified); see _sv_work."""
    w = np.empty((_WS_ROWS, 6))
    w[:6] = a
    return _sv_work(w)


@njit(cache=True, fastmath=FASTMATH)
def _lci_6x6(a):
    """sigma_min / sigma_max of the 6x6 matrix ``a`` (not modified); see _sv_work."""
    return _sv_6x6(a)[0]


@njit(cache=True, fastmath=FASTMATH)
def _put_row(a, row, scale, gx, gy, gz, rx, ry, rz, inv_alen):
    """Row ``row`` of the scaled Jacobian: scale * [g, (r x g) / angle_length]."""
    a[row, 0] = scale * gx
    a[row, 1] = scale * gy
    a[row, 2] = scale * gz
    k = scale * inv_alen
    a[row, 3] = k * (ry * gz - rz * gy)
    a[row, 4] = k * (rz * gx - rx * gz)
    a[row, 5] = k * (rx * gy - ry * gx)


@njit(cache=True, fastmath=FASTMATH)
def _force_flex(p, ll, lx, ly, lz, s, ax, ay, az, fax, fay, faz, fbx, fby, fbz, hax, hay, haz, hbx, hby, hbz, hk):
    """Flexibility f_a^T C f_b of a chain under two forces through C (see _chain_columns): the link (length ll,
    unit l, clamped at D), the column (length s, unit a, clamped at B; the force's moment about D is ll l x f) and
    the springs (g_a . f)(g_a . f') hk + (g_b . f)(g_b . f') / k."""
    link = _legs_k.tip_bilinear(ll, p[_EA_LINK], p[_EA_LINK + 1], p[_EA_LINK + 2], lx, ly, lz, fax, fay, faz, 0.0,
                                0.0, 0.0, fbx, fby, fbz, 0.0, 0.0, 0.0)
    col = _legs_k.tip_bilinear(s, p[_EA_COL], p[_EA_COL + 1], p[_EA_COL + 2], ax, ay, az, fax, fay, faz,
                               ll * (ly * faz - lz * fay), ll * (lz * fax - lx * faz), ll * (lx * fay - ly * fax),
                               fbx, fby, fbz,
                               ll * (ly * fbz - lz * fby), ll * (lz * fbx - lx * fbz), ll * (lx * fby - ly * fbx))
    springs = ((hax * fax + hay * fay + haz * faz) * (hax * fbx + hay * fby + haz * fbz) * hk
               + (hbx * fax + hby * fay + hbz * faz) * (hbx * fbx + hby * fby + hbz * fbz) / p[_KACT])
    return link + col + springs


# not inlined into _stiffness (Numba's inline="always" would type and lower its body, with 6 tip_bilinear, three
# times): _stiffness's own compile 7.6 s -> 2.6 s with this function, and `scalesynth evaluate
# configs/pprs_rprs.yaml`'s first-process compile 40.4 -> 30.0 s with the other changes of 2026-12-02 afternoon
# (`python benchmarks/bench.py compile_commands`), at the same evaluation time; the stiffness statistics move by up
# to 1.5e-9 relative (rounding near singular poses), the kinematic fields not at all
@njit(cache=True, fastmath=FASTMATH)
def _chain_columns(p, kk, ox, oy, oz, cx, cy, cz, bx, by, bz, dx, dy, dz, ax, ay, az, s, nx, ny, nz, hax, hay, haz,
                   hbx, hby, hbz, hk):
    """kk + the two wrench columns of one chain (column B -> D along a = (ax, ay, az), length s; link D -> C; revolute
    about n at D; spherical at C) at the reference point O: with ideal joints the chain passes the forces through C
    in the plane (link direction, n). Flexibility Phi (2x2) of those two forces: the link (a cantilever clamped at
    D), the column (clamped at B, loaded by the force through C) and the actuator springs, which see the force
    through the compliances hk[j] (g_j . f)^2 with g_j = (hax, hay, haz) (a linear spring, or for a revolute
    spring the moment arm of its axis) and g_j = (hbx, hby, hbz) (a second linear spring; 1 / k each)."""
    lx, ly, lz = cx - dx, cy - dy, cz - dz
    ll = math.sqrt(lx * lx + ly * ly + lz * lz)
    lx, ly, lz = lx / ll, ly / ll, lz / ll
    p11 = _force_flex(p, ll, lx, ly, lz, s, ax, ay, az, lx, ly, lz, lx, ly, lz, hax, hay, haz, hbx, hby, hbz, hk)
    p12 = _force_flex(p, ll, lx, ly, lz, s, ax, ay, az, lx, ly, lz, nx, ny, nz, hax, hay, haz, hbx, hby, hbz, hk)
    p22 = _force_flex(p, ll, lx, ly, lz, s, ax, ay, az, nx, ny, nz, nx, ny, nz, hax, hay, haz, hbx, hby, hbz, hk)
    l11 = math.sqrt(p11)
    l21 = p12 / l11
    q22 = p22 - l21 * l21
    if not (l11 > 0.0 and q22 > 0.0):
        return False, kk
    i11 = 1.0 / l11
    i22 = 1.0 / math.sqrt(q22)
    rx, ry, rz = cx - ox, cy - oy, cz - oz
    # column 1: f1 / l11; column 2: (f2 - l21 f1 / l11) / l22; wrench (f, (C - O) x f)
    ux, uy, uz = lx * i11, ly * i11, lz * i11
    kk = _legs_k.outer_add(kk, ux, uy, uz, ry * uz - rz * uy, rz * ux - rx * uz, rx * uy - ry * ux)
    t = l21 * i11
    vx, vy, vz = (nx - t * lx) * i22, (ny - t * ly) * i22, (nz - t * lz) * i22
    kk = _legs_k.outer_add(kk, vx, vy, vz, ry * vz - rz * vy, rz * vx - rx * vz, rx * vy - ry * vx)
    return True, kk


@njit(cache=True, fastmath=FASTMATH)
def _stiffness(p, ox, oy, oz, c1x, c1y, c1z, s1, c2x, c2y, c2z, p2x, p2y, s2, c3x, c3y, c3z, b3x, b3y, t3x, t3y,
               t3z, s3, d3x, d3y, d3z, e3x, e3y):
    """(stiffness_min N/mm, deflection mm) at O1, ideal joints, the frame of stiffness_model, by per-chain
    condensation in the wrench form K = sum_i W_i Phi_i^-1 W_i^T (scalesynth.stiffness.legs). Each chain is serial:
    chains 1, 2: carriage on the rail (spring w_i along u_i), column B_i -> D_i along z (spring s_i along z), link
    D_i -> C_i (revolute about u_i at D_i, spherical at C_i); chain 3: rocker at B3 (torsional spring beta about e3),
    column B3 -> top along d3 (spring s3), link top -> C3 (revolute about n3 = e3 x d3, spherical at C3). With ideal
    joints each chain passes two forces through C_i, in the plane of its link and its revolute axis; their
    flexibility (2x2) adds the link, the column and the springs. Six wrench columns; the platform response from
    the 21 entries of K (legs.response_upper). Round sections (EIy = EIz)."""
    k = p[_KACT]
    kk = (0.0,) * 21
    # chain 1: u1 = x, B1 = (c1x, 0, 0), D1 = B1 + s1 z, revolute about u1
    ok1, kk = _chain_columns(p, kk, ox, oy, oz, c1x, c1y, c1z, c1x, 0.0, 0.0, c1x, 0.0, s1, 0.0, 0.0, 1.0, s1,
                             1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0 / k)
    # chain 2: u2 = (-1/2, sqrt3/2, 0), B2 = (p2x, p2y, 0)
    ok2, kk = _chain_columns(p, kk, ox, oy, oz, c2x, c2y, c2z, p2x, p2y, 0.0, p2x, p2y, s2, 0.0, 0.0, 1.0, s2,
                             -0.5, SQRT3_2, 0.0, -0.5, SQRT3_2, 0.0, 0.0, 0.0, 1.0, 1.0 / k)
    # chain 3: n3 = e3 x d3; the beta spring turns C3 by e3 x (C3 - B3) per rad: g = (C3 - B3) x e3 (up to sign)
    n3x, n3y, n3z = e3y * d3z, -e3x * d3z, e3x * d3y - e3y * d3x
    nn = math.sqrt(n3x * n3x + n3y * n3y + n3z * n3z)
    n3x, n3y, n3z = n3x / nn, n3y / nn, n3z / nn
    rx, ry, rz = c3x - b3x, c3y - b3y, c3z  # C3 - B3
    gx, gy, gz = ry * 0.0 - rz * e3y, rz * e3x - rx * 0.0, rx * e3y - ry * e3x  # (C3 - B3) x e3
    ok3, kk = _chain_columns(p, kk, ox, oy, oz, c3x, c3y, c3z, b3x, b3y, 0.0, t3x, t3y, t3z, d3x, d3y, d3z, s3,
                             n3x, n3y, n3z, gx, gy, gz, d3x, d3y, d3z, 1.0 / p[_KBETA])
    zero = 0.0 if (p[_FX] == 0.0 and p[_FX + 1] == 0.0 and p[_FX + 2] == 0.0) else _legs_k.DEFLECTION_CAP
    if not (ok1 and ok2 and ok3):
        return 0.0, zero
    # the reference solver's characteristic length: its longest link (columns, links)
    length = max(s1, s2, s3, p[_L1], p[_L2], p[_L3])
    return _legs_k.response_upper(kk, p[_FX], p[_FX + 1], p[_FX + 2], length)


@njit(cache=True, fastmath=FASTMATH)
def point_fields(p, x, y, z, out):
    """Every field at O1 = (x, y, z) (see _fields): LCI, sigma_min, sigma_max, clearance, stiffness_min, deflection."""
    _fields(p, x, y, z, out, True)


@njit(cache=True, fastmath=FASTMATH)
def kinematic_fields(p, x, y, z, out):
    """Slots 0-3 only (LCI, sigma_min, sigma_max, clearance), for benchmarks (the cost without stiffness)."""
    _fields(p, x, y, z, out, False)


@njit(cache=True, fastmath=FASTMATH)
def lci_fields(p, x, y, z, out):
    """Slot 0 of point_fields alone, computed as there (the LCI or -1; with interference_free the clearance still
    decides reachability), the other slots not written: the search's kernel when it needs only the LCI's metrics
    (Mechanism.lci_kernel); no capsule clearance, stiffness or sigma."""
    _fields(p, x, y, z, out, False, True, False)


@njit(cache=True, fastmath=FASTMATH)
def point_reach(p, x, y, z, out):
    """Slot 0 of point_fields up to its value: >= 0 exactly where point_fields' LCI is (the same branch, rail,
    beta and stroke checks and, with interference_free, the same clearance), -1 elsewhere; no conditioning,
    stiffness or (without interference_free) clearance. The adaptive evaluator's nodes and bisections
    (Mechanism.reach_kernel)."""
    _fields(p, x, y, z, out, False, False)


@njit(cache=True, fastmath=FASTMATH)
def _conditioning(p, conv_r, u3x, u3y, e3x, e3y, rho3, h3, mu3sq, mu3, lam1, k1, lam2, k2, lam3, k3):
    """(LCI, sigma_min, sigma_max) of the scaled twist Jacobian (_fields). Not inlined: point_fields and lci_fields
    then run the same compiled code, so their LCIs agree bit for bit (inlined, the optimiser contracts the rows'
    products differently next to the clearance and stiffness code: 1-ulp differences)."""
    # rows [g, r x g] of J_t (spec §1.5), beta row times beta_length, angular columns over angle_length
    inv_alen = 1.0 / p[_ALEN]
    a = np.empty((_WS_ROWS, 6))  # rows 0-5: the Jacobian; the rest: _sv_work's workspace
    wsign = -1.0 if conv_r else 1.0
    r1x, r1y, r1z = p[_R1], p[_R1 + 1], p[_R1 + 2]
    r2x, r2y, r2z = p[_R2], p[_R2 + 1], p[_R2 + 2]
    r3x, r3y, r3z = p[_R3], p[_R3 + 1], p[_R3 + 2]
    _put_row(a, 0, wsign, 1.0, 0.0, 0.0, r1x, r1y, r1z, inv_alen)
    _put_row(a, 1, wsign, -0.5, SQRT3_2, 0.0, r2x, r2y, r2z, inv_alen)
    inv_mu2 = 1.0 / mu3sq
    _put_row(a, 2, p[_BLEN], h3 * u3x * inv_mu2, h3 * u3y * inv_mu2, rho3 * inv_mu2, r3x, r3y, r3z, inv_alen)
    t1 = p[_SG1] * lam1 / k1
    _put_row(a, 3, 1.0, 0.0, t1, 1.0, r1x, r1y, r1z, inv_alen)
    t2 = p[_SG2] * lam2 / k2
    _put_row(a, 4, 1.0, -SQRT3_2 * t2, -0.5 * t2, 1.0, r2x, r2y, r2z, inv_alen)
    t3 = p[_SG3] * lam3 / k3
    inv_mu = 1.0 / mu3
    # g = d3 + t3 e3 with d3 = (-rho3 u3 + h3 z) / mu3
    gx = -rho3 * u3x * inv_mu + t3 * e3x
    gy = -rho3 * u3y * inv_mu + t3 * e3y
    _put_row(a, 5, 1.0, gx, gy, h3 * inv_mu, r3x, r3y, r3z, inv_alen)
    return _sv_work(a)


@njit(cache=True, fastmath=FASTMATH)
def _capsule_gap(p, rail, u3x, u3y, b3x, b3y, p2x, p2y, s1, s2, d3x, d3y, d3z, c1x, c1y, c1z, c2x, c2y, c2z, c3x, c3y,
                 c3z):
    """Clearance (field 3, mm) of the capsules of link_geometry at one pose (_fields' points)."""
    seg = np.empty((12, 6))
    _put_seg(seg, 0, 0.0, 0.0, 0.0, rail, 0.0, 0.0)
    _put_seg(seg, 1, 0.0, 0.0, 0.0, -0.5 * rail, SQRT3_2 * rail, 0.0)
    _put_seg(seg, 2, 0.0, 0.0, 0.0, b3x, b3y, 0.0)
    _put_seg(seg, 3, c1x, 0.0, 0.0, c1x, 0.0, s1)
    _put_seg(seg, 4, p2x, p2y, 0.0, p2x, p2y, s2)
    _put_seg(seg, 5, b3x, b3y, 0.0, d3x, d3y, d3z)
    _put_seg(seg, 6, c1x, 0.0, s1, c1x, c1y, c1z)
    _put_seg(seg, 7, p2x, p2y, s2, c2x, c2y, c2z)
    _put_seg(seg, 8, d3x, d3y, d3z, c3x, c3y, c3z)
    _put_seg(seg, 9, c1x, c1y, c1z, c2x, c2y, c2z)
    _put_seg(seg, 10, c2x, c2y, c2z, c3x, c3y, c3z)
    _put_seg(seg, 11, c3x, c3y, c3z, c1x, c1y, c1z)
    gap = math.inf
    for k in range(_PAIRS.shape[0]):
        i = _PAIRS[k, 0]
        j = _PAIRS[k, 1]
        d = segment_distance(seg[i, 0], seg[i, 1], seg[i, 2], seg[i, 3], seg[i, 4], seg[i, 5],
                             seg[j, 0], seg[j, 1], seg[j, 2], seg[j, 3], seg[j, 4], seg[j, 5])
        gap = min(gap, d - p[_RAD + _SEGMENT_BODY[i]] - p[_RAD + _SEGMENT_BODY[j]])
    return gap


@njit(cache=True, fastmath=FASTMATH)
def _fields(p, x, y, z, out, stiffness, every=True, others=True):
    """LCI of the scaled twist Jacobian at O1 = (x, y, z) with the packed orientation and branch, or -1 if the
    IK is not real or an actuator leaves its limits (spec §1.3, §1.5, §1.8). 0 at a serial singularity.
    Fields (kernels.grid contract): LCI, sigma_min, sigma_max of J = dx/dq, x = (O1, angle_length x angular
    velocity), the beta input times beta_length (dimensionless); clearance (mm) of the link capsules (with
    interference_free, overlapping capsules make the pose unreachable); with ``stiffness``, stiffness_min (N/mm) and
    deflection (mm) at O1 under the packed load (ideal joints, docs/stiffness.md; _stiffness). ``every`` False (a
    constant, point_reach): slot 0 alone, 0 where reachable, -1 elsewhere; ``others`` False (a constant,
    lci_fields): slot 0 alone, the LCI as with True."""
    c1x = x + p[_R1]
    c1y = y + p[_R1 + 1]
    c1z = z + p[_R1 + 2]
    c2x = x + p[_R2]
    c2y = y + p[_R2 + 1]
    c2z = z + p[_R2 + 2]
    c3x = x + p[_R3]
    c3y = y + p[_R3 + 1]
    c3z = z + p[_R3 + 2]
    rail = p[_RAIL]
    conv_r = p[_CONV] > 0.0
    wlo = p[_WLO]
    whi = p[_WHI]
    slo = p[_SLO]
    shi = p[_SHI]
    # rails: u1 = (1, 0, 0), u2 = (-1/2, sqrt3/2, 0)
    w1 = rail - c1x if conv_r else c1x
    if w1 < wlo or w1 > whi:
        _grid.write_unreachable(out)
        return
    p2 = -0.5 * c2x + SQRT3_2 * c2y
    w2 = rail - p2 if conv_r else p2
    if w2 < wlo or w2 > whi:
        _grid.write_unreachable(out)
        return
    # chains 1, 2: lambda_i = e_i . C_i with e1 = (0, 1, 0), e2 = (-sqrt3/2, -1/2, 0)
    l1 = p[_L1]
    lam1 = c1y
    k1sq = l1 * l1 - lam1 * lam1
    if k1sq < 0.0:
        _grid.write_unreachable(out)
        return
    k1 = math.sqrt(k1sq)
    s1 = c1z - p[_SG1] * k1
    if s1 < slo or s1 > shi:
        _grid.write_unreachable(out)
        return
    l2 = p[_L2]
    lam2 = -SQRT3_2 * c2x - 0.5 * c2y
    k2sq = l2 * l2 - lam2 * lam2
    if k2sq < 0.0:
        _grid.write_unreachable(out)
        return
    k2 = math.sqrt(k2sq)
    s2 = c2z - p[_SG2] * k2
    if s2 < slo or s2 > shi:
        _grid.write_unreachable(out)
        return
    # chain 3 in its plane: rho3 = R - u3.C3, h3 = z_C3, beta = atan2(h3, rho3), s3 = mu3 - sigma3 kappa3
    u3x = p[_U3X]
    u3y = p[_U3Y]
    e3x = -u3y
    e3y = u3x
    rho3 = rail - (u3x * c3x + u3y * c3y)
    h3 = c3z
    mu3sq = rho3 * rho3 + h3 * h3
    if not mu3sq > 0.0:
        # C3 on the revolute axis at B3: beta undefined, cannot be checked against its limits
        _grid.write_unreachable(out)
        return
    beta = math.atan2(h3, rho3)
    if beta < p[_BLO] or beta > p[_BHI]:
        _grid.write_unreachable(out)
        return
    mu3 = math.sqrt(mu3sq)
    l3 = p[_L3]
    lam3 = e3x * c3x + e3y * c3y
    k3sq = l3 * l3 - lam3 * lam3
    if k3sq < 0.0:
        _grid.write_unreachable(out)
        return
    k3 = math.sqrt(k3sq)
    s3 = mu3 - p[_SG3] * k3
    if s3 < slo or s3 > shi:
        _grid.write_unreachable(out)
        return
    if not every and not p[_FREE_ONLY] > 0.0:
        out[0] = 0.0  # reachable (point_reach); the clearance decides only with interference_free
        return
    # clearance (field 3) of the capsules of link_geometry: B_i = (u_i . C_i) u_i carries the slider to
    # D_i = B_i + s_i z; chain 3's prismatic runs from B3 = R u3 along d3 = (-rho3 u3 + h3 z) / mu3
    b3x = rail * u3x
    b3y = rail * u3y
    d3x = b3x - s3 * rho3 * u3x / mu3
    d3y = b3y - s3 * rho3 * u3y / mu3
    d3z = s3 * h3 / mu3
    p2x = -0.5 * p2
    p2y = SQRT3_2 * p2
    gap = 0.0
    if others or p[_FREE_ONLY] > 0.0:
        gap = _capsule_gap(p, rail, u3x, u3y, b3x, b3y, p2x, p2y, s1, s2, d3x, d3y, d3z, c1x, c1y, c1z, c2x, c2y,
                           c2z, c3x, c3y, c3z)
        if gap < 0.0 and p[_FREE_ONLY] > 0.0:
            _grid.write_unreachable(out)
            return
    if not every:
        out[0] = 0.0
        return
    if k1 == 0.0 or k2 == 0.0 or k3 == 0.0:
        _grid.write_singular(out)  # serial singularity: a link D_iC_i lies along e_i, J_t has an unbounded row
        if not others:
            return
        out[_F_CLEARANCE] = gap
        if stiffness and (p[_FX] != 0.0 or p[_FX + 1] != 0.0 or p[_FX + 2] != 0.0):
            out[_F_DEFLECTION] = _legs_k.DEFLECTION_CAP  # stiffness_min 0
        return
    if others:
        out[_F_CLEARANCE] = gap
    if stiffness and others:
        out[_F_STIFFNESS_MIN], out[_F_DEFLECTION] = _stiffness(
            p, x, y, z, c1x, c1y, c1z, s1, c2x, c2y, c2z, p2x, p2y, s2, c3x, c3y, c3z, b3x, b3y, d3x, d3y, d3z, s3,
            -rho3 * u3x / mu3, -rho3 * u3y / mu3, h3 / mu3, e3x, e3y)
    lci, smin, smax = _conditioning(p, conv_r, u3x, u3y, e3x, e3y, rho3, h3, mu3sq, mu3, lam1, k1, lam2, k2, lam3, k3)
    out[0] = lci
    if others:
        out[1], out[2] = inverse_singular_values(smin, smax)


# ----- reachable intervals of a z-column (closed form) ----------------------------------------------------
_MAX_CUTS = 11  # candidate heights per column: 2 per stroke limit of chains 1, 2; 4 of s3; 2 of beta; h3 = 0


@njit(cache=True, fastmath=FASTMATH)
def _put_cut(cuts, n, z, zlo, zhi):
    """Append the candidate height z to cuts[:n] if it lies strictly inside (zlo, zhi) (NaN never does)."""
    if zlo < z < zhi:
        cuts[n] = z
        return n + 1
    return n


@njit(cache=True, fastmath=FASTMATH)
def column_intervals(p, x, y, zlo, zhi, out):
    """Reachable set of the column (x, y, z in [zlo, zhi]) of O1 (mm) in closed form: writes its closed intervals
    [out[i, 0], out[i, 1]] (mm, i < k, sorted, disjoint with gaps between them, inside [zlo, zhi]) into out (float64,
    (K, 2)) and returns k >= 0: z is in one exactly where point_reach(p, x, y, z) >= 0, to rounding at the ends
    (isolated reachable heights, of zero length, are left out). -1 (out undefined) with interference_free (the
    clearance decides too) or when out has fewer rows than the column needs.

    At the fixed orientation the column moves the triangle vertically: w1, w2, lambda_i (so kappa_i) and rho3 are
    constant along it, s1 and s2 are z plus constants, h3 = z_C3 is z plus a constant, beta = atan2(h3, rho3) and
    s3 = sqrt(rho3^2 + h3^2) - sigma3 kappa3. Every reachability check can change only at the heights where s1, s2
    or s3 meets a stroke limit, beta a beta limit, or h3 = 0 (atan2's branch cut and mu3 = 0): those candidates cut
    the column into pieces on which each check is constant, so each piece is classified at its midpoint with
    point_reach's checks (in its arithmetic; those that do not depend on z once per column) and neighbouring
    reachable pieces are merged."""
    if p[_FREE_ONLY] > 0.0:
        return -1
    if not zlo <= zhi:  # also NaN
        return 0
    slo = p[_SLO]
    shi = p[_SHI]
    cuts = np.empty(_MAX_CUTS + 2)
    cuts[0] = zlo
    n = 1
    # kappa_i as _fields computes them (NaN where the link cannot reach: no cut, and every piece is unreachable)
    lam1 = y + p[_R1 + 1]
    k1 = math.sqrt(p[_L1] * p[_L1] - lam1 * lam1) if p[_L1] * p[_L1] - lam1 * lam1 >= 0.0 else math.nan
    c2x = x + p[_R2]
    c2y = y + p[_R2 + 1]
    lam2 = -SQRT3_2 * c2x - 0.5 * c2y
    k2 = math.sqrt(p[_L2] * p[_L2] - lam2 * lam2) if p[_L2] * p[_L2] - lam2 * lam2 >= 0.0 else math.nan
    u3x = p[_U3X]
    u3y = p[_U3Y]
    c3x = x + p[_R3]
    c3y = y + p[_R3 + 1]
    lam3 = -u3y * c3x + u3x * c3y
    k3 = math.sqrt(p[_L3] * p[_L3] - lam3 * lam3) if p[_L3] * p[_L3] - lam3 * lam3 >= 0.0 else math.nan
    rho = p[_RAIL] - (u3x * c3x + u3y * c3y)
    arho = abs(rho)
    r3z = p[_R3 + 2]
    for s in (slo, shi):
        # s_i = z + r_iz - sigma_i kappa_i (chains 1, 2)
        n = _put_cut(cuts, n, s + p[_SG1] * k1 - p[_R1 + 2], zlo, zhi)
        n = _put_cut(cuts, n, s + p[_SG2] * k2 - p[_R2 + 2], zlo, zhi)
        # s3 = s: mu3 = m = s + sigma3 kappa3, h3 = +-sqrt(m^2 - rho^2) (factored: no cancellation near m = |rho|)
        m = s + p[_SG3] * k3
        if m >= arho:
            h = math.sqrt((m - arho) * (m + arho))
            n = _put_cut(cuts, n, h - r3z, zlo, zhi)
            n = _put_cut(cuts, n, -h - r3z, zlo, zhi)
    for b in (p[_BLO], p[_BHI]):
        # atan2(h3, rho) = b on the half-line of direction (cos b, sin b): h3 = rho tan b where rho cos b > 0
        cb = math.cos(b)
        if rho * cb > 0.0:
            n = _put_cut(cuts, n, rho * (math.sin(b) / cb) - r3z, zlo, zhi)
    n = _put_cut(cuts, n, -r3z, zlo, zhi)  # h3 = 0
    cuts[n] = zhi
    n += 1
    sort_span(cuts, 1, n - 1)  # the candidates between zlo and zhi
    # each piece is classified at its midpoint with point_reach's checks (_fields up to its reach verdict), in its
    # arithmetic, so the same verdicts (tests/test_pprs_intervals.py compares them point by point): those that do
    # not depend on z once for the column (the rails, and kappa_i real), the others per piece (the strokes s1, s2,
    # s3 and beta). A point_reach call per piece repeated the column's checks: 0.342 against 0.185 us per column
    # in one A/B (benchmarks/notes/pprs_rprs.md; `python benchmarks/pprs_columns.py ab` times this kernel)
    c1x = x + p[_R1]
    w1 = p[_RAIL] - c1x if p[_CONV] > 0.0 else c1x
    p2 = -0.5 * c2x + SQRT3_2 * c2y
    w2 = p[_RAIL] - p2 if p[_CONV] > 0.0 else p2
    if (w1 < p[_WLO] or w1 > p[_WHI] or w2 < p[_WLO] or w2 > p[_WHI]
            or not (k1 >= 0.0 and k2 >= 0.0 and k3 >= 0.0)):  # NaN: the link cannot reach
        return 0
    k = 0
    for i in range(n - 1):
        a = cuts[i]
        b = cuts[i + 1]
        if not b > a:
            continue  # a piece of zero length: neither extends nor ends an interval
        z = 0.5 * (a + b)
        s1 = (z + p[_R1 + 2]) - p[_SG1] * k1
        s2 = (z + p[_R2 + 2]) - p[_SG2] * k2
        h3 = z + r3z
        mu3sq = rho * rho + h3 * h3
        if s1 < slo or s1 > shi or s2 < slo or s2 > shi or not mu3sq > 0.0:
            continue
        beta = math.atan2(h3, rho)
        s3 = math.sqrt(mu3sq) - p[_SG3] * k3
        if beta < p[_BLO] or beta > p[_BHI] or s3 < slo or s3 > shi:
            continue
        k = add_piece(out, k, a, b)
        if k < 0:
            return -1
    return k


# ----- NumPy kinematics ----------------------------------------------------------------------------------
def rotation(phi, theta, psi) -> np.ndarray:
    """R = Rz(phi) Ry(theta) Rx(psi) for scalars or arrays of angles (rad); shape (..., 3, 3)."""
    cf, sf = np.cos(phi), np.sin(phi)
    ct, st = np.cos(theta), np.sin(theta)
    cp, sp = np.cos(psi), np.sin(psi)
    return np.stack(
        [
            np.stack([cf * ct, cf * st * sp - sf * cp, cf * st * cp + sf * sp], axis=-1),
            np.stack([sf * ct, sf * st * sp + cf * cp, sf * st * cp - cf * sp], axis=-1),
            np.stack([-st, ct * sp, ct * cp], axis=-1),
        ],
        axis=-2,
    )


def euler_angles(rot: np.ndarray) -> tuple[float, float, float]:
    """(phi, theta, psi) rad with rotation(phi, theta, psi) = rot (3, 3), theta in [-pi/2, pi/2]."""
    theta = -math.asin(max(-1.0, min(1.0, float(rot[2, 0]))))
    return math.atan2(rot[1, 0], rot[0, 0]), theta, math.atan2(rot[2, 1], rot[2, 2])


def _rodrigues(w: np.ndarray) -> np.ndarray:
    """Rotation matrix (3, 3) of the rotation vector w (3,) rad (Rodrigues' formula)."""
    angle = float(np.linalg.norm(w))
    if angle == 0.0:
        return np.eye(3)
    k = np.asarray(w, dtype=float) / angle
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * kx + (1.0 - math.cos(angle)) * (kx @ kx)


@dataclass(frozen=True)
class Geometry:
    """Resolved geometry (mm, rad): rails u_i and normals e_i = z x u_i (rows), body vectors c_i' (rows)."""

    r: float
    rail: float
    links: np.ndarray
    u: np.ndarray
    e: np.ndarray
    body: np.ndarray
    conv_r: bool
    beta_length: float
    angle_length: float

    @classmethod
    def of(cls, design: Mapping[str, float], options: Mapping[str, Any]) -> Geometry:
        r = float(design["r"])
        az = math.radians(options["chain3_azimuth_deg"])
        u = np.array([[1.0, 0.0, 0.0], [-0.5, SQRT3_2, 0.0], [math.cos(az), math.sin(az), 0.0]])
        e = np.stack([-u[:, 1], u[:, 0], np.zeros(3)], axis=1)
        body = np.array([[r, 0.0, 0.0], [-0.5 * r, SQRT3_2 * r, 0.0], [-0.5 * r, -SQRT3_2 * r, 0.0]])
        bl = options.get("beta_length")
        al = options.get("angle_length")
        return cls(
            r=r,
            rail=float(design["R"]),
            links=np.array([design["L1"], design["L2"], design["L3"]], dtype=float),
            u=u,
            e=e,
            body=body,
            conv_r=options["w_convention"] == "R",
            beta_length=float(design["R"] if bl is None else bl),
            angle_length=float(r if al is None else al),
        )


def sigma_vector(label: str) -> np.ndarray:
    """Branch label such as '+-+' as a vector of +-1."""
    return np.array([1.0 if ch == "+" else -1.0 for ch in label])


@dataclass(frozen=True)
class ChainState:
    """IK of one or many poses for one branch: q (..., 6) and the intermediates of spec §1.3.

    ``ok`` is False where a link cannot reach (|lambda_i| > L_i) or beta is undefined (mu3 = 0); q is NaN there.
    """

    q: np.ndarray
    ok: np.ndarray
    rk: np.ndarray  # (..., 3, 3): r_k = R c_k'
    centres: np.ndarray  # (..., 3, 3): C_k
    lam: np.ndarray  # (..., 3)
    kappa: np.ndarray  # (..., 3)
    rho3: np.ndarray
    h3: np.ndarray
    mu3: np.ndarray
    sigma: np.ndarray


def chain_state(geo: Geometry, X: np.ndarray, sigma: np.ndarray, reach_tol: float = 1e-12) -> ChainState:
    """Closed-form IK (spec §1.3) of poses X (..., 6) for branch signs sigma (3,). A pose within
    ``reach_tol * L_i`` of a reach boundary is accepted with kappa_i = 0 (double root)."""
    X = np.asarray(X, dtype=float)
    rot = rotation(X[..., 3], X[..., 4], X[..., 5])
    rk = np.einsum("...ij,kj->...ki", rot, geo.body)
    centres = X[..., None, :3] + rk
    proj = np.einsum("...kj,kj->...k", centres, geo.u)
    lam = np.einsum("...kj,kj->...k", centres, geo.e)
    k2 = geo.links**2 - lam**2
    rho3 = geo.rail - proj[..., 2]
    h3 = centres[..., 2, 2]
    mu3 = np.hypot(rho3, h3)
    ok = np.all(k2 >= -2.0 * reach_tol * geo.links**2, axis=-1) & (mu3 > 0.0)
    kappa = np.sqrt(np.maximum(k2, 0.0))
    w = geo.rail - proj[..., :2] if geo.conv_r else proj[..., :2]
    s12 = centres[..., :2, 2] - sigma[:2] * kappa[..., :2]
    s3 = mu3 - sigma[2] * kappa[..., 2]
    q = np.stack([w[..., 0], w[..., 1], np.arctan2(h3, rho3), s12[..., 0], s12[..., 1], s3], axis=-1)
    q = np.where(ok[..., None], q, np.nan)
    return ChainState(q, ok, rk, centres, lam, kappa, rho3, h3, mu3, np.asarray(sigma, dtype=float))


def actuator_directions(geo: Geometry, st: ChainState) -> np.ndarray:
    """g_j of spec §1.5 (q_dot_j = g_j . C_dot_k), shape (..., 6, 3); inf/NaN at a serial singularity."""
    shape = st.lam.shape[:-1]
    z = np.zeros(shape + (3,))
    z[..., 2] = 1.0
    g = np.empty(shape + (6, 3))
    wsign = -1.0 if geo.conv_r else 1.0
    g[..., 0, :] = wsign * geo.u[0]
    g[..., 1, :] = wsign * geo.u[1]
    mu2 = st.mu3**2
    with np.errstate(divide="ignore", invalid="ignore"):
        g[..., 2, :] = (st.rho3[..., None] * z + st.h3[..., None] * geo.u[2]) / mu2[..., None]
        ratio = st.sigma * st.lam / st.kappa
        g[..., 3, :] = z + ratio[..., 0, None] * geo.e[0]
        g[..., 4, :] = z + ratio[..., 1, None] * geo.e[1]
        d3 = (-st.rho3[..., None] * geo.u[2] + st.h3[..., None] * z) / st.mu3[..., None]
        g[..., 5, :] = d3 + ratio[..., 2, None] * geo.e[2]
    return g


def twist_jacobian(geo: Geometry, st: ChainState) -> np.ndarray:
    """J_t (..., 6, 6): q_dot = J_t [v; omega], row j = [g_j, r_k x g_j] (spec §1.5)."""
    g = actuator_directions(geo, st)
    r = st.rk[..., CHAIN_OF_JOINT, :]
    return np.concatenate([g, np.cross(r, g)], axis=-1)


def euler_rate_map(X: np.ndarray) -> np.ndarray:
    """T (..., 6, 6) with [v; omega] = T X_dot: omega = phi' z + theta' Rz(phi) y + psi' Rz(phi) Ry(theta) x."""
    X = np.asarray(X, dtype=float)
    phi, theta = X[..., 3], X[..., 4]
    t = np.zeros(X.shape[:-1] + (6, 6))
    t[..., 0, 0] = t[..., 1, 1] = t[..., 2, 2] = 1.0
    t[..., 5, 3] = 1.0
    t[..., 3, 4] = -np.sin(phi)
    t[..., 4, 4] = np.cos(phi)
    t[..., 3, 5] = np.cos(phi) * np.cos(theta)
    t[..., 4, 5] = np.sin(phi) * np.cos(theta)
    t[..., 5, 5] = -np.sin(theta)
    return t


def scaled(geo: Geometry, jt: np.ndarray) -> np.ndarray:
    """The homogenised Jacobian whose LCI is reported: beta row * beta_length, angular columns / angle_length."""
    row = np.array([1.0, 1.0, geo.beta_length, 1.0, 1.0, 1.0])
    col = np.array([1.0, 1.0, 1.0, 1.0 / geo.angle_length, 1.0 / geo.angle_length, 1.0 / geo.angle_length])
    return jt * row[:, None] * col[None, :]


def normalise_euler(X: np.ndarray) -> np.ndarray:
    """Pick the representative of the Euler duplicate pair (phi+pi, pi-theta, psi+pi) with theta in
    [-pi/2, pi/2], all angles in (-pi, pi] (spec §1.4 item 3)."""
    X = np.array(X, dtype=float)
    theta = wrap_angle(X[..., 4])
    flip = np.abs(theta) > np.pi / 2
    X[..., 3] = wrap_angle(np.where(flip, X[..., 3] + np.pi, X[..., 3]))
    X[..., 4] = np.where(flip, wrap_angle(np.pi - theta), theta)
    X[..., 5] = wrap_angle(np.where(flip, X[..., 5] + np.pi, X[..., 5]))
    return X


def newton_fk(
    geo: Geometry, sigma: np.ndarray, q: np.ndarray, starts: np.ndarray, max_iter: int = 60
) -> tuple[np.ndarray, np.ndarray]:
    """Newton-Raphson on IK(X) - q = 0 from every start (n, 6) at once, with the analytic pose Jacobian
    J = J_t T, pseudo-inverse steps and step halving (spec §1.4). ``q`` is one input vector (6,) or one per
    start (n, 6). Returns (X (n, 6), converged (n,)).

    Residuals are compared in mm, the beta residual multiplied by R. Converged means the residual reached
    1e-12 of max(1, |q|) (round-off level) within ``max_iter`` iterations.
    """
    X = np.array(starts, dtype=float, copy=True)
    q = np.broadcast_to(np.asarray(q, dtype=float), X.shape)
    weight = np.array([1.0, 1.0, geo.rail, 1.0, 1.0, 1.0])
    tol = 1e-12 * np.maximum(1.0, np.max(np.abs(q * weight), axis=-1))

    def residual(Xs, rows):
        st = chain_state(geo, Xs, sigma)
        res = st.q - q[rows]
        res[..., 2] = wrap_angle(res[..., 2])
        err = np.max(np.abs(res * weight), axis=-1)
        return res, np.where(st.ok, err, np.inf)

    res, err = residual(X, np.arange(X.shape[0]))
    alive = np.isfinite(err)
    done = alive & (err <= tol)
    for _ in range(max_iter):
        act = np.nonzero(alive & ~done)[0]
        if act.size == 0:
            break
        sub = chain_state(geo, X[act], sigma)
        with np.errstate(invalid="ignore", divide="ignore"):
            jac = twist_jacobian(geo, sub) @ euler_rate_map(X[act])
        bad = ~np.all(np.isfinite(jac), axis=(-2, -1))  # a serial singularity: no Newton step from there
        jac[bad] = 0.0
        step = -np.einsum("nij,nj->ni", np.linalg.pinv(jac), res[act])
        alpha = np.ones(act.size)
        pending = ~bad
        for _half in range(40):
            idx = np.nonzero(pending)[0]
            if idx.size == 0:
                break
            rows = act[idx]
            trial = X[rows] + alpha[idx, None] * step[idx]
            tres, terr = residual(trial, rows)
            better = terr < err[rows]
            acc = rows[better]
            X[acc] = trial[better]
            res[acc] = tres[better]
            err[acc] = terr[better]
            pending[idx[better]] = False
            alpha[idx[~better]] *= 0.5
        # no decrease along the Newton direction: a local minimum of |G| (no assembly) or the round-off floor
        alive[act[pending | bad]] = False
        done |= alive & (err <= tol)
    # polish: converged rows take full Newton steps while the residual does not grow (down to round-off)
    for _ in range(3):
        rows = np.nonzero(done)[0]
        if rows.size == 0:
            break
        with np.errstate(invalid="ignore", divide="ignore"):
            jac = twist_jacobian(geo, chain_state(geo, X[rows], sigma)) @ euler_rate_map(X[rows])
        fine = np.all(np.isfinite(jac), axis=(-2, -1))
        rows, jac = rows[fine], jac[fine]
        trial = X[rows] - np.einsum("nij,nj->ni", np.linalg.pinv(jac), res[rows])
        tres, terr = residual(trial, rows)
        keep = terr <= err[rows]
        X[rows[keep]], res[rows[keep]], err[rows[keep]] = trial[keep], tres[keep], terr[keep]
    return X, done


def dedupe(X: np.ndarray, length: float, tol: float = 1e-6) -> np.ndarray:
    """Distinct rows of X (first occurrence kept), comparing positions in mm and angles times ``length``."""
    out: list[np.ndarray] = []
    for x in X:
        if all(_pose_distance(x, y, length) > tol for y in out):
            out.append(x)
    return np.array(out).reshape(-1, 6)


def _pose_distance(a: np.ndarray, b: np.ndarray, length: float) -> float:
    return max(float(np.max(np.abs(a[:3] - b[:3]))), length * float(np.max(np.abs(wrap_angle(a[3:] - b[3:])))))


# ----- the mechanism ---------------------------------------------------------------------------------------
class PprsRprs(Mechanism):
    """Seed-001 mechanism; see module docstring. FK solutions are full poses named by ``pose_axes``."""

    # the adaptive evaluator's plans (scalesynth.evaluation.plans). Node plan (interference_free only: else the
    # interval plan): the 3-D default; searched before its box pad (bounding_box) and column intervals: none of 332
    # plans (against N = 192) was within 0.8x on seed 0, the default included (0.96x); N = 192 is itself up to 1.35x
    # off N = 384 on seed-0 designs, and the default is 1.9x off N = 768 on a seed-1 design (0.36 % too large, its
    # own estimate 0.88x: it stops early; benchmarks/notes/adaptive_plans.md)
    node_plan = None
    # interval plan: its workspaces are thin slabs (median 27-28 mm of a 215-256 mm box) whose columns hold one
    # interval, so 1 z-cell and the midpoint rule serve the fields; its refinement is driven by walls (vertical planes
    # of the rail and link limits), where the measure jumps but the LCI does not, so the refined columns inherit their
    # fields (field_levels 0, kernels.adaptive step 3b) and refine 4 times less eagerly (beta 4): (24, 1, 5, 3,
    # beta 4, no faces, fields on level 0, 1 Gauss point) is within 0.68x / 0.54x / 0.76x / 0.78x / 0.63x (volume,
    # against the exact volume of the column intervals on a 2400^2 cross grid) and 0.47x / 0.51x / 0.50x / 0.56x /
    # 0.76x (GCI, against 324^2 columns of exact intervals with fields everywhere) on seeds 0-4 at 2 056-2 609 calls
    # per design, where the plan before, (24, 2, 5, 3, beta 1, faces), took 5 341-6 793 and was 1.14x off on a seed-3
    # design; 12 or 16 columns miss small workspaces (1.52x, 1.16x on seed 1) (benchmarks/pprs_columns.py,
    # benchmarks/notes/pprs_rprs.md)
    interval_plan = ColumnPlan(24, 1, 5, 3, beta=4.0, field_levels=0, gauss_points=1)

    pose_axes = ("x", "y", "z", "phi", "theta", "psi")

    def check_options(self, options: dict[str, Any]) -> None:
        orient = options["orientation"]
        if not isinstance(orient, (list, tuple, np.ndarray)) or len(orient) != 3:
            raise InvalidParameter(f"options.orientation: expected [phi, theta, psi] in rad, got {orient!r}")
        options["orientation"] = tuple(_finite(f"options.orientation[{i}]", v) for i, v in enumerate(orient))
        if not isinstance(options["sigma"], str) or options["sigma"] not in BRANCHES:
            raise InvalidParameter(
                f"options.sigma: expected three signs from '+-' such as '+++', got {options['sigma']!r}"
            )
        for name in ("w_limits", "s_limits", "beta_limits"):
            value = parse_range(name, options[name])
            if value is None:
                raise InvalidParameter(f"options.{name}: actuator limits are required, got null")
            options[name] = value
        lo, hi = options["beta_limits"]
        if lo < -math.pi or hi > math.pi:
            raise InvalidParameter(f"options.beta_limits: expected radians within [-pi, pi], got [{lo:g}, {hi:g}]")
        options["chain3_azimuth_deg"] = _finite("options.chain3_azimuth_deg", options["chain3_azimuth_deg"])
        if options["w_convention"] not in CONVENTIONS:
            raise InvalidParameter(f"options.w_convention: must be 'O' or 'R', got {options['w_convention']!r}")
        for name in ("beta_length", "angle_length"):
            value = options[name]
            if value is not None:
                value = _finite(f"options.{name}", value)
                if value <= 0.0:
                    raise InvalidParameter(f"options.{name}: must be > 0 (a length in mm) or null, got {value:g}")
                options[name] = value
        links.check_radius_option(options, LINK_RADII)
        links.check_flag_option(options, "interference_free")
        check_stiffness_options(options, 3, LINK_GROUPS)
        check_positive_option(options, "beta_stiffness")

    # ----- kernel side -------------------------------------------------------------------------------
    def pack(self, design: Mapping[str, float], options: Mapping[str, Any]) -> np.ndarray:
        geo = Geometry.of(design, options)
        rot = rotation(*options["orientation"])
        p = np.empty(N_PACKED)
        p[_R1 : _R3 + 3] = (geo.body @ rot.T).ravel()
        p[_U3X], p[_U3Y] = geo.u[2, 0], geo.u[2, 1]
        p[_RAIL] = geo.rail
        p[_L1], p[_L2], p[_L3] = geo.links
        p[_SG1:_SG3 + 1] = sigma_vector(options["sigma"])
        p[_CONV] = 1.0 if geo.conv_r else 0.0
        p[_WLO], p[_WHI] = options["w_limits"]
        p[_SLO], p[_SHI] = options["s_limits"]
        p[_BLO], p[_BHI] = options["beta_limits"]
        p[_BLEN] = geo.beta_length
        p[_ALEN] = geo.angle_length
        p[_RAD : _RAD + 8] = list(links.radii(options, LINK_RADII).values())
        p[_FREE_ONLY] = 1.0 if options["interference_free"] else 0.0
        from scalesynth.stiffness.sections import tube_section

        for o, group in ((_EA_COL, "column"), (_EA_LINK, "link")):
            sec = tube_section(options, group, "mm")
            p[o], p[o + 1], p[o + 2] = sec.EA, sec.EI, sec.GJ
        p[_KACT], p[_KBETA] = options["actuator_stiffness"], options["beta_stiffness"]
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
        """column_intervals(p, x, y, zlo, zhi, out) -> k: the reachable intervals of a z-column in closed form (-1:
        not handled, evaluate points with reach_kernel instead)."""
        return column_intervals

    def interval_kernel_for(self, options):
        """None with interference_free (the clearance then decides reachability too: column_intervals returns -1
        on every column), else the interval kernel."""
        return None if options["interference_free"] else column_intervals

    def kernel_branch(self, options) -> str:
        return options["sigma"]

    def bounding_box(self, design, options):
        """Box of O1 implied by the actuator limits at the fixed orientation (it holds every reachable position,
        so no other box clips it: the spec §1.8 search box, +-300 x +-300 x 0-500 mm, once did, and a design
        beyond it read volume 0, issue 27; grid.region clips on purpose). x: u1.C1 = x + r1x is w1 (or R - w1);
        y: from u2.C2 (w2) given x, and |lambda1| = |y + r1y| <= L1, widened by Y_PAD (3.09 %) of its span on
        each side where both y faces come from w2; z: z_Ci = s_i + sigma_i kappa_i with 0 <= kappa_i <= L_i, for
        chains 1 and 2."""
        geo = Geometry.of(design, options)
        rk = geo.body @ rotation(*options["orientation"]).T
        wlo, whi = options["w_limits"]
        plo, phi_ = (geo.rail - whi, geo.rail - wlo) if geo.conv_r else (wlo, whi)
        xlo, xhi = plo - rk[0, 0], phi_ - rk[0, 0]
        u2 = geo.u[1]
        a_lo, a_hi = plo - u2 @ rk[1], phi_ - u2 @ rk[1]  # u2 . p
        # y = (u2.p - u2x x) / u2y with u2x < 0 < u2y
        ylo_w2, yhi_w2 = (a_lo - u2[0] * xlo) / u2[1], (a_hi - u2[0] * xhi) / u2[1]
        ylo = max(ylo_w2, -geo.links[0] - rk[0, 1])
        yhi = min(yhi_w2, geo.links[0] - rk[0, 1])
        if ylo == ylo_w2 and yhi == yhi_w2:
            # both y faces come from the w2 limits: then the y span is sqrt3 times the x span and the w2 walls
            # (slope 1/sqrt3, through the corners (xlo, ylo) and (xhi, yhi)) run through a line of cell centres of
            # every cell-centred grid over the box (every third column, any N), whose reachability rounding decides:
            # a first-order error of half a strip of columns (+2 to +3 % of the volume at 24 columns per axis,
            # 0.5-0.8 % at N = 96). Widening y by the irrational Y_PAD of its span on each side puts the walls in
            # general position (benchmarks/notes/pprs_rprs.md)
            pad = Y_PAD * (yhi - ylo)
            ylo, yhi = ylo - pad, yhi + pad
        slo, shi = options["s_limits"]
        sig = sigma_vector(options["sigma"])
        zlo, zhi = -math.inf, math.inf
        for k in (0, 1):
            lo_k = slo - (geo.links[k] if sig[k] < 0 else 0.0)
            hi_k = shi + (geo.links[k] if sig[k] > 0 else 0.0)
            zlo, zhi = max(zlo, lo_k - rk[k, 2]), min(zhi, hi_k - rk[k, 2])
        lo = np.array([xlo, ylo, zlo])
        hi = np.array([xhi, yhi, zhi])
        return lo, np.maximum(hi, lo)

    # ----- NumPy kinematics ----------------------------------------------------------------------------
    def full_pose(self, options: Mapping[str, Any], pose) -> np.ndarray:
        """(x, y, z) with the options' orientation, or a full (x, y, z, phi, theta, psi) pose (mm, rad)."""
        arr = np.asarray(pose, dtype=float) if _is_vector(pose) else None
        if arr is None or arr.shape not in ((3,), (6,)) or not np.all(np.isfinite(arr)):
            raise InvalidPose(f"pose: expected 3 (x, y, z) or 6 (x, y, z, phi, theta, psi) numbers, got {pose!r}")
        return np.concatenate([arr, options["orientation"]]) if arr.shape == (3,) else arr

    def inverse_kinematics(self, design, options, pose) -> list[Solution]:
        """All eight sign branches (sigma1 sigma2 sigma3, '+' = D_i below C_i) as (w1, w2, beta, s1, s2, s3) in
        mm and rad, limits not applied; [] if a link cannot reach its sphere centre."""
        X = self.full_pose(options, pose)
        geo = Geometry.of(design, options)
        out = []
        for label in BRANCHES:
            st = chain_state(geo, X, sigma_vector(label))
            if not st.ok:
                return []
            out.append(Solution(label, st.q))
        return out

    def forward_kinematics(
        self, design, options, inputs, *, guess=None, starts: int = 200, seed: int = 0
    ) -> list[Solution]:
        """Assembly modes of inputs (w1, w2, beta, s1, s2, s3) in the working mode ``options.sigma``, as poses
        (x, y, z, phi, theta, psi), Euler duplicates normalised to theta in [-pi/2, pi/2].

        Newton (spec §1.4) from X0 = (0, 0, s1 + L1, 0, 0, 0), from ``guess`` if given (continuation), and from
        ``starts`` seeded pseudo-random poses (|x|, |y| <= R, z in [0, s_max + L], angles within +-60 deg);
        deterministic for a given ``seed``. Labels: '<sigma>#k'; #1 is the mode reached from ``guess`` (or X0)
        when that start converges; the others follow in order of distance from it. A multi-start search
        cannot prove that no other mode exists.
        """
        q = self.check_vector("inputs", inputs, 6)
        geo = Geometry.of(design, options)
        sigma = sigma_vector(options["sigma"])
        first = [np.array([0.0, 0.0, q[3] + geo.links[0], 0.0, 0.0, 0.0])]
        if guess is not None:
            first.insert(0, self.full_pose(options, guess))
        rng = np.random.default_rng(seed)
        zmax = max(float(np.max(q[3:])), 0.0) + float(np.max(geo.links))
        lo = np.array([-geo.rail, -geo.rail, 0.0, -math.pi / 3, -math.pi / 3, -math.pi / 3])
        hi = np.array([geo.rail, geo.rail, zmax, math.pi / 3, math.pi / 3, math.pi / 3])
        rand = lo + (hi - lo) * rng.random((starts, 6))
        X, ok = newton_fk(geo, sigma, q, np.vstack([np.array(first), rand]))
        found = dedupe(normalise_euler(X[ok]), geo.r)
        if found.shape[0] > 1:
            dist = [_pose_distance(found[0], f, geo.r) for f in found[1:]]
            found = np.vstack([found[:1], found[1:][np.argsort(dist, kind="stable")]])
        return [Solution(f"{options['sigma']}#{k + 1}", f) for k, f in enumerate(found)]

    def branch_of(self, design, options, pose, q) -> str:
        """Sign branch of joint values q at a pose: sigma_i = '+' when D_i is not above C_i."""
        X = self.full_pose(options, pose)
        q = self.check_vector("inputs", q, 6)
        st = chain_state(Geometry.of(design, options), X, np.ones(3))
        if not st.ok:
            raise InvalidPose(f"pose: out of reach ({', '.join(f'{v:g}' for v in X)})")
        # for sigma = +1, q(s) = base - kappa, so base - q_s = sigma * kappa
        base = np.array([st.centres[0, 2], st.centres[1, 2], st.mu3])
        return "".join("+" if b - s >= 0.0 else "-" for b, s in zip(base, q[3:], strict=True))

    def _state_at(self, design, options, pose, q) -> tuple[np.ndarray, Geometry, ChainState]:
        """Full pose, geometry and chain state of the branch that q takes at the pose."""
        X = self.full_pose(options, pose)
        geo = Geometry.of(design, options)
        return X, geo, chain_state(geo, X, sigma_vector(self.branch_of(design, options, X, q)))

    def jacobians(self, design, options, pose, q) -> dict[str, np.ndarray]:
        """J_t (twist), T (Euler rates), the pose Jacobian J = J_t T and the homogenised J_t whose LCI is
        reported ("Js"), for the branch of q at the pose. Rows w1, w2, beta, s1, s2, s3."""
        X, geo, st = self._state_at(design, options, pose, q)
        jt = twist_jacobian(geo, st)
        t = euler_rate_map(X)
        return {"Jt": jt, "T": t, "J": jt @ t, "Js": scaled(geo, jt)}

    def singularity(self, design, options, pose, q, tol: float = 1e-7) -> str:
        """'inverse' (serial: kappa_i <= tol L_i, or mu3 <= tol R), 'forward' (parallel: the row-normalised
        homogenised J_t with kappa_i and mu3 multiplied out has sigma_min / sigma_max <= tol), 'both', 'none'."""
        X, geo, st = self._state_at(design, options, pose, q)
        inverse = bool(np.any(st.kappa <= tol * geo.links) or st.mu3 <= tol * geo.rail)
        # A t = B q_dot with B = diag(1, 1, mu3^2, kappa1, kappa2, kappa3): A stays finite where J_t does not
        g = actuator_directions(geo, st)
        with np.errstate(invalid="ignore"):
            g[2] *= st.mu3**2
            # kappa_i g_j -> sigma_i lambda_i e_i as kappa_i -> 0
            limit = st.sigma[:, None] * st.lam[:, None] * geo.e
            g[3:] = np.where(st.kappa[:, None] > 0, g[3:] * st.kappa[:, None], limit)
        a = np.concatenate([g, np.cross(st.rk[list(CHAIN_OF_JOINT)], g) / geo.angle_length], axis=-1)
        a /= np.linalg.norm(a, axis=1, keepdims=True)
        sv = np.linalg.svd(a, compute_uv=False)
        forward = bool(sv[-1] <= tol * sv[0])
        return singularity_label(inverse, forward)

    def lci(self, design, options, pose, q) -> float:
        """LCI = sigma_min / sigma_max of the homogenised J_t (NumPy SVD); 0 at a serial singularity."""
        X, geo, st = self._state_at(design, options, pose, q)
        if np.any(st.kappa == 0.0) or st.mu3 == 0.0:
            return 0.0
        sv = np.linalg.svd(scaled(geo, twist_jacobian(geo, st)), compute_uv=False)
        return float(sv[-1] / sv[0])

    def link_geometry(self, design, options, pose, q) -> links.LinkGeometry:
        """Capsules (mm) at a pose (x, y, z[, phi, theta, psi]) with inputs q: base = the rails O -> R u_1,
        O -> R u_2 and the strut O -> B3; slider_i the vertical slider B_i -> D_i = B_i + s_i z on its carriage
        (chains 1, 2); leg3 the tilting prismatic B3 -> D3 = B3 + s3 d3; link_i D_i -> C_i; platform the triangle
        C1 C2 C3. Adjacent: base-slider1, base-slider2, base-leg3, slider_i-link_i, leg3-link3,
        link_i-platform. Radii: option ``link_radius``, defaults LINK_RADII."""
        X = self.full_pose(options, pose)
        w1, w2, beta, s1, s2, s3 = self.check_vector("inputs", q, 6)
        geo = Geometry.of(design, options)
        c = X[:3] + geo.body @ rotation(*X[3:]).T  # rows C_1, C_2, C_3
        rad = links.radii(options, LINK_RADII)
        z = np.array([0.0, 0.0, 1.0])
        o = np.zeros(3)
        b = [(geo.rail - w if geo.conv_r else w) * geo.u[k] for k, w in enumerate((w1, w2))]
        d = [b[0] + s1 * z, b[1] + s2 * z]
        b3 = geo.rail * geo.u[2]
        d3 = b3 + s3 * (-math.cos(beta) * geo.u[2] + math.sin(beta) * z)
        parts = [
            ("rail1", "base", o, geo.rail * geo.u[0]), ("rail2", "base", o, geo.rail * geo.u[1]),
            ("strut3", "base", o, b3),
            ("slider1", "slider1", b[0], d[0]), ("slider2", "slider2", b[1], d[1]), ("leg3", "leg3", b3, d3),
            ("link1", "link1", d[0], c[0]), ("link2", "link2", d[1], c[1]), ("link3", "link3", d3, c[2]),
            ("platform12", "platform", c[0], c[1]), ("platform23", "platform", c[1], c[2]),
            ("platform31", "platform", c[2], c[0]),
        ]
        segments = tuple(links.Segment(n, body, np.array(a), np.array(e), rad[body]) for n, body, a, e in parts)
        return links.LinkGeometry(segments, links.adjacency([
            ("base", "slider1"), ("base", "slider2"), ("base", "leg3"), ("slider1", "link1"), ("slider2", "link2"),
            ("leg3", "link3"), ("link1", "platform"), ("link2", "platform"), ("link3", "platform"),
        ]))

    def link_endpoints(self, design, options, poses, q) -> np.ndarray:
        """Vectorised twin of link_geometry's segment endpoints at poses (m, 3) (the options' orientation) or (m, 6)
        with inputs q (m, 6): links.SegmentPoints, segments in link_geometry's order."""
        pts, q = np.asarray(poses, dtype=float), np.asarray(q, dtype=float)
        geo = Geometry.of(design, options)
        if pts.shape[1] == 3:  # one rotation for every pose, as full_pose adds it
            off = geo.body @ rotation(*np.asarray(options["orientation"], dtype=float)).T
            c = [pts + off[i] for i in range(3)]
        else:
            rot = rotation(pts[:, 3], pts[:, 4], pts[:, 5])
            c = [pts[:, :3] + np.einsum("mij,j->mi", rot, geo.body[i]) for i in range(3)]
        w1, w2, beta, s1, s2, s3 = q.T
        b = [np.multiply.outer(geo.rail - w if geo.conv_r else w, geo.u[k]) for k, w in enumerate((w1, w2))]
        d = [(b[0][:, 0], b[0][:, 1], b[0][:, 2] + s1), (b[1][:, 0], b[1][:, 1], b[1][:, 2] + s2)]
        b3 = geo.rail * geo.u[2]
        d3 = b3 + s3[:, None] * (-np.cos(beta)[:, None] * geo.u[2] + np.sin(beta)[:, None] * np.array([0.0, 0.0, 1.0]))
        o = np.zeros(3)
        return links.segment_points([
            (o, geo.rail * geo.u[0]), (o, geo.rail * geo.u[1]), (o, b3), (b[0], d[0]), (b[1], d[1]), (b3, d3),
            (d[0], c[0]), (d[1], c[1]), (d3, c[2]), (c[0], c[1]), (c[1], c[2]), (c[2], c[0])], len(pts))

    def velocity_map(self, design, options, pose, q) -> np.ndarray:
        """The twist Jacobian J_t (6 x 6): q_dot = J_t [v; omega]; the task axes are v (mm/s), the held
        orientation's angular velocity omega (rad/s) is 0 along a constant-orientation cycle (spec §1.5)."""
        return self.jacobians(design, options, pose, q)["Jt"]

    def cycle_kinematics(self, design, options, poses, label: str) -> tuple[np.ndarray, np.ndarray]:
        """Vectorised twin of Mechanism.cycle_kinematics: chain_state of branch ``label`` at every pose (n, 3) at
        the options' orientation and its twist Jacobian J_t (velocity_map); NaN rows where a link cannot reach."""
        pts = np.asarray(poses, dtype=float)
        X = np.concatenate([pts, np.tile(np.asarray(options["orientation"], dtype=float), (len(pts), 1))], axis=1)
        geo = Geometry.of(design, options)
        with np.errstate(invalid="ignore", divide="ignore"):
            st = chain_state(geo, X, sigma_vector(label))
            jt = twist_jacobian(geo, st)
        ok = np.asarray(st.ok, dtype=bool)
        return np.where(ok[:, None], st.q, np.nan), np.where(ok[:, None, None], jt, np.nan)

    def held_link_jacobian(self, design, options, poses, label: str, step: float = 1e-5) -> np.ndarray:
        """d(segment endpoints)/d(theta_j) (n, 3, s, 2, 3), mm per rad: link_geometry's endpoints as the platform
        turns by a small angle theta_j about the fixed frame's axis j at fixed O1 (R -> Rod(theta_j e_j) R, the
        omega of velocity_map's last three columns: J_t's row [g, r_k x g] is the twist of C_k about fixed axes),
        the IK of branch ``label`` re-solved at the turned orientation; central differences of ``step`` rad. The
        inverse dynamics needs it for the moments the actuators apply to hold the orientation
        (dynamics.inverse); NaN where the branch does not reach."""
        pts = np.asarray(poses, dtype=float)
        rot = rotation(*np.asarray(options["orientation"], dtype=float))
        sides = []
        for j in range(3):
            for sign in (1.0, -1.0):
                w = np.zeros(3)
                w[j] = sign * step
                turned = dict(options, orientation=list(euler_angles(_rodrigues(w) @ rot)))
                q, _ = self.cycle_kinematics(design, turned, pts, label)
                sides.append(np.moveaxis(self.link_endpoints(design, turned, pts, q).segments(), -1, 0))
        e = np.stack(sides, axis=1)  # (n, 6, s, 2, 3)
        return (e[:, 0::2] - e[:, 1::2]) / (2.0 * step)

    def joint_limits(self, options: Mapping[str, Any]) -> np.ndarray:
        """Limits (6, 2) of (w1, w2, beta, s1, s2, s3), mm and rad."""
        return np.array([options["w_limits"]] * 2 + [options["beta_limits"]] + [options["s_limits"]] * 3)

    def limit_violations(self, options: Mapping[str, Any], q) -> list[str]:
        """Names of the actuators of q outside their limits (empty when all are within)."""
        q = np.asarray(q, dtype=float)
        return [n for n, v, (lo, hi) in zip(JOINTS, q, self.joint_limits(options), strict=True) if not lo <= v <= hi]

    # ----- stiffness (scalesynth.stiffness; pose level) ------------------------------------------------------
    def stiffness_model(self, design, options, pose, joints: str = "ideal"):
        """Frame model (scalesynth.stiffness.FrameModel, spatial, mm, N) at O1 = (x, y, z) with the options'
        orientation, working mode ``options.sigma``; raises InvalidPose outside the workspace (out of reach or an
        actuator outside its limits). Joints as in joint_screws. Chains 1, 2: a rigid carriage at B_i = (u_i.C_i) u_i
        on the rail (prismatic actuator w_i along u_i to the base), the column slider_i B_i -> D_i = B_i + s_i z
        (prismatic actuator s_i along z between column and carriage at B_i), the link D_i C_i (revolute about u_i at
        D_i, spherical at C_i). Chain 3: a rigid rocker at B3 = R u3 (revolute actuator beta about e3 to the base),
        the column leg3 B3 -> D3 = B3 + s3 d3 (prismatic actuator s3 along d3 at B3), the link D3 C3 (revolute about
        n3 = e3 x d3 at D3, spherical at C3). The platform C1 C2 C3 is rigid with reference point O1 (6 DOFs: x, y,
        z and the small rotations rx, ry, rz about the fixed axes); the load is a force at O1. ``joints`` 'bonded'
        welds the passive joints."""
        from scalesynth.stiffness.builder import FrameBuilder
        from scalesynth.stiffness.model import Body
        from scalesynth.stiffness.sections import tube_section

        x, y, z = self.check_vector("pose", pose, 3)
        if self.point_kernel(self.pack(design, options), x, y, z) < 0.0:
            raise InvalidPose(f"pose: ({x:g}, {y:g}, {z:g}) is outside the workspace (mode {options['sigma']}, "
                              "actuator limits included)")
        geo = Geometry.of(design, options)
        X = self.full_pose(options, (x, y, z))
        st = chain_state(geo, X, sigma_vector(options["sigma"]))
        q = st.q
        zhat = np.array([0.0, 0.0, 1.0])
        k, k_beta = options["actuator_stiffness"], options["beta_stiffness"]
        fb = FrameBuilder({g: tube_section(options, g, "mm") for g in LINK_GROUPS}, joints)
        bodies = [Body("base", np.zeros(3))]
        for i in (0, 1):
            n = i + 1
            u, c = geo.u[i], st.centres[i]
            b = (u @ c) * u
            d = b + q[3 + i] * zhat
            bodies.append(Body(f"carriage{n}", b.copy()))
            fb.link(f"slider{n}", "column", b, d)
            fb.link(f"link{n}", "link", d, c)
            fb.joint(f"P_w{n}", "prismatic", b, f"carriage{n}", "base", (u,), k)
            fb.joint(f"P_s{n}", "prismatic", b, f"slider{n}.a", f"carriage{n}", (zhat,), k)
            fb.joint(f"R{n}", "revolute", d, f"slider{n}.b", f"link{n}.a", (u,))
            fb.joint(f"S{n}", "spherical", c, f"link{n}.b", "platform")
        u3, e3, beta = geo.u[2], geo.e[2], q[2]
        d3 = -math.cos(beta) * u3 + math.sin(beta) * zhat
        b3 = geo.rail * u3
        top = b3 + q[5] * d3
        c3 = st.centres[2]
        bodies.append(Body("rocker3", b3.copy()))
        fb.link("leg3", "column", b3, top)
        fb.link("link3", "link", top, c3)
        fb.joint("R_beta", "revolute", b3, "rocker3", "base", (e3,), k_beta)
        fb.joint("P_s3", "prismatic", b3, "leg3.a", "rocker3", (d3,), k)
        fb.joint("R3", "revolute", top, "leg3.b", "link3.a", (np.cross(e3, d3),))
        fb.joint("S3", "spherical", c3, "link3.b", "platform")
        bodies.append(Body("platform", X[:3].copy()))
        notes = ["spatial frame O-xyz of the paper (z up, mm); rigid platform C1C2C3 with reference point O1, "
                 "DOFs x, y, z, rx, ry, rz (small rotations about the fixed axes); the load is a force at O1",
                 f"orientation (phi, theta, psi) = {tuple(float(v) for v in X[3:])} rad, "
                 f"working mode {options['sigma']}"]
        return fb.model("mm", bodies, options["load"], notes)

    # ----- mobility (scalesynth.mobility) ---------------------------------------------------------
    def topology(self, design, options):
        """Joint list of spec §1.2: chains PPRS, PPRS, RPRS; n = 11 (base, platform, three links per chain),
        g = 12, sum f = 18, classical G-K 6(11 - 12 - 1) + 18 = 6 with no redundant constraint."""
        from scalesynth.mobility import Topology

        return Topology(
            n_links=11,
            chains=(
                ("PPRS-1", ("P", "P", "R", "S")),
                ("PPRS-2", ("P", "P", "R", "S")),
                ("RPRS", ("R", "P", "R", "S")),
            ),
            note="spec §1.2 (paper): classical G-K, every chain has six independent joint twists",
        )

    def joint_screws(self, design, options, pose, q):
        """Unit joint screws (omega; v) per chain at a pose (x, y, z[, phi, theta, psi]) with inputs
        q = (w1, w2, beta, s1, s2, s3), fixed frame of spec §1.1 (mm).

        PPRS_i: carriage along u_i, slider along z, revolute about u_i through D_i = B_i + s_i z, spherical
        joint at C_i. RPRS: revolute about e3 through B3 = R u3, prismatic along
        d3 = -cos(beta) u3 + sin(beta) z, revolute about n3 = e3 x d3 through D3 = B3 + s3 d3, spherical joint
        at C3."""
        from scalesynth.mobility import Joint, chain_screws

        X = self.full_pose(options, pose)
        w1, w2, beta, s1, s2, s3 = self.check_vector("inputs", q, 6)
        geo = Geometry.of(design, options)
        centres = X[:3] + rotation(*X[3:]) @ geo.body.T
        zhat = np.array([0.0, 0.0, 1.0])
        chains = []
        for k, (w, s) in enumerate(((w1, s1), (w2, s2))):
            u = geo.u[k]
            b = (geo.rail - w if geo.conv_r else w) * u
            chains.append(chain_screws([
                Joint("P", axes=(u,)),
                Joint("P", axes=(zhat,)),
                Joint("R", b + s * zhat, (u,)),
                Joint("S", centres[:, k]),
            ]))
        u3, e3 = geo.u[2], geo.e[2]
        d3 = -math.cos(beta) * u3 + math.sin(beta) * zhat
        b3 = geo.rail * u3
        chains.append(chain_screws([
            Joint("R", b3, (e3,)),
            Joint("P", axes=(d3,)),
            Joint("R", b3 + s3 * d3, (np.cross(e3, d3),)),
            Joint("S", centres[:, 2]),
        ]))
        return chains


def _is_vector(value) -> bool:
    try:
        return np.asarray(value, dtype=float).ndim == 1
    except (TypeError, ValueError):
        return False


def _finite(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise InvalidParameter(f"{name}: expected a finite number, got {value!r}")
    return float(value)


MECHANISM = PprsRprs(
    name="pprs-rprs",
    title="2PPRS-RPRS six-DOF parallel mechanism (seed 001)",
    seed="001",
    motion="3T3R",
    task_axes=("x", "y", "z"),
    task_units=("length", "length", "length"),
    joints=JOINTS,
    joint_units=("length", "length", "angle", "length", "length", "length"),
    parameters=(
        Parameter("r", 160.0, "circumradius of the moving triangle C1C2C3 (mm)"),
        Parameter("R", 180.0, "|OB3|, distance of chain 3's fixed revolute from O, and rail length (mm)"),
        Parameter("L1", 100.0, "link |D1C1| of chain 1 (paper's l, mm)"),
        Parameter("L2", 120.0, "link |D2C2| of chain 2 (paper's n, mm)"),
        Parameter("L3", 120.0, "link |D3C3| of chain 3 (paper's m, mm)"),
    ),
    options=(
        Option("orientation", (0.0, 0.0, 0.0), "[phi, theta, psi] rad of the constant-orientation workspace"),
        Option("sigma", "+++", "branch signs sigma1 sigma2 sigma3; '+' = D_i below C_i (spec §1.3)"),
        Option("w_limits", (80.0, 180.0), "[lo, hi] mm for the rail inputs w1, w2"),
        Option("s_limits", (37.5, 137.5), "[lo, hi] mm for the slider inputs s1, s2, s3"),
        Option("beta_limits", (math.pi / 3, 2 * math.pi / 3), "[lo, hi] rad for chain 3's revolute input beta"),
        Option("chain3_azimuth_deg", 210.0, "azimuth of OB3 in degrees: 210 (spec) or 240 (open question O2)"),
        Option("w_convention", "O", "'O': B_i = w_i u_i (spec); 'R': B_i = (R - w_i) u_i (eq.10-12, E5)"),
        Option("beta_length", None, "mm multiplying the beta row of J_t for the LCI; null = R"),
        Option("angle_length", None, "mm dividing the angular-velocity columns of J_t for the LCI; null = r"),
        Option("link_radius", None, "capsule radius (mm) of every body, or {body: radius}; null = defaults base 5, "
               "slider1/slider2/leg3 8, link1/link2/link3 5, platform 5 (illustrative)"),
        Option("interference_free", False, "true: a pose whose link capsules overlap (clearance < 0) is unreachable"),
        *stiffness_options("mm", ACTUATOR_STIFFNESS, "axial stiffness of each linear actuator (w1, w2, s1, s2, s3), "
                           "N/mm (an assumption)", [0.0, 0.0, -150.0], "default 150 N along -z, the gravity direction "
                           "(z up), at O1"),
        Option("beta_stiffness", BETA_STIFFNESS, "stiffness: torsional stiffness of chain 3's revolute actuator beta, "
               "N mm/rad (1e5 N m/rad, an assumption)"),
    ),
    default_length_unit="mm",
    fields=(*base_fields("1", "J = dx/dq, the twist of O1 with its angular part times angle_length and the beta "
                         "input times beta_length (mm/mm)"), links.CLEARANCE_FIELD,
            Field("stiffness_min", "N/{length}", "smallest eigenvalue of the platform's translational stiffness at "
                  "O1 under a pure force (ideal joints, Euler-Bernoulli links, actuator springs; docs/stiffness.md)",
                  "max"),
            Field("deflection", "{length}", "magnitude of the deflection of O1 under options.load (default 150 N "
                  "along -z); 1e12 at a singular pose", "min", (0.0, _legs_k.DEFLECTION_CAP))),
    design_metrics=(
        DesignMetric(
            "link_length_sum", "{length}",
            "moving links of fixed length: the links L1 + L2 + L3 and the moving triangle's edges 3 sqrt(3) r",
            lambda d, o: d["L1"] + d["L2"] + d["L3"] + 3.0 * math.sqrt(3.0) * d["r"],
        ),
        DesignMetric(
            "footprint_radius", "{length}",
            "radius of the smallest circle in the base plane holding the rails and chain 3's revolute, all within R "
            "of O: R",
            lambda d, o: d["R"],
        ),
    ),
)
