"""ups-sspr: the closed-form reachable intervals of a Y-column (UpsSspr.interval_kernel,
ups_sspr.column_intervals) against the reach kernel it replaces (point_reach) point by point."""

import math
from collections import Counter

import numpy as np

from scalesynth.mechanisms import get
from scalesynth.mechanisms.ups_sspr import _legs

from interval_checks import K, check_column, reach_column

UPS = get("ups-sspr")
DEFAULT = UPS.resolve_design({})  # a = 100, b = 80, c = 120 mm
N_DESIGNS = 60
N_COLUMNS = 10  # per design: 600 columns
N_POINTS = 2000  # per column: 1.2 million reach-kernel points


def _random_case(rng, i):
    """A design (a, b, c: the default scaled by U(0.6, 1.5), U(0.5, 1.5), U(0.9, 1.1)) and options: l1 limits
    [U(40, 100), + U(10, 80)] mm ([0, ...] for every seventh design, none for every fifth), l2 and l3 limits
    [q1, q2] mm each, quantiles U(0, 0.6) and U(0.6, 1.0) of the leg's length over 200 random poses of the ranges
    (legs 2 and 3 differ; none for every fourth design: then only the l1 slab and the box cut the column), alpha
    and beta ranges [U(-1, 0.2), + U(0.05, 1)] rad (asymmetric, some not holding 0; beta within +-pi/2), Y_range
    default (+-0.999 c) on even designs, else [U(-1.1, 0), + U(0.1, 1.2)] c (a range reaching past +-c is clipped
    to it)."""
    design = {"a": DEFAULT["a"] * rng.uniform(0.6, 1.5), "b": DEFAULT["b"] * rng.uniform(0.5, 1.5),
              "c": DEFAULT["c"] * rng.uniform(0.9, 1.1)}
    c = design["c"]
    lo = rng.uniform(40.0, 100.0)
    l1 = [lo, lo + rng.uniform(10.0, 80.0)]
    if i % 7 == 0:
        l1[0] = 0.0
    if i % 5 == 0:
        l1 = None

    def angles(bound):
        a = rng.uniform(-1.0, 0.2)
        return [max(a, -bound), min(a + rng.uniform(0.05, 1.0), bound)]

    alpha, beta = angles(math.pi), angles(math.pi / 2 - 1e-3)
    poses = [(rng.uniform(*alpha), rng.uniform(*beta), rng.uniform(-0.99, 0.99) * c) for _ in range(200)]
    lengths = np.array([_legs(design["a"], design["b"], c, *pose)[0] for pose in poses])

    def leg(m):
        return [float(np.quantile(lengths[:, m], rng.uniform(0.0, 0.6))),
                float(np.quantile(lengths[:, m], rng.uniform(0.6, 1.0)))]

    l2, l3 = (None, None) if i % 4 == 0 else (leg(1), leg(2))
    yl = rng.uniform(-1.1, 0.0) * c
    options = UPS.resolve_options({"l1_limits": l1, "l2_limits": l2, "l3_limits": l3,
                                   "alpha_range": alpha, "beta_range": beta,
                                   "Y_range": None if i % 2 == 0 else [yl, yl + rng.uniform(0.1, 1.2) * c]})
    return UPS.resolve_design(design), options


def test_intervals_match_reach_kernel():
    """600 random columns (60 random designs x 10; _random_case) at random (alpha, beta) in a box 10 % wider than
    the ranges (columns outside them are empty), over random Y windows (the whole box height on even columns, a
    random part of it on odd ones), each at 2000 uniform random Y: Y lies in a returned interval exactly where
    point_reach >= 0, except within 1e-9 x (box height) of an interval end (rounding of the roots against the
    kernel's own arithmetic); every interval end inside (zlo, zhi) is a crossing of the kernel to 2e-9 x (box
    height) on either side. The sample must hold an unreachable column (k = 0), a wholly reachable one ([zlo, zhi]
    itself) and split ones (k >= 2: a leg's lower stroke limit cuts the column); on those, out with k - 1 rows
    returns -1."""
    rng = np.random.default_rng(20261202)
    counts = Counter()
    for i in range(N_DESIGNS):
        design, options = _random_case(rng, i)
        p = UPS.pack(design, options)
        lo, hi = UPS.bounding_box(design, options)
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        tol = 1e-9 * (hi[2] - lo[2])
        for j in range(N_COLUMNS):
            x, y = rng.uniform(lo[:2] - 0.05 * (hi[:2] - lo[:2]), hi[:2] + 0.05 * (hi[:2] - lo[:2]))
            zlo, zhi = (lo[2], hi[2]) if j % 2 == 0 else np.sort(rng.uniform(lo[2], hi[2], 2))
            check_column(UPS.interval_kernel, lambda zs, p=p, x=x, y=y: reach_column(UPS.reach_kernel, p, x, y, zs),
                         p, x, y, zlo, zhi, rng.uniform(zlo, zhi, N_POINTS), tol, counts)
            counts["outside"] += not (lo[0] <= x <= hi[0] and lo[1] <= y <= hi[1])
    assert counts["points"] == N_DESIGNS * N_COLUMNS * N_POINTS == 1_200_000
    assert all(counts[key] > 0 for key in ("empty", "whole", "split", "ends", "outside")), counts


def test_default_column_by_hand():
    """Default design (a = 100, b = 80, c = 120 mm), column alpha = beta = 0: legs 2 and 3 have the same length,
    l^2 = c^2 + |e|^2 + 2 e_y Y + 2 e_z rho with e = (-+(ax - bx), by + am, 0), so e_z = 0 and l^2 = c^2 + (ax -
    bx)^2 + (by + am)^2 + 2 (by + am) Y is linear in Y; l1 in [80, 110] is the slab Y in [-37.5, 48] (the config's
    comment). With the default l2, l3 limits [120, 220] mm the whole slab is reachable (l = 120 at Y = -57.5, 220
    at Y = 102); with [150, 220] mm the column is the slab cut by l2 >= 150 at Y = (150^2 - c^2 - (ax - bx)^2 -
    (by + am)^2) / (2 (by + am))."""
    a, b, c = DEFAULT["a"], DEFAULT["b"], DEFAULT["c"]
    p = UPS.pack(DEFAULT, UPS.resolve_options({}))
    out = np.empty((K, 2))
    assert UPS.interval_kernel(p, 0.0, 0.0, -c, c, out) == 1
    np.testing.assert_allclose(out[0], [-37.5, 48.0], rtol=0, atol=1e-12)
    ex, ey = math.sqrt(3.0) / 2.0 * a - b / math.sqrt(2.0), b / math.sqrt(2.0) + a / 2.0
    y150 = (150.0**2 - c * c - ex * ex - ey * ey) / (2.0 * ey)
    assert -37.5 < y150 < 48.0
    p = UPS.pack(DEFAULT, UPS.resolve_options({"l2_limits": [150.0, 220.0], "l3_limits": [150.0, 220.0]}))
    assert UPS.interval_kernel(p, 0.0, 0.0, -c, c, out) == 1
    np.testing.assert_allclose(out[0], [y150, 48.0], rtol=0, atol=1e-11)
    # a column window that ends inside the reachable part is clipped to it exactly
    assert UPS.interval_kernel(p, 0.0, 0.0, 40.0, 45.0, out) == 1
    assert tuple(out[0]) == (40.0, 45.0)
    # zlo > zhi, and a column whose alpha leaves alpha_range ([-0.5, 0.5])
    assert UPS.interval_kernel(p, 0.0, 0.0, 45.0, 40.0, out) == 0
    assert UPS.interval_kernel(p, 0.6, 0.0, -c, c, out) == 0


def test_interference_free_falls_back():
    """With interference_free the clearance decides reachability too: -1, whatever the column."""
    options = UPS.resolve_options({"interference_free": True})
    p = UPS.pack(DEFAULT, options)
    assert UPS.interval_kernel(p, 0.0, 0.0, -100.0, 100.0, np.empty((K, 2))) == -1
    assert UPS.interval_kernel(p, 0.6, 0.0, -100.0, 100.0, np.empty((K, 2))) == -1
    assert UPS.interval_kernel_for(options) is None
    assert UPS.interval_kernel_for(UPS.resolve_options({})) is UPS.interval_kernel


def test_the_interval_plan_only_where_every_column_is_in_closed_form():
    """evaluate.adaptive_plan: ups-sspr's interval plan (2 z-cells: the column lengths are exact, the z-cells only
    serve the fields' Gauss rule) with its interval kernel; with interference_free the node plan (4 z-cells and
    bisection)."""
    from scalesynth.evaluate import ADAPTIVE_PLAN, adaptive_plan

    plain = UPS.resolve_options({})
    free = UPS.resolve_options({"interference_free": True})
    assert adaptive_plan(UPS, plain) == UPS.interval_plan
    assert adaptive_plan(UPS, plain).cells < UPS.node_plan.cells
    assert adaptive_plan(UPS, free) == UPS.node_plan
    assert adaptive_plan(UPS) == UPS.node_plan
    assert UPS.node_plan not in (None, ADAPTIVE_PLAN[3]) and UPS.interval_plan not in (None, UPS.node_plan)
