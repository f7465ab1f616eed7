"""Accuracy-targeted (adaptive) evaluator: reachable intervals along columns, found by bisection, integrated by
Gauss rules; the columns refined (ternary) only where the column measures curve.

Algorithm, per design (``tests/naive.py::column_stats`` is its NumPy twin):

0. z-levels (``zlevels`` > 0): level 0 is computed with m z-cells, then again with 2m, 4m, ... (every column of
   the coarse grid) until ``zconfirm`` consecutive changes of the measure (relative) and of the GCI (absolute)
   meet the tolerance, or ``zlevels`` doublings; the later steps use that z-resolution. A reachable shell thinner
   than a z-cell lies between two nodes of every column, so no cross level can see it; nested node sets (m, 2m)
   can miss the same shell twice, hence the confirmations (issue 15: 2pauu-ppap's lobe tips, pprs-rprs's and
   rps-upu-tool's thin slabs, 1-24 % of the volume at m = 8).
1. Columns run along the last task axis ("z"; planar mechanisms: y) over a cell-centred grid of the other axes
   (nx x ny columns: column_stats's n, ny; planar: nx). Along a column reachability is evaluated at the m + 1
   nodes ``zlo + k hz`` (the mechanism's reach kernel: slot 0 alone); where reachability changes between two
   nodes, ``nbis`` bisection steps locate the boundary (estimate: the midpoint of the last bracket, error <=
   hz / 2^(nbis+1)). So the column's reachable length is exact to that precision, not a voxel count.
   With an interval kernel (Mechanism.interval_kernel, 3-D; column_stats's ``interval_kernel``) a column's
   reachable intervals come in closed form instead (one call), and each z-cell's intersections with them are the
   pieces of step 2; no nudge is needed at the column ends (the Gauss points lie inside the pieces); where it
   returns -1 the column takes the nodes and bisections (``_column_intervals``).
2. Each reachable piece of a z-cell is integrated by the 2-point Gauss-Legendre rule: every field at its two points,
   each with half the piece's length (a point that turns out unreachable gives its weight to the other; a piece
   with neither reachable is dropped). The points' fields and weights feed the shared statistics accumulator
   (kernels.grid), so every statistic of the row layout (count, sum, sum of squares, min, max per field, band
   measures) exists as for uniform grids. With ``gauss_points`` 1 the midpoint rule instead: the fields at the
   piece's midpoint with its whole length (dropped if unreachable).
3. Level 0 integrates the column measures L and LCI sums S over the cross grid by the midpoint rule. Its local
   error indicator is the second difference of L (and of S) over the neighbouring columns (the midpoint rule is
   exact for linear variation; walls and silhouettes give large second differences). At the box the neighbour is
   the edge column itself (clamped), or, with ``faces``, the ghost value 2 F - L where F is the column on the box
   face (x = lo or hi; y = lo or hi) next to it: a wall between an edge column's centre and the box face (a task
   box cutting the workspace: rps-upu-tool) is otherwise invisible. A lo face declared a mirror plane (``mirror``:
   a half box of a field symmetric about that face) has no ghost: the neighbour across it is the edge column's
   mirror image, i.e. the edge column itself (clamped). A column whose indicator x cell area / 24 exceeds its
   share ``beta * tol * V / (nx ny)`` (planar: ``/ nx``) is refined: its cell splits into 3 x 3 (planar: 3)
   cells, each with its own column (the centre one is its parent's column: the same point, reused with 1/9 of
   the weight, not recomputed). The next level repeats steps 1-3 on the new columns, with
   the others held at their coarser values.
3b. Inherited fields (``field_levels`` = f >= 0): a new column at a level above f takes its measure alone (its
   intervals, or nodes and bisections: no Gauss points) and its parent's statistics row scaled by its measure over
   the parent's (L / (L_parent nk)): the fields' distribution per unit measure of the parent (its LCI sum S =
   L S_parent / L_parent). Refinement is mostly driven by walls, where the measure jumps but the fields do not;
   the fields then cost only the coarse levels. A column's children still evaluate their own fields where it has
   no measure (nothing to inherit) or where the second difference of its mean LCI S / L along a cross axis (a
   neighbour without measure replaced by the column itself), x L x cell area / 24, exceeds the GCI share of step 3
   (``field_flags``). The level-to-level estimate of step 4 does not see what inheriting costs (a child's mean
   differs from its parent's by the gradient over a third of a cell, which cancels between children except where
   a wall keeps only some of them): the plans that use it are checked against references (evaluate.py).
4. After each level l >= 1 the error estimate is the change of the workspace measure (relative) and of the GCI
   (absolute) from level l-1; the design stops at the first level whose estimate meets the tolerance, or at
   ``maxlev``, or when no column is flagged for refinement (the estimate is then the last change, reported as
   it is even when above the tolerance; 0 if that happens at level 0: the midpoint rule sees no curvature). The
   reported estimate is the larger of it and the last z-level change.

Limits: a change of 0 between two levels is not proof of accuracy (a wall whose refined columns' centres all stay
on one side of it; tests/test_adaptive.py::test_box_face_columns_see_a_wall_inside_the_edge_columns); a shell
thinner than the finest z-cell, or a slit narrower than the finest column spacing, is still missed.

Counts are in units of the coarse cell (cross cell x hz with hz = box / m): measure = count x hx hy hz with
hx = box / nx, hy = box / ny. So the half box [0, hi] of a box symmetric about 0 on a cross axis, with half the
columns on that axis and its lo face a mirror plane, evaluates the same columns as the full box's upper half and
makes the same refinement decisions there (up to rounding): its extensive statistics are half the full box's.
Parallel over designs, each design serial with a fixed order of columns: deterministic whatever the thread count.
Compilation: the design and population loops (``_design_stats``, ``_population_column_stats``) compile once for
every mechanism (kernels.bind.shared); a mechanism's column kernel (``_column`` or ``_column_intervals`` bound to
its field, reach and interval kernels, COLUMN_SIGNATURE) is their first argument, a first-class function.
The columns' L and S live in a sparse cell store (initial_cells, refine_cells: each column with its neighbours'
cells), not in a dense grid of the finest level, whose copies and sums cost more than the refined columns at level
3 (tests/test_adaptive_store.py compares the two; benchmarks/adaptive_store_ab.py, in git history at 76b48df, the
evaluator before and after).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numba import types as nbtypes

from scalesynth.kernels.bind import bind, shared
from scalesynth.kernels.flags import FASTMATH
from scalesynth.kernels.grid import accumulate_cells, init_row
from scalesynth.kernels.threads import in_threads

# placeholders: kernels.bind gives each bound copy one mechanism's field kernel and field count, and (``_column``)
# its reach kernel: same signature, slot 0 >= 0 exactly where the field kernel's is, the other slots not written
# (Mechanism.reach_kernel; the field kernel itself where a mechanism has none). Nodes and bisection points need
# reachability alone: a reach kernel skips the conditioning, clearance and stiffness there (the Gauss points get
# every field).
FIELD_KERNEL = None
REACH_KERNEL = None
N_FIELDS = 0

GAUSS_X = 1.0 / math.sqrt(3.0)  # 2-point Gauss-Legendre abscissa on [-1, 1] (weights 1)
# the end nodes of a column are evaluated this fraction of hz inside the box: a box is often made of the limits
# themselves, and reachability exactly on a limit depends on rounding (fused multiply-adds differ between two
# compilations of the same field kernel)
END_NUDGE = 2.0**-20
# rows of the interval kernel's out (Mechanism.interval_kernel): a column needing more falls back to nodes
MAX_INTERVALS = 8
# more placeholders, of the interval variant (_column_intervals) alone: the mechanism's interval kernel and the
# bound node-and-bisection column (_column) it falls back to
INTERVAL_KERNEL = None
NODE_COLUMN = None


@njit(cache=True)
def _add_product(a, b, c):
    """a + b c without fastmath (no fused multiply-add): sample coordinates are computed exactly as the NumPy
    twin computes them, so a point on the box face (where reachability may flip) is the same point in both."""
    return a + b * c


@njit(cache=True)
def _div(a, b):
    """a / b without fastmath ('arcp' would multiply by a rounded reciprocal): cell sizes as the twin computes them."""
    return a / b


@njit(cache=True)
def _centre(lo, i, h, scale):
    """lo + (i + 0.5) h / scale without fastmath (no reciprocal, no fused multiply-add): a column's cross coordinate
    exactly as the NumPy twin computes it (near a singular surface a field can change by 1e-6 relative per ulp)."""
    return lo + (i + 0.5) * h / scale


@njit(cache=True, fastmath=FASTMATH)
def add_row(acc, row, n_fields):
    """Fold statistics row ``row`` into ``acc`` (sums added, min/max combined)."""
    acc[0] += row[0]
    for f in range(n_fields):
        c = 1 + 4 * f
        acc[c] += row[c]
        acc[c + 1] += row[c + 1]
        acc[c + 2] = min(acc[c + 2], row[c + 2])
        acc[c + 3] = max(acc[c + 3], row[c + 3])
    for b in range(1 + 4 * n_fields, acc.shape[0]):
        acc[b] += row[b]


@njit(cache=True, fastmath=FASTMATH)
def _neighbour_values(gv, nb, a, axis, c):
    """(below, above) of active column a's value ``c`` along a cross axis: its neighbours' values in ``gv``, the
    column itself (clamped) at the box (``nb`` -1)."""
    lo_ref = nb[a, 2 * axis]
    hi_ref = nb[a, 2 * axis + 1]
    return (c if lo_ref < 0 else gv[lo_ref]), (c if hi_ref < 0 else gv[hi_ref])


@njit(cache=True, fastmath=FASTMATH)
def flag_columns(gl, gs, gi, nb, ci, cj, n_active, ndim, area, budget_v, budget_g, faces, mirror_x, mirror_y, fxg,
                 fyg, flags):
    """flags[a] = whether active column a (cell ci[a], cj[a]; its values gl[gi[a]], gs[gi[a]]; its neighbours
    nb[a]) is refined: a second difference of the column measure (or LCI sum) along a cross axis, x area / 24,
    above its budget (neighbours clamped at the box; with ``faces`` the face ghosts instead, except on a lo face
    that is a mirror plane: ``mirror_x``, ``mirror_y``)."""
    for a in range(n_active):
        f = False
        for axis in range(ndim - 1):
            for t in range(2):
                g = gl if t == 0 else gs
                c = g[gi[a]]
                below, above = _neighbour_values(g, nb, a, axis, c)
                if faces:
                    # at the box, the neighbour is the ghost 2 F - c, F the face column's value (linear
                    # extrapolation through the face): a wall between the edge column and the face shows
                    other = cj[a] if axis == 0 else ci[a]
                    fg = fxg if axis == 0 else fyg
                    # a mirror plane keeps the clamped neighbour: the edge column's mirror image is itself
                    if nb[a, 2 * axis] < 0 and not (mirror_x if axis == 0 else mirror_y):
                        below = 2.0 * fg[0, t, other] - c
                    if nb[a, 2 * axis + 1] < 0:
                        above = 2.0 * fg[1, t, other] - c
                d2 = abs(above + below - 2.0 * c)
                if d2 * area / 24.0 > (budget_v if t == 0 else budget_g):
                    f = True
        flags[a] = f


@njit(cache=True, fastmath=FASTMATH)
def field_flags(gl, gs, gi, nb, n_active, ndim, area, budget_g, fflags):
    """fflags[a] = whether active column a's children evaluate their own fields (step 3b): its column has no
    measure, or the second difference of the mean LCI S / L along a cross axis (a neighbour without measure
    replaced by the column itself), x L x area / 24, exceeds the GCI budget (flag_columns' for S)."""
    for a in range(n_active):
        lc = gl[gi[a]]
        if not lc > 0.0:
            fflags[a] = True
            continue
        mc = gs[gi[a]] / lc
        f = False
        for axis in range(ndim - 1):
            r0 = nb[a, 2 * axis]
            r1 = nb[a, 2 * axis + 1]
            below = gs[r0] / gl[r0] if r0 >= 0 and gl[r0] > 0.0 else mc
            above = gs[r1] / gl[r1] if r1 >= 0 and gl[r1] > 0.0 else mc
            if abs(above + below - 2.0 * mc) * lc * area / 24.0 > budget_g:
                f = True
        fflags[a] = f


@njit(cache=True, fastmath=FASTMATH)
def leaf_sums(gl, gs, gchild, seg, level, ndim):
    """(measure, LCI sum) in coarse-cell units of the cell store's leaves (gchild -1) up to ``level``: a leaf of
    level l, cells seg[l]:seg[l + 1], weighs its cell's area, 1 / 9^l (planar 1 / 3^l). A sum of non-negative
    terms: exactly 0 where nothing is reachable."""
    vol = 0.0
    ssum = 0.0
    scale = 1.0
    for lev in range(level + 1):
        area = 1.0 / (scale * scale) if ndim == 3 else 1.0 / scale
        v = 0.0
        s = 0.0
        for c in range(seg[lev], seg[lev + 1]):
            if gchild[c] < 0:
                v += gl[c]
                s += gs[c]
        vol += v * area
        ssum += s * area
        scale *= 3.0
    return vol, ssum


@njit(cache=True)
def _grow(g, n):
    """``g`` (1-D) with ``n`` more slots at its end (uninitialised)."""
    out = np.empty(g.shape[0] + n, dtype=g.dtype)
    out[: g.shape[0]] = g
    return out


@njit(cache=True)
def initial_cells(nx, ny, ndim):
    """The cell store of level 0's nx x ny columns (planar: ny 1), cell a = i ny + j: (gl, gs, gchild, gi, nb) as
    refine_cells returns them, values 0."""
    n = nx * ny
    gl = np.zeros(n)
    gs = np.zeros(n)
    gchild = np.full(n, -1, dtype=np.int64)
    gi = np.arange(n)
    nb = np.full((n, 4), -1, dtype=np.int64)
    for a in range(n):
        i = a // ny
        j = a - i * ny
        if i > 0:
            nb[a, 0] = a - ny
        if i < nx - 1:
            nb[a, 1] = a + ny
        if ndim == 3 and j > 0:
            nb[a, 2] = a - 1
        if ndim == 3 and j < ny - 1:
            nb[a, 3] = a + 1
    return gl, gs, gchild, gi, nb


@njit(cache=True)
def refine_cells(gl, gs, gchild, gi, nb, flags, n_active, ndim):
    """The children of the flagged active columns, in (parent, a, b) order (3 x 3; planar: 3 along axis 0): the
    cell store (gl, gs, gchild) grown by their slots, each child's L and S its parent's until computed, each
    flagged parent's gchild its first child; the children's global indices and neighbours (-x, +x, -y, +y: a
    sibling, the child of a refined neighbour across the border, or an unrefined neighbour itself, which keeps
    its value over the finer cells it covers; -1 at the box). Returns (gl, gs, gchild, gi, nb)."""
    ry = 3 if ndim == 3 else 1
    nk = 3 * ry
    n_flag = 0
    for a in range(n_active):
        if flags[a]:
            n_flag += 1
    base = gl.shape[0]
    gl = _grow(gl, n_flag * nk)
    gs = _grow(gs, n_flag * nk)
    gchild = _grow(gchild, n_flag * nk)
    k = 0
    for a in range(n_active):
        if flags[a]:
            gchild[gi[a]] = base + k * nk
            k += 1
    cgi = np.empty(n_flag * nk, dtype=np.int64)
    cnb = np.empty((n_flag * nk, 4), dtype=np.int64)
    t = 0
    for a in range(n_active):
        if not flags[a]:
            continue
        p = gi[a]
        first = gchild[p]
        for da in range(3):
            for db in range(ry):
                g = first + da * ry + db
                gl[g] = gl[p]
                gs[g] = gs[p]
                gchild[g] = -1
                cgi[t] = g
                for side in range(4):
                    axis = side // 2
                    step = -1 if side % 2 == 0 else 1
                    d = da if axis == 0 else db
                    if axis == 1 and ndim == 2:
                        cnb[t, side] = -1  # planar: no second cross axis
                    elif 0 <= d + step <= 2:  # a sibling
                        cnb[t, side] = g + (step * ry if axis == 0 else step)
                    else:
                        nbr = nb[a, side]
                        if nbr < 0:
                            cnb[t, side] = -1
                        elif gchild[nbr] >= 0:  # the neighbour was refined too: its child across the border
                            e = 2 if step < 0 else 0
                            cnb[t, side] = gchild[nbr] + (e * ry + db if axis == 0 else da * ry + e)
                        else:
                            cnb[t, side] = nbr
                t += 1
    return gl, gs, gchild, cgi, cnb


@njit(cache=True, fastmath=FASTMATH)
def refine_faces(fg, r):
    """Face-column values [side, L or S, index] at the next level: every value repeated over its r children."""
    out = np.empty((2, 2, fg.shape[2] * r))
    for s in range(2):
        for t in range(2):
            for i in range(out.shape[2]):
                out[s, t, i] = fg[s, t, i // r]
    return out


def _column(p, x, y, zfix, ndim, zlo, hz, hz0, mz, nbis, area, nodes, cell, q0, q1, buf, wbuf, out, gauss):
    """Template (serial): one column at (x, y) with ``mz`` z-cells of height ``hz`` (steps 1-2): its Gauss points'
    fields into buf[:, :npts] and weights (x ``area``, in units of ``hz0``) into wbuf; out = (column measure L, LCI
    sum S, npts, field-kernel calls)."""
    n_fields = N_FIELDS
    evals = 0.0
    for k in range(mz + 1):
        zk = _add_product(zlo, END_NUDGE if k == 0 else (mz - END_NUDGE if k == mz else k), hz)
        if ndim == 3:
            REACH_KERNEL(p, x, y, zk, cell)
        else:
            REACH_KERNEL(p, x, zk, zfix, cell)
        nodes[k] = cell[0]
    evals += mz + 1
    npts = 0
    col_l = 0.0
    col_s = 0.0
    for k in range(mz):
        r0 = nodes[k] >= 0.0
        r1 = nodes[k + 1] >= 0.0
        if not r0 and not r1:
            continue
        za = _add_product(zlo, k, hz)
        zb = _add_product(zlo, k + 1, hz)
        if r0 != r1:
            # bisection: [a, b] keeps node k's reachability at a
            ba = za
            bb = zb
            for _ in range(nbis):
                mid = 0.5 * (ba + bb)
                if ndim == 3:
                    REACH_KERNEL(p, x, y, mid, cell)
                else:
                    REACH_KERNEL(p, x, mid, zfix, cell)
                if (cell[0] >= 0.0) == r0:
                    ba = mid
                else:
                    bb = mid
            evals += nbis
            cross = 0.5 * (ba + bb)
            if r0:
                zb = cross
            else:
                za = cross
        if gauss == 0:
            col_l += (zb - za) / hz0  # the measure alone (a column whose fields are inherited)
            continue
        # 2. 2-point Gauss rule on the piece [za, zb]
        half = 0.5 * (zb - za)
        zm = 0.5 * (za + zb)
        # the first point (the 1-point rule: the piece's midpoint, with its whole length); one call site per point,
        # since the field kernel is compiled into each
        z0 = zm if gauss == 1 else _add_product(zm, -half, GAUSS_X)
        if ndim == 3:
            FIELD_KERNEL(p, x, y, z0, q0)
        else:
            FIELD_KERNEL(p, x, z0, zfix, q0)
        if gauss == 1:
            evals += 1
            if q0[0] >= 0.0:
                w = 2.0 * half / hz0
                for f in range(n_fields):
                    buf[f, npts] = q0[f]
                wbuf[npts] = w * area
                npts += 1
                col_l += w
                col_s += w * q0[0]
            continue
        if ndim == 3:
            FIELD_KERNEL(p, x, y, _add_product(zm, half, GAUSS_X), q1)
        else:
            FIELD_KERNEL(p, x, _add_product(zm, half, GAUSS_X), zfix, q1)
        evals += 2
        ok0 = q0[0] >= 0.0
        ok1 = q1[0] >= 0.0
        if not ok0 and not ok1:
            continue
        w = half / hz0 if ok0 and ok1 else 2.0 * half / hz0
        if ok0:
            for f in range(n_fields):
                buf[f, npts] = q0[f]
            wbuf[npts] = w * area
            npts += 1
            col_l += w
            col_s += w * q0[0]
        if ok1:
            for f in range(n_fields):
                buf[f, npts] = q1[f]
            wbuf[npts] = w * area
            npts += 1
            col_l += w
            col_s += w * q1[0]
    out[0] = col_l
    out[1] = col_s
    out[2] = npts
    out[3] = evals


def _column_intervals(p, x, y, zfix, ndim, zlo, hz, hz0, mz, nbis, area, nodes, cell, q0, q1, buf, wbuf, out,
                      gauss):
    """Template (serial), ``_column``'s variant with an interval kernel (step 1 in closed form; 3-D only): the
    reachable intervals of the column over [zlo, zlo + mz hz] from INTERVAL_KERNEL, then each z-cell's intersection
    with each interval (a piece; none, one or several per cell, a piece of zero length dropped) integrated as in
    ``_column`` (step 2). Evaluations: 1 for the interval call, ``gauss`` per piece (0: the measure alone). Where
    the interval kernel returns -1 (planar tasks: always) the column is NODE_COLUMN's, plus the 1 call. ``nodes`` has
    >= 2 MAX_INTERVALS slots:
    its head holds the intervals. buf, wbuf hold >= 2 (mz + MAX_INTERVALS) points (a cell split by gaps between
    intervals has one piece more per gap)."""
    if ndim != 3:
        NODE_COLUMN(p, x, y, zfix, ndim, zlo, hz, hz0, mz, nbis, area, nodes, cell, q0, q1, buf, wbuf, out, gauss)
        return
    n_fields = N_FIELDS
    iv = nodes[: 2 * MAX_INTERVALS].reshape((MAX_INTERVALS, 2))
    # the top is the last node of the node path (zlo + mz hz), not the box's hi: the same column to rounding
    k = INTERVAL_KERNEL(p, x, y, zlo, _add_product(zlo, mz, hz), iv)
    if k < 0:
        NODE_COLUMN(p, x, y, zfix, ndim, zlo, hz, hz0, mz, nbis, area, nodes, cell, q0, q1, buf, wbuf, out, gauss)
        out[3] += 1.0
        return
    evals = 1.0
    npts = 0
    col_l = 0.0
    col_s = 0.0
    t = 0  # first interval not wholly below the current cell
    for c in range(mz):
        if t >= k:
            break
        ca = _add_product(zlo, c, hz)
        cb = _add_product(zlo, c + 1, hz)
        while t < k and iv[t, 1] <= ca:
            t += 1
        u = t
        while u < k and iv[u, 0] < cb:
            za = max(ca, iv[u, 0])
            zb = min(cb, iv[u, 1])
            u += 1
            if not zb > za:
                continue
            if gauss == 0:
                col_l += (zb - za) / hz0  # the measure alone (a column whose fields are inherited)
                continue
            # 2. 2-point Gauss rule on the piece [za, zb], weights as in _column (a copy of its lines: one shared
            # inline helper was byte-identical but made rps_upu_tool's search loop about 10 % slower)
            half = 0.5 * (zb - za)
            zm = 0.5 * (za + zb)
            # the first point as in _column (one call site per point); the 1-point rule's lines are _column's,
            # copied as the 2-point ones below (same reason)
            FIELD_KERNEL(p, x, y, zm if gauss == 1 else _add_product(zm, -half, GAUSS_X), q0)
            if gauss == 1:
                evals += 1
                if q0[0] >= 0.0:
                    w = 2.0 * half / hz0
                    for f in range(n_fields):
                        buf[f, npts] = q0[f]
                    wbuf[npts] = w * area
                    npts += 1
                    col_l += w
                    col_s += w * q0[0]
                continue
            FIELD_KERNEL(p, x, y, _add_product(zm, half, GAUSS_X), q1)
            evals += 2
            ok0 = q0[0] >= 0.0
            ok1 = q1[0] >= 0.0
            if not ok0 and not ok1:
                continue
            w = half / hz0 if ok0 and ok1 else 2.0 * half / hz0
            if ok0:
                for f in range(n_fields):
                    buf[f, npts] = q0[f]
                wbuf[npts] = w * area
                npts += 1
                col_l += w
                col_s += w * q0[0]
            if ok1:
                for f in range(n_fields):
                    buf[f, npts] = q1[f]
                wbuf[npts] = w * area
                npts += 1
                col_l += w
                col_s += w * q1[0]
    out[0] = col_l
    out[1] = col_s
    out[2] = npts
    out[3] = evals


def _design_stats(column, n_fields, p, lo_d, hi_d, ndim, nx, ny3, m, nbis, maxlev, tol_v, tol_g, beta, zlevels,
                  zconfirm, faces, mirror_x, mirror_y, field_levels, gauss_points, edges, row, info):
    """Template (serial; compiled once for every mechanism, ``shared``): statistics row of one design into ``row``
    by the column kernel ``column`` (the bound ``_column`` or ``_column_intervals``, COLUMN_SIGNATURE) of a
    mechanism with ``n_fields`` field slots; info:
    error_volume, error_gci, level, evaluations. nx, ny3: coarse columns along cross axes 0, 1 (ny3 unused when
    planar); mirror_x, mirror_y: the lo face of cross axis 0, 1 is a mirror plane (no face ghost there)."""
    nb = edges.shape[0] - 1
    ncol = 1 + 4 * n_fields + nb
    ny = ny3 if ndim == 3 else 1
    ca = ndim - 1
    init_row(row, n_fields)
    zlo = lo_d[ca]
    hz0 = _div(hi_d[ca] - zlo, m)
    hx = _div(hi_d[0] - lo_d[0], nx)
    hy = _div(hi_d[1] - lo_d[1], ny) if ndim == 3 else 1.0
    zfix = lo_d[2]
    info[:] = 0.0
    if not (hz0 > 0.0 and hx > 0.0 and hy > 0.0):
        return  # an empty box (a degenerate design's bounding box): nothing reachable
    mmax = m
    for _ in range(zlevels):
        mmax *= 2
    # zeros, not empty: an LCI kernel (lci_only) writes slot 0 alone, so the other fields' statistics sum these
    # zeros instead of whatever the allocation held (garbage could overflow, and differ between runs)
    cell = np.zeros(n_fields)
    # slot 0 (reachability) of each node; the interval variant (_column_intervals) keeps its intervals there
    nodes = np.empty(max(mmax + 1, 2 * MAX_INTERVALS))
    # the Gauss points of one column: 2 per piece, a piece per z-cell plus one per gap between intervals
    buf = np.empty((n_fields, 2 * (mmax + MAX_INTERVALS)))
    wbuf = np.empty(2 * (mmax + MAX_INTERVALS))
    q0 = np.zeros(n_fields)
    q1 = np.zeros(n_fields)
    colrow = np.empty(ncol)
    out = np.empty(4)
    evals = 0.0
    # level 0: every cell of the cross grid is active, in (i, j) order
    n_active = nx * ny
    ci = np.empty(n_active, dtype=np.int64)
    cj = np.empty(n_active, dtype=np.int64)
    for a in range(n_active):
        ci[a] = a // ny
        cj[a] = a - (a // ny) * ny
    # src[a]: the parent (index into the previous level's rows) whose column active column a repeats, else -1;
    # par[a]: active column a's parent (every child; level 0: -1)
    src = np.full(n_active, -1, dtype=np.int64)
    par = np.full(n_active, -1, dtype=np.int64)
    # own[a]: active column a evaluates its fields (step 3b: its parent's field flag); else it inherits them
    own = np.ones(n_active, dtype=np.bool_)
    prev_rows = np.empty((0, ncol))
    nk = 9 if ndim == 3 else 3
    # the cell store: every column ever active, level 0's first (a = i ny + j), then each level's children: its
    # measure gl and LCI sum gs (a child holds its parent's until computed), gchild its first child (-1: a leaf);
    # gi[a]: active column a's cell; nb[a]: its neighbours' cells (-x, +x, -y, +y; -1 at the box), a coarser leaf
    # where the neighbouring region was not refined (it keeps its value over the finer cells it covers). Sparse:
    # a dense grid at the finest level (648^2 cells at level 3 of 24^2) costs more than the columns refined.
    gl, gs, gchild, gi, nb = initial_cells(nx, ny, ndim)
    seg = np.zeros(maxlev + 2, dtype=np.int64)  # seg[l]: the store's first cell of level l (levels in order)
    # box-face columns (step 3): measure and LCI sum of the column on the face x = lo, x = hi (per j), y = lo,
    # y = hi (per i) next to each edge column, [side, L or S, index]
    fxg = np.zeros((2, 2, ny))
    fyg = np.zeros((2, 2, nx))
    prev_v = 0.0
    prev_g = 0.0
    err_v = 0.0
    err_g = 0.0
    zerr_v = 0.0
    zerr_g = 0.0
    level = 0
    mz = m
    zl = 0
    zok = 0
    while True:
        hz = _div(hi_d[ca] - zlo, mz)
        inherit = field_levels >= 0 and level > field_levels
        scale = 1.0
        for _ in range(level):
            scale *= 3.0
        area = 1.0 / (scale * scale) if ndim == 3 else 1.0 / scale
        rows = np.empty((n_active, ncol))
        for a in range(n_active):
            if src[a] >= 0:
                # the centre child is its parent's column (same x, y and z-cells): its L and S are already in its
                # cell (refine_cells), its row is the parent's with 1/nk of the weight (min and max unchanged)
                for c in range(ncol):
                    rows[a, c] = prev_rows[src[a], c]
                rows[a, 0] /= nk
                for f in range(n_fields):
                    rows[a, 1 + 4 * f] /= nk
                    rows[a, 2 + 4 * f] /= nk
                for c in range(1 + 4 * n_fields, ncol):
                    rows[a, c] /= nk
                continue
            x = _centre(lo_d[0], ci[a], hx, scale)
            y = _centre(lo_d[1], cj[a], hy, scale)
            # a child's cell holds its parent's L and S (refine_cells) until it is computed
            g = gi[a]
            lpar = gl[g]
            # step 3b: the measure alone where the column inherits its parent's fields (one call site: the column
            # and the field kernel in it are compiled into each)
            inh = inherit and lpar > 0.0 and not own[a]
            column(p, x, y, zfix, ndim, zlo, hz, hz0, mz, nbis, area, nodes, cell, q0, q1, buf, wbuf, out,
                   0 if inh else gauss_points)
            evals += out[3]
            if inh:
                # the fields' statistics are the parent's per unit measure
                lc = out[0]
                if lc > 0.0:
                    r = lc / (lpar * nk)
                    for c in range(ncol):
                        rows[a, c] = prev_rows[par[a], c]
                    rows[a, 0] *= r
                    for f in range(n_fields):
                        rows[a, 1 + 4 * f] *= r
                        rows[a, 2 + 4 * f] *= r
                    for c in range(1 + 4 * n_fields, ncol):
                        rows[a, c] *= r
                else:
                    init_row(colrow, n_fields)
                    for c in range(ncol):
                        rows[a, c] = colrow[c]
                gs[g] = lc * (gs[g] / lpar)
                gl[g] = lc
                continue
            init_row(colrow, n_fields)
            accumulate_cells(colrow, buf, wbuf, int(out[2]), edges)
            for c in range(ncol):
                rows[a, c] = colrow[c]
            gl[g] = out[0]
            gs[g] = out[1]
        seg[level + 1] = gl.shape[0]
        vol, ssum = leaf_sums(gl, gs, gchild, seg, level, ndim)
        gci = ssum / vol if vol > 0.0 else 0.0
        if level == 0 and zl > 0:
            zerr_v = abs(vol - prev_v) / vol if vol > 0.0 else (0.0 if prev_v == 0.0 else 1.0)
            zerr_g = abs(gci - prev_g)
            zok = zok + 1 if zerr_v <= tol_v and zerr_g <= tol_g else 0
        if level == 0 and zl < zlevels and zok < zconfirm:
            # 0. z-levels: the coarse cross grid again with twice the z-cells until ``zconfirm`` consecutive
            # changes meet the tolerance (nested node sets can miss the same thin shell twice)
            prev_v = vol
            prev_g = gci
            mz *= 2
            zl += 1
            continue
        # 4. error estimate against the previous level
        if level > 0:
            if vol > 0.0:
                err_v = abs(vol - prev_v) / vol
            else:
                err_v = 0.0 if prev_v == 0.0 else 1.0
            err_g = abs(gci - prev_g)
        prev_v = vol
        prev_g = gci
        stop = level >= maxlev or (level >= 1 and err_v <= tol_v and err_g <= tol_g)
        flags = np.zeros(n_active, dtype=np.bool_)
        fflags = np.ones(n_active, dtype=np.bool_)
        if not stop:
            if faces:
                for a in range(n_active):
                    for axis in range(ndim - 1):
                        for side in range(2):
                            if nb[a, 2 * axis + side] >= 0:
                                continue  # not at the box
                            if side == 0 and (mirror_x if axis == 0 else mirror_y):
                                continue  # a mirror plane: the clamped neighbour, no ghost (flag_columns)
                            x = _centre(lo_d[0], ci[a], hx, scale)
                            y = _centre(lo_d[1], cj[a], hy, scale)
                            fpos = END_NUDGE if side == 0 else (nx if axis == 0 else ny) - END_NUDGE
                            if axis == 0:
                                x = _add_product(lo_d[0], fpos, hx)
                            else:
                                y = _add_product(lo_d[1], fpos, hy)
                            # with inherited fields the face column's LCI sum is its measure times the edge
                            # column's mean LCI (unless the edge column has none)
                            ledge = gl[gi[a]]
                            fon = not (inherit and ledge > 0.0)
                            column(p, x, y, zfix, ndim, zlo, hz, hz0, mz, nbis, area, nodes, cell, q0, q1, buf, wbuf,
                                   out, gauss_points if fon else 0)
                            evals += out[3]
                            fs = out[1] if fon else out[0] * (gs[gi[a]] / ledge)
                            if axis == 0:
                                fxg[side, 0, cj[a]] = out[0]
                                fxg[side, 1, cj[a]] = fs
                            else:
                                fyg[side, 0, ci[a]] = out[0]
                                fyg[side, 1, ci[a]] = fs
            ncell0 = nx * ny
            flag_columns(gl, gs, gi, nb, ci, cj, n_active, ndim, area, tol_v * vol * beta / ncell0,
                         tol_g * vol * beta / ncell0, faces, mirror_x, mirror_y, fxg, fyg, flags)
            if field_levels >= 0 and level >= field_levels:
                field_flags(gl, gs, gi, nb, n_active, ndim, area, tol_g * vol * beta / ncell0, fflags)
        n_flag = 0
        for a in range(n_active):
            if flags[a]:
                n_flag += 1
            else:
                add_row(row, rows[a], n_fields)
        if stop or n_flag == 0:
            break
        # 3. children of the flagged cells, in (parent, a, b) order; the centre one repeats its parent's column
        ni = np.empty(n_flag * nk, dtype=np.int64)
        nj = np.empty(n_flag * nk, dtype=np.int64)
        ns = np.empty(n_flag * nk, dtype=np.int64)
        npar = np.empty(n_flag * nk, dtype=np.int64)
        nown = np.empty(n_flag * nk, dtype=np.bool_)
        t = 0
        for a in range(n_active):
            if flags[a]:
                for da in range(3):
                    for db in range(3 if ndim == 3 else 1):
                        ni[t] = 3 * ci[a] + da
                        nj[t] = 3 * cj[a] + db if ndim == 3 else 0
                        ns[t] = a if da == 1 and (db == 1 or ndim == 2) else -1
                        npar[t] = a
                        nown[t] = fflags[a]
                        t += 1
        ci = ni
        cj = nj
        src = ns
        par = npar
        own = nown
        prev_rows = rows
        gl, gs, gchild, gi, nb = refine_cells(gl, gs, gchild, gi, nb, flags, n_active, ndim)
        n_active = t
        fxg = refine_faces(fxg, 3 if ndim == 3 else 1)
        fyg = refine_faces(fyg, 3)
        level += 1
    info[0] = max(err_v, zerr_v)
    info[1] = max(err_g, zerr_g)
    info[2] = level
    info[3] = evals


def _population_column_stats(column, n_fields, params, lo, hi, ndim, nx, ny, m, nbis, maxlev, tol_v, tol_g, beta,
                             zlevels, zconfirm, faces, mirror_x, mirror_y, field_levels, gauss_points, edges, stats,
                             info, start, step):
    """Template (designs start, start + step, ... of the population; threads.in_threads runs the strides; compiled
    once, ``shared``, its DESIGN_STATS the shared ``_design_stats``). Each design writes its own rows of ``stats``
    and ``info``."""
    for d in range(start, params.shape[0], step):
        DESIGN_STATS(column, n_fields, params[d], lo[d], hi[d], ndim, nx, ny, m, nbis, maxlev, tol_v, tol_g, beta,
                     zlevels, zconfirm, faces, mirror_x, mirror_y, field_levels, gauss_points, edges, stats[d],
                     info[d])


DESIGN_STATS = None  # placeholder: the shared _design_stats (_shared_kernels)

_F8 = nbtypes.float64
_I8 = nbtypes.int64
_B1 = nbtypes.boolean
_V = nbtypes.float64[::1]
_M = nbtypes.float64[:, ::1]
# the column kernel (bound _column / _column_intervals): p, x, y, zfix, ndim, zlo, hz, hz0, mz, nbis, area, nodes,
# cell, q0, q1, buf, wbuf, out, gauss
COLUMN_SIGNATURE = nbtypes.none(_V, _F8, _F8, _F8, _I8, _F8, _F8, _F8, _I8, _I8, _F8, _V, _V, _V, _V, _M, _V, _V,
                                _I8)
_COLUMN = nbtypes.FunctionType(COLUMN_SIGNATURE)
# column, n_fields, then the shared arguments of one design (p, lo_d, hi_d) or of the population (params, lo, hi)
_OPTIONS = (_I8, _I8, _I8, _I8, _I8, _I8, _F8, _F8, _F8, _I8, _I8, _B1, _B1, _B1, _I8, _I8, _V)
DESIGN_SIGNATURE = nbtypes.none(_COLUMN, _I8, _V, _V, _V, *_OPTIONS, _V, _V)
POPULATION_SIGNATURE = nbtypes.none(_COLUMN, _I8, _M, _M, _M, *_OPTIONS, _M, _M, _I8, _I8)


def _shared_kernels():
    """(design, population): the column algorithm compiled once for every mechanism (kernels.bind.shared), on
    first use (an explicit signature compiles at once, or loads from the disk cache)."""
    one = shared(_design_stats, DESIGN_SIGNATURE, fastmath=FASTMATH)
    run = shared(_population_column_stats, POPULATION_SIGNATURE, extra={"DESIGN_STATS": one}, nogil=True,
                 fastmath=FASTMATH)
    return one, run


def column_stats(field_kernel, n_fields, params, lo, hi, ndim, n, m, nbis, maxlev, tol_v, tol_g, edges,
                 beta=1.0, zlevels=0, zconfirm=1, faces=False, reach_kernel=None, ny: int | None = None,
                 mirror: tuple[bool, bool] = (False, False), interval_kernel=None, field_levels: int = -1,
                 gauss_points: int = 2):
    """Statistics rows of every design by the column algorithm (module docstring).

    params (d, k) packed designs; lo, hi (d, 3): each design's box (planar: lo[2] is the fixed z); n: coarse columns
    along cross axis 0 (and axis 1 unless ``ny``); ny: coarse columns along cross axis 1 (default n; ignored when
    planar); m: z-cells per column; nbis: bisection steps per boundary crossing; maxlev: most refinement
    levels; tol_v, tol_g: relative measure and absolute GCI tolerance; edges: band edges; beta: share of the
    tolerance one coarse column's error indicator may take before it is refined. Returns (stats (d,
    stat_columns), error_volume (d,), error_gci (d,), levels (d,) int64, evaluations (d,)): counts in units of the
    coarse cell (hx hy hz with hx = (hi - lo)[0] / n, hy = (hi - lo)[1] / ny; planar hx hz). reach_kernel: the
    nodes' and bisection points' kernel (module header; default the field kernel). Evaluations count calls of
    either kernel. mirror: (axis 0, axis 1) whether the box's lo face on that cross axis is a mirror plane of the
    fields: the edge columns' neighbour across it is themselves and no face column is evaluated there even with
    ``faces`` (module docstring, step 3); planar: axis 1 is the column axis, a mirror there is an error.
    interval_kernel: Mechanism.interval_kernel (3-D only; None: nodes and bisection): each column's reachable
    intervals in closed form where it returns k >= 0 (module docstring); each call counts as one evaluation.
    field_levels: the last level whose new columns all evaluate their fields; deeper ones inherit their parent's
    (module docstring, step 3b); -1: every level evaluates them. gauss_points: 2 (the 2-point Gauss-Legendre rule
    per piece) or 1 (the midpoint rule: half the field evaluations, for fields that vary little along a piece).
    """
    ny = int(n) if ny is None or int(ndim) == 2 else int(ny)
    mirror_x, mirror_y = (bool(v) for v in mirror)
    if int(gauss_points) not in (1, 2):
        raise ValueError(f"gauss_points must be 1 or 2, got {gauss_points}")
    if ny < 1 or int(n) < 1:
        raise ValueError(f"column counts must be >= 1 (n={n}, ny={ny})")
    if mirror_y and int(ndim) == 2:
        raise ValueError("mirror on axis 1 of a planar task: that is the column axis, not a cross axis")
    reach = field_kernel if reach_kernel is None else reach_kernel
    # the mechanism's column kernel is its only compilation here; the algorithm around it is shared
    col = bind(_column, field_kernel, n_fields, extra={"REACH_KERNEL": reach}, signature=COLUMN_SIGNATURE,
               fastmath=FASTMATH)
    if interval_kernel is not None and int(ndim) == 3:
        # a separate bound variant: without an interval kernel the compiled code is the node column's, bit for bit
        col = bind(_column_intervals, field_kernel, n_fields,
                   extra={"INTERVAL_KERNEL": interval_kernel, "NODE_COLUMN": col}, signature=COLUMN_SIGNATURE,
                   fastmath=FASTMATH)
    # serial over designs, run in threads (kernels.threads: a parfor would be a third of this chain's compile time)
    _, run = _shared_kernels()
    # the explicit signatures take writable C arrays of float64 (a read-only or strided view would not match)
    params, lo, hi, edges = (np.require(a, float, ["C", "W"]) for a in (params, lo, hi, edges))
    stats = np.zeros((params.shape[0], 1 + 4 * int(n_fields) + edges.shape[0] - 1))
    info = np.zeros((params.shape[0], 4))
    in_threads(run, params.shape[0], col, int(n_fields), params, lo, hi, int(ndim), int(n), ny, int(m), int(nbis),
               int(maxlev), float(tol_v), float(tol_g), float(beta), int(zlevels), int(zconfirm), bool(faces),
               mirror_x, mirror_y, int(field_levels), int(gauss_points), edges, stats, info)
    return stats, info[:, 0].copy(), info[:, 1].copy(), info[:, 2].astype(np.int64), info[:, 3].copy()
