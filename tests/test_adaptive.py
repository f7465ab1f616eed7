"""The accuracy-targeted (adaptive, column) evaluator: the Numba kernel against its NumPy twin (tests/naive.py, the
same algorithm level by level), the seed-000 volume against the exact quadrature, the half box with a mirror plane
against the full box of a symmetric workspace, determinism, degenerate designs and the config form."""

import os
import subprocess
import sys

import numpy as np
import pytest
import yaml
from numba import njit

from scalesynth.config import config_from_dict, load_config
from scalesynth.errors import ConfigError
from scalesynth.evaluate import (
    ColumnPlan,
    Tolerance,
    adaptive_population_stats,
    column_order,
    evaluate_config,
    evaluate_population,
    make_grid,
)
from scalesynth.kernels import grid as kgrid
from scalesynth.kernels.adaptive import column_stats
from scalesynth.mechanisms import available, get
from scalesynth.metrics import nullable_columns
from test_registry import config_for

from exact_volume import exact_volume
from naive import column_stats as column_twin

EDGES = np.array([0.0, 0.1, 0.3, 1.0])


def _box(mech, design, options):
    g = make_grid(mech, design, options, 1)
    return g.lo, g.lo + g.step * g.shape


@pytest.mark.parametrize("name", available())
def test_column_kernel_equals_numpy_twin(name):
    """Same nodes, bisections, Gauss points, refinement decisions and stopping level: the same number of field
    evaluations, the same error estimates, and every statistic of every field equal to the twin's up to the order
    of the floating-point sums and of the field kernel's own rounding, which differs in the last bits between two
    compilations of it (fused multiply-adds): 1e-12 relative for the count, the LCI statistics and the band
    measures; the other fields' statistics within 1e-12 plus 4x their change when the twin evaluates those fields
    one ulp away from the same points (~1e-16 relative except next to a singular surface). Plans with and without
    z-levels and box-face columns, one with ny = n - 2 (3-D) and mirror planes on every cross axis (with box-face
    columns, where the mirror matters), and one with inherited fields (step 3b: fewer field evaluations than
    without) and the 1-point (midpoint) rule, with and without the column intervals. The kernel runs as the
    evaluator binds it, with the mechanism's reach kernel at the nodes and bisections; the twin decides
    reachability by the field kernel's LCI (test_reach_kernel_is_the_sign_of_the_field_kernels_lci checks the two
    agree point by point), and evaluates the fields through the mechanism's kernel (population_points_fields) so
    that only the algorithm is compared; the field kernels themselves are checked against NumPy SVD twins in
    test_fields.py."""
    mech = get(name)
    cfg = load_config(config_for(name))
    design, options = cfg.resolved_design(), cfg.resolved_options()
    ndim = len(mech.task_axes)
    lo, hi = _box(mech, design, options)
    packed = mech.pack(design, options)

    def fields(pts):
        return kgrid.population_points_fields(mech.field_kernel, mech.n_fields, packed[None, :], pts)[0]

    n = 6 if ndim == 3 else 12
    mirror = dict(ny=n - 2, mirror=(True, ndim == 3))
    # step 3b: refined columns inherit their parent's fields; the 1-point (midpoint) rule (the ellipsoid test
    # below compares inheriting with the 2-point rule)
    inherit = dict(field_levels=0, gauss_points=1)
    plans = [(0, 1.0, 0, 1, False, {}), (2, 1.0, 0, 1, False, {}), (2, 3.0, 0, 1, False, {}),
             (2, 1.0, 2, 2, True, {}), (2, 1.0, 0, 1, True, mirror), (2, 1.0, 0, 1, True, inherit)]
    if mech.interval_kernel_for(options) is not None:  # the closed-form column intervals (the twin reads the same)
        ivs = dict(interval_kernel=mech.interval_kernel), dict(intervals=_interval_twin(mech.interval_kernel, packed))
        plans += [(2, 1.0, 0, 1, False, ivs), (2, 1.0, 2, 2, True, ivs), (2, 1.0, 1, 1, True, (
            {**ivs[0], **mirror}, {**ivs[1], **mirror})), (2, 1.0, 0, 1, True, (
            {**ivs[0], **inherit}, {**ivs[1], **inherit}))]
    for maxlev, beta, zlevels, zconfirm, faces, more in plans:
        kern, twin = more if isinstance(more, tuple) else (more, more)
        opt = dict(zlevels=zlevels, zconfirm=zconfirm, faces=faces)
        # interval columns run along the mechanism's column axis: the kernel then takes (and the twin gets) the task
        # coordinates in column order (evaluate.column_order; rps-upu: (theta, psi, z))
        axis = mech.column_axis(options) if "interval_kernel" in kern else ndim - 1
        order = column_order(ndim, axis)
        kernel, reach = mech.field_kernel, mech.reach_kernel
        if axis != ndim - 1:
            kernel, reach = mech.column_order_kernel(kernel, options), mech.column_order_kernel(reach, options)
        clo, chi = lo[order], hi[order]
        cfields = fields if axis == ndim - 1 else (lambda pts, back=np.argsort(order): fields(pts[:, back]))
        # the evaluator's own binding (field kernel, reach kernel): the variant every run compiles and uses
        s, ev, eg, lv, ne = column_stats(kernel, mech.n_fields, packed[None, :], clo[None, :], chi[None, :], ndim,
                                         n, 6, 5, maxlev, 0.002, 5e-4, EDGES, beta, **opt, reach_kernel=reach,
                                         **kern)
        row, tv, tg, tl, tn = column_twin(cfields, mech.n_fields, clo, chi, ndim, n, 6, 5, maxlev, 0.002, 5e-4,
                                          EDGES, beta, **opt, **twin)
        assert row[0] > 0, name
        assert lv[0] == tl and ne[0] == tn
        assert ev[0] == pytest.approx(tv, rel=1e-10, abs=1e-15)
        assert eg[0] == pytest.approx(tg, rel=1e-10, abs=1e-15)
        # the other fields' statistics up to their sensitivity to the field kernel's rounding: 4x their change when
        # the twin evaluates every field but the LCI (so the same points are reachable) one ulp away, either way
        # (pprs-rprs's deflection changes by 2.6e-6 relative per ulp of z next to its singular surface, LCI 5e-6,
        # where the two compilations differ by 1.2e-8 relative in its max, 1.25x its one-ulp change; elsewhere
        # the slack is ~1e-16)
        slack = np.zeros(row.shape)
        for direction in (np.inf, -np.inf):
            ulp, *_ = column_twin(lambda pts, d=direction, f=cfields: np.c_[f(pts)[:, :1],
                                                                           f(np.nextafter(pts, d))[:, 1:]],
                                  mech.n_fields, clo, chi, ndim, n, 6, 5, maxlev, 0.002, 5e-4, EDGES, beta, **opt,
                                  **twin)
            slack = np.maximum(slack, 4.0 * np.abs(ulp - row))
        lci_cols = [0, 1, 2, 3, 4] + list(range(1 + 4 * mech.n_fields, len(row)))
        np.testing.assert_allclose(s[0][lci_cols], row[lci_cols], rtol=1e-12, atol=1e-12 * np.abs(row).max())
        assert np.all(np.abs(s[0] - row) <= 1e-12 * np.abs(row) + 1e-12 * np.abs(row).max() + slack), name
        if beta == 1.0 and maxlev == 2 and not zlevels:
            assert tl >= 1  # the refinement itself was compared
        if kern.get("field_levels", -1) >= 0:  # refined columns inherited their fields: fewer field evaluations
            full = column_stats(kernel, mech.n_fields, packed[None, :], clo[None, :], chi[None, :], ndim, n, 6, 5,
                                maxlev, 0.002, 5e-4, EDGES, beta, **opt, **{**kern, "field_levels": -1})
            assert tl >= 1 and ne[0] < full[4][0], name


def _interval_twin(interval_kernel, p, rows=8):
    """The twin's ``intervals`` callable over a Numba interval kernel: [(a, b), ...] or None where it returns -1."""
    def intervals(x, y, zlo, zhi):
        out = np.empty((rows, 2))
        k = interval_kernel(p, x, y, zlo, zhi, out)
        return None if k < 0 else [(float(a), float(b)) for a, b in out[:k]]
    return intervals


@pytest.mark.parametrize("name", [n for n in available() if get(n).reach_kernel is not get(n).field_kernel])
def test_reach_kernel_is_the_sign_of_the_field_kernels_lci(name):
    """The nodes and bisections use Mechanism.reach_kernel: reachable (slot 0 >= 0) at exactly the points where the
    field kernel's LCI is >= 0, on a 24^3 grid over 1.1x the bounding box (in and out of the box) of the config's
    design and 5 random designs in its bounds (planar: a 96^2 grid), with the config's options and, where the
    mechanism has the option, interference_free (_interference_free; then the clearance decides too: it removes
    points of the workspaces)."""
    mech = get(name)
    cfg = load_config(config_for(name))
    designs = _random_designs(mech, cfg, 5, 3)
    reach_counts = []
    for options in _option_variants(mech, cfg):
        counts = 0
        for d in designs:
            lo, hi = _box(mech, d, options)
            mid, half = 0.5 * (lo + hi), 0.55 * (hi - lo)
            npt = 24 if len(mech.task_axes) == 3 else 96
            axes = [np.linspace(mid[a] - half[a], mid[a] + half[a], npt) if a < len(mech.task_axes)
                    else np.array([lo[a]]) for a in range(3)]
            pts = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
            packed = mech.pack(d, options)[None, :]
            lci = kgrid.population_points_fields(mech.field_kernel, mech.n_fields, packed, pts)[0, :, 0]
            reach = kgrid.population_points_fields(mech.reach_kernel, mech.n_fields, packed, pts)[0, :, 0]
            np.testing.assert_array_equal(reach >= 0.0, lci >= 0.0)
            assert (lci >= 0).sum() < len(pts), name
            counts += int((lci >= 0).sum())
        assert counts > 0, name  # both kinds of point were compared (a random design's workspace may be empty)
        reach_counts.append(counts)
    if len(reach_counts) == 2:
        assert reach_counts[1] < reach_counts[0], name  # the clearance made points unreachable: it was compared


def _random_designs(mech, cfg, count, seed):
    """The config's design and ``count`` random ones in its bounds (uniform, numpy default_rng(seed))."""
    rng = np.random.default_rng(seed)
    return [cfg.resolved_design()] + [mech.resolve_design({**cfg.resolved_design(), **{
        k: float(rng.uniform(lo, hi)) for k, (lo, hi) in cfg.bounds.items()}}) for _ in range(count)]


# link radius with which interference_free removes part of the test designs' workspaces (tried on seed 3's designs
# below: 15 mm leaves pprs-rprs's and the five-bar's untouched, 60 mm would empty pprs-rprs's, 80 mm a five-bar's)
# link radii for the interference_free variants, in each mechanism's length unit (default 15: mm): the clearance
# must remove some points of the test grids but not all. The described mechanisms (m): axis-to-axis distances of
# their capsules over the reach test's grids are delta 0.048-0.30 (5 % below 0.28), linear-delta 1e-4-0.05 (5 %
# below 0.008), hexa 0.001-0.035, hexapod 0.008-0.10 (5 % below 0.036), so 2 r sits among the small ones
INTERFERENCE_RADIUS = {"2pauu-ppap": 0.015, "pprs-rprs": 30.0, "planar-fivebar": 60.0, "delta": 0.14,
                       "linear-delta": 0.01, "hexa": 0.01, "hexapod": 0.015}


def _option_variants(mech, cfg):
    """The config's options, and with interference_free where the mechanism has that option."""
    variants = [cfg.resolved_options()]
    if "interference_free" in mech.default_options():
        variants.append(_interference_free(mech, cfg))
    return variants


def _interference_free(mech, cfg):
    """The config's options with interference_free and INTERFERENCE_RADIUS links (the mechanism's length unit)."""
    return {**cfg.resolved_options(), "interference_free": True,
            "link_radius": INTERFERENCE_RADIUS.get(mech.name, 15.0)}



@pytest.mark.parametrize("group", [0, 1, 2])
def test_adaptive_seed000_volume_against_exact_quadrature(group):
    """Seed 000's workspace volume has an exact 1-D quadrature (spec §1.9): on Table-4 designs the adaptive
    evaluator at the default tolerance (0.2 %) is within it, and its own error estimate does not understate the
    actual error (it is conservative: the change from the previous level, here 0.3-0.4 % against an actual
    0.02-0.06 %)."""
    mech = get("2pauu-ppap")
    table4 = [dict(m=0.857, n=0.706, l1=1.499, l2=1.5, c=0.1), dict(m=0.719, n=0.579, l1=1.499, l2=1.5, c=0.1),
              dict(m=0.516, n=0.342, l1=1.5, l2=1.5, c=0.1)]
    design = mech.resolve_design(table4[group])
    options = mech.resolve_options({})
    tol = Tolerance()
    r = adaptive_population_stats(mech, [design], options, mech.pack(design, options)[None, :], tol, EDGES)
    volume = r.stats[0, 0] * r.cell[0]
    exact = exact_volume(**design)
    assert volume == pytest.approx(exact, rel=tol.volume)
    assert r.error_volume[0] >= abs(volume - exact) / exact


@njit(cache=True)
def _slab_field(p, x, y, z, out):
    """Synthetic field kernel with the three slots every mechanism has (LCI, sigma_min, sigma_max): LCI 0.5 inside
    the region p[0] < z < p[1] and x > p[2], else -1; sigma_min 1, sigma_max 2."""
    out[0] = 0.5 if p[0] < z < p[1] and x > p[2] else -1.0
    out[1] = 1.0
    out[2] = 2.0


def _synthetic(params, n, m, nbis, maxlev, tol=0.002, **opt):
    """(volume, GCI, error_volume, levels, evaluations) of the unit box by the kernel, after checking that the NumPy
    twin gives the same row, estimates and number of evaluations."""
    lo, hi = np.zeros(3), np.ones(3)
    p = np.asarray(params, dtype=float)
    s, ev, eg, lv, ne = column_stats(_slab_field, 3, p[None, :], lo[None], hi[None], 3, n, m, nbis, maxlev, tol,
                                     tol, EDGES, 1.0, **opt)

    def fields(pts):
        inside = (p[0] < pts[:, 2]) & (pts[:, 2] < p[1]) & (pts[:, 0] > p[2])
        return np.c_[np.where(inside, 0.5, -1.0), np.ones(len(pts)), np.full(len(pts), 2.0)]

    row, tv, tg, tl, tn = column_twin(fields, 3, lo, hi, 3, n, m, nbis, maxlev, tol, tol, EDGES, 1.0, **opt)
    assert (lv[0], ne[0]) == (tl, tn)
    assert ev[0] == pytest.approx(tv, rel=1e-10, abs=1e-15)
    np.testing.assert_allclose(s[0], row, rtol=1e-12, atol=1e-15)
    volume = s[0, 0] / (n * n * m)  # counts in coarse cells of the unit box
    return volume, (s[0, 1] / s[0, 0] if s[0, 0] > 0 else 0.0), ev[0], lv[0], ne[0]


def test_z_levels_find_a_slab_between_the_coarse_nodes():
    """A slab 0.40 < z < 0.43 across the whole unit box (volume 0.03) lies between the coarse nodes z = 0.375 and
    0.5 of m = 8 z-cells and between those of m = 16 (0.375, 0.4375): without z-levels the evaluator reports an
    empty workspace with error estimate 0, and with z-levels trusted after one small change it stops at m = 16
    (the change 8 -> 16 is 0: nested node sets miss the same slab twice). With two confirmations it doubles
    to m = 32 (node 0.40625 inside the slab), then to 64 and 128 (two changes within the tolerance): volume 0.03
    within its two bisected boundaries' bracket, 2 x (1/128) / 2^13 (12 bisection steps), GCI 0.5 (the constant
    LCI)."""
    slab = (0.40, 0.43, -1.0)
    assert _synthetic(slab, 6, 8, 12, 0)[:3] == (0.0, 0.0, 0.0)
    assert _synthetic(slab, 6, 8, 12, 0, zlevels=5, zconfirm=1)[:3] == (0.0, 0.0, 0.0)
    volume, gci, est, _, evals = _synthetic(slab, 6, 8, 12, 0, zlevels=5, zconfirm=2)
    assert volume == pytest.approx(0.03, abs=2 * (1 / 128) / 2**13)
    assert gci == pytest.approx(0.5, rel=1e-12)
    assert est <= 0.002
    # nodes of m = 8, 16, 32, 64, 128 for each of the 36 columns: the doubling stopped at 128
    assert evals >= 36 * (9 + 17 + 33 + 65 + 129)


def test_box_face_columns_see_a_wall_inside_the_edge_columns():
    """A workspace x > 0.03 filling the rest of the unit box (volume 0.97): the edge columns (6 per axis: centres
    x = 1/12 and beyond) are all reachable, so every column has the same measure, no second difference flags
    anything and the evaluator reports 1.0 with error estimate 0, even for a tolerance it cannot meet (1e-9). The
    face columns (x = 0) see the wall: with that tolerance the evaluator refines the columns next to it up to the
    last level (3): 17/18 at level 1 (column centre 1/36 < 0.03), 26/27 at level 2, 157/162 at level 3 (the 5
    columns of width 1/162 whose centres lie below 0.03 unreachable), within 1/162 of 0.97 (the wall lies in one
    full-height column of that width), with a nonzero estimate (the change 26/27 -> 157/162). A wall at 0.05 or
    0.02 would stop with a change of 0 (the refined columns' centres all on one side of it: the limit stated in
    kernels.adaptive)."""
    wall = (-1.0, 2.0, 0.03)
    volume, _, est, levels, _ = _synthetic(wall, 6, 4, 5, 3, tol=1e-9)
    assert (volume, est, levels) == (1.0, 0.0, 0)
    volume, _, est, levels, _ = _synthetic(wall, 6, 4, 5, 3, tol=1e-9, faces=True)
    assert levels == 3
    assert volume == pytest.approx(157 / 162, rel=1e-12)
    assert abs(volume - 0.97) <= 1 / 162
    assert est == pytest.approx(abs(157 / 162 - 26 / 27) / (157 / 162), rel=1e-12)


@njit(cache=True)
def _ellipsoid_field(p, x, y, z, out):
    """Synthetic field kernel, mirror-symmetric about x = p[0] and about y = p[1]: LCI 1 - r^2 inside the ellipsoid
    r^2 = sum(((x, y, z) - p[0:3]) / p[3:6])^2) < 1, else -1; slot 1 (x - p[0])^2 + (y - p[1])^2 + z; slot 2 r."""
    u = (x - p[0]) / p[3]
    v = (y - p[1]) / p[4]
    w = (z - p[2]) / p[5]
    r2 = u * u + v * v + w * w
    out[0] = 1.0 - r2 if r2 < 1.0 else -1.0
    dx = x - p[0]
    dy = y - p[1]
    out[1] = dx * dx + dy * dy + z
    out[2] = np.sqrt(r2)


def _ellipsoid_fields(p):
    """NumPy twin of _ellipsoid_field: points (k, 3) -> fields (k, 3)."""
    def fields(pts):
        d = pts - p[:3]
        r2 = ((d / p[3:6]) ** 2).sum(axis=1)
        return np.c_[np.where(r2 < 1.0, 1.0 - r2, -1.0), d[:, 0] ** 2 + d[:, 1] ** 2 + pts[:, 2], np.sqrt(r2)]
    return fields


@njit(cache=True)
def _ellipsoid_intervals(p, x, y, zlo, zhi, out):
    """Interval kernel of _ellipsoid_field: the chord |z - p[2]| < p[5] s, s^2 = 1 - u^2 - v^2, within [zlo, zhi];
    -1 (nodes and bisection instead) on the columns with x > p[6], so that one design takes both paths."""
    if x > p[6]:
        return -1
    u = (x - p[0]) / p[3]
    v = (y - p[1]) / p[4]
    s2 = 1.0 - u * u - v * v
    if not s2 > 0.0:
        return 0
    h = p[5] * np.sqrt(s2)
    a = max(p[2] - h, zlo)
    b = min(p[2] + h, zhi)
    if not b > a:
        return 0
    out[0, 0] = a
    out[0, 1] = b
    return 1


def test_interval_columns_equal_the_numpy_twin():
    """Closed-form column intervals (column_stats' interval_kernel; the twin's ``intervals``), with columns that
    fall back to nodes and bisection in the same design: the same level and number of evaluations, estimates to
    1e-10, rows to 1e-12 relative (as test_column_kernel_equals_numpy_twin), with and without z-levels, face
    columns and a mirror plane; and fewer evaluations than nodes and bisection everywhere."""
    lo, hi = np.array([-0.6, -0.3, 0.0]), np.array([0.8, 0.7, 1.0])
    p = np.array([0.1, 0.2, 0.5, 0.9, 0.6, 0.45, 0.4])
    twin_iv = _interval_twin(_ellipsoid_intervals, p)
    for opt in (dict(), dict(zlevels=1, zconfirm=1, faces=True), dict(faces=True, ny=4, mirror=(True, False))):
        s, ev, eg, lv, ne = column_stats(_ellipsoid_field, 3, p[None], lo[None], hi[None], 3, 6, 6, 6, 2, 2e-4,
                                         2e-4, EDGES, 1.0, interval_kernel=_ellipsoid_intervals, **opt)
        row, tv, tg, tl, tn = column_twin(_ellipsoid_fields(p), 3, lo, hi, 3, 6, 6, 6, 2, 2e-4, 2e-4, EDGES, 1.0,
                                          intervals=twin_iv, **opt)
        nodes = column_stats(_ellipsoid_field, 3, p[None], lo[None], hi[None], 3, 6, 6, 6, 2, 2e-4, 2e-4, EDGES,
                             1.0, **opt)
        assert (lv[0], ne[0]) == (tl, tn), opt
        assert lv[0] == 2  # the refinement with intervals was compared
        # the estimates are differences of two sums of ~10^3 column measures, which the twin adds in NumPy's
        # pairwise order and the kernel sequentially: 1e-13 of the measure (measured 5.9e-15 on 8.4e-6)
        assert ev[0] == pytest.approx(tv, rel=1e-10, abs=1e-13)
        assert eg[0] == pytest.approx(tg, rel=1e-10, abs=1e-13)
        np.testing.assert_allclose(s[0], row, rtol=1e-12, atol=1e-12 * np.abs(row).max())
        assert ne[0] < nodes[4][0]


@njit(cache=True)
def _ellipsoid_constant_field(p, x, y, z, out):
    """_ellipsoid_field's reachable set with a constant LCI 0.25 (other slots as there)."""
    _ellipsoid_field(p, x, y, z, out)
    if out[0] >= 0.0:
        out[0] = 0.25


def test_inherited_fields_on_an_ellipsoid():
    """Step 3b (``field_levels=0``) on an ellipsoid wholly inside its box, with closed-form column intervals:
    - a constant LCI: refined columns that inherit their parent's fields give the same statistics as columns that
      evaluate them (to 1e-12: the same pieces, the weights scaled), with fewer evaluations;
    - LCI = 1 - r^2 (r the ellipsoid radius): the volume is the same as with evaluated fields (the measure is
      exact either way) and the GCI is within 1e-3 of the exact mean of 1 - r^2 over the ball, 1 - 3/5 = 0.4
      (the inherited per-column means are first-order accurate where a wall leaves the children asymmetric);
      the kernel equals the NumPy twin."""
    lo, hi = np.array([-0.5, -0.5, 0.0]), np.array([0.5, 0.5, 1.0])
    p = np.array([0.03, -0.02, 0.5, 0.41, 0.33, 0.37, np.inf])
    run = dict(interval_kernel=_ellipsoid_intervals, faces=True)
    plan = (lo[None], hi[None], 3, 8, 2, 5, 3, 2e-4, 1e-4, EDGES, 1.0)  # 8 x 8 columns, 2 z-cells, 3 levels
    const = [column_stats(_ellipsoid_constant_field, 3, p[None], *plan, **run, field_levels=f) for f in (-1, 0)]
    np.testing.assert_allclose(const[1][0][0, :5], const[0][0][0, :5], rtol=1e-12)
    assert const[1][3][0] == const[0][3][0] >= 2 and const[1][4][0] < const[0][4][0]
    full, inh = (column_stats(_ellipsoid_field, 3, p[None], *plan, **run, field_levels=f) for f in (-1, 0))
    cell = 1.0 / 8**2 / 2  # coarse cell: box / (8 x 8 columns x 2 z-cells)
    exact_volume = 4.0 / 3.0 * np.pi * 0.41 * 0.33 * 0.37
    assert inh[0][0, 0] == pytest.approx(full[0][0, 0], rel=1e-12)
    assert inh[0][0, 0] * cell == pytest.approx(exact_volume, rel=2e-3)
    assert inh[0][0, 1] / inh[0][0, 0] == pytest.approx(0.4, abs=1e-3)
    assert inh[4][0] < full[4][0]
    row, tv, tg, tl, tn = column_twin(_ellipsoid_fields(p), 3, lo, hi, *plan[2:], faces=True,
                                      intervals=_interval_twin(_ellipsoid_intervals, p), field_levels=0)
    assert (inh[3][0], inh[4][0]) == (tl, tn)
    np.testing.assert_allclose(inh[0][0], row, rtol=1e-12, atol=1e-12 * np.abs(row).max())


def test_interval_column_lengths_are_exact():
    """One column through the ellipsoid's axis, no refinement: its measure is the exact chord 2 c (c the z
    semi-axis; 0.9 of the box height) in units of the coarse cell (hx hy hz0), where nodes and 5 bisection steps
    over 4 z-cells place each end within hz / 2^6."""
    lo, hi = np.array([-0.5, -0.5, 0.0]), np.array([0.5, 0.5, 1.0])
    p = np.array([0.0, 0.0, 0.5, 0.9, 0.6, 0.45, np.inf])
    s, *_ = column_stats(_ellipsoid_field, 3, p[None], lo[None], hi[None], 3, 1, 4, 5, 0, 2e-4, 2e-4, EDGES,
                         interval_kernel=_ellipsoid_intervals)
    assert s[0, 0] == pytest.approx(0.9 / 0.25, rel=1e-14)  # chord 0.9 over hz0 = 1 / 4
    nodes, *_ = column_stats(_ellipsoid_field, 3, p[None], lo[None], hi[None], 3, 1, 4, 5, 0, 2e-4, 2e-4, EDGES)
    assert 0.0 < abs(nodes[0, 0] - 3.6) <= 2 * 0.5 / 2**5


def test_per_axis_columns_and_mirror_planes_equal_the_numpy_twin():
    """ny != n and a mirror plane on each cross axis (and both), with and without box-face columns: the kernel
    equals its NumPy twin (same level and number of evaluations, estimates to 1e-10, rows to 1e-12 relative as in
    test_column_kernel_equals_numpy_twin) on an ellipsoid cut by the box on every cross face (3-D, 6 x 4 columns,
    refining to level 2) and an ellipse (planar, 8 columns; ny is ignored there). Without face columns a mirror
    plane changes nothing (the clamped neighbour is what the box edge uses anyway): byte-identical rows. With
    them, it drops that face's ghost columns and so changes the refinement (the evaluation counts below)."""
    lo, hi = np.array([-0.6, -0.3, 0.0]), np.array([0.8, 0.7, 1.0])
    for ndim, n, ny, mirrors in ((3, 6, 4, ((False, False), (True, False), (False, True), (True, True))),
                                 (2, 8, 5, ((False, False), (True, False)))):
        # planar: the plane z = lo[2] = 0 through the centre
        p = np.array([0.1, 0.2, 0.5 if ndim == 3 else 0.0, 0.9, 0.6, 0.45])
        runs = {}
        for mirror in mirrors:
            for faces in (False, True):
                opt = dict(zlevels=1, zconfirm=1, faces=faces, ny=ny, mirror=mirror)
                s, ev, eg, lv, ne = column_stats(_ellipsoid_field, 3, p[None], lo[None], hi[None], ndim, n, 6, 6, 2,
                                                 2e-4, 2e-4, EDGES, 1.0, **opt)
                row, tv, tg, tl, tn = column_twin(_ellipsoid_fields(p), 3, lo, hi, ndim, n, 6, 6, 2, 2e-4, 2e-4,
                                                  EDGES, 1.0, **opt)
                assert (lv[0], ne[0]) == (tl, tn), (ndim, mirror, faces)
                assert lv[0] == 2  # the refinement, and the mirror's role in it at level 1, were compared
                assert ev[0] == pytest.approx(tv, rel=1e-10, abs=1e-15)
                assert eg[0] == pytest.approx(tg, rel=1e-10, abs=1e-15)
                np.testing.assert_allclose(s[0], row, rtol=1e-12, atol=1e-12 * np.abs(row).max())
                runs[mirror, faces] = (s[0], ne[0])
        for mirror in mirrors[1:]:
            assert runs[mirror, False][0].tobytes() == runs[(False, False), False][0].tobytes()
        # with face columns the mirror planes drop the lo faces' ghosts and so change the refinement: evaluations
        # (both kernel and twin) 64 976 without, 65 096 / 64 288 / 64 408 with mirror x / y / both (3-D); 1 856
        # against 1 766 with mirror x (planar)
        calls = [int(runs[mirror, True][1]) for mirror in mirrors]
        assert calls == ([64976, 65096, 64288, 64408] if ndim == 3 else [1856, 1766])
    # planar: axis 1 is the column axis, not a cross axis, so a mirror plane there is refused
    with pytest.raises(ValueError, match="mirror on axis 1 of a planar task"):
        column_stats(_ellipsoid_field, 3, p[None], lo[None], hi[None], 2, 8, 6, 6, 2, 2e-4, 2e-4, EDGES,
                     mirror=(False, True))


def _mirror_pair(kernel, n_fields, packed, lo, hi, ndim, axis, n, m, nbis, maxlev, tol_v, tol_g, beta,
                 reach_kernel=None, **opt):
    """column_stats of the box made symmetric about 0 on cross axis ``axis`` ([-a, a], a = max(-lo, hi) there;
    n x n columns) and of its half [0, a] (n / 2 columns on that axis, its lo face a mirror plane):
    (full, half), each column_stats's 5-tuple for one design."""
    lo, hi = np.array(lo, dtype=float), np.array(hi, dtype=float)
    a = max(-lo[axis], hi[axis])
    lo[axis], hi[axis] = -a, a
    full = column_stats(kernel, n_fields, packed[None], lo[None], hi[None], ndim, n, m, nbis, maxlev, tol_v, tol_g,
                        EDGES, beta, reach_kernel=reach_kernel, **opt)
    lo[axis] = 0.0
    nx, ny = (n // 2, n) if axis == 0 else (n, n // 2)
    half = column_stats(kernel, n_fields, packed[None], lo[None], hi[None], ndim, nx, m, nbis, maxlev, tol_v, tol_g,
                        EDGES, beta, reach_kernel=reach_kernel, ny=ny, mirror=(axis == 0, axis == 1), **opt)
    return full, half


def _assert_half_is_half(full, half, n_fields):
    """The half box's row (counts in its coarse cells, which are the full box's) doubled equals the full box's:
    count, every field's sum and sum of squares and the band measures to 1e-9 relative (the same columns at the
    same points up to the rounding of their coordinates, summed in another order: measured <= 2e-13); min and max
    to 1e-12 of the field's magnitude (a minimum near 0, e.g. an LCI of 2e-5 next to the boundary, differs in
    the last bits of its point: 1e-16 absolute); the same refinement level and error estimates (relative
    quantities: 1e-9); kernel calls exactly half (the full box's columns are the half box's and their mirror
    images, with as many calls each; the mirror face's ghost columns are not evaluated): measured 0.5000 on
    every case here."""
    sf, sh = full[0][0], half[0][0]
    mm = [c for f in range(n_fields) for c in (3 + 4 * f, 4 + 4 * f)]
    ext = [c for c in range(len(sf)) if c not in mm]
    np.testing.assert_allclose(2.0 * sh[ext], sf[ext], rtol=1e-9, atol=0.0)
    scale = np.repeat(np.maximum(np.abs(sf[3::4][:n_fields]), np.abs(sf[4::4][:n_fields])), 2)
    assert np.all(np.abs(sh[mm] - sf[mm]) <= 1e-12 * scale)
    assert sf[0] > 0
    assert half[3][0] == full[3][0]
    assert half[1][0] == pytest.approx(full[1][0], rel=1e-9)
    assert half[2][0] == pytest.approx(full[2][0], rel=1e-9)
    assert half[4][0] == 0.5 * full[4][0]


@pytest.mark.parametrize("axis", [0, 1])
@pytest.mark.parametrize("faces", [False, True])
def test_mirror_half_box_equals_the_full_box_synthetic(axis, faces):
    """An ellipsoid centred on the plane x = 0 (axis 0) or y = 0 (axis 1), cut by the box's faces on that axis
    (box +-0.8 against semi-axis 1, +-0.6 against 0.7): the full box with 6 x 6 columns and the half box with 3 on
    that axis and a mirror plane at 0 agree (_assert_half_is_half), refining to level 3 (tolerance 2e-4, one
    z-level); also planar (an ellipse symmetric about x = 0, 8 columns, up to 4 levels: it stops at level 3, with
    face columns at 2). Measured calls full / half: x 109 360 / 54 680 (with faces 114 204 / 57 102), y 81 568 /
    40 784 (86 436 / 43 218), planar 4 460 / 2 230 (4 566 / 2 283); sums within 6e-15 relative."""
    if axis == 0:
        p, lo, hi = np.array([0.0, 0.1, 0.5, 1.0, 0.7, 0.4]), [-0.8, -0.7, 0.0], [0.8, 0.9, 1.0]
    else:
        p, lo, hi = np.array([0.1, 0.0, 0.5, 1.0, 0.7, 0.4]), [-0.95, -0.6, 0.0], [1.15, 0.6, 1.0]
    full, half = _mirror_pair(_ellipsoid_field, 3, p, lo, hi, 3, axis, 6, 6, 8, 3, 2e-4, 2e-4, 1.0, zlevels=1,
                              faces=faces)
    assert full[3][0] == 3
    _assert_half_is_half(full, half, 3)
    if axis == 0:
        p2 = np.array([0.0, 0.3, 0.0, 1.0, 0.7, 1.0])
        full, half = _mirror_pair(_ellipsoid_field, 3, p2, [-0.8, -0.5, 0.0], [0.8, 1.1, 0.0], 2, 0, 8, 16, 8, 4,
                                  1e-5, 1e-5, 1.0, faces=faces)
        assert full[3][0] == (2 if faces else 3)
        _assert_half_is_half(full, half, 3)


@pytest.mark.parametrize("name, axis", [("rps-upu-tool", 1), ("ups-sspr", 1), ("planar-fivebar", 0),
                                        ("2pauu-ppap", 0), ("2pauu-ppap", 1)])
def test_mirror_half_box_equals_the_full_box(name, axis):
    """Mechanisms whose fields are mirror-symmetric about 0 on a cross axis (rps-upu-tool in y, ups-sspr in beta,
    the five-bar in x, 2pauu-ppap in x and y), the config's design and options, its bounding box made symmetric
    on that axis (it already is for all five), with the mechanism's own plan (planar-fivebar: 16 columns, 32
    z-cells, 8 bisections, 4 levels instead of 64 / 128 / 8 / 6; an odd column count would be rounded up, none
    is): the half box with a mirror plane equals the full box (_assert_half_is_half). Measured: rps-upu-tool
    77 754 / 38 877 calls (level 2: z-levels, faces and both refinements), ups-sspr 4 832 / 2 416 (level 1),
    the five-bar 3 096 / 1 548 (level 2), 2pauu-ppap 238 156 / 119 078 (level 1, faces); sums within 2e-13. On 40
    random designs each (same plans) levels and calls (exactly half) agree everywhere, the count, LCI statistics
    and band measures within 2e-14, the other fields' sums within 1.2e-9 (five-bar deflection, 2pauu-ppap
    sigma_max 6e-10) except rps-upu-tool's stiffness_min and deflection: up to 8e-7 relative. Those field kernels
    change by up to 1.9e-6 (five-bar 5e-8) relative when the point moves one ulp, next to a singular pose, and the
    half box's column coordinates are the full box's up to rounding: a property of the field kernels, not of the
    mirror plane (hence the config designs here, where every sum stays within 2e-13)."""
    from scalesynth.evaluate import adaptive_plan, design_boxes

    mech = get(name)
    cfg = load_config(config_for(name))
    design, options = cfg.resolved_design(), cfg.resolved_options()
    ndim = len(mech.task_axes)
    lo, hi = design_boxes(mech, [design], options)
    assert lo[0, axis] == -hi[0, axis]
    plan = adaptive_plan(mech) if ndim == 3 else ColumnPlan(16, 32, 8, 4)
    n = plan.columns + plan.columns % 2
    full, half = _mirror_pair(mech.field_kernel, mech.n_fields, mech.pack(design, options), lo[0], hi[0], ndim, axis,
                              n, plan.cells, plan.bisections, plan.levels, 0.002, 5e-4, plan.beta,
                              reach_kernel=mech.reach_kernel, zlevels=plan.zlevels, zconfirm=plan.zconfirm,
                              faces=plan.faces)
    assert full[3][0] >= 1
    _assert_half_is_half(full, half, mech.n_fields)


@pytest.mark.parametrize("name", ["rps-upu", "rps-upu-tool"])
def test_adaptive_is_deterministic_and_independent_of_the_batch(name):
    """Two runs give byte-identical rows, a design evaluated alone gives the same row as inside a population
    (each design is evaluated serially, designs in parallel: no dependence on threads or scheduling), and every
    field's statistics use the same weights (the band measures add up to the count). rps-upu-tool: the plan with
    z-levels and box-face columns."""
    mech = get(name)
    cfg = load_config(config_for(name))
    options = cfg.resolved_options()
    base = cfg.resolved_design()
    k0, k1 = list(base)[:2]
    designs = [base, {**base, k0: base[k0] * 1.05}, {**base, k1: base[k1] * 0.95}]
    packed = np.stack([mech.pack(d, options) for d in designs])
    a = adaptive_population_stats(mech, designs, options, packed, Tolerance(), EDGES)
    b = adaptive_population_stats(mech, designs, options, packed, Tolerance(), EDGES)
    assert a.stats.tobytes() == b.stats.tobytes()
    alone = adaptive_population_stats(mech, designs[1:2], options, packed[1:2], Tolerance(), EDGES)
    assert alone.stats.tobytes() == a.stats[1:2].tobytes()
    assert alone.evaluations[0] == a.evaluations[1]
    bands = a.stats[:, kgrid.band_column(mech.n_fields, 0):]
    np.testing.assert_allclose(bands.sum(axis=1), a.stats[:, 0], rtol=1e-12)


def test_adaptive_empty_workspace_is_zero_not_nan():
    """A box where nothing is reachable (a region far outside the workspace): measure 0, GCI 0 and error
    estimates 0; every other statistic over the empty set NaN (null, issue 27), never a number read as best."""
    mech = get("2pauu-ppap")
    cfg = load_config(config_for("2pauu-ppap"))
    out = evaluate_population(mech, [cfg.resolved_design()], cfg.resolved_options(), tolerance=Tolerance(),
                              region={"x": (50.0, 51.0), "y": (50.0, 51.0), "z": (50.0, 51.0)})
    nullable = nullable_columns(mech, "m", 3)
    for key, value in out.items():
        assert np.all(np.isnan(value) if key in nullable else np.isfinite(value)), key
    assert out["volume_m3"][0] == 0.0 and out["gci"][0] == 0.0
    assert out["error_volume"][0] == 0.0 and out["error_gci"][0] == 0.0


def test_adaptive_zero_size_box_is_an_empty_workspace():
    """A five-bar whose arms cannot meet (l1 + l2 < r) has a zero-size bounding box: kernel and twin give an empty
    row (count 0) without dividing by the zero cell size, and the metrics are 0."""
    mech = get("planar-fivebar")
    cfg = load_config(config_for("planar-fivebar"))
    options = cfg.resolved_options()
    design = mech.resolve_design({**cfg.resolved_design(), "r": 400.0, "l1": 100.0, "l2": 100.0})
    lo, hi = _box(mech, design, options)
    assert np.all(lo[:2] == hi[:2])
    packed = mech.pack(design, options)[None, :]
    s, ev, eg, lv, ne = column_stats(mech.field_kernel, mech.n_fields, packed, lo[None], hi[None], 2, 8, 8, 4, 2,
                                     0.002, 5e-4, EDGES)
    row, *_ = column_twin(lambda pts: None, mech.n_fields, lo, hi, 2, 8, 8, 4, 2, 0.002, 5e-4, EDGES)
    assert s[0, 0] == 0.0 and ne[0] == 0.0 and ev[0] == 0.0 and eg[0] == 0.0
    np.testing.assert_array_equal(s[0], row)
    out = evaluate_population(mech, [design], options, tolerance=Tolerance())
    assert out[mech.measure_key(mech.default_length_unit)][0] == 0.0 and out["gci"][0] == 0.0


def test_plan_levels_refine_and_the_estimate_tracks_the_change():
    """With more levels allowed and a tolerance that cannot be met, the evaluator refines to the last level; the
    error estimate it reports is the change of the measure between the last two levels."""
    mech = get("rps-upu")
    cfg = load_config(config_for("rps-upu"))
    design, options = cfg.resolved_design(), cfg.resolved_options()
    packed = mech.pack(design, options)[None, :]
    tight = Tolerance(volume=1e-9, gci=1e-9)
    runs = [adaptive_population_stats(mech, [design], options, packed, tight, EDGES,
                                      plan=ColumnPlan(12, 8, 6, lev)) for lev in (1, 2)]
    assert [int(r.levels[0]) for r in runs] == [1, 2]
    v1, v2 = (r.stats[0, 0] for r in runs)
    assert runs[1].error_volume[0] == pytest.approx(abs(v2 - v1) / v2, rel=1e-9)
    assert runs[1].evaluations[0] > runs[0].evaluations[0]


def test_tolerance_config_and_resolution_override():
    """`grid: {tolerance: ...}` without a resolution runs the adaptive evaluator and reports its error estimates
    (within the tolerance on the config's design); an explicit resolution (what `--resolution N` sets) forces the
    uniform grid; a bad tolerance is a one-line config error naming the field."""
    data = yaml.safe_load(config_for("rps-upu").read_text())
    data["grid"] = {"tolerance": {"volume": 0.002, "gci": 5.0e-4}}
    cfg = config_from_dict(data)
    assert cfg.grid.adaptive
    rep = evaluate_config(cfg)
    assert 0.0 <= rep.metrics["error_volume"] <= 0.002
    assert 0.0 <= rep.metrics["error_gci"] <= 5.0e-4
    forced = config_from_dict(data, ["grid.resolution=24"])
    assert not forced.grid.adaptive
    rep24 = evaluate_config(forced)
    assert "error_volume" not in rep24.metrics and rep24.resolution == 24
    # within the tolerance of a fine uniform grid (192^3)
    fine = evaluate_config(config_from_dict(data, ["grid.resolution=192"]))
    assert rep.metrics["gci"] == pytest.approx(fine.metrics["gci"], abs=5.0e-4)
    assert rep.measure == pytest.approx(fine.measure, rel=0.002)
    data["grid"] = {"tolerance": {"volume": -1.0}}
    with pytest.raises(ConfigError, match="grid.tolerance.volume"):
        config_from_dict(data)


_THREADS_PROBE = """
import sys
import numpy as np
from scalesynth.config import load_config
from scalesynth.evaluate import Tolerance, adaptive_population_stats
cfg = load_config(sys.argv[1])
mech, options = cfg.mech, cfg.resolved_options()
base = cfg.resolved_design()
k0 = list(base)[0]
designs = [{**base, k0: base[k0] * f} for f in (1.0, 1.05, 0.95, 1.1)]
packed = np.stack([mech.pack(d, options) for d in designs])
r = adaptive_population_stats(mech, designs, options, packed, Tolerance(), np.array([0.0, 0.1, 0.3, 1.0]))
sys.stdout.write(r.stats.tobytes().hex())
"""


def test_adaptive_rows_do_not_depend_on_the_thread_count():
    """The same population evaluated with 1 and with 2 Numba threads (fresh processes, shared disk cache) gives
    byte-identical statistics rows."""
    out = []
    for threads in ("1", "2"):
        env = dict(os.environ, NUMBA_NUM_THREADS=threads)
        res = subprocess.run([sys.executable, "-c", _THREADS_PROBE, str(config_for("rps-upu"))], env=env,
                             capture_output=True, text=True, timeout=600, check=True)
        out.append(res.stdout)
    assert out[0] and out[0] == out[1]
