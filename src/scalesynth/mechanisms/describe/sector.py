"""The sector evaluator of rotationally symmetric described 3T mechanisms (experiment; issue 28, performance).

Where the legs are n-fold rotationally symmetric about z (and possibly mirrored), every field is too, so the
workspace statistics are those of one fundamental sector phi in [phi0, phi1] times 2 pi / (phi1 - phi0). The
template's closed-form column intervals (kernel.column_intervals) give each z-column's reachable set exactly, so
the volume is the integral over the sector of the column lengths, in polar coordinates:

    V_sector = int_{phi0}^{phi1} int_0^{R(phi)} len(r, phi) r dr dphi,

R(phi) the outermost radius with a nonempty column on the ray (a coarse scan, then bisection on "the column is
nonempty"). The substitution r = R (1 - s^2) turns the sqrt-type vanishing of len at R (a boundary surface with
a vertical tangent) into a smooth factor of s; s and phi run over Gauss-Legendre nodes. Each column's LCI integral
is a Gauss-Legendre rule on every reachable z-interval (nz nodes per interval, the weight of a node the product of
the three rules' weights); the statistics row (kernels.grid layout) accumulates those nodes with those weights:
count = volume in units of the caller's cell, sums of every field (LCI, sigma_min, sigma_max, and the stiffness
and clearance fields, 0 unless the packed design turns them on) and sums of squares,
bands of LCI, and min/max over the nodes (an estimate from inside, as every grid's).

The stiffness and clearance stages are most of the template's compile time, so the nodes run point_fields only
where some design's packed flag (options.stiffness_metrics or clearance_metrics) is set, else point_lci (slots 0-2
bit for bit, slots 3-5 left 0 as point_fields writes them with the flags off): a run without the flags never
compiles those stages.
"""

import math

import numpy as np
from numba import njit, prange

from scalesynth.kernels import grid as _grid
from scalesynth.kernels.flags import FASTMATH
from scalesynth.mechanisms.describe.kernel import CLEAR, F_CLEARANCE, STIFF, column_intervals, point_fields, point_lci

MAX_INTERVALS = 8  # reachable z-intervals per column (column_intervals' K)
N_FIELDS = F_CLEARANCE + 1  # the template's fields: LCI, sigma_min, sigma_max, stiffness_min, deflection, clearance
MAX_BISECTIONS = 64  # a boundary radius below 2^-64 of a scan step is 0 to any tolerance


@njit(cache=True, fastmath=FASTMATH)
def _column_length(p, x, y, zlo, zhi, iv):
    """Total length of the reachable set of the column at (x, y) over [zlo, zhi] and the interval count (negative:
    the column is not handled in closed form)."""
    k = column_intervals(p, x, y, zlo, zhi, iv)
    total = 0.0
    for i in range(k):
        total += iv[i, 1] - iv[i, 0]
    return total, k


@njit(cache=True, fastmath=FASTMATH)
def boundary_radius(p, c, s, rmax, zlo, zhi, nscan, nbisect, iv):
    """R on the ray (cos, sin) = (c, s): the last of nscan equal steps in [0, rmax] whose column is nonempty
    (r = 0 included: a workspace narrower than one step), refined by nbisect bisections against the next (empty)
    step, and where that is r = 0 by more until the bracket is within 2^-nbisect of its inner end (at most
    MAX_BISECTIONS in all); 0 when no step is nonempty, -1 when a column is not handled in closed form. Returns
    (R, interval-kernel calls)."""
    calls = 0
    last = -1
    for i in range(nscan, -1, -1):
        r = rmax * i / nscan
        length, k = _column_length(p, r * c, r * s, zlo, zhi, iv)
        calls += 1
        if k < 0:
            return -1.0, calls
        if length > 0.0:
            last = i
            break
    if last < 0:
        return 0.0, calls
    a = rmax * last / nscan
    if last == nscan:
        return a, calls
    b = rmax * (last + 1) / nscan
    # nbisect halvings; where only r = 0 is nonempty (last = 0: a sliver about the axis, narrower than one scan
    # step) more, until the bracket is within 2^-nbisect of its inner end: R to the relative precision that
    # last >= 1 has after nbisect (bracket step / 2^nbisect, inner end >= step); at most MAX_BISECTIONS in all
    tight = 0.5**nbisect
    for i in range(MAX_BISECTIONS):
        if i >= nbisect and (last > 0 or b - a <= tight * a):
            break
        m = 0.5 * (a + b)
        length, k = _column_length(p, m * c, m * s, zlo, zhi, iv)
        calls += 1
        if k < 0:
            return -1.0, calls
        if length > 0.0:
            a = m
        else:
            b = m
    return 0.5 * (a + b), calls


@njit(cache=True, fastmath=FASTMATH)
def sector_row(p, phi0, phi1, rmax, zlo, zhi, nscan, nbisect, xphi, wphi, xs, ws, xz, wz, zmin, edges, cell, row,
               stiffness):
    """Statistics row (kernels.grid layout, N_FIELDS fields, row pre-initialised by grid.init_row) of the sector
    [phi0, phi1] of the workspace in [zlo, zhi], radius at most rmax, extensive columns NOT yet scaled to the whole
    turn; counts in units of ``cell`` (m^3). Gauss-Legendre nodes/weights on [-1, 1]: xphi, wphi over phi, xs, ws
    over s in [0, 1] (r = R (1 - s^2)); on a z-interval of length len the n-point rule xz[n, :n], wz[n, :n] (tables
(nz + 1, nz)) with n = ceil(nz len / (zhi - zlo)) clamped to [zmin, nz]: nodes at about the same spacing on
every interval. ``stiffness`` True: the nodes run point_fields; None: point_lci (the stiffness fields stay 0; a
    None test, kernel._fields' comment: only the branch taken is compiled). Returns the kernel calls (interval +
    field), or -1 when a column is not handled in closed form."""
    iv = np.empty((MAX_INTERVALS, 2))
    out = np.zeros(N_FIELDS)  # point_lci writes slots 0-2 alone
    nb = edges.shape[0] - 1
    band0 = _grid.band_column(N_FIELDS, 0)
    calls = 0
    hphi = 0.5 * (phi1 - phi0)
    for i in range(xphi.shape[0]):
        phi = phi0 + hphi * (xphi[i] + 1.0)
        c = math.cos(phi)
        s = math.sin(phi)
        big_r, n = boundary_radius(p, c, s, rmax, zlo, zhi, nscan, nbisect, iv)
        calls += n
        if big_r < 0.0:
            return -1
        if big_r == 0.0:
            continue
        for j in range(xs.shape[0]):
            t = 0.5 * (xs[j] + 1.0)  # s in [0, 1]
            r = big_r * (1.0 - t * t)
            # dr = 2 R t dt, dt = ds_ref / 2; area element r dr dphi
            wcol = wphi[i] * hphi * ws[j] * 0.5 * 2.0 * big_r * t * r
            k = column_intervals(p, r * c, r * s, zlo, zhi, iv)
            calls += 1
            if k < 0:
                return -1
            nzmax = xz.shape[1]
            for m in range(k):
                a = iv[m, 0]
                h = 0.5 * (iv[m, 1] - a)
                row[_grid.COL_COUNT] += wcol * 2.0 * h / cell  # the exact column length
                nq = min(nzmax, max(zmin, int(math.ceil(nzmax * 2.0 * h / (zhi - zlo)))))
                for q in range(nq):
                    z = a + h * (xz[nq, q] + 1.0)
                    if stiffness is None:
                        point_lci(p, r * c, r * s, z, out)
                    else:
                        point_fields(p, r * c, r * s, z, out)
                    calls += 1
                    lci = out[0]
                    if lci < 0.0:  # an interval's node is reachable by construction; rounding at an end: skip
                        continue
                    w = wcol * h * wz[nq, q] / cell
                    for f in range(N_FIELDS):
                        v = out[f]
                        col = 1 + 4 * f
                        row[col] += w * v
                        row[col + 1] += w * v * v
                        if v < row[col + 2]:
                            row[col + 2] = v
                        if v > row[col + 3]:
                            row[col + 3] = v
                    band = nb - 1
                    for b in range(nb - 1):
                        if lci <= edges[b + 1]:
                            band = b
                            break
                    row[band0 + band] += w
    return calls


def population_sector_stats(params, phi0, phi1, rmax, zlo, zhi, nscan, nbisect, xphi, wphi, xs, ws, xz, wz, zmin,
                            edges, cell, rows, calls):
    """sector_row for every design (params (n, N_PACKED); rmax, zlo, zhi, cell: (n,)) into rows (n, columns) and
    calls (n,); parallel over designs (each writes its own row: the result does not depend on the threads). The
    stiffness stage is compiled and run only where some design's packed flag asks for it (module docstring)."""
    stiffness = True if np.any(params[:, STIFF] > 0.0) or np.any(params[:, CLEAR] > 0.0) else None
    # contiguous per-design arrays: a column of the boxes (lo[:, 2]) is strided, except for one design, and Numba
    # would compile the kernel once for each layout
    rmax, zlo, zhi, cell = (np.ascontiguousarray(a, dtype=np.float64) for a in (rmax, zlo, zhi, cell))
    _population_stats(params, phi0, phi1, rmax, zlo, zhi, nscan, nbisect, xphi, wphi, xs, ws, xz, wz, zmin, edges,
                      cell, rows, calls, stiffness)


@njit(cache=True, fastmath=FASTMATH, parallel=True)
def _population_stats(params, phi0, phi1, rmax, zlo, zhi, nscan, nbisect, xphi, wphi, xs, ws, xz, wz, zmin, edges,
                      cell, rows, calls, stiffness):
    """population_sector_stats; ``stiffness`` True or None as sector_row's (one compilation for each)."""
    for d in prange(params.shape[0]):
        _grid.init_row(rows[d], N_FIELDS)
        calls[d] = sector_row(params[d], phi0, phi1, rmax[d], zlo[d], zhi[d], nscan, nbisect, xphi, wphi, xs, ws,
                              xz, wz, zmin, edges, cell[d], rows[d], stiffness)
