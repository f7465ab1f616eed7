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
platform stiffness into the fields stiffness_min and deflection.

Every routine works on caller-provided small arrays (one scratch allocation per voxel); none writes NaN.
Units: lengths in the mechanism's unit, EA in N, EI and GJ in N * length^2, a prismatic spring in N / length,
a revolute spring in N * length / rad. Checked against the NumPy reference solver and a NumPy twin
(tests/test_stiffness_legs.py).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from scalesynth.kernels.conditioning import SIGMA_CAP, sv_3x3
from scalesynth.kernels.flags import FASTMATH
from scalesynth.stiffness.solve import SINGULAR_RTOL

DEFLECTION_CAP = SIGMA_CAP  # length unit: the per-voxel deflection at a singular pose (the field contract has no inf)
# a joint twist whose part outside the span of the previous ones is below this (relative, rotations as arc lengths
# at the characteristic length) adds no free direction (a dependent joint axis, e.g. at a leg's own singularity)
DEPENDENT_RTOL = 1e-9
N_SCRATCH = 8  # 6x6 matrices a voxel needs: see scratch()


@njit(cache=True, fastmath=FASTMATH, inline="always")
def scratch():
    """Work space of one voxel: N_SCRATCH 6x6 matrices (one allocation)."""
    return np.empty((N_SCRATCH, 6, 6))


@njit(cache=True, fastmath=FASTMATH, inline="always")
def _unit(x, y, z):
    n = math.sqrt(x * x + y * y + z * z)
    if n > 0.0:
        inv = 1.0 / n
        return x * inv, y * inv, z * inv, n
    return 0.0, 0.0, 0.0, 0.0


@njit(cache=True, fastmath=FASTMATH, inline="always")
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


@njit(cache=True, fastmath=FASTMATH, inline="always")
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
def platform_response(K, fx, fy, fz, length, work):
    """(stiffness_min, deflection) of a platform of stiffness K (6x6 at its reference point) under the force
    F = (fx, fy, fz) N: C = K^-1, stiffness_min = 1 / lambda_max(C_t) (C_t its translational block: the stiffness
    felt by a pure force, N/length) and |C_t F| (length unit). Singular as in the reference solver: the smallest
    eigenvalue of K with rotations as arc lengths at ``length`` (the longest link) is at most SINGULAR_RTOL times
    the largest; then (0, DEFLECTION_CAP) for a non-zero load (0 for a zero load); never NaN."""
    zero = 0.0 if (fx == 0.0 and fy == 0.0 and fz == 0.0) else DEFLECTION_CAP
    s = work
    inv = 1.0 / length
    for i in range(6):
        si = 1.0 if i < 3 else inv
        for j in range(6):
            sj = 1.0 if j < 3 else inv
            s[i, j] = K[i, j] * si * sj
    tr = 0.0
    for i in range(6):
        tr += s[i, i]
    scaled = s.copy()
    if not tr > 0.0 or not cholesky(s, 6):
        return 0.0, zero
    x = np.zeros((6, 6))
    for i in range(6):
        x[i, i] = 1.0
    _forward(s, 6, x, 6)
    _backward(s, 6, x, 6)  # x = K~^-1 (translations unscaled: its tt block is C_t)
    tri = 0.0
    for i in range(6):
        tri += x[i, i]
    # lambda_max / lambda_min <= tr(K~) tr(K~^-1) <= 36 lambda_max / lambda_min: decide by the eigenvalues
    # only where the bound cannot
    if not tr * tri * SINGULAR_RTOL < 1.0:
        if not math.isfinite(tri):
            return 0.0, zero
        w = np.linalg.eigvalsh(scaled)
        if not w[0] > SINGULAR_RTOL * w[5]:
            return 0.0, zero
    lci, cmin, cmax = sv_3x3(x[0, 0], x[0, 1], x[0, 2], x[1, 0], x[1, 1], x[1, 2], x[2, 0], x[2, 1], x[2, 2])
    if not cmax > 0.0:
        return 0.0, zero
    dx = x[0, 0] * fx + x[0, 1] * fy + x[0, 2] * fz
    dy = x[1, 0] * fx + x[1, 1] * fy + x[1, 2] * fz
    dz = x[2, 0] * fx + x[2, 1] * fy + x[2, 2] * fz
    return 1.0 / cmax, min(math.sqrt(dx * dx + dy * dy + dz * dz), DEFLECTION_CAP)


@njit(cache=True, fastmath=FASTMATH)
def leg_wrench_columns(C, N, n, A, col, work):
    """The leg of compliance C (6x6 at ref) and constraint wrenches N[:, :n] as columns col..col+n-1 of A:
    N L^-T with L L^T = N^T C N, so that the leg's stiffness is their outer-product sum (K_leg = N (N^T C N)^-1
    N^T). Stacking every leg's columns gives the platform stiffness K = A A^T (platform_response_wrenches).
    Returns the next free column, or -1 if N^T C N is not positive definite."""
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
        return -1
    wrench_columns(m, N, n, A, col)
    return col + n


@njit(cache=True, fastmath=FASTMATH, inline="always")
def wrench_columns(L, W, n, A, col):
    """A[:, col:col+n] = W L^-T (L the lower Cholesky factor of a leg's flexibility on its wrench basis W[:, :n])."""
    for i in range(6):
        for a in range(n):
            t = W[i, a]
            for k in range(a):
                t -= L[a, k] * A[i, col + k]
            A[i, col + a] = t / L[a, a]


@njit(cache=True, fastmath=FASTMATH)
def platform_response_wrenches(A, fx, fy, fz, length, work):
    """(stiffness_min, deflection) as :func:`platform_response` for the platform stiffness K = A A^T, A (6x6) the
    stacked wrench columns of the legs (a non-redundant mechanism: six in all), without forming K: with rotations
    as arc lengths at ``length`` (A~ = S A, S = diag(1, 1, 1, 1/length, ...)), X = A~^-1 by LU with partial
    pivoting, K~^-1 = X^T X and C_t = X[:, :3]^T X[:, :3]. Singular as in the reference solver (eigenvalue ratio of
    K~ at most SINGULAR_RTOL; decided from tr(K~) tr(K~^-1), which bounds the ratio within a factor 36, and from
    the eigenvalues where that bound cannot decide); ``work``: a 6x6 scratch. A is overwritten."""
    zero = 0.0 if (fx == 0.0 and fy == 0.0 and fz == 0.0) else DEFLECTION_CAP
    inv = 1.0 / length
    tr = 0.0
    for i in range(6):
        for j in range(6):
            if i >= 3:
                A[i, j] *= inv
            tr += A[i, j] * A[i, j]
    if not tr > 0.0 or not math.isfinite(tr):
        return 0.0, zero
    piv = np.empty(6, dtype=np.int64)
    for j in range(6):  # LU, partial pivoting, in place
        p = j
        big = abs(A[j, j])
        for i in range(j + 1, 6):
            if abs(A[i, j]) > big:
                big = abs(A[i, j])
                p = i
        piv[j] = p
        if not big > 0.0:
            return 0.0, zero
        if p != j:
            for k in range(6):
                A[j, k], A[p, k] = A[p, k], A[j, k]
        d = 1.0 / A[j, j]
        for i in range(j + 1, 6):
            A[i, j] *= d
            f = A[i, j]
            for k in range(j + 1, 6):
                A[i, k] -= f * A[j, k]
    x = work  # X = A~^-1: solve A~ X = I
    for c in range(6):
        for i in range(6):
            x[i, c] = 0.0
        x[c, c] = 1.0
    for j in range(6):  # apply the row swaps to I
        p = piv[j]
        if p != j:
            for c in range(6):
                x[j, c], x[p, c] = x[p, c], x[j, c]
    for c in range(6):
        for i in range(6):
            t = x[i, c]
            for k in range(i):
                t -= A[i, k] * x[k, c]
            x[i, c] = t
        for i in range(5, -1, -1):
            t = x[i, c]
            for k in range(i + 1, 6):
                t -= A[i, k] * x[k, c]
            x[i, c] = t / A[i, i]
    tri = 0.0
    for i in range(6):
        for j in range(6):
            tri += x[i, j] * x[i, j]
    if not tr * tri * SINGULAR_RTOL < 1.0:
        if not math.isfinite(tri):
            return 0.0, zero
        # P A~ = L U, so K~ = A~ A~^T has the eigenvalues of (L U)(L U)^T
        lu = np.zeros((6, 6))
        for i in range(6):
            for j in range(6):
                t = A[i, j] if i <= j else 0.0
                for k in range(min(i, j + 1)):
                    t += A[i, k] * A[k, j]
                lu[i, j] = t
        w = np.linalg.eigvalsh(lu @ lu.T)
        if not w[0] > SINGULAR_RTOL * w[5]:
            return 0.0, zero
    c00 = c01 = c02 = c11 = c12 = c22 = 0.0
    for k in range(6):
        a0, a1, a2 = x[k, 0], x[k, 1], x[k, 2]
        c00 += a0 * a0
        c01 += a0 * a1
        c02 += a0 * a2
        c11 += a1 * a1
        c12 += a1 * a2
        c22 += a2 * a2
    lci, cmin, cmax = sv_3x3(c00, c01, c02, c01, c11, c12, c02, c12, c22)
    if not cmax > 0.0:
        return 0.0, zero
    dx = c00 * fx + c01 * fy + c02 * fz
    dy = c01 * fx + c11 * fy + c12 * fz
    dz = c02 * fx + c12 * fy + c22 * fz
    return 1.0 / cmax, min(math.sqrt(dx * dx + dy * dy + dz * dz), DEFLECTION_CAP)
