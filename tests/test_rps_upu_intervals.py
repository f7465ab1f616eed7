"""rps-upu (P-model): z-columns with closed-form reachable intervals (RpsUpu.interval_kernel,
rps_upu._p_column_intervals) against the reach kernel they replace (point_reach) point by point; the kernels in
column order (theta, psi, z) against the task-order ones; which options get the z-columns and their plan."""

import math
from collections import Counter

import numpy as np
from numba import njit

from scalesynth.evaluate import (
    ADAPTIVE_PLAN,
    Tolerance,
    adaptive_plan,
    adaptive_population_stats,
    column_axis,
)
from scalesynth.kernels.grid import population_points_fields
from scalesynth.mechanisms import get

from interval_checks import K, check_column

MECH = get("rps-upu")
DEFAULT = MECH.resolve_design({})  # g = 80, h = 50, c = 50, e = 0 mm
N_DESIGNS = 60
N_COLUMNS = 10  # per design: 600 columns
N_POINTS = 2000  # per column: 1.2 million reach-kernel points
EDGES = np.array([0.0, 0.1, 0.3, 1.0])


@njit
def _reach_column(kernel, p, theta, psi, zs):
    """kernel(p, z, theta, psi) slot 0 at each z of zs (task order)."""
    out = np.empty(1)
    r = np.empty(zs.shape[0])
    for i in range(zs.shape[0]):
        kernel(p, zs[i], theta, psi, out)
        r[i] = out[0]
    return r


def _random_case(rng, i):
    """A design (the default scaled by U(0.7, 1.3) per parameter; every third one also e ~ U(-20, 20) mm, which
    the scaling leaves 0) and P-model options: stroke [U(20, 60), + U(20, 60)] mm, [0, ...] for every seventh design
    and none for every fifth; theta and psi ranges [U(-0.9, 0.1), + U(0.05, 1.0)] rad (asymmetric, some not holding
    0); z_range [U(-90, 20), + U(30, 150)] mm (low ends below 0: columns through z = 0, where the legs are shortest,
    cross the lower stroke limits)."""
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
        a = rng.uniform(-0.9, 0.1)
        return [a, a + rng.uniform(0.05, 1.0)]

    zl = rng.uniform(-90.0, 20.0)
    options = MECH.resolve_options({"stroke_limits": stroke, "theta_range": angles(), "psi_range": angles(),
                                    "z_range": [zl, zl + rng.uniform(30.0, 150.0)]})
    return MECH.resolve_design(design), options


def test_intervals_match_reach_kernel():
    """600 random columns (60 random designs x 10; _random_case) at random (theta, psi) of the box, over the whole
    z-range (even columns) or a random part of it (odd ones), each at 2000 uniform random z: z lies in a returned
    interval exactly where point_reach(p, z, theta, psi) >= 0, except within 1e-9 x (box height) of an interval end
    (rounding of the roots against the kernel's own arithmetic); every interval end inside (zlo, zhi) is a crossing
    of the kernel to 2e-9 x (box height) on either side. The sample must hold an unreachable column (k = 0), a
    wholly reachable one ([zlo, zhi] itself) and split ones (k >= 2); on those, out with k - 1 rows returns -1."""
    rng = np.random.default_rng(20261202)
    counts = Counter()
    for i in range(N_DESIGNS):
        design, options = _random_case(rng, i)
        p = MECH.pack(design, options)
        lo, hi = MECH.bounding_box(design, options)
        tol = 1e-9 * (hi[0] - lo[0])
        for j in range(N_COLUMNS):
            theta, psi = rng.uniform(lo[1], hi[1]), rng.uniform(lo[2], hi[2])
            zlo, zhi = (lo[0], hi[0]) if j % 2 == 0 else np.sort(rng.uniform(lo[0], hi[0], 2))
            check_column(MECH.interval_kernel,
                         lambda zs, p=p, t=theta, s=psi: _reach_column(MECH.reach_kernel, p, t, s, zs),
                         p, theta, psi, zlo, zhi, rng.uniform(zlo, zhi, N_POINTS), tol, counts)
    assert counts["points"] == N_DESIGNS * N_COLUMNS * N_POINTS == 1_200_000
    assert counts["empty"] > 0 and counts["whole"] > 0 and counts["split"] > 0 and counts["ends"] > 0, counts


def test_default_column_by_hand():
    """Default design and options (q in [40, 90] mm), column theta = psi = 0: q1^2 = q2^2 = z^2 + (g - h)^2 =
    z^2 + 900 and q3^2 = z^2 + c^2 = z^2 + 2500. q3 >= 40 always; q1 >= 40 needs |z| >= sqrt(700); q1 <= 90 needs
    |z| <= sqrt(7200); q3 <= 90 needs |z| <= sqrt(5600). So z in [sqrt(700), sqrt(5600)] and its mirror image."""
    p = MECH.pack(DEFAULT, MECH.resolve_options({}))
    out = np.empty((K, 2))
    a, b = math.sqrt(700.0), math.sqrt(5600.0)
    assert MECH.interval_kernel(p, 0.0, 0.0, -100.0, 100.0, out) == 2
    np.testing.assert_allclose(out[:2], [[-b, -a], [a, b]], rtol=0, atol=1e-12)
    # the config's z_range [-10, 90]: the upper piece alone
    assert MECH.interval_kernel(p, 0.0, 0.0, -10.0, 90.0, out) == 1
    np.testing.assert_allclose(out[0], [a, b], rtol=0, atol=1e-12)
    # a column window that ends inside the reachable part is clipped to it exactly; zlo > zhi is empty
    assert MECH.interval_kernel(p, 0.0, 0.0, 30.0, 40.0, out) == 1
    assert tuple(out[0]) == (30.0, 40.0)
    assert MECH.interval_kernel(p, 0.0, 0.0, 10.0, 0.0, out) == 0


def test_c_model_and_interference_free_keep_the_psi_columns():
    """The C-model's legs are no quadratics in z, and with interference_free the clearance decides reachability
    too: the interval kernel returns -1 on their packed designs, interval_kernel_for gives None, the columns stay
    along psi with the node plan. The P-model gets the z-columns (axis 0) and the interval plan."""
    plain = MECH.resolve_options({})
    others = [MECH.resolve_options({"model": "C"}), MECH.resolve_options({"model": "C", "c3_variant": "upu"}),
              MECH.resolve_options({"interference_free": True})]
    for options in others:
        p = MECH.pack(DEFAULT, options)
        assert MECH.interval_kernel(p, 0.0, 0.0, -10.0, 90.0, np.empty((K, 2))) == -1
        assert MECH.interval_kernel_for(options) is None
        assert MECH.column_axis(options) == 2 and column_axis(MECH, options) == 2
        assert MECH.column_order_kernel(MECH.lci_kernel, options) is MECH.lci_kernel
        assert adaptive_plan(MECH, options) == MECH.node_plan
    assert MECH.interval_kernel_for(plain) is MECH.interval_kernel
    assert MECH.column_axis(plain) == 0 and column_axis(MECH, plain) == 0
    assert column_axis(MECH, plain, intervals=False) == 2
    assert adaptive_plan(MECH, plain) == MECH.interval_plan
    assert adaptive_plan(MECH) == MECH.node_plan
    assert MECH.node_plan not in (None, ADAPTIVE_PLAN[3]) and MECH.interval_plan not in (None, MECH.node_plan)
    # rps-upu-tool (a subclass) keeps its own columns along its last axis
    tool = get("rps-upu-tool")
    tool_options = tool.resolve_options({})
    assert tool.column_axis(tool_options) == 2 and column_axis(tool, tool_options) == 2
    assert tool.column_order_kernel(tool.lci_kernel, tool_options) is tool.lci_kernel


def test_column_order_kernels_equal_the_task_order_kernels():
    """Field, LCI and reach kernels in column order (theta, psi, z) give out bit for bit as the task-order kernels
    at the same points, on 20 000 random points of 1.2x the box of 5 random designs (reachable and not)."""
    rng = np.random.default_rng(7)
    options = MECH.resolve_options({})
    for i in range(5):
        design, _ = _random_case(rng, 1)
        p = MECH.pack(design, options)[None, :]
        lo, hi = MECH.bounding_box(design, options)
        mid, half = 0.5 * (lo + hi), 0.6 * (hi - lo)
        pts = mid + rng.uniform(-1.0, 1.0, (4000, 3)) * half
        col = pts[:, [1, 2, 0]]
        for kernel in (MECH.field_kernel, MECH.lci_kernel, MECH.reach_kernel):
            ordered = MECH.column_order_kernel(kernel, options)
            assert ordered is not kernel
            a = population_points_fields(kernel, MECH.n_fields, p, pts)[0]
            b = population_points_fields(ordered, MECH.n_fields, p, col)[0]
            used = [0] if kernel is not MECH.field_kernel else slice(None)
            assert np.array_equal(a[:, used], b[:, used], equal_nan=True), (i, kernel)
            reach = a[:, 0] >= 0.0
            assert 0.05 < reach.mean() < 0.95


def test_z_columns_agree_with_the_psi_columns():
    """The z-column evaluator (intervals, its plan) and the psi-column node evaluator (its plan) on 8 random designs
    of the config's bounds, every field: the volume within 2x the 0.2 % tolerance and the GCI within 2x 5e-4 of
    each other (each is within 0.8x of the reference on the benchmark's designs), the band measures summing to the
    count, and fewer kernel calls in all on the z-columns."""
    rng = np.random.default_rng(3)
    options = MECH.resolve_options({})
    designs = [{"g": rng.uniform(40, 120), "h": rng.uniform(20, 80), "c": rng.uniform(20, 80), "e": 0.0}
               for _ in range(8)]
    packed = np.stack([MECH.pack(d, options) for d in designs])
    tol = Tolerance()
    z = adaptive_population_stats(MECH, designs, options, packed, tol, EDGES)
    psi = adaptive_population_stats(MECH, designs, options, packed, tol, EDGES, intervals=False)
    vz, vp = z.stats[:, 0] * z.cell, psi.stats[:, 0] * psi.cell
    assert np.all(vp > 0)
    gz, gp = z.stats[:, 1] / z.stats[:, 0], psi.stats[:, 1] / psi.stats[:, 0]
    assert np.all(np.abs(vz - vp) <= 2 * tol.volume * vp)
    assert np.all(np.abs(gz - gp) <= 2 * tol.gci)
    nb = len(EDGES) - 1
    np.testing.assert_allclose(z.stats[:, -nb:].sum(axis=1), z.stats[:, 0], rtol=1e-12)
    # per design the z-columns take 0.1-1.3x the calls (the z-levels double the z-cells up to 64 where the LCI
    # varies along z), in all 0.40x here
    assert z.evaluations.sum() < 0.6 * psi.evaluations.sum()
