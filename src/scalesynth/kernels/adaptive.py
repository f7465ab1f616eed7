"""Accuracy-targeted (adaptive) grid evaluator: a coarse vertex lattice, cells refined by octree bisection only
where they matter.

Algorithm (per design; ``tests/naive.py::adaptive_stats`` is its NumPy twin):

1. Evaluate every field at the (n0x + 1) x (n0y + 1) x (n0z + 1) corners of the coarse cells (``lo + i * step``;
   planar: ``ndim = 2``, z fixed at lo[2]).
2. Visit the coarse cells in (i, j, k) order. A cell of level l (edge step / 2^l) is refined when l < ``levels``
   and its corners disagree on reachability (the workspace boundary crosses it), or it lies next to such a cell
   (a coarse neighbour or a sibling: bulges of the workspace hide in cells whose corners are all outside), or,
   all reachable, their LCI range exceeds ``tau`` (the field varies fast). Refining evaluates the 3^ndim points
   of its bisection (the corners are reused) and visits its 2^ndim children depth first, in a fixed order.
3. A cell that is not refined is a leaf: each of its 2^ndim corners enters the statistics row with weight
   (cell measure / coarse cell measure) / 2^ndim (trapezoid rule; a boundary cell counts its reachable corners'
   share), so weights are binary fractions, exact in floating point, and every field's statistics use the same
   weights. Counts are in coarse-cell units: measure = count x coarse cell measure.

A second row is accumulated as if ``levels - 1`` were the deepest level; the difference of the two is the error
estimate of the result (Richardson with first-order convergence, which is conservative for these sums).
Parallel over (design, coarse x-slab) with a fixed reduction order: deterministic whatever the thread count.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from scalesynth.kernels.bind import bind
from scalesynth.kernels.flags import FASTMATH
from scalesynth.kernels.grid import accumulate_cells, gather_column, init_row, reduce_partials

# placeholders: kernels.bind gives each bound copy one mechanism's field kernel and field count
FIELD_KERNEL = None
N_FIELDS = 0


def _lattice(params, lo, step, shape, ndim):
    """Template: fields at the coarse corners, (n_designs, n0x + 1, n0y + 1, n0z + 1, n_fields)."""
    n_fields = N_FIELDS
    n_designs = params.shape[0]
    mx = shape[0] + 1
    my = shape[1] + 1
    mz = shape[2] + 1 if ndim == 3 else 1
    out = np.empty((n_designs, mx, my, mz, n_fields))
    for task in prange(n_designs * mx):
        d = task // mx
        i = task - d * mx
        p = params[d]
        cell = np.empty(n_fields)
        x = lo[d, 0] + i * step[d, 0]
        for j in range(my):
            y = lo[d, 1] + j * step[d, 1]
            for k in range(mz):
                FIELD_KERNEL(p, x, y, lo[d, 2] + k * step[d, 2], cell)
                for f in range(n_fields):
                    out[d, i, j, k, f] = cell[f]
    return out


@njit(cache=True, fastmath=FASTMATH)
def _mixed(corners, n_corners):
    """Whether the corners (n_corners, n_fields) disagree on reachability."""
    n_in = 0
    for c in range(n_corners):
        if corners[c, 0] >= 0.0:
            n_in += 1
    return 0 < n_in < n_corners


@njit(cache=True, fastmath=FASTMATH)
def _coarse_mixed(lattice, d, i, j, k, ndim):
    """Whether coarse cell (i, j, k) of design d, or one of its neighbours, has corners that disagree on
    reachability (cells outside the grid do not count)."""
    nx = lattice.shape[1] - 1
    ny = lattice.shape[2] - 1
    nz = lattice.shape[3] - 1 if ndim == 3 else 1
    kr = 1 if ndim == 3 else 0
    for a in range(max(i - 1, 0), min(i + 1, nx - 1) + 1):
        for b in range(max(j - 1, 0), min(j + 1, ny - 1) + 1):
            for c in range(max(k - kr, 0), min(k + kr, nz - 1) + 1):
                n_in = 0
                n_all = 0
                for da in range(2):
                    for db in range(2):
                        for dc in range(kr + 1):
                            n_all += 1
                            if lattice[d, a + da, b + db, c + dc, 0] >= 0.0:
                                n_in += 1
                if 0 < n_in < n_all:
                    return True
    return False


@njit(cache=True, fastmath=FASTMATH)
def _refine(corners, n_corners, level, levels, tau, forced):
    """Whether a cell with these corner fields (n_corners, n_fields) is bisected: below the last level, and
    ``forced`` (next to the workspace boundary), or its corners disagree on reachability, or their LCI range
    exceeds tau."""
    if level >= levels:
        return False
    if forced:
        return True
    n_in = 0
    lmin = 2.0
    lmax = -2.0
    for c in range(n_corners):
        v = corners[c, 0]
        if v >= 0.0:
            n_in += 1
        lmin = min(lmin, v)
        lmax = max(lmax, v)
    if n_in == 0:
        return False
    if n_in < n_corners:
        return True
    return lmax - lmin > tau


_BUFFER = 4096  # cells buffered per statistics row before they are reduced into it (kernels.grid accumulator)


@njit(cache=True, fastmath=FASTMATH)
def _add_leaf(row, corners, n_corners, w, edges, vals, buf, wbuf, m):
    """Buffer a leaf's corners, each with weight w / n_corners; reduce the buffer into the row when full.
    Returns the new fill."""
    for c in range(n_corners):
        for f in range(vals.shape[0]):
            vals[f, c] = corners[c, f]
    if m + n_corners > buf.shape[1]:
        accumulate_cells(row, buf, wbuf, m, edges)
        m = 0
    return gather_column(buf, wbuf, m, vals, 0, n_corners - 1, w / n_corners)


def _adaptive_stats(params, lo, step, shape, edges, ndim, levels, tau, lattice):
    """Template: (stats, stats_one_level_coarser, evaluations) per design; see the module docstring."""
    n_fields = N_FIELDS
    n_designs = params.shape[0]
    nx, ny = shape[0], shape[1]
    nz = shape[2] if ndim == 3 else 1
    nb = edges.shape[0] - 1
    ncol = 1 + 4 * n_fields + nb
    nc = 1 << ndim
    n_sub = 27 if ndim == 3 else 9
    partial = np.zeros((n_designs * nx, ncol))
    partial2 = np.zeros((n_designs * nx, ncol))
    evals = np.zeros(n_designs * nx)
    cap = 8 * (levels + 1) + 1
    for task in prange(n_designs * nx):
        d = task // nx
        i = task - d * nx
        p = params[d]
        row = partial[task]
        row2 = partial2[task]
        init_row(row, n_fields)
        init_row(row2, n_fields)
        vals = np.empty((n_fields, 8))
        cell = np.empty(n_fields)
        sub = np.empty((27, n_fields))
        st_o = np.empty((cap, 3))
        st_l = np.empty(cap, dtype=np.int64)
        st_c = np.empty((cap, 8, n_fields))
        st_f = np.empty(cap, dtype=np.bool_)
        buf = np.empty((n_fields, _BUFFER))
        wbuf = np.empty(_BUFFER)
        buf2 = np.empty((n_fields, _BUFFER))
        wbuf2 = np.empty(_BUFFER)
        m = 0
        m2 = 0
        n_eval = 0.0
        for j in range(ny):
            for k in range(nz):
                # the coarse cell (i, j, k) on the stack
                for c in range(nc):
                    ci = i + (c & 1)
                    cj = j + ((c >> 1) & 1)
                    ck = k + ((c >> 2) & 1) if ndim == 3 else 0
                    for f in range(n_fields):
                        st_c[0, c, f] = lattice[d, ci, cj, ck, f]
                st_o[0, 0] = lo[d, 0] + i * step[d, 0]
                st_o[0, 1] = lo[d, 1] + j * step[d, 1]
                st_o[0, 2] = lo[d, 2] + k * step[d, 2]
                st_l[0] = 0
                st_f[0] = _coarse_mixed(lattice, d, i, j, k, ndim)
                top = 1
                while top > 0:
                    top -= 1
                    level = st_l[top]
                    corners = st_c[top]
                    w = 1.0 / (1 << (ndim * level))
                    if not _refine(corners, nc, level, levels, tau, st_f[top]):
                        m = _add_leaf(row, corners, nc, w, edges, vals, buf, wbuf, m)
                        if level <= levels - 1 or levels == 0:
                            m2 = _add_leaf(row2, corners, nc, w, edges, vals, buf2, wbuf2, m2)
                        continue
                    if level == levels - 1:
                        m2 = _add_leaf(row2, corners, nc, w, edges, vals, buf2, wbuf2, m2)
                    h = 0.5 / (1 << level)
                    hx = h * step[d, 0]
                    hy = h * step[d, 1]
                    hz = h * step[d, 2]
                    ox = st_o[top, 0]
                    oy = st_o[top, 1]
                    oz = st_o[top, 2]
                    # the 3^ndim bisection points, index a + 3 b + 9 c; corners (even a, b, c) reused
                    for s in range(n_sub):
                        a = s % 3
                        b = (s // 3) % 3
                        cc = s // 9
                        if a != 1 and b != 1 and cc != 1:
                            src = (a >> 1) | ((b >> 1) << 1) | ((cc >> 1) << 2)
                            for f in range(n_fields):
                                sub[s, f] = corners[src, f]
                        else:
                            FIELD_KERNEL(p, ox + a * hx, oy + b * hy, oz + cc * hz, cell)
                            n_eval += 1.0
                            for f in range(n_fields):
                                sub[s, f] = cell[f]
                    # children pushed in reverse so that child 0 is visited first; all of them are refined further
                    # when one is crossed by the boundary (a bulge of the workspace may hide in a child whose
                    # corners are all outside)
                    base = top
                    any_mixed = False
                    for child in range(nc - 1, -1, -1):
                        ca = child & 1
                        cb = (child >> 1) & 1
                        cz = (child >> 2) & 1
                        for c in range(nc):
                            s = (ca + (c & 1)) + 3 * (cb + ((c >> 1) & 1)) + 9 * (cz + ((c >> 2) & 1))
                            for f in range(n_fields):
                                st_c[top, c, f] = sub[s, f]
                        st_o[top, 0] = ox + ca * hx
                        st_o[top, 1] = oy + cb * hy
                        st_o[top, 2] = oz + cz * hz
                        st_l[top] = level + 1
                        any_mixed = any_mixed or _mixed(st_c[top], nc)
                        top += 1
                    for t in range(base, top):
                        st_f[t] = any_mixed
        accumulate_cells(row, buf, wbuf, m, edges)
        accumulate_cells(row2, buf2, wbuf2, m2, edges)
        evals[task] = n_eval
    out_evals = np.zeros(n_designs)
    for d in range(n_designs):
        for i in range(nx):
            out_evals[d] += evals[d * nx + i]
    return (reduce_partials(partial, n_designs, nx, n_fields), reduce_partials(partial2, n_designs, nx, n_fields),
            out_evals)


def adaptive_stats(field_kernel, n_fields, params, lo, step, shape, edges, ndim, levels, tau):
    """Statistics rows of every design by the adaptive algorithm (module docstring).

    params (n, k); lo, step (n, 3): origin and edge of the coarse cells; shape int64[3]: coarse cells per axis
    (planar: shape[2] = 1 and ndim = 2); levels: bisection levels; tau: LCI range that triggers refinement.
    Returns (stats, stats_coarser, evaluations): two (n, stat_columns) arrays with counts in coarse-cell units
    (the second as if levels - 1 were the deepest) and the field-kernel calls per design (float64 (n,)).
    """
    lattice = bind(_lattice, field_kernel, n_fields, parallel=True, fastmath=FASTMATH)(params, lo, step, shape,
                                                                                        ndim)
    run = bind(_adaptive_stats, field_kernel, n_fields, parallel=True, fastmath=FASTMATH)
    stats, coarser, evals = run(params, lo, step, shape, edges, ndim, levels, tau, lattice)
    return stats, coarser, evals + lattice.shape[1] * lattice.shape[2] * lattice.shape[3]
