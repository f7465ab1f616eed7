"""pprs-rprs: the closed-form reachable intervals of a z-column (PprsRprs.interval_kernel,
pprs_rprs.column_intervals) against the reach kernel it replaces (point_reach) point by point, and the bounding
box's y pad that keeps the w2 walls off the cell centres."""

import math
from collections import Counter

import numpy as np
import pytest

from scalesynth.mechanisms import get
from scalesynth.mechanisms.pprs_rprs import Y_PAD

from interval_checks import K, check_column, reach_column

PPRS = get("pprs-rprs")
DEFAULT = PPRS.resolve_design({})  # r = 160, R = 180, L1 = 100, L2 = L3 = 120 mm
N_DESIGNS = 60
N_COLUMNS = 10  # per design: 600 columns
N_POINTS = 2000  # per column: 1.2 million reach-kernel points


def _random_case(rng, i):
    """A design (the default scaled by U(0.7, 1.3) per parameter) and options: the branch '+++' (the one with a
    workspace under Table-1-like limits) on three designs in four, another of the eight on the fourth; every third
    design a random orientation (each angle U(-0.2, 0.2) rad); every fifth chain 3 at 240 deg; stroke limits
    [U(0, 50), + U(60, 160)] mm; beta limits [U(0.4, 1.3), + U(0.5, 1.8)] rad; every sixth design has the branch
    '--+' or '---' (D1, D2 above C1, C2: the platform reaches below the base plane, h3 < 0) with long strokes
    [U(10, 40), + U(150, 280)] mm and beta limits [-U(0.6, 1.5), U(0.6, 1.5)] (chain 3's stroke annulus then cuts
    a column twice), every seventh [U(-pi, 2), +
    U(0.3, 3)] clipped to pi (some holding atan2's cut at +-pi)."""
    design = PPRS.resolve_design({k: v * rng.uniform(0.7, 1.3) for k, v in DEFAULT.items()})
    branches = ("++-", "+-+", "+--", "-++", "-+-", "--+", "---")
    lo = rng.uniform(0.0, 50.0)
    blo = rng.uniform(0.4, 1.3)
    beta = [blo, min(math.pi, blo + rng.uniform(0.5, 1.8))]
    sigma = branches[i % 7] if i % 4 == 3 else "+++"
    if i % 7 == 0:
        blo = rng.uniform(-math.pi, 2.0)
        beta = [blo, min(math.pi, blo + rng.uniform(0.3, 3.0))]
    stroke = [lo, lo + rng.uniform(60.0, 160.0)]
    if i % 6 == 0:
        sigma = ("--+", "---")[i % 12 // 6]
        beta = [-rng.uniform(0.6, 1.5), rng.uniform(0.6, 1.5)]
        lo = rng.uniform(10.0, 40.0)
        stroke = [lo, lo + rng.uniform(150.0, 280.0)]
    opts = {"sigma": sigma, "s_limits": stroke, "beta_limits": beta}
    if i % 3 == 0:
        opts["orientation"] = [float(a) for a in rng.uniform(-0.2, 0.2, 3)]
    if i % 5 == 0:
        opts["chain3_azimuth_deg"] = 240.0
    return design, PPRS.resolve_options(opts)


def _column_box(design, options):
    """A box around the mechanism's: its bounding box widened by 30 % per side (so that columns leave the
    workspace and every check is crossed), or a random box where the bounding box is empty."""
    lo, hi = PPRS.bounding_box(design, options)
    span = np.maximum(hi - lo, 50.0)
    return lo - 0.3 * span, hi + 0.3 * span


def _check_column(p, x, y, zlo, zhi, tol, zs, counts):
    """One column against point_reach (interval_checks.check_column)."""
    check_column(PPRS.interval_kernel, lambda z: reach_column(PPRS.reach_kernel, p, x, y, z), p, x, y, zlo, zhi, zs,
                 tol, counts)


def test_intervals_match_reach_kernel():
    """600 random columns (60 random designs x 10; _random_case), each over a random height range [zlo, zhi] (the
    whole widened box height on half the columns, a random part of it on the others) and at 2000 uniform random z:
    z lies in a returned interval exactly where point_reach >= 0, except within 1e-9 x (box height) of an interval
    end (rounding of the candidates against the kernel's own arithmetic); every interval end inside (zlo, zhi) is a
    crossing of the kernel to 2e-9 x (box height) on either side. Half the columns are drawn next to a point where
    the reach kernel finds the workspace (else most would miss the thin workspaces). The sample must hold
    unreachable columns (k = 0), more than 200 interval ends and reachable points."""
    rng = np.random.default_rng(20261202)
    counts = Counter()
    for i in range(N_DESIGNS):
        design, options = _random_case(rng, i)
        p = PPRS.pack(design, options)
        lo, hi = _column_box(design, options)
        tol = 1e-9 * (hi[2] - lo[2])
        # reachable points of a coarse grid, to draw half the columns through the workspace
        g = [np.linspace(lo[a], hi[a], 24) for a in range(3)]
        pts = np.stack(np.meshgrid(*g, indexing="ij"), -1).reshape(-1, 3)
        hit = pts[[reach_column(PPRS.reach_kernel, p, q[0], q[1], q[2:3])[0] >= 0.0 for q in pts]]
        for j in range(N_COLUMNS):
            if j % 2 and len(hit):
                x, y = hit[rng.integers(len(hit)), :2] + rng.uniform(-2.0, 2.0, 2)
            else:
                x, y = rng.uniform(lo[0], hi[0]), rng.uniform(lo[1], hi[1])
            zlo, zhi = (lo[2], hi[2]) if j % 4 < 2 else np.sort(rng.uniform(lo[2], hi[2], 2))
            _check_column(p, x, y, zlo, zhi, tol, rng.uniform(zlo, zhi, N_POINTS), counts)
    assert counts["points"] == N_DESIGNS * N_COLUMNS * N_POINTS == 1_200_000
    assert counts["empty"] > 0 and counts["ends"] > 200, counts
    assert counts["reachable"] > 0.05 * counts["points"], counts


def test_split_columns_match_reach_kernel():
    """Columns cut twice: the default design on branch '--+' (the platform reaches below the base plane) with
    strokes [20, 300] mm and beta in [-1.5, 1.5] rad, where chain 3's lower stroke limit removes |h3| < h_min from
    a column that beta and the other chains allow on both sides of h3 = 0; every column of a 60 x 60 grid over the
    widened box is checked as in test_intervals_match_reach_kernel (500 random z each). More than 20 columns hold
    two intervals."""
    rng = np.random.default_rng(7)
    options = PPRS.resolve_options({"sigma": "--+", "s_limits": [20.0, 300.0], "beta_limits": [-1.5, 1.5]})
    p = PPRS.pack(DEFAULT, options)
    lo, hi = _column_box(DEFAULT, options)
    tol = 1e-9 * (hi[2] - lo[2])
    counts = Counter()
    for x in np.linspace(lo[0], hi[0], 60):
        for y in np.linspace(lo[1], hi[1], 60):
            _check_column(p, x, y, lo[2], hi[2], tol, rng.uniform(lo[2], hi[2], 500), counts)
    assert counts["split"] > 20 and counts["empty"] > 0, counts


def test_paper_column_by_hand():
    """Table-1 design, column through x = y = 0 (O1 above the base centre, zero orientation): C1 = (160, 0, z),
    so w1 = 160, lambda1 = 0, kappa1 = L1 = 100 and s1 = z - 100 in [37.5, 137.5]: z in [137.5, 237.5]; C2 =
    (-80, 80 sqrt3, z): w2 = 160, lambda2 = 0, s2 = z - 120: z in [157.5, 257.5]; C3 = 160 (cos 240, sin 240) = (-80,
    -80 sqrt3) with u3 at 210 deg: rho3 = 180 - u3 . C3 = 180 - 160 cos 30 = 41.44, lambda3 = e3 . C3 = -80, kappa3 =
    sqrt(120^2 - 80^2); s3 = sqrt(rho3^2 + z^2) - kappa3 <= 137.5 bounds z above, beta = atan2(z, rho3) >= 60 deg
    below (z >= rho3 tan 60 = 71.8, inactive). So the column holds [157.5, sqrt((137.5 + kappa3)^2 - rho3^2)]."""
    options = PPRS.resolve_options({})
    p = PPRS.pack(DEFAULT, options)
    out = np.empty((K, 2))
    k = PPRS.interval_kernel(p, 0.0, 0.0, 0.0, 400.0, out)
    rho3 = 180.0 - 160.0 * math.cos(math.radians(30.0))
    kappa3 = math.sqrt(120.0**2 - 80.0**2)
    top = math.sqrt((137.5 + kappa3) ** 2 - rho3**2)
    assert k == 1
    np.testing.assert_allclose(out[0], [157.5, top], rtol=1e-13)
    # a subrange cuts the interval at its own ends
    assert PPRS.interval_kernel(p, 0.0, 0.0, 200.0, 220.0, out) == 1
    np.testing.assert_array_equal(out[0], [200.0, 220.0])
    assert PPRS.interval_kernel(p, 0.0, 0.0, 0.0, 150.0, out) == 0


def test_interference_free_is_not_handled():
    """With interference_free the clearance decides reachability too: the kernel returns -1 and the mechanism
    offers no interval kernel for those options (the adaptive evaluator then runs nodes and bisection)."""
    options = PPRS.resolve_options({"interference_free": True})
    p = PPRS.pack(DEFAULT, options)
    assert PPRS.interval_kernel(p, 0.0, 0.0, 0.0, 400.0, np.empty((K, 2))) == -1
    assert PPRS.interval_kernel_for(options) is None
    assert PPRS.interval_kernel_for(PPRS.resolve_options({})) is PPRS.interval_kernel


def _w2(design, options, x, y):
    """w2 = u2 . C2 at O1 = (x, y) (conv O, zero orientation), mm."""
    r = design["r"]
    return -0.5 * (x - 0.5 * r) + math.sqrt(3.0) / 2.0 * (y + math.sqrt(3.0) / 2.0 * r)


def test_box_pad_only_where_both_y_faces_come_from_w2():
    """bounding_box widens y by Y_PAD of its span on each side exactly where both y faces come from the w2 limits.
    There the unpadded y span is sqrt3 times the x span and every cell-centred grid over the unpadded box (N = 24,
    96, 99) has cell centres on both w2 walls (|w2 - limit| below 1e-9 mm: rounding decides them); over the padded
    box none is within 1e-6 mm. The Table-1 design (y from |lambda1| <= L1 below, from w2 above) keeps its
    unpadded box: y in [-100, 30 / (sqrt3 / 2)]."""
    options = PPRS.resolve_options({})
    design = PPRS.resolve_design({"r": 154.02, "R": 180.48, "L1": 159.61, "L2": 155.92, "L3": 116.8})
    lo, hi = PPRS.bounding_box(design, options)
    span = (hi[1] - lo[1]) / (1.0 + 2.0 * Y_PAD)
    ylo, yhi = lo[1] + Y_PAD * span, hi[1] - Y_PAD * span
    assert span == pytest.approx(math.sqrt(3.0) * (hi[0] - lo[0]), rel=1e-12)
    assert _w2(design, options, lo[0], ylo) == pytest.approx(80.0, abs=1e-9)
    assert _w2(design, options, hi[0], yhi) == pytest.approx(180.0, abs=1e-9)
    for n in (24, 96, 99):
        for box_lo, box_hi, on_wall in ((ylo, yhi, True), (lo[1], hi[1], False)):
            x = lo[0] + (np.arange(n) + 0.5) * (hi[0] - lo[0]) / n
            y = box_lo + (np.arange(n) + 0.5) * (box_hi - box_lo) / n
            w2 = _w2(design, options, x[:, None], y[None, :])
            gap = np.minimum(np.abs(w2 - 80.0), np.abs(w2 - 180.0)).min()
            assert (gap < 1e-9) if on_wall else (gap > 1e-6), (n, on_wall, gap)
    lo, hi = PPRS.bounding_box(DEFAULT, options)
    np.testing.assert_allclose([lo[1], hi[1]], [-100.0, 30.0 / (math.sqrt(3.0) / 2.0)], rtol=1e-12)
