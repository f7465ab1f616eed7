"""Seed 000 (2pauu-ppap): the per-voxel clearance field (slot 3) against the NumPy link geometry and brute-force
sampling of the capsules, interference_free, and the evaluator's choice between the fast path (no clearance
statistics) and the generic kernel (link_radius set)."""

import numpy as np
import pytest

from scalesynth.cycle.clearance import clearance
from scalesynth.evaluate import evaluate, evaluate_population, make_grid
from scalesynth.kernels import grid as kgrid
from scalesynth.mechanisms import get
from scalesynth.metrics import result_columns

from conftest import TABLE4

M = get("2pauu-ppap")
SLOT = M.field_names.index("clearance")
EDGES = np.array([0.0, 0.1, 0.3, 1.0])


def _fields(design, options, resolution):
    g = make_grid(M, design, options, resolution)
    return g, kgrid.sample_fields(M.field_kernel, M.n_fields, M.pack(design, options), g.lo, g.step, g.shape)


def _geometry(design, options, g, node):
    pose = tuple(g.axis(a)[n] for a, n in enumerate(node))
    q = next(s.values for s in M.inverse_kinematics(design, options, pose) if s.label == options["mode"])
    return M.link_geometry(design, options, pose, q)


@pytest.mark.parametrize("options", [{}, {"link_radius": 0.3}, {"mode": "+-", "link_radius": {"platform": 0.2}},
                                     {"mode": "--", "e": 0.1}])
def test_clearance_field_matches_numpy_link_geometry(options):
    """At every reachable node of a 9^3 grid: the kernel's clearance equals cycle.clearance (NumPy, the cycle's
    code path) of link_geometry at the node's IK solution in the configured mode; interference_free keeps exactly
    the reachable nodes with clearance >= 0."""
    design = M.resolve_design(TABLE4[1])
    opts = M.resolve_options(options)
    g, fields = _fields(design, opts, 9)
    reach = fields[..., 0] >= 0
    assert reach.sum() > 50
    for node in zip(*np.nonzero(reach), strict=True):
        expected = clearance(_geometry(design, opts, g, node)).value
        assert fields[(*node, SLOT)] == pytest.approx(expected, abs=1e-12)
    assert (fields[~reach][:, SLOT] == 0.0).all()
    free = M.resolve_options({**options, "interference_free": True})
    _, only = _fields(design, free, 9)
    assert np.array_equal(only[..., 0] >= 0, reach & (fields[..., SLOT] >= 0))
    assert (reach & (fields[..., SLOT] < 0)).any() and (reach & (fields[..., SLOT] > 0)).any()  # both kinds occur


def test_clearance_field_against_points_sampled_on_the_capsules():
    """Brute force, independent of the segment-distance formula: 400 points along each capsule's axis; the
    smallest point-set distance of each non-adjacent pair minus the two radii exceeds the exact clearance by at
    most half the point spacing (longest segment / 399 covers both segments' halves)."""
    design = M.resolve_design(TABLE4[4])
    opts = M.resolve_options({"link_radius": 0.1})
    g, fields = _fields(design, opts, 7)
    nodes = list(zip(*np.nonzero(fields[..., 0] >= 0), strict=True))
    assert len(nodes) > 10
    for node in nodes[:: max(1, len(nodes) // 12)]:
        geo = _geometry(design, opts, g, node)
        clouds = [a + np.linspace(0.0, 1.0, 400)[:, None] * (b - a) for a, b in
                  ((s.a, s.b) for s in geo.segments)]
        brute = min(np.min(np.linalg.norm(clouds[i][:, None, :] - clouds[j][None, :, :], axis=2))
                    - geo.segments[i].radius - geo.segments[j].radius for i, j in geo.checked_pairs())
        longest = max(np.linalg.norm(s.b - s.a) for s in geo.segments)
        value = fields[(*node, SLOT)]
        assert value <= brute + 1e-9
        assert brute - value <= longest / 399 + 1e-9
    # the 9 checked pairs: base-link_i, base-platform, arm1-arm2, arm_i-link_j (i != j), arm_i-platform, link1-link2
    assert len(geo.checked_pairs()) == 9


def test_clearance_metrics_need_link_radius_and_use_the_generic_kernel():
    """Without link_radius the results have no clearance columns and grid_stats is the fast path (the clearance
    columns of its rows are empty); with it, grid_stats is the generic kernel over point_fields, and the catalogue
    statistics equal those of the sampled field."""
    assert not any("clearance_m" in c and "cycle" not in c for c in result_columns(M, "m", 3, False, False, {}))
    cols = result_columns(M, "m", 3, True, False, {"link_radius": 0.02})
    for c in ("mean_clearance_m", "std_clearance_m", "min_clearance_m", "max_clearance_m", "task_min_clearance_m"):
        assert c in cols
    designs = [M.resolve_design(TABLE4[k]) for k in (1, 3)]
    for options, generic in (({}, False), ({"link_radius": 0.02}, True), ({"interference_free": True}, True)):
        opts = M.resolve_options(options)
        packed = np.stack([M.pack(d, opts) for d in designs])
        grids = [make_grid(M, d, opts, 20) for d in designs]
        lo, step = np.stack([g.lo for g in grids]), np.stack([g.step for g in grids])
        rows = M.grid_stats(packed, lo, step, grids[0].shape, EDGES)
        ref = kgrid.population_stats(M.field_kernel, M.n_fields, packed, lo, step, grids[0].shape, EDGES)
        c_min = kgrid.field_column(SLOT, kgrid.STAT_MIN)
        if generic:
            assert np.array_equal(rows, ref)
        else:
            assert (rows[:, c_min] == np.inf).all() and (ref[:, c_min] < np.inf).all()
    opts = M.resolve_options({"link_radius": 0.02})
    rep = evaluate(M, designs[0], opts, resolution=16)
    g, fields = _fields(designs[0], opts, 16)
    vals = fields[..., SLOT][fields[..., 0] >= 0]
    assert rep.metrics["min_clearance_m"] == vals.min() and rep.metrics["max_clearance_m"] == vals.max()
    assert rep.metrics["mean_clearance_m"] == pytest.approx(vals.mean(), rel=1e-12)
    assert rep.metrics["std_clearance_m"] == pytest.approx(vals.std(), rel=1e-9)
    # interference_free shrinks the workspace to the clearance >= 0 voxels
    free = evaluate_population(M, [designs[0]], {"link_radius": 0.02, "interference_free": True}, resolution=16)
    assert free["voxels"][0] == int((vals >= 0).sum()) < vals.size
    assert free["min_clearance_m"][0] >= 0.0
