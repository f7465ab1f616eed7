"""Closed-form extreme singular values of small matrices, and LCI = 1/kappa_2 = sigma_min / sigma_max.

Written without SVD so that the point kernels stay cheap and branch-free; each function has a NumPy twin in
``tests/naive.py`` / ``np.linalg.svd`` and the tests compare them.

``sv_3x3`` / ``sv_2x2`` return ``(lci, s_min, s_max)`` of the matrix. Point kernels whose conditioning matrix A
is the inverse Jacobian dq/dx report the singular values of J = dx/dq as ``inverse_singular_values``: 1/s_max(A)
and 1/s_min(A), the latter capped at ``SIGMA_CAP`` where A is singular (J unbounded).
"""

import math

from numba import njit

from scalesynth.kernels.flags import FASTMATH


@njit(cache=True, fastmath=FASTMATH)
def sv_3x3(a11, a12, a13, a21, a22, a23, a31, a32, a33):
    """(sigma_min/sigma_max, sigma_min, sigma_max) of the 3x3 matrix with rows (a11, a12, a13), (a21, ...), (a31, ...).

    With G = A A^T (eigenvalues l1 >= l2 >= l3 = squared singular values): lmax from the trigonometric cubic
    solution (well conditioned for the largest root); then the two smaller ones from
    l2 l3 = det(A)^2 / lmax and l2 + l3 = (c2 - l2 l3) / lmax, where c2 = sum of |r_i x r_j|^2 (Cauchy-Binet)
    is formed from cross products of the rows, never by cancellation in G, so tiny LCIs near singularities
    keep their relative accuracy.
    """
    g11 = a11 * a11 + a12 * a12 + a13 * a13
    g22 = a21 * a21 + a22 * a22 + a23 * a23
    g33 = a31 * a31 + a32 * a32 + a33 * a33
    g12 = a11 * a21 + a12 * a22 + a13 * a23
    g13 = a11 * a31 + a12 * a32 + a13 * a33
    g23 = a21 * a31 + a22 * a32 + a23 * a33
    # cross products of row pairs
    x12 = a12 * a23 - a13 * a22
    y12 = a13 * a21 - a11 * a23
    z12 = a11 * a22 - a12 * a21
    x13 = a12 * a33 - a13 * a32
    y13 = a13 * a31 - a11 * a33
    z13 = a11 * a32 - a12 * a31
    x23 = a22 * a33 - a23 * a32
    y23 = a23 * a31 - a21 * a33
    z23 = a21 * a32 - a22 * a31
    c2 = x12 * x12 + y12 * y12 + z12 * z12 + x13 * x13 + y13 * y13 + z13 * z13 + x23 * x23 + y23 * y23 + z23 * z23
    det = a11 * x23 + a12 * y23 + a13 * z23
    tr = g11 + g22 + g33
    if not tr > 0.0:
        return 0.0, 0.0, 0.0
    q = tr / 3.0
    p1 = g12 * g12 + g13 * g13 + g23 * g23
    b11 = g11 - q
    b22 = g22 - q
    b33 = g33 - q
    p2 = b11 * b11 + b22 * b22 + b33 * b33 + 2.0 * p1
    if p2 <= 1e-300 * q * q:
        sq = math.sqrt(q)
        return 1.0, sq, sq  # G = q I: all singular values equal
    p = math.sqrt(p2 / 6.0)
    inv_p = 1.0 / p
    b11 *= inv_p
    b22 *= inv_p
    b33 *= inv_p
    b12 = g12 * inv_p
    b13 = g13 * inv_p
    b23 = g23 * inv_p
    r = 0.5 * (b11 * (b22 * b33 - b23 * b23) - b12 * (b12 * b33 - b23 * b13) + b13 * (b12 * b23 - b22 * b13))
    if r >= 1.0:
        phi = 0.0
    elif r <= -1.0:
        phi = math.pi / 3.0
    else:
        phi = math.acos(r) / 3.0
    lmax = q + 2.0 * p * math.cos(phi)
    if not lmax > 0.0:
        return 0.0, 0.0, 0.0
    smax = math.sqrt(lmax)
    prod = det * det / lmax  # l2 * l3
    s = (c2 - prod) / lmax  # l2 + l3
    if s <= 0.0 or prod <= 0.0:
        return 0.0, 0.0, smax
    disc = s * s - 4.0 * prod
    if disc < 0.0:
        disc = 0.0
    lmid = 0.5 * (s + math.sqrt(disc))
    ratio = prod / lmid / lmax
    if ratio >= 1.0:
        return 1.0, smax, smax
    return math.sqrt(ratio), math.sqrt(prod / lmid), smax


@njit(cache=True, fastmath=FASTMATH)
def cos_third_acos(r):
    """cos(acos(r) / 3) for r in [-1, 1] (clamped), the scaled largest eigenvalue of the trigonometric cubic solution,
    without a transcendental call, so that a loop of it vectorises (libm's acos and cos do not).

    t = cos(acos(r) / 3) is the root in [1/2, 1] of 4 t^3 - 3 t = r (the triple-angle identity); with t = (1 + u) / 2
    that is u^3 + 3 u^2 = 2 (1 + r), u in [0, 1]. The guess u0 = sqrt(2 (1 + r) / (3 + sqrt((1 + r) / 2))) is exact
    at both ends; two Halley steps take it to rounding (2.3e-16 from the libm form over [-1, 1], tests). Near r = -1,
    where the two largest eigenvalues meet, both forms share the same conditioning (t - 1/2 ~ sqrt(1 + r)). Every
    divisor is bounded away from 0 by a max, which also keeps Numba's division-by-zero branch out of the loop."""
    s2 = max(0.0, min(4.0, 2.0 * (1.0 + r)))
    u = math.sqrt(s2 / max(3.0, 3.0 + math.sqrt(0.25 * s2)))
    for _ in range(2):  # Halley: u -= 2 h h' / (2 h'^2 - h h'') on h(u) = u^3 + 3 u^2 - s2
        uu = u * u
        h = uu * (u + 3.0) - s2
        d = 3.0 * uu + 6.0 * u
        u = u - 2.0 * h * d / max(1e-300, 2.0 * d * d - h * (6.0 * u + 6.0))
    return 0.5 * (1.0 + u)


@njit(cache=True, fastmath=FASTMATH)
def lci_3x3(a11, a12, a13, a21, a22, a23, a31, a32, a33):
    """sigma_min/sigma_max of the 3x3 matrix with rows (a11, a12, a13), (a21, ...), (a31, ...) (see sv_3x3)."""
    return sv_3x3(a11, a12, a13, a21, a22, a23, a31, a32, a33)[0]


@njit(cache=True, fastmath=FASTMATH)
def sv_2x2(a, b, c, d):
    """(sigma_min/sigma_max, sigma_min, sigma_max) of [[a, b], [c, d]] in closed form."""
    f = a * a + b * b + c * c + d * d
    det = a * d - b * c
    if not f > 0.0:
        return 0.0, 0.0, 0.0
    # sigma_max^2 + sigma_min^2 = f, sigma_max * sigma_min = |det|
    disc = f * f - 4.0 * det * det
    if disc < 0.0:
        disc = 0.0
    smax2 = 0.5 * (f + math.sqrt(disc))
    smin2 = det * det / smax2
    smax = math.sqrt(smax2)
    ratio = smin2 / smax2
    if ratio >= 1.0:
        return 1.0, smax, smax
    return math.sqrt(ratio), math.sqrt(smin2), smax


@njit(cache=True, fastmath=FASTMATH)
def lci_2x2(a, b, c, d):
    """sigma_min/sigma_max of [[a, b], [c, d]] in closed form (see sv_2x2)."""
    return sv_2x2(a, b, c, d)[0]


# Stands for an unbounded singular value (J = dx/dq at a singularity of dq/dx), so that every statistic stays finite.
SIGMA_CAP = 1e12


@njit(cache=True, fastmath=FASTMATH)
def inverse_singular_values(smin_a, smax_a):
    """(sigma_min, sigma_max) of J = A^-1 from A's extreme singular values: 1/smax_a and 1/smin_a (capped)."""
    lo = 1.0 / smax_a if smax_a > 1.0 / SIGMA_CAP else SIGMA_CAP
    hi = 1.0 / smin_a if smin_a > 1.0 / SIGMA_CAP else SIGMA_CAP
    return min(lo, SIGMA_CAP), min(hi, SIGMA_CAP)
