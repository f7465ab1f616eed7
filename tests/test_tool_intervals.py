"""rps-upu-tool: the closed-form reachable intervals of a z-column (RpsUpuTool.interval_kernel,
rps_upu._tool_column_intervals) against the reach kernel it replaces (tool_point_reach) point by point."""

import math
from collections import Counter

import numpy as np

from scalesynth.mechanisms import get

from interval_checks import K, check_column, reach_column

TOOL = get("rps-upu-tool")
DEFAULT = TOOL.resolve_design({})  # g = 80, h = 50, c = 50, e = 0 mm
N_DESIGNS = 60
N_COLUMNS = 10  # per design: 600 columns
N_POINTS = 2000  # per column: 1.2 million reach-kernel points


def _random_case(rng, i):
    """A design (the default scaled by U(0.7, 1.3) per parameter; every third one also e ~ U(-20, 20) mm, which
    the scaling leaves 0) and options: tool offset U(20, 100) mm; stroke [U(20, 60), + U(20, 60)] mm, [0, ...] for
    every seventh design and none for every fifth; theta and psi ranges [U(-0.6, 0.1), + U(0.05, 0.7)] rad
    (asymmetric, some not holding 0); z_range [U(-80, 20), + U(30, 120)] mm (low ends below 0 put the legs'
    lower limits inside the column)."""
    design = {k: v * rng.uniform(0.7, 1.3) for k, v in DEFAULT.items()}
    if i % 3 == 0:
        design["e"] = rng.uniform(-20.0, 20.0)
    lo = rng.uniform(20.0, 60.0)
    stroke = [lo, lo + rng.uniform(20.0, 60.0)]
    if i % 7 == 0:
        stroke[0] = 0.0
    if i % 5 == 0:
        stroke = None

    def angles():
        a = rng.uniform(-0.6, 0.1)
        return [a, a + rng.uniform(0.05, 0.7)]

    zl = rng.uniform(-80.0, 20.0)
    options = TOOL.resolve_options({"tool_offset": rng.uniform(20.0, 100.0), "stroke_limits": stroke,
                                    "theta_range": angles(), "psi_range": angles(),
                                    "z_range": [zl, zl + rng.uniform(30.0, 120.0)]})
    return TOOL.resolve_design(design), options


def test_intervals_match_reach_kernel():
    """600 random columns (60 random designs x 10; _random_case) of random heights [zlo, zhi] (the whole bounding
    box height on even columns, a random part of it on odd ones), each at 2000 uniform random z: z lies in a
    returned interval exactly where tool_point_reach >= 0, except within 1e-9 x (box height) of an interval end
    (rounding of the roots against the kernel's own arithmetic); every interval end inside (zlo, zhi) is a
    crossing of the kernel to 2e-9 x (box height) on either side. The sample must hold an unreachable column
    (k = 0), a wholly reachable one ([zlo, zhi] itself) and split ones (k >= 2: a leg's lower stroke limit cuts
    the column); on those, out with k - 1 rows returns -1."""
    rng = np.random.default_rng(20261202)
    counts = Counter()
    for i in range(N_DESIGNS):
        design, options = _random_case(rng, i)
        p = TOOL.pack(design, options)
        lo, hi = TOOL.bounding_box(design, options)
        tol = 1e-9 * (hi[2] - lo[2])
        for j in range(N_COLUMNS):
            x, y = rng.uniform(lo[0], hi[0]), rng.uniform(lo[1], hi[1])
            zlo, zhi = (lo[2], hi[2]) if j % 2 == 0 else np.sort(rng.uniform(lo[2], hi[2], 2))
            check_column(TOOL.interval_kernel, lambda zs, p=p, x=x, y=y: reach_column(TOOL.reach_kernel, p, x, y, zs),
                         p, x, y, zlo, zhi, rng.uniform(zlo, zhi, N_POINTS), tol, counts)
    assert counts["points"] == N_DESIGNS * N_COLUMNS * N_POINTS == 1_200_000
    assert counts["empty"] > 0 and counts["whole"] > 0 and counts["split"] > 0 and counts["ends"] > 0, counts


def test_default_column_by_hand():
    """Default design and options (d = 50 mm, q in [40, 90] mm, z_range [-10, 90] mm), column x = y = 0: theta =
    psi = 0, z0 = z + 50; q1^2 = q2^2 = z0^2 + (g - h)^2 = z0^2 + 900 and q3^2 = z0^2 + c^2 = z0^2 + 2500. q3 >= 40
    always; q1 >= 40 needs |z0| >= sqrt(700); q1 <= 90 needs |z0| <= sqrt(7200); q3 <= 90 needs |z0| <= sqrt(5600).
    With z0 in [-10, 90]: z0 in [sqrt(700), sqrt(5600)], i.e. z in [sqrt(700) - 50, sqrt(5600) - 50]."""
    p = TOOL.pack(DEFAULT, TOOL.resolve_options({}))
    out = np.empty((K, 2))
    assert TOOL.interval_kernel(p, 0.0, 0.0, -100.0, 100.0, out) == 1
    np.testing.assert_allclose(out[0], [math.sqrt(700.0) - 50.0, math.sqrt(5600.0) - 50.0], rtol=0, atol=1e-12)
    # a column window that ends inside the reachable part is clipped to it exactly
    assert TOOL.interval_kernel(p, 0.0, 0.0, 0.0, 10.0, out) == 1
    assert tuple(out[0]) == (0.0, 10.0)
    # zlo > zhi, and a column whose psi = asin(y / d) leaves psi_range (y = 30 mm: psi = 0.6435 > 0.314)
    assert TOOL.interval_kernel(p, 0.0, 0.0, 10.0, 0.0, out) == 0
    assert TOOL.interval_kernel(p, 0.0, 30.0, -100.0, 100.0, out) == 0


def test_interference_free_falls_back():
    """With interference_free the clearance decides reachability too: -1, whatever the column."""
    options = TOOL.resolve_options({"interference_free": True})
    p = TOOL.pack(DEFAULT, options)
    assert TOOL.interval_kernel(p, 0.0, 0.0, -100.0, 100.0, np.empty((K, 2))) == -1
    assert TOOL.interval_kernel(p, 0.0, 30.0, -100.0, 100.0, np.empty((K, 2))) == -1


def test_the_interval_plan_only_where_every_column_is_in_closed_form():
    """evaluate.adaptive_plan: rps-upu-tool's interval plan (no z-levels: the column lengths are exact) with its
    interval kernel; with interference_free (the clearance decides reachability too, so every column would fall
    back to nodes) the node plan, whose z-levels find the thin slabs nodes miss."""
    from scalesynth.evaluate import ADAPTIVE_PLAN, adaptive_plan

    mech = get("rps-upu-tool")
    plain = mech.resolve_options({})
    free = mech.resolve_options({"interference_free": True})
    assert mech.interval_kernel_for(plain) is mech.interval_kernel
    assert mech.interval_kernel_for(free) is None
    assert adaptive_plan(mech, plain) == mech.interval_plan
    assert adaptive_plan(mech, plain).zlevels == 0
    assert adaptive_plan(mech, free) == mech.node_plan
    assert adaptive_plan(mech) == mech.node_plan
    assert mech.node_plan not in (None, ADAPTIVE_PLAN[3]) and mech.interval_plan not in (None, mech.node_plan)
