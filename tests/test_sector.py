"""The sector evaluator (mechanisms/describe/sector.py, evaluation/sector.py) on the Delta: against the NumPy twin
(tests/naive_delta.py, a uniform cell-centred grid of its textbook kinematics), against the uniform N = 192 grid
of the kernel template at the paper tolerance, and its symmetry test (describe/symmetry.fundamental_sectors); on
the linear Delta: thin workspaces (slivers) against the closed-form volume, and the twin node for node."""

import math

import numpy as np
import pytest

from naive_delta import delta_fields, linear_delta_fields, linear_delta_volume
from naive_sector import sector_volume_gci
from scalesynth.config import load_config
from scalesynth.evaluate import Tolerance, config_tolerance, evaluate_population
from scalesynth.evaluation.grid import design_boxes, make_grid
from scalesynth.evaluation.sector import sector_plan, sector_population_stats
from scalesynth.kernels.grid import N_STATS
from scalesynth.mechanisms import get
from scalesynth.mechanisms.describe.symmetry import fundamental_sectors

from conftest import ROOT

PAPER = Tolerance(0.002, 0.0005)


def _cfg():
    return load_config(ROOT / "configs" / "delta.yaml", [])


def test_the_delta_has_the_60_degree_sector_and_an_offset_leg_has_none():
    mech = get("delta")
    cfg = _cfg()
    p = mech.pack(cfg.resolved_design(), cfg.resolved_options())
    assert fundamental_sectors(p)[0] == math.pi / 3  # 3-fold rotation and the y mirror (leg 1 along +x)
    q = p.copy()
    q[2 + 1] += 0.01  # leg 1's base moved along x: the rotation no longer maps the legs onto each other
    assert np.isnan(fundamental_sectors(q)[0])
    assert sector_plan(mech, PAPER)[1].z_points == 32
    assert sector_plan(mech, Tolerance(0.001, 0.0005)) is None


def test_the_sector_evaluator_agrees_with_the_numpy_twin_grid():
    """The default design (theta in [0, 90 deg], z in [-2.5, -0.3]): the sector evaluator against the NumPy twin's
    mean over a uniform N = 40 grid (64 000 cells, np.linalg.svd per reachable cell). The twin grid's own error
    there against N = 192 of the kernel template (measured once, h31-polar): volume +0.47 %, GCI -1.3e-3; with the
    sector plan's tolerance (0.2 %, 5e-4) the bounds are 1 % and 2e-3."""
    cfg = _cfg()
    mech, options, region = cfg.mech, cfg.resolved_options(), cfg.grid.region
    design = cfg.resolved_design()
    got = evaluate_population(mech, [design], options, region=region, tolerance=PAPER, fields=["lci"])
    g = make_grid(mech, design, options, 40, region)
    axes = [g.lo[a] + (np.arange(g.shape[a]) + 0.5) * g.step[a] for a in range(3)]
    x, y, z = np.meshgrid(*axes, indexing="ij")
    f = delta_fields(design, options, x, y, z)
    lci = f[..., 0]
    reach = lci >= 0.0
    volume = reach.sum() * g.cell_measure
    gci = lci[reach].mean()
    assert abs(got["volume_m3"][0] / volume - 1.0) <= 0.01, (got["volume_m3"][0], volume)
    assert abs(got["gci"][0] - gci) <= 2e-3, (got["gci"][0], gci)


def test_a_design_that_reaches_nothing_is_volume_0_and_gci_0_through_the_sector_plan():
    """Arms of 0.1 m and forearms of 0.05 m: no platform point lies more than 0.15 m below the base plane, and the
    region starts 0.3 m below it (configs/delta.yaml), so nothing is reachable."""
    cfg = _cfg()
    mech, options, region = cfg.mech, cfg.resolved_options(), cfg.grid.region
    design = dict(cfg.resolved_design(), upper_arm=0.1, forearm=0.05)
    got = evaluate_population(mech, [design], options, region=region, tolerance=PAPER)
    assert got["volume_m3"][0] == 0.0 and got["gci"][0] == 0.0
    assert np.isnan(got["min_lci"][0])  # a statistic over nothing is null


def test_the_sector_evaluator_equals_its_numpy_twin_node_for_node():
    """The same algorithm in plain Python (tests/naive_sector.py: the same nodes, scan, bisection and rules, the
    fields by np.linalg.svd of the textbook Jacobian) on the default design and two random designs in the config's
    bounds: volume and GCI equal to 1e-9 relative (the two compute the LCI at the same points by different
    arithmetic: ~1e-15 apart)."""
    cfg = _cfg()
    mech, options, region = cfg.mech, cfg.resolved_options(), cfg.grid.region
    rng = np.random.default_rng(5)
    designs = [cfg.resolved_design()] + [
        dict(cfg.resolved_design(), **{k: rng.uniform(*cfg.bounds[k]) for k in cfg.bounds}) for _ in range(2)]
    plan = sector_plan(mech, PAPER)[1]
    got = evaluate_population(mech, designs, options, region=region, tolerance=PAPER, fields=["lci"])
    lo, hi = design_boxes(mech, designs, options, region)
    for i, design in enumerate(designs):
        p = mech.pack(design, options)
        angle = float(fundamental_sectors(p)[0])
        rmax = math.hypot(max(abs(lo[i, 0]), abs(hi[i, 0])), max(abs(lo[i, 1]), abs(hi[i, 1])))
        volume, gci = sector_volume_gci(design, options, p, angle, rmax, lo[i, 2], hi[i, 2], plan)
        assert volume > 0.0
        assert got["volume_m3"][i] == pytest.approx(volume, rel=1e-9), (i, design)
        assert got["gci"][i] == pytest.approx(gci, rel=1e-9), (i, design)


def test_a_load_the_rotation_does_not_keep_gives_no_sector():
    """With the per-voxel stiffness fields on, the deflection under a load with a horizontal component is not
    3-fold symmetric: no sector (the evaluator falls back to the column plan); a vertical load keeps it."""
    mech, cfg = get("delta"), _cfg()
    design = cfg.resolved_design()
    down = mech.pack(design, {**cfg.resolved_options(), "stiffness_metrics": True})
    across = mech.pack(design, {**cfg.resolved_options(), "stiffness_metrics": True, "load": [40.0, 0.0, -150.0]})
    assert fundamental_sectors(down)[0] == math.pi / 3
    assert np.isnan(fundamental_sectors(across)[0])


def test_the_stiffness_flag_changes_no_conditioning_statistic_of_the_sector_evaluator():
    """Without options.stiffness_metrics the sector kernel runs point_lci at its nodes, with it point_fields
    (describe/sector.py; the default vertical load keeps the sector): the count, the bands and the statistics of
    LCI, sigma_min and sigma_max are the same bits either way (point_lci's slots 0-2 are point_fields', kernel.py),
    the stiffness fields' statistics 0 without the flag and positive with it."""
    cfg = _cfg()
    mech, region, design = cfg.mech, cfg.grid.region, cfg.resolved_design()
    edges = np.array(cfg.dexterity.band_edges)
    rows = {}
    for flag in (False, True):
        options = {**cfg.resolved_options(), "stiffness_metrics": flag}
        packed = mech.pack(design, options)[None, :]
        rows[flag] = sector_population_stats(mech, [design], options, packed, edges, region,
                                             sector_plan(mech, PAPER)[1]).stats[0]
    stiff = slice(1 + N_STATS * 3, 1 + N_STATS * mech.n_fields)  # stiffness_min, deflection
    same = np.r_[0:stiff.start, stiff.stop:rows[True].shape[0]]
    assert rows[True][0] > 0.0
    np.testing.assert_array_equal(rows[False][same], rows[True][same])
    assert np.all(rows[False][stiff] == 0.0)
    assert rows[True][stiff][0] > 0.0 and rows[True][stiff][N_STATS] > 0.0  # the sums of both fields


def _linear():
    return load_config(ROOT / "configs" / "linear_delta.yaml", [])


def _sliver(cfg, a, eps):
    """A linear-Delta sliver: base_radius - platform_radius = a, forearm a (1 + eps); its workspace is nonempty
    iff forearm >= a, and just above that a thin prism about the axis (about 4 a eps across) the stroke tall."""
    d = cfg.resolved_design()
    return dict(d, base_radius=a + d["platform_radius"], forearm=a * (1.0 + eps))


def test_linear_delta_slivers_meet_the_config_tolerance_against_the_closed_form_volume():
    """The linear Delta's sector plan at configs/linear_delta.yaml's tolerance (1 %, 0.002) on its default design and
    three slivers (forearm 1e-4, 1e-3 and 1e-2 above base_radius - platform_radius: workspaces about 0.1, 1.5 and
    9 mm across, 0.8 m tall) against the closed-form volume (naive_delta.linear_delta_volume: a double integral,
    n = 1000 on the sliver's own box; within 3e-4 of n = 2000). Measured (the NumPy twin of the same rule): within
    0.014 % of it. With 12 bisections of the 0.026 m scan step alone (the rule before R was bisected to a relative
    precision where only r = 0 reaches) the 1e-4 sliver came out 6.7 % short."""
    cfg = _linear()
    mech, options, region, tol = cfg.mech, cfg.resolved_options(), cfg.grid.region, config_tolerance(cfg)
    assert sector_plan(mech, tol) is not None
    designs = [cfg.resolved_design()] + [_sliver(cfg, a, eps) for a, eps in ((0.4, 1e-4), (0.5, 1e-3), (0.3, 1e-2))]
    got = evaluate_population(mech, designs, options, region=region, tolerance=tol, fields=["lci"])
    exact = np.array([linear_delta_volume(d, options, region["z"], n=1000) for d in designs])
    assert np.all(exact > 0.0)
    rel = np.abs(got["volume_m3"] / exact - 1.0)
    assert np.all(rel <= tol.volume), rel


def test_the_linear_delta_sector_evaluator_equals_its_numpy_twin_node_for_node():
    """tests/naive_sector.py with the linear Delta's textbook fields (naive_delta.linear_delta_fields) on a random
    design in the config's bounds and a sliver only r = 0 of whose scan steps reaches (forearm 1e-3 above
    base_radius - platform_radius: the boundary radius bisected past the plan's 12 steps): volume and GCI equal to
    1e-9 relative."""
    cfg = _linear()
    mech, options, region, tol = cfg.mech, cfg.resolved_options(), cfg.grid.region, config_tolerance(cfg)
    rng = np.random.default_rng(7)
    designs = [dict(cfg.resolved_design(), **{k: rng.uniform(*cfg.bounds[k]) for k in cfg.bounds}),
               _sliver(cfg, 0.45, 1e-3)]
    plan = sector_plan(mech, tol)[1]
    got = evaluate_population(mech, designs, options, region=region, tolerance=tol, fields=["lci"])
    lo, hi = design_boxes(mech, designs, options, region)
    for i, design in enumerate(designs):
        p = mech.pack(design, options)
        rmax = math.hypot(max(abs(lo[i, 0]), abs(hi[i, 0])), max(abs(lo[i, 1]), abs(hi[i, 1])))
        volume, gci = sector_volume_gci(design, options, p, float(fundamental_sectors(p)[0]), rmax, lo[i, 2],
                                        hi[i, 2], plan, fields=linear_delta_fields)
        assert volume > 0.0
        assert got["volume_m3"][i] == pytest.approx(volume, rel=1e-9), (i, design)
        assert got["gci"][i] == pytest.approx(gci, rel=1e-9), (i, design)
