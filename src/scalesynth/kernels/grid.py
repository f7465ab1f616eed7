"""Generic voxel-grid evaluator over multi-field point kernels, parallel over (design, x-slab) and deterministic.

Point-kernel contract (every mechanism's ``field_kernel``; Numba ``@njit``)::

    kernel(p, x, y, z, out) -> None

``p`` is the float64 vector of ``Mechanism.pack``; ``out`` a float64 array of the mechanism's ``n_fields`` local
fields, written in the order of ``Mechanism.fields``. Slot 0 is the LCI in [0, 1], or ``-1.0`` when the pose is
unreachable under any limit (then the other slots are written 0 and ignored). Slots 1 and 2 are sigma_min and
sigma_max of the homogenised Jacobian dx/dq; a mechanism may append its own fields. A kernel never writes NaN.
``write_unreachable`` / ``write_singular`` fill the slots the same way for every mechanism.

Each x-slab of each design accumulates into its own statistics row; the rows are reduced in a fixed order, so
results do not depend on thread scheduling. Grids are cell-centred: node i of an axis sits at
``lo + (i + 0.5) * step``. ``gather_column`` + ``accumulate_cells`` are THE accumulator: the generic kernel and
every mechanism's fast path (seed 000) gather the reachable cells of each column of an x-slab with their weights,
then reduce the slab once (one long loop), so both produce the same statistics.

Statistics row layout for ``n_fields`` fields and ``n_bands`` dexterity bands (``stat_columns``)::

    [count, (sum, sum_sq, min, max) of field 0, ... of field n_fields-1, band_0, ..., band_{n_bands-1}]

so ``field_column(f, STAT_SUM)`` = 1 + 4 f; bands start at ``band_column(n_fields, 0)`` = 1 + 4 n_fields; the
band counts (and count) are weighted cell counts, bands classify LCI (field 0).

The evaluators that take a field kernel (``population_stats``, ``sample_fields``, ...) are plain functions over
templates that ``kernels.bind`` compiles once per field kernel with the kernel as a global: Numba disk-caches those
copies, so a second process loads them instead of compiling (a kernel passed as an argument could not be cached).
"""

import math

import numpy as np
from numba import njit

from scalesynth.kernels.bind import bind
from scalesynth.kernels.conditioning import SIGMA_CAP
from scalesynth.kernels.flags import FASTMATH
from scalesynth.kernels.threads import in_threads

# names a template's bound copy resolves to one mechanism's kernel (kernels.bind); placeholders here
FIELD_KERNEL = None
N_FIELDS = 0

# field slots every mechanism provides
FIELD_LCI, FIELD_SIGMA_MIN, FIELD_SIGMA_MAX = 0, 1, 2
N_BASE_FIELDS = 3

# statistics row: count, then 4 columns per field
COL_COUNT = 0
STAT_SUM, STAT_SUMSQ, STAT_MIN, STAT_MAX = 0, 1, 2, 3
N_STATS = 4
# LCI's columns (field 0), as in the one-field layout of earlier versions
COL_SUM, COL_SUMSQ, COL_MIN, COL_MAX = 1, 2, 3, 4


@njit(cache=True)
def field_column(field: int, stat: int) -> int:
    """Column of statistic ``stat`` (STAT_*) of field ``field`` in a statistics row."""
    return 1 + N_STATS * field + stat


@njit(cache=True)
def band_column(n_fields: int, band: int) -> int:
    return 1 + N_STATS * n_fields + band


@njit(cache=True)
def stat_columns(n_fields: int, n_bands: int) -> int:
    return 1 + N_STATS * n_fields + n_bands


def scale_extensive(stats: np.ndarray, n_fields: int, factor: float) -> np.ndarray:
    """Statistics rows (d, stat_columns) with the extensive columns (count, every field's sum and sum of squares,
    the bands) multiplied by ``factor`` and min/max kept: the rows of ``factor`` mirror-image copies of the
    evaluated region (evaluate.adaptive_population_stats)."""
    out = np.array(stats, dtype=float, copy=True)
    out[:, COL_COUNT] *= factor
    for f in range(n_fields):
        out[:, 1 + N_STATS * f + STAT_SUM] *= factor
        out[:, 1 + N_STATS * f + STAT_SUMSQ] *= factor
    out[:, 1 + N_STATS * n_fields:] *= factor
    return out


@njit(cache=True, fastmath=FASTMATH)
def write_unreachable(out):
    """The pose is not reachable: LCI -1, every other field 0."""
    out[0] = -1.0
    for f in range(1, out.shape[0]):
        out[f] = 0.0


@njit(cache=True, fastmath=FASTMATH)
def write_singular(out):
    """An exact singular pose where the conditioning matrix is not formed (a zero-length leg, a folded chain):
    LCI 0, sigma_min 0 and sigma_max SIGMA_CAP (unbounded or undetermined), other fields 0. Grids meet such
    poses only by coincidence (a set of measure zero)."""
    out[0] = 0.0
    out[1] = 0.0
    out[2] = SIGMA_CAP
    for f in range(3, out.shape[0]):
        out[f] = 0.0


@njit(cache=True, fastmath=FASTMATH)
def _band_index(lci, edges):
    """Band k holds (edges[k], edges[k+1]]; the first band also holds its lower edge."""
    nb = edges.shape[0] - 1
    for k in range(nb - 1):
        if lci <= edges[k + 1]:
            return k
    return nb - 1


@njit(cache=True, fastmath=FASTMATH)
def init_row(row, n_fields):
    """Empty statistics row: zero sums and counts, min +inf, max -inf."""
    row[:] = 0.0
    for f in range(n_fields):
        row[1 + 4 * f + 2] = math.inf
        row[1 + 4 * f + 3] = -math.inf




@njit(cache=True, fastmath=FASTMATH)
def gather_column(buf, wbuf, m, vals, k0, k1, w):
    """Append cells k0..k1 of a column (fields ``vals[:, k]``) to the slab buffers buf (n_fields, capacity) and
    wbuf (capacity) from index m, each with weight ``w`` if reachable (vals[0, k] >= 0), else 0; returns the new
    fill. Symmetric grids visit a part of the grid and weight the cells (2 or 4)."""
    nf = vals.shape[0]
    n = k1 - k0 + 1
    for f in range(nf):
        src = vals[f, k0 : k1 + 1]
        dst = buf[f, m : m + n]
        for i in range(n):
            dst[i] = src[i]
    lci = vals[0, k0 : k1 + 1]
    wdst = wbuf[m : m + n]
    for i in range(n):
        wdst[i] = w if lci[i] >= 0.0 else 0.0
    return m + n


@njit(cache=True, fastmath=FASTMATH)
def accumulate_cells(row, buf, wbuf, m, edges):
    """Add the first m buffered cells to a statistics row; a cell of weight 0 is unreachable and ignored.

    Weighted count, per field the weighted sum and sum of squares and min/max, and band counts of LCI (field 0):
    band b holds (edges[b], edges[b+1]] (band 0 also its lower edge), from the weighted counts above each inner
    edge. The three fields every mechanism has (LCI, sigma_min, sigma_max) and the first two inner band edges go
    through one loop: its nine sums and six extremes are independent chains that overlap, where separate passes
    would each wait on the latency of one or two sequential sums (the sums are not reassociated, see
    kernels.flags, so they do not vectorise).
    Each chain still sums the cells in index order, so the row does not depend on how the passes are grouped."""
    if m == 0:
        return
    nf = buf.shape[0]  # >= N_BASE_FIELDS: every mechanism has LCI, sigma_min and sigma_max
    nb = edges.shape[0] - 1
    band0 = 1 + 4 * nf
    wv = wbuf[:m]
    lci = buf[0, :m]
    xa = buf[1, :m]
    xb = buf[2, :m]
    e1 = edges[1] if nb > 1 else 2.0  # LCI <= 1: nothing is above 2
    e2 = edges[2] if nb > 2 else 2.0
    count = 0.0
    s1 = 0.0
    s2 = 0.0
    n1 = 0.0
    n2 = 0.0
    sa1 = 0.0
    sa2 = 0.0
    sb1 = 0.0
    sb2 = 0.0
    ca = 1 + N_STATS * FIELD_SIGMA_MIN  # first column of field 1 (field 0's are COL_SUM ...)
    cb = 1 + N_STATS * FIELD_SIGMA_MAX
    lo0, hi0 = row[COL_MIN], row[COL_MAX]
    lo1, hi1 = row[ca + STAT_MIN], row[ca + STAT_MAX]
    lo2, hi2 = row[cb + STAT_MIN], row[cb + STAT_MAX]
    for i in range(m):
        w = wv[i]
        r = w > 0.0
        v = lci[i]
        a = xa[i]
        b = xb[i]
        count += w
        wx = w * v
        s1 += wx
        s2 += wx * v
        n1 += w if v > e1 else 0.0
        n2 += w if v > e2 else 0.0
        wa = w * a
        sa1 += wa
        sa2 += wa * a
        wb = w * b
        sb1 += wb
        sb2 += wb * b
        lo0 = v if r and v < lo0 else lo0
        hi0 = v if r and v > hi0 else hi0
        lo1 = a if r and a < lo1 else lo1
        hi1 = a if r and a > hi1 else hi1
        lo2 = b if r and b < lo2 else lo2
        hi2 = b if r and b > hi2 else hi2
    if count == 0.0:
        return
    row[COL_COUNT] += count
    row[COL_SUM] += s1
    row[COL_SUMSQ] += s2
    row[COL_MIN], row[COL_MAX] = lo0, hi0
    row[ca + STAT_SUM] += sa1
    row[ca + STAT_SUMSQ] += sa2
    row[ca + STAT_MIN], row[ca + STAT_MAX] = lo1, hi1
    row[cb + STAT_SUM] += sb1
    row[cb + STAT_SUMSQ] += sb2
    row[cb + STAT_MIN], row[cb + STAT_MAX] = lo2, hi2
    # bands: weighted cells with LCI above each inner edge; the first two edges counted above, then two per pass
    above = count
    b = 0
    if nb > 1:
        row[band0] += count - n1
        if nb > 2:
            row[band0 + 1] += n1 - n2
        above = n2 if nb > 2 else n1
        b = 2
    while b < nb - 1:
        e1 = edges[b + 1]
        e2 = edges[b + 2] if b + 2 < nb else 2.0
        n1 = 0.0
        n2 = 0.0
        for i in range(m):
            n1 += wv[i] if lci[i] > e1 else 0.0
            n2 += wv[i] if lci[i] > e2 else 0.0
        row[band0 + b] += above - n1
        if b + 2 < nb:
            row[band0 + b + 1] += n1 - n2
        above = n2 if b + 2 < nb else n1
        b += 2
    row[band0 + nb - 1] += above
    # a mechanism's own fields
    for f in range(N_BASE_FIELDS, nf):
        xs = buf[f, :m]
        s1 = 0.0
        s2 = 0.0
        lo_, hi_ = row[1 + 4 * f + 2], row[1 + 4 * f + 3]
        for i in range(m):
            w = wv[i]
            x = xs[i]
            wx = w * x
            s1 += wx
            s2 += wx * x
            lo_ = x if w > 0.0 and x < lo_ else lo_
            hi_ = x if w > 0.0 and x > hi_ else hi_
        c = 1 + 4 * f
        row[c] += s1
        row[c + 1] += s2
        row[c + 2], row[c + 3] = lo_, hi_


@njit(cache=True)
def reduce_partials(partial, n_designs, nx, n_fields):
    """Combine the per-slab rows of each design in slab order (deterministic, whatever the thread schedule)."""
    ncol = partial.shape[1]
    out = np.zeros((n_designs, ncol))
    for d in range(n_designs):
        acc = out[d]
        init_row(acc, n_fields)
        for i in range(nx):
            row = partial[d * nx + i]
            acc[0] += row[0]
            for f in range(n_fields):
                c = 1 + 4 * f
                acc[c] += row[c]
                acc[c + 1] += row[c + 1]
                acc[c + 2] = min(acc[c + 2], row[c + 2])
                acc[c + 3] = max(acc[c + 3], row[c + 3])
            for b in range(1 + 4 * n_fields, ncol):
                acc[b] += row[b]
    return out


def _population_stats(params, lo, step, shape, edges, partial, start, stride):
    """Template of population_stats (FIELD_KERNEL, N_FIELDS bound by kernels.bind): the slabs (design, x index)
    start, start + stride, ... into their rows of ``partial`` (threads.in_threads runs the strides)."""
    n_fields = N_FIELDS
    n_designs = params.shape[0]
    nx, ny, nz = shape[0], shape[1], shape[2]
    for task in range(start, n_designs * nx, stride):
        d = task // nx
        i = task - d * nx
        p = params[d]
        x = lo[d, 0] + (i + 0.5) * step[d, 0]
        row = partial[task]
        init_row(row, n_fields)
        vals = np.empty((n_fields, nz))
        cell = np.zeros(n_fields)  # an LCI kernel writes slot 0 alone: the other fields stay 0, not garbage
        buf = np.empty((n_fields, ny * nz))
        wbuf = np.empty(ny * nz)
        m = 0
        for j in range(ny):
            y = lo[d, 1] + (j + 0.5) * step[d, 1]
            for k in range(nz):
                FIELD_KERNEL(p, x, y, lo[d, 2] + (k + 0.5) * step[d, 2], cell)
                for f in range(n_fields):
                    vals[f, k] = cell[f]
            m = gather_column(buf, wbuf, m, vals, 0, nz - 1, 1.0)
        accumulate_cells(row, buf, wbuf, m, edges)


def _sample_fields(p, lo, step, shape, out, start, stride):
    """Template of sample_fields: the x indices start, start + stride, ... into ``out`` (nx, ny, nz, N_FIELDS)."""
    n_fields = N_FIELDS
    nx, ny, nz = shape[0], shape[1], shape[2]
    for i in range(start, nx, stride):
        x = lo[0] + (i + 0.5) * step[0]
        cell = np.zeros(n_fields)
        for j in range(ny):
            y = lo[1] + (j + 0.5) * step[1]
            for k in range(nz):
                FIELD_KERNEL(p, x, y, lo[2] + (k + 0.5) * step[2], cell)
                out[i, j, k, :] = cell


def _population_points_fields(params, pts, out, start, stride):
    """Template of population_points_fields: designs start, start + stride, ... into ``out`` (n_designs, n,
    N_FIELDS)."""
    n_fields = N_FIELDS
    n = pts.shape[0]
    for d in range(start, params.shape[0], stride):
        p = params[d]
        cell = np.zeros(n_fields)
        for i in range(n):
            FIELD_KERNEL(p, pts[i, 0], pts[i, 1], pts[i, 2], cell)
            out[d, i, :] = cell


def _point_lci(p, x, y, z):
    """Template of the scalar LCI kernel over a field kernel."""
    out = np.empty(N_FIELDS)
    FIELD_KERNEL(p, x, y, z, out)
    return out[0]


def _sample_grid(p, lo, step, shape, out, start, stride):
    """Template of sample_grid (FIELD_KERNEL is a scalar LCI kernel here): x indices start, start + stride, ...
    into ``out`` (nx, ny, nz)."""
    nx, ny, nz = shape[0], shape[1], shape[2]
    for i in range(start, nx, stride):
        x = lo[0] + (i + 0.5) * step[0]
        for j in range(ny):
            y = lo[1] + (j + 0.5) * step[1]
            for k in range(nz):
                out[i, j, k] = FIELD_KERNEL(p, x, y, lo[2] + (k + 0.5) * step[2])


def _points_lci(p, pts):
    """Template of points_lci (FIELD_KERNEL is a scalar LCI kernel)."""
    n = pts.shape[0]
    out = np.empty(n)
    for i in range(n):
        out[i] = FIELD_KERNEL(p, pts[i, 0], pts[i, 1], pts[i, 2])
    return out


# serial kernels over strides of their rows, run in threads (kernels.threads: no parfor to compile per binding)
_THREADED = {"nogil": True, "fastmath": FASTMATH}
_SERIAL = {"fastmath": FASTMATH}


def population_stats(field_kernel, n_fields, params, lo, step, shape, edges):
    """Workspace statistics of every field for every design on its own grid.

    params: (n_designs, k) packed designs; lo, step: (n_designs, 3); shape: int64[3] (nx, ny, nz);
    edges: dexterity band edges. Returns (n_designs, stat_columns(n_fields, n_bands)) float64.
    """
    n_designs, nx = params.shape[0], int(shape[0])
    partial = np.zeros((n_designs * nx, stat_columns(int(n_fields), edges.shape[0] - 1)))
    in_threads(bind(_population_stats, field_kernel, n_fields, **_THREADED), n_designs * nx, params, lo, step, shape,
               edges, partial)
    return reduce_partials(partial, n_designs, nx, int(n_fields))


def sample_fields(field_kernel, n_fields, p, lo, step, shape):
    """Every field at every node of one design's grid: (nx, ny, nz, n_fields); field 0 (LCI) -1 = unreachable."""
    out = np.empty((int(shape[0]), int(shape[1]), int(shape[2]), int(n_fields)))
    in_threads(bind(_sample_fields, field_kernel, n_fields, **_THREADED), int(shape[0]), p, lo, step, shape, out)
    return out


def population_points_fields(field_kernel, n_fields, params, pts):
    """Every field of every design at the same points: params (n_designs, k), pts (n, 3) ->
    (n_designs, n, n_fields); field 0 (LCI) -1 where unreachable."""
    out = np.empty((params.shape[0], pts.shape[0], int(n_fields)))
    in_threads(bind(_population_points_fields, field_kernel, n_fields, **_THREADED), params.shape[0], params, pts,
               out)
    return out


def lci_kernel(field_kernel, n_fields: int):
    """A scalar kernel ``f(p, x, y, z) -> LCI or -1`` over a field kernel (for single points and the LCI-only
    helpers below; the evaluators use the field kernel itself). Disk-cached like the grid kernels."""
    return bind(_point_lci, field_kernel, n_fields, **_SERIAL)


def sample_grid(point_kernel, p, lo, step, shape):
    """LCI at every node of one design's grid, shape (nx, ny, nz), from a scalar LCI kernel; -1 = unreachable."""
    out = np.empty((int(shape[0]), int(shape[1]), int(shape[2])))
    in_threads(bind(_sample_grid, point_kernel, 0, **_THREADED), int(shape[0]), p, lo, step, shape, out)
    return out


def points_lci(point_kernel, p, pts):
    """LCI (or -1) at arbitrary points, pts shape (n, 3), from a scalar LCI kernel."""
    return bind(_points_lci, point_kernel, 0, **_SERIAL)(p, pts)
