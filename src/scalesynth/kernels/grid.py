"""Generic voxel-grid evaluator, parallel over (design, x-slab) and deterministic.

Each x-slab of each design writes its partial sums into its own row; the rows are then reduced in a fixed
order, so results do not depend on thread scheduling. Grids are cell-centred: node i of an axis sits at
``lo + (i + 0.5) * step``.

The functions that take a point kernel as an argument are compiled per mechanism and NOT cached on disk: Numba
keys such cache entries by the dispatcher object, so they never hit in a new process and a stale entry can break
later saves. Mechanisms that need a fast start provide their own cached ``grid_stats`` (seed 000 does).

Statistics row layout (``N_FIXED`` leading columns, then one count per dexterity band):
``[count, sum_lci, sum_lci2, min_lci, max_lci, band_0, ..., band_{k-1}]``.
"""

import numpy as np
from numba import njit, prange

from scalesynth.kernels.flags import FASTMATH

COL_COUNT, COL_SUM, COL_SUMSQ, COL_MIN, COL_MAX = 0, 1, 2, 3, 4
N_FIXED = 5


@njit(cache=True, fastmath=FASTMATH, inline="always")
def _band_index(lci, edges):
    """Band k holds (edges[k], edges[k+1]]; the first band also holds its lower edge."""
    nb = edges.shape[0] - 1
    for k in range(nb - 1):
        if lci <= edges[k + 1]:
            return k
    return nb - 1


@njit(parallel=True, fastmath=FASTMATH)
def population_stats(point_kernel, params, lo, step, shape, edges):
    """Workspace statistics for every design on its own grid.

    params: (n_designs, k) packed designs; lo, step: (n_designs, 3); shape: int64[3] (nx, ny, nz);
    edges: dexterity band edges. Returns (n_designs, N_FIXED + n_bands) float64.
    """
    n_designs = params.shape[0]
    nx, ny, nz = shape[0], shape[1], shape[2]
    nb = edges.shape[0] - 1
    ncol = N_FIXED + nb
    partial = np.zeros((n_designs * nx, ncol))
    for task in prange(n_designs * nx):
        d = task // nx
        i = task - d * nx
        p = params[d]
        x = lo[d, 0] + (i + 0.5) * step[d, 0]
        count = 0.0
        s1 = 0.0
        s2 = 0.0
        vmin = 2.0
        vmax = -1.0
        row = partial[task]
        for j in range(ny):
            y = lo[d, 1] + (j + 0.5) * step[d, 1]
            for k in range(nz):
                z = lo[d, 2] + (k + 0.5) * step[d, 2]
                v = point_kernel(p, x, y, z)
                if v >= 0.0:
                    count += 1.0
                    s1 += v
                    s2 += v * v
                    if v < vmin:
                        vmin = v
                    if v > vmax:
                        vmax = v
                    row[N_FIXED + _band_index(v, edges)] += 1.0
        row[COL_COUNT] = count
        row[COL_SUM] = s1
        row[COL_SUMSQ] = s2
        row[COL_MIN] = vmin
        row[COL_MAX] = vmax
    return reduce_partials(partial, n_designs, nx)


@njit(cache=True)
def reduce_partials(partial, n_designs, nx):
    """Sum the per-slab rows of each design in slab order (deterministic, whatever the thread schedule)."""
    ncol = partial.shape[1]
    out = np.zeros((n_designs, ncol))
    for d in range(n_designs):
        acc = out[d]
        acc[COL_MIN] = 2.0
        acc[COL_MAX] = -1.0
        for i in range(nx):
            row = partial[d * nx + i]
            acc[COL_COUNT] += row[COL_COUNT]
            acc[COL_SUM] += row[COL_SUM]
            acc[COL_SUMSQ] += row[COL_SUMSQ]
            if row[COL_MIN] < acc[COL_MIN]:
                acc[COL_MIN] = row[COL_MIN]
            if row[COL_MAX] > acc[COL_MAX]:
                acc[COL_MAX] = row[COL_MAX]
            for b in range(N_FIXED, ncol):
                acc[b] += row[b]
    return out


@njit(parallel=True, fastmath=FASTMATH)
def sample_grid(point_kernel, p, lo, step, shape):
    """LCI at every node of one design's grid, shape (nx, ny, nz); -1 marks unreachable nodes."""
    nx, ny, nz = shape[0], shape[1], shape[2]
    out = np.empty((nx, ny, nz))
    for i in prange(nx):
        x = lo[0] + (i + 0.5) * step[0]
        for j in range(ny):
            y = lo[1] + (j + 0.5) * step[1]
            for k in range(nz):
                z = lo[2] + (k + 0.5) * step[2]
                out[i, j, k] = point_kernel(p, x, y, z)
    return out


@njit(fastmath=FASTMATH)
def points_lci(point_kernel, p, pts):
    """LCI (or -1) at arbitrary points, pts shape (n, 3)."""
    n = pts.shape[0]
    out = np.empty(n)
    for i in range(n):
        out[i] = point_kernel(p, pts[i, 0], pts[i, 1], pts[i, 2])
    return out


@njit(parallel=True, fastmath=FASTMATH)
def population_points_lci(point_kernel, params, pts):
    """LCI (or -1) of every design at the same points: params (n_designs, k), pts (n, 3) -> (n_designs, n)."""
    n_designs = params.shape[0]
    n = pts.shape[0]
    out = np.empty((n_designs, n))
    for d in prange(n_designs):
        p = params[d]
        for i in range(n):
            out[d, i] = point_kernel(p, pts[i, 0], pts[i, 1], pts[i, 2])
    return out
