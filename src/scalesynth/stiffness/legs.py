"""Numba per-leg condensation (virtual-joint style) for the per-voxel stiffness fields of spatial mechanisms.

Conventions (those of :mod:`scalesynth.stiffness.solve`): a *twist* of the platform at its reference point ``ref``
is (t, r) (translation, length unit; small rotation, rad), so a point q moves by t + r x (q - ref); a *wrench* at
``ref`` is (F, M) (N; N * length, moment about ``ref``); work = wrench . twist. A 6x6 compliance maps a wrench at
``ref`` to a twist, a 6x6 stiffness a twist to a wrench.

A **leg** is a serial chain from the base to the platform: straight Euler-Bernoulli beams, each clamped to the
previous one (or to the base), an actuator spring, and passive joints with free directions (twists). With ideal
joints the leg transmits only wrenches reciprocal to the joint twists: its constraint wrenches N (6 x m, the
orthogonal complement of the twists under the work pairing). With the compliance C of the clamped chain at ``ref``
(beams in series: C = sum_i Ad_i C_i Ad_i^T, C_i a cantilever's tip compliance; plus g g^T / k for the actuator),
minimising the strain energy over the joint motions gives the leg stiffness

    K_leg = N (N^T C N)^-1 N^T,

equal to the projection K - K J (J^T K J)^-1 J^T K of K = C^-1 on the joint twists J, but without subtraction
(no cancellation between stiff and soft parts). Legs in parallel add their stiffnesses; a chain meeting another
one at an intermediate node combines in series (:func:`series_stiffness`). :func:`platform_response` turns the
platform stiffness into the fields stiffness_min and deflection (a 3x3 Schur complement, no 6x6 inverse).

The general routines (beams, springs, joint twists, constraint wrenches, series) work on caller-provided 6x6
arrays and allocate a few 3x3 temporaries: fine for a mechanism's generic per-voxel path and for cross-checks. A
kernel within a few times the kinematic fields' cost writes the same condensation out in closed form for its
chains (the wrench form K = sum W Phi^-1 W^T, ``Phi`` the chain's flexibility on its wrench basis W) and calls
:func:`response_upper` on the 21 entries of K (ups-sspr). None writes NaN.
Units: lengths in the mechanism's unit, EA in N, EI and GJ in N * length^2, a prismatic spring in N / length,
a revolute spring in N * length / rad. Checked against the NumPy reference solver and a NumPy twin
(tests/test_stiffness_legs.py).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from scalesynth.kernels.conditioning import SIGMA_CAP
from scalesynth.kernels.flags import FASTMATH
from scalesynth.stiffness.solve import SINGULAR_RTOL

DEFLECTION_CAP = SIGMA_CAP  # length unit: the per-voxel deflection at a singular pose (the field contract has no inf)
# a joint twist whose part outside the span of the previous ones is below this (relative, rotations as arc lengths
# at the characteristic length) adds no free direction (a dependent joint axis, e.g. at a leg's own singularity)
DEPENDENT_RTOL = 1e-9


@njit(cache=True, fastmath=FASTMATH)
def _unit(x, y, z):
    n = math.sqrt(x * x + y * y + z * z)
    if n > 0.0:
        inv = 1.0 / n
        return x * inv, y * inv, z * inv, n
    return 0.0, 0.0, 0.0, 0.0


@njit(cache=True, fastmath=FASTMATH)
def beam_frame(ax, ay, az, bx, by, bz, upx, upy, upz):
    """Local axes of the beam a -> b: ex along it, ey = ``up`` made orthogonal to ex, ez = ex x ey (as the
    reference solver); returns (ex, ey, ez as 9 floats, length). A beam of zero length, or an ``up`` along it,
    gives length 0 (the caller skips it)."""
    exx, exy, exz, length = _unit(bx - ax, by - ay, bz - az)
    dot = upx * exx + upy * exy + upz * exz
    eyx, eyy, eyz, n = _unit(upx - dot * exx, upy - dot * exy, upz - dot * exz)
    if n <= 1e-12 * math.sqrt(upx * upx + upy * upy + upz * upz):
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    ezx = exy * eyz - exz * eyy
    ezy = exz * eyx - exx * eyz
    ezz = exx * eyy - exy * eyx
    return exx, exy, exz, eyx, eyy, eyz, ezx, ezy, ezz, length


@njit(cache=True, fastmath=FASTMATH)
def add_beam_compliance(C, ax, ay, az, bx, by, bz, upx, upy, upz, ea, eiy, eiz, gj, rx, ry, rz):
    """C += compliance (6x6, at ref = (rx, ry, rz)) of the beam a -> b clamped at a and loaded at b: the
    cantilever tip compliance (axial L/EA; bending L^3/3EI, L^2/2EI, L/EI in the local xy plane with EIz and the
    xz plane with EIy; torsion L/GJ), carried rigidly from b to ref (Ad C_b Ad^T). Returns False for a beam of
    zero length (nothing added)."""
    exx, exy, exz, eyx, eyy, eyz, ezx, ezy, ezz, L = beam_frame(ax, ay, az, bx, by, bz, upx, upy, upz)
    if not L > 0.0:
        return False
    ex = (exx, exy, exz)
    ey = (eyx, eyy, eyz)
    ez = (ezx, ezy, ezz)
    ca = L / ea
    cvz = L * L * L / (3.0 * eiz)
    cwy = L * L * L / (3.0 * eiy)
    ctz = L / eiz
    cty = L / eiy
    cx = L / gj
    kz = L * L / (2.0 * eiz)  # v (along ey) with theta_z (about ez)
    ky = -L * L / (2.0 * eiy)  # w (along ez) with theta_y (about ey)
    # tip blocks at b: tt, tr (t rows, r columns), rr
    dx, dy, dz = rx - bx, ry - by, rz - bz
    # Ad = [[I, -[d]x], [0, I]]: t_ref = t_b - d x r_b. Build the tip blocks, then transport.
    tt = np.empty((3, 3))
    tr = np.empty((3, 3))
    rr = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            tt[i, j] = ca * ex[i] * ex[j] + cvz * ey[i] * ey[j] + cwy * ez[i] * ez[j]
            rr[i, j] = cx * ex[i] * ex[j] + ctz * ez[i] * ez[j] + cty * ey[i] * ey[j]
            tr[i, j] = kz * ey[i] * ez[j] + ky * ez[i] * ey[j]
    _add_transported(C, tt, tr, rr, dx, dy, dz)
    return True


@njit(cache=True, fastmath=FASTMATH)
def _cross_rows(m, dx, dy, dz, out):
    """out = [d]x m for a 3x3 m ([d]x v = d x v)."""
    for j in range(3):
        out[0, j] = dy * m[2, j] - dz * m[1, j]
        out[1, j] = dz * m[0, j] - dx * m[2, j]
        out[2, j] = dx * m[1, j] - dy * m[0, j]


@njit(cache=True, fastmath=FASTMATH)
def _add_transported(C, tt, tr, rr, dx, dy, dz):
    """C += Ad [[tt, tr], [tr^T, rr]] Ad^T with Ad = [[I, -D], [0, I]], D = [d]x: blocks
    tt - D tr^T - tr D^T + D rr D^T, tr - D rr, rr (D^T = -D)."""
    drr = np.empty((3, 3))
    _cross_rows(rr, dx, dy, dz, drr)  # D rr
    dtrt = np.empty((3, 3))
    trt = tr.T.copy()
    _cross_rows(trt, dx, dy, dz, dtrt)  # D tr^T
    m = np.empty((3, 3))
    drrt = drr.T.copy()
    _cross_rows(drrt, dx, dy, dz, m)  # D (D rr)^T
    for i in range(3):
        for j in range(3):
            drrdt = m[j, i]  # D rr D^T = (D rr) D^T = (D (D rr)^T)^T
            C[i, j] += tt[i, j] - dtrt[i, j] - dtrt[j, i] + drrdt
            C[i, 3 + j] += tr[i, j] - drr[i, j]
            C[3 + j, i] += tr[i, j] - drr[i, j]
            C[3 + i, 3 + j] += rr[i, j]


@njit(cache=True, fastmath=FASTMATH)
def add_prismatic_spring(C, axx, axy, axz, k):
    """C += a a^T / k on the translations: a linear spring of stiffness k (N/length) along the unit axis a, in
    series in the chain (the relative translation along a is F . a / k wherever ref is)."""
    a = (axx, axy, axz)
    for i in range(3):
        for j in range(3):
            C[i, j] += a[i] * a[j] / k


@njit(cache=True, fastmath=FASTMATH)
def add_revolute_spring(C, qx, qy, qz, axx, axy, axz, k, rx, ry, rz):
    """C += g g^T / k, g = (a x (ref - q), a): a torsional spring k (N*length/rad) about the unit axis a through q."""
    g = np.empty(6)
    g[0] = axy * (rz - qz) - axz * (ry - qy)
    g[1] = axz * (rx - qx) - axx * (rz - qz)
    g[2] = axx * (ry - qy) - axy * (rx - qx)
    g[3], g[4], g[5] = axx, axy, axz
    for i in range(6):
        for j in range(6):
            C[i, j] += g[i] * g[j] / k


@njit(cache=True, fastmath=FASTMATH)
def set_rotation_twist(J, col, qx, qy, qz, axx, axy, axz, rx, ry, rz):
    """Column ``col`` of J = the twist at ref of a unit rotation about axis a through q: (a x (ref - q), a)."""
    J[0, col] = axy * (rz - qz) - axz * (ry - qy)
    J[1, col] = axz * (rx - qx) - axx * (rz - qz)
    J[2, col] = axx * (ry - qy) - axy * (rx - qx)
    J[3, col], J[4, col], J[5, col] = axx, axy, axz


@njit(cache=True, fastmath=FASTMATH)
def set_spherical_twists(J, col, qx, qy, qz, rx, ry, rz):
    """Columns col..col+2 of J: the three rotations (about x, y, z) of a spherical joint at q."""
    set_rotation_twist(J, col, qx, qy, qz, 1.0, 0.0, 0.0, rx, ry, rz)
    set_rotation_twist(J, col + 1, qx, qy, qz, 0.0, 1.0, 0.0, rx, ry, rz)
    set_rotation_twist(J, col + 2, qx, qy, qz, 0.0, 0.0, 1.0, rx, ry, rz)


@njit(cache=True, fastmath=FASTMATH)
def set_translation_twist(J, col, axx, axy, axz):
    """Column ``col`` of J: a passive sliding joint along the unit axis a, (a, 0)."""
    J[0, col], J[1, col], J[2, col] = axx, axy, axz
    J[3, col], J[4, col], J[5, col] = 0.0, 0.0, 0.0


@njit(cache=True, fastmath=FASTMATH)
def constraint_wrenches(J, m, length, N):
    """Columns of N (6 x n, returned n = 6 - rank(J)): a basis of the wrenches reciprocal to the m joint twists in
    J[:, :m] (N^T J = 0 under the work pairing). Computed by Gram-Schmidt in coordinates where rotations are arc
    lengths at ``length`` (twist (t / length, r), wrench (F length, M)), so the result does not depend on the unit;
    a twist dependent on the previous ones (DEPENDENT_RTOL) frees nothing. The basis is returned in physical
    units (columns (F, M))."""
    q = np.empty((6, 6))  # orthonormal basis of the scaled twist span, then of its complement
    r = 0
    inv = 1.0 / length
    v = np.empty(6)
    for c in range(m):
        for i in range(3):
            v[i] = J[i, c] * inv
            v[3 + i] = J[3 + i, c]
        n0 = 0.0
        for i in range(6):
            n0 += v[i] * v[i]
        for _ in range(2):  # Gram-Schmidt twice: orthogonal to working precision
            for b in range(r):
                d = 0.0
                for i in range(6):
                    d += q[i, b] * v[i]
                for i in range(6):
                    v[i] -= d * q[i, b]
        n1 = 0.0
        for i in range(6):
            n1 += v[i] * v[i]
        if n1 > DEPENDENT_RTOL * DEPENDENT_RTOL * n0 and n1 > 0.0:
            s = 1.0 / math.sqrt(n1)
            for i in range(6):
                q[i, r] = v[i] * s
            r += 1
    # complement: the unit vectors with the largest residual, one at a time
    n = 0
    while r + n < 6:
        best = -1.0
        bi = 0
        for e in range(6):
            for i in range(6):
                v[i] = 0.0
            v[e] = 1.0
            for b in range(r + n):
                d = q[e, b]
                for i in range(6):
                    v[i] -= d * q[i, b]
            s = 0.0
            for i in range(6):
                s += v[i] * v[i]
            if s > best:
                best = s
                bi = e
        for i in range(6):
            v[i] = 0.0
        v[bi] = 1.0
        for _ in range(2):
            for b in range(r + n):
                d = 0.0
                for i in range(6):
                    d += q[i, b] * v[i]
                for i in range(6):
                    v[i] -= d * q[i, b]
        s = 0.0
        for i in range(6):
            s += v[i] * v[i]
        s = 1.0 / math.sqrt(s)
        for i in range(6):
            q[i, r + n] = v[i] * s
        n += 1
    # back to physical wrenches: (F, M) with F = scaled F / length
    for c in range(n):
        for i in range(3):
            N[i, c] = q[i, r + c] * inv
            N[3 + i, c] = q[3 + i, r + c]
    return n


@njit(cache=True, fastmath=FASTMATH)
def cholesky(A, n):
    """In-place lower Cholesky factor of the leading n x n block of the symmetric A; False if not positive
    definite (a pivot <= 0 or not finite)."""
    for j in range(n):
        s = A[j, j]
        for k in range(j):
            s -= A[j, k] * A[j, k]
        if not s > 0.0 or not math.isfinite(s):
            return False
        d = math.sqrt(s)
        A[j, j] = d
        inv = 1.0 / d
        for i in range(j + 1, n):
            t = A[i, j]
            for k in range(j):
                t -= A[i, k] * A[j, k]
            A[i, j] = t * inv
    return True


@njit(cache=True, fastmath=FASTMATH)
def _forward(L, n, B, ncol):
    """B[:n, :ncol] <- L^-1 B (L lower triangular, leading n x n block)."""
    for c in range(ncol):
        for i in range(n):
            t = B[i, c]
            for k in range(i):
                t -= L[i, k] * B[k, c]
            B[i, c] = t / L[i, i]


@njit(cache=True, fastmath=FASTMATH)
def _backward(L, n, B, ncol):
    """B[:n, :ncol] <- L^-T B."""
    for c in range(ncol):
        for i in range(n - 1, -1, -1):
            t = B[i, c]
            for k in range(i + 1, n):
                t -= L[k, i] * B[k, c]
            B[i, c] = t / L[i, i]


@njit(cache=True, fastmath=FASTMATH)
def add_leg_stiffness(C, N, n, K, work):
    """K += N (N^T C N)^-1 N^T for the leg of compliance C (6x6, at ref) and constraint wrenches N[:, :n];
    ``work`` a 6x6 scratch. Returns False (nothing added) if N^T C N is not positive definite."""
    if n == 0:
        return True
    m = work
    for a in range(n):
        for b in range(a, n):
            s = 0.0
            for i in range(6):
                ci = 0.0
                for j in range(6):
                    ci += C[i, j] * N[j, b]
                s += N[i, a] * ci
            m[a, b] = s
            m[b, a] = s
    if not cholesky(m, n):
        return False
    y = np.empty((6, 6))  # rows 0..n-1: L^-1 N^T
    for a in range(n):
        for i in range(6):
            y[a, i] = N[i, a]
    _forward(m, n, y, 6)
    for i in range(6):
        for j in range(i, 6):
            s = 0.0
            for a in range(n):
                s += y[a, i] * y[a, j]
            K[i, j] += s
            if j != i:
                K[j, i] += s
    return True


@njit(cache=True, fastmath=FASTMATH)
def series_stiffness(Ka, Kb, out, work):
    """out = Ka (Ka + Kb)^-1 Kb: two springs (6x6 stiffnesses at the same ref, either may be singular) in series,
    e.g. the stiffness at a chain's node and the chain beyond it (Kb relative to that node). Written without
    subtraction. Returns False (out = 0) if Ka + Kb is singular."""
    s = work
    for i in range(6):
        for j in range(6):
            s[i, j] = Ka[i, j] + Kb[i, j]
    if not cholesky(s, 6):
        out[:, :] = 0.0
        return False
    x = np.empty((6, 6))
    x[:, :] = Kb
    _forward(s, 6, x, 6)
    _backward(s, 6, x, 6)  # x = (Ka + Kb)^-1 Kb
    for i in range(6):
        for j in range(6):
            t = 0.0
            for k in range(6):
                t += Ka[i, k] * x[k, j]
            out[i, j] = t
    for i in range(6):
        for j in range(i + 1, 6):
            a = 0.5 * (out[i, j] + out[j, i])
            out[i, j] = a
            out[j, i] = a
    return True


@njit(cache=True, fastmath=FASTMATH)
def platform_response(K, fx, fy, fz, length):
    """(stiffness_min, deflection) of a platform of stiffness K (6x6 at its reference point: translations, then
    rotations) under the force F = (fx, fy, fz) N: the translational stiffness felt by a pure force is the Schur
    complement S = K_tt - K_tr K_rr^-1 K_rt (= C_t^-1, C_t the translational block of C = K^-1); stiffness_min =
    1 / lambda_max(C_t) (N/length) and the deflection |C_t F| (length unit). Singular (the per-voxel stand-in for
    the reference solver's eigenvalue test): K_rr or S not positive definite, or lambda_max(C_t) tr(K~) >=
    1 / SINGULAR_RTOL, K~ = K with rotations as arc lengths at ``length`` (lambda_max(C_t) <= 1 / lambda_min(K~)
    and lambda_max(K~) <= tr(K~), so this flags an eigenvalue ratio of K~ of at most SINGULAR_RTOL seen by a
    force); then (0, DEFLECTION_CAP) for a non-zero load (0 for a zero load). Never NaN."""
    return _response(K[0, 0], K[0, 1], K[0, 2], K[1, 1], K[1, 2], K[2, 2], K[0, 3], K[0, 4], K[0, 5], K[1, 3],
                     K[1, 4], K[1, 5], K[2, 3], K[2, 4], K[2, 5], K[3, 3], K[3, 4], K[3, 5], K[4, 4], K[4, 5],
                     K[5, 5], fx, fy, fz, length)


@njit(cache=True, fastmath=FASTMATH)
def outer_add(k, a0, a1, a2, a3, a4, a5):
    """k + a a^T for the 21 upper entries k of a symmetric 6x6 matrix (a tuple, row-major: 00, 01, ..., 05, 11, ...,
    55): a kernel sums its legs' wrench columns a into K in scalars and hands k to response_upper."""
    return (k[0] + a0 * a0, k[1] + a0 * a1, k[2] + a0 * a2, k[3] + a0 * a3, k[4] + a0 * a4, k[5] + a0 * a5,
            k[6] + a1 * a1, k[7] + a1 * a2, k[8] + a1 * a3, k[9] + a1 * a4, k[10] + a1 * a5,
            k[11] + a2 * a2, k[12] + a2 * a3, k[13] + a2 * a4, k[14] + a2 * a5,
            k[15] + a3 * a3, k[16] + a3 * a4, k[17] + a3 * a5, k[18] + a4 * a4, k[19] + a4 * a5, k[20] + a5 * a5)


@njit(cache=True, fastmath=FASTMATH)
def response_upper(k, fx, fy, fz, length):
    """:func:`platform_response` of the symmetric K given by its 21 upper entries k (row-major: 00, 01, ..., 05,
    11, ..., 55), for kernels that assemble K in scalars."""
    return _response(k[0], k[1], k[2], k[6], k[7], k[11], k[3], k[4], k[5], k[8], k[9], k[10], k[12], k[13], k[14],
                     k[15], k[16], k[17], k[18], k[19], k[20], fx, fy, fz, length)


@njit(cache=True, fastmath=FASTMATH)
def response_2x2(k00, k01, k11, fx, fy):
    """:func:`platform_response` of a planar platform that only translates (a pin where pinned links meet, e.g. the
    described 2T mechanisms'): K the symmetric 2x2 translational stiffness (N/length) by its upper entries, F =
    (fx, fy) N. stiffness_min = lambda_min(K) (= 1 / lambda_max(K^-1)), the deflection |K^-1 F| (length unit, capped
    at DEFLECTION_CAP); singular (0, DEFLECTION_CAP, or 0 deflection under no load) unless lambda_min(K) >
    SINGULAR_RTOL lambda_max(K) (the reference solver's eigenvalue-ratio test; no rotation, so no characteristic
    length). lambda_min is det / lambda_max: no cancellation. Never NaN."""
    zero = 0.0 if (fx == 0.0 and fy == 0.0) else DEFLECTION_CAP
    half = 0.5 * (k00 + k11)
    diff = 0.5 * (k00 - k11)
    kmax = half + math.sqrt(diff * diff + k01 * k01)
    det = k00 * k11 - k01 * k01
    if not (kmax > 0.0 and math.isfinite(kmax)):
        return 0.0, zero
    kmin = det / kmax
    if not kmin > SINGULAR_RTOL * kmax:
        return 0.0, zero
    dx = (k11 * fx - k01 * fy) / det
    dy = (k00 * fy - k01 * fx) / det
    return kmin, min(math.sqrt(dx * dx + dy * dy), DEFLECTION_CAP)


@njit(cache=True, fastmath=FASTMATH)
def response_translational(k00, k01, k02, k11, k12, k22, fx, fy, fz):
    """:func:`platform_response` of a platform whose rotations are held rigidly (only translations are DOFs, e.g.
    seed 000's PPaP chain): K is the symmetric 3x3 translational stiffness given by its upper entries (N/length).
    stiffness_min = lambda_min(K), the deflection |K^-1 F|; singular (0, DEFLECTION_CAP) when K is not positive
    definite or lambda_max(K^-1) tr(K) >= 1 / SINGULAR_RTOL (the reference solver's eigenvalue-ratio test with
    tr(K) >= lambda_max(K)). Never NaN."""
    return _stiffness_3x3_response(k00, k01, k02, k11, k12, k22, fx, fy, fz, k00 + k11 + k22)


@njit(cache=True, fastmath=FASTMATH)
def _stiffness_3x3_response(s00, s01, s02, s11, s12, s22, fx, fy, fz, trace):
    """(stiffness_min, deflection) of the symmetric 3x3 translational stiffness S (upper entries): 1/lambda_max(S^-1)
    and |S^-1 F| capped at DEFLECTION_CAP; singular (0, DEFLECTION_CAP, or 0 deflection under no load) when S is not
    positive definite or lambda_max(S^-1) * trace >= 1 / SINGULAR_RTOL (``trace``: that of the stiffness the
    singularity test scales by)."""
    zero = 0.0 if (fx == 0.0 and fy == 0.0 and fz == 0.0) else DEFLECTION_CAP
    ok, a00, a01, a02, a11, a12, a22 = _sym3_inverse(s00, s01, s02, s11, s12, s22)
    if not ok:
        return 0.0, zero
    cmax = sym3_max_eigenvalue(a00, a01, a02, a11, a12, a22)
    if not (cmax > 0.0 and math.isfinite(cmax)) or not cmax * trace * SINGULAR_RTOL < 1.0:
        return 0.0, zero
    dx = a00 * fx + a01 * fy + a02 * fz
    dy = a01 * fx + a11 * fy + a12 * fz
    dz = a02 * fx + a12 * fy + a22 * fz
    return 1.0 / cmax, min(math.sqrt(dx * dx + dy * dy + dz * dz), DEFLECTION_CAP)


@njit(cache=True, fastmath=FASTMATH)
def sym3_inverse(a00, a01, a02, a11, a12, a22):
    """(ok, inverse entries 00, 01, 02, 11, 12, 22) of a symmetric positive definite 3x3 matrix (ok False if it
    is not), for kernels that invert a small stiffness in scalars."""
    return _sym3_inverse(a00, a01, a02, a11, a12, a22)


@njit(cache=True, fastmath=FASTMATH)
def _sym3_inverse(a00, a01, a02, a11, a12, a22):
    """(ok, inverse entries 00, 01, 02, 11, 12, 22) of a symmetric 3x3 matrix by its adjugate; ok False unless it
    is positive definite (leading minors > 0)."""
    m00 = a11 * a22 - a12 * a12
    m01 = a02 * a12 - a01 * a22
    m02 = a01 * a12 - a02 * a11
    det = a00 * m00 + a01 * m01 + a02 * m02
    if not (a00 > 0.0 and a00 * a11 - a01 * a01 > 0.0 and det > 0.0 and math.isfinite(det)):
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    inv = 1.0 / det
    return (True, m00 * inv, m01 * inv, m02 * inv, (a00 * a22 - a02 * a02) * inv, (a01 * a02 - a00 * a12) * inv,
            (a00 * a11 - a01 * a01) * inv)


@njit(cache=True, fastmath=FASTMATH)
def _response(t00, t01, t02, t11, t12, t22, c00, c01, c02, c10, c11, c12, c20, c21, c22, r00, r01, r02, r11, r12,
              r22, fx, fy, fz, length):
    """platform_response from the blocks of K: tt (upper entries), tr (c_ij = K[i, 3 + j]) and rr (upper)."""
    zero = 0.0 if (fx == 0.0 and fy == 0.0 and fz == 0.0) else DEFLECTION_CAP
    tr = t00 + t11 + t22 + (r00 + r11 + r22) / (length * length)
    ok, i00, i01, i02, i11, i12, i22 = _sym3_inverse(r00, r01, r02, r11, r12, r22)
    if not ok:
        return 0.0, zero
    # T = K_tr K_rr^-1, S = K_tt - T K_rt
    u00 = c00 * i00 + c01 * i01 + c02 * i02
    u01 = c00 * i01 + c01 * i11 + c02 * i12
    u02 = c00 * i02 + c01 * i12 + c02 * i22
    u10 = c10 * i00 + c11 * i01 + c12 * i02
    u11 = c10 * i01 + c11 * i11 + c12 * i12
    u12 = c10 * i02 + c11 * i12 + c12 * i22
    u20 = c20 * i00 + c21 * i01 + c22 * i02
    u21 = c20 * i01 + c21 * i11 + c22 * i12
    u22 = c20 * i02 + c21 * i12 + c22 * i22
    s00 = t00 - (u00 * c00 + u01 * c01 + u02 * c02)
    s01 = t01 - (u00 * c10 + u01 * c11 + u02 * c12)
    s02 = t02 - (u00 * c20 + u01 * c21 + u02 * c22)
    s11 = t11 - (u10 * c10 + u11 * c11 + u12 * c12)
    s12 = t12 - (u10 * c20 + u11 * c21 + u12 * c22)
    s22 = t22 - (u20 * c20 + u21 * c21 + u22 * c22)
    return _stiffness_3x3_response(s00, s01, s02, s11, s12, s22, fx, fy, fz, tr)


@njit(cache=True, fastmath=FASTMATH)
def sym3_max_eigenvalue(a00, a01, a02, a11, a12, a22):
    """Largest eigenvalue of the symmetric 3x3 matrix [[a00, a01, a02], [a01, a11, a12], [a02, a12, a22]] by the
    trigonometric solution of its characteristic cubic (well conditioned for the largest root)."""
    q = (a00 + a11 + a22) / 3.0
    b00, b11, b22 = a00 - q, a11 - q, a22 - q
    p2 = b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * (a01 * a01 + a02 * a02 + a12 * a12)
    if p2 <= 1e-300:
        return q
    p = math.sqrt(p2 / 6.0)
    inv = 1.0 / p
    b00 *= inv
    b11 *= inv
    b22 *= inv
    c01, c02, c12 = a01 * inv, a02 * inv, a12 * inv
    r = 0.5 * (b00 * (b11 * b22 - c12 * c12) - c01 * (c01 * b22 - c12 * c02) + c02 * (c01 * c12 - b11 * c02))
    if r >= 1.0:
        return q + 2.0 * p
    if r <= -1.0:
        return q + p
    return q + 2.0 * p * math.cos(math.acos(r) / 3.0)


@njit(cache=True, fastmath=FASTMATH)
def tip_bilinear(length, ea, ei, gj, ex, ey, ez, f1x, f1y, f1z, m1x, m1y, m1z, f2x, f2y, f2z, m2x, m2y, m2z):
    """w1^T C w2 for two wrenches w = (F, M) at the tip of a round-section cantilever (length, unit axis e from
    the clamp to the tip; EA, EI, GJ): C's translations (L/EA) e e^T + (L^3/3EI)(I - e e^T), rotations
    (L/GJ) e e^T + (L/EI)(I - e e^T), coupling (L^2/2EI) e . (F1 x M2 + F2 x M1) (the blocks of
    add_beam_compliance with EIy = EIz). Zero for a beam of zero length."""
    if not length > 0.0:
        return 0.0
    a = length / ea
    b = length * length * length / (3.0 * ei)
    r = length / ei
    t = length / gj
    k = length * length / (2.0 * ei)
    fe1 = f1x * ex + f1y * ey + f1z * ez
    fe2 = f2x * ex + f2y * ey + f2z * ez
    me1 = m1x * ex + m1y * ey + m1z * ez
    me2 = m2x * ex + m2y * ey + m2z * ez
    ff = f1x * f2x + f1y * f2y + f1z * f2z
    mm = m1x * m2x + m1y * m2y + m1z * m2z
    c1 = ex * (f1y * m2z - f1z * m2y) + ey * (f1z * m2x - f1x * m2z) + ez * (f1x * m2y - f1y * m2x)
    c2 = ex * (f2y * m1z - f2z * m1y) + ey * (f2z * m1x - f2x * m1z) + ez * (f2x * m1y - f2y * m1x)
    return b * ff + (a - b) * fe1 * fe2 + r * mm + (t - r) * me1 * me2 + k * (c1 + c2)
