"""Seed 000 (2pauu-ppap): the per-voxel stiffness fields (stiffness_min slot 4, deflection slot 5) against the
pose-level frame model (PauuPpap.stiffness_model, FE-checked in test_stiffness_seeds.py) solved by the NumPy reference
solver stiffness.solve, the evaluator's statistics, and the evaluator's choice between the fast path and the
generic kernel (options.stiffness_metrics)."""

import math

import numpy as np
import pytest

from scalesynth.config import ConfigError, config_from_dict
from scalesynth.errors import InvalidParameter
from scalesynth.evaluate import evaluate, make_grid
from scalesynth.kernels import grid as kgrid
from scalesynth.mechanisms import get
from scalesynth.mechanisms import pauu_ppap as P
from scalesynth.metrics import result_columns
from scalesynth.stiffness import legs
from scalesynth.stiffness.solve import solve
from scalesynth.workspace_view import stiffness_map_fields

from conftest import SMALL

M = get("2pauu-ppap")
EDGES = np.array([0.0, 0.1, 0.3, 1.0])
KMIN, DEFL = M.field_names.index("stiffness_min"), M.field_names.index("deflection")
# designs (m, n, l1, l2, c) and options: the paper's default, Table-4-like ones in other working modes, other
# sections, actuator stiffnesses and loads (so every term of the closed form is exercised)
CASES = [
    ({}, {}),
    ({"m": 1.2, "n": 0.4, "l1": 0.9, "l2": 1.3, "c": 0.3}, {"mode": "+-", "load": [30.0, -20.0, -150.0]}),
    ({"m": 0.7, "n": 0.6, "l1": 1.3, "l2": 0.8, "c": 0.2},
     {"mode": "--", "sections": {"arm": [0.06, 0.004], "link": [0.03, 0.002]}, "actuator_stiffness": 2e4}),
    ({"m": 1.0, "n": 0.3, "l1": 1.1, "l2": 1.2, "c": 0.45},
     {"mode": "-+", "sections": {"arm_link": [0.02, 0.002]}, "stroke_stiffness": 3e5, "load": [0.0, 80.0, -10.0]}),
]


def fields_at(p, pose):
    out = np.full(M.n_fields, np.nan)
    M.field_kernel(p, *map(float, pose), out)
    assert not np.any(np.isnan(out))
    return out


def test_slots_and_layout():
    assert M.field_names[3:] == ("clearance", "stiffness_min", "deflection")
    assert (P._F_STIFFNESS_MIN, P._F_DEFLECTION, P.N_KERNEL_FIELDS) == (KMIN, DEFL, M.n_fields)
    assert M.pack(M.resolve_design({}), M.resolve_options({})).shape == (P.N_PACKED,)


@pytest.mark.parametrize(("design", "opts"), CASES)
def test_fields_equal_the_reference_solver_at_random_reachable_poses(design, opts):
    """12 random reachable poses per design in its bounding box: stiffness_min (N/m) and deflection (m) equal the
    reference solver on stiffness_model's frame to 1e-7 relative (measured <= 2e-11); unreachable poses write 0, and
    so do all poses without options.stiffness_metrics."""
    design = M.resolve_design(design)
    opt = M.resolve_options({**opts, "stiffness_metrics": True})
    p = M.pack(design, opt)
    off = M.pack(design, M.resolve_options(opts))
    lo, hi = M.bounding_box(design, opt)
    rng = np.random.default_rng(len(CASES) + int(1e3 * design["m"]))
    checked = 0
    for _ in range(2000):
        pose = lo + rng.uniform(size=3) * (hi - lo)
        out = fields_at(p, pose)
        if out[0] < 0:
            assert out[KMIN] == 0.0 and out[DEFL] == 0.0
            continue
        # without options.stiffness_metrics the stiffness slots are written as 0, the other slots unchanged
        without = fields_at(off, pose)
        assert without[KMIN] == 0.0 and without[DEFL] == 0.0 and np.array_equal(without[:KMIN], out[:KMIN])
        res = solve(M.stiffness_model(design, opt, pose))
        assert not res.singular and res.dofs == ("x", "y", "z")
        assert out[KMIN] == pytest.approx(res.stiffness_min, rel=1e-7), pose
        assert out[DEFL] == pytest.approx(res.deflection_norm, rel=1e-7), pose
        checked += 1
        if checked == 12:
            break
    assert checked == 12


def test_every_reachable_cell_of_a_grid_and_the_evaluator_statistics():
    """sample_fields over a 6^3 grid of a design with the stiffness metrics on: every reachable cell equals the
    reference solver at its centre, and evaluate's workspace statistics (now from the generic kernel) are the NumPy
    reductions of those values."""
    design = M.resolve_design(CASES[1][0])
    opt = M.resolve_options({**CASES[1][1], "stiffness_metrics": True})
    g = make_grid(M, design, opt, 6)
    vals = kgrid.sample_fields(M.field_kernel, M.n_fields, M.pack(design, opt), g.lo, g.step, g.shape)
    assert not np.any(np.isnan(vals))
    kmin, defl = [], []
    for idx in np.ndindex(6, 6, 6):
        cell = vals[idx]
        if cell[0] < 0:
            assert cell[KMIN] == 0.0 and cell[DEFL] == 0.0
            continue
        res = solve(M.stiffness_model(design, opt, g.lo + (np.array(idx) + 0.5) * g.step))
        assert cell[KMIN] == pytest.approx(res.stiffness_min, rel=1e-7)
        assert cell[DEFL] == pytest.approx(res.deflection_norm, rel=1e-7)
        kmin.append(res.stiffness_min)
        defl.append(res.deflection_norm)
    assert len(defl) >= 20
    rep = evaluate(M, design, opt, resolution=6).metrics
    assert rep["voxels"] == len(defl)
    assert rep["max_deflection_m"] == pytest.approx(max(defl), rel=1e-7)
    assert rep["mean_deflection_m"] == pytest.approx(np.mean(defl), rel=1e-7)
    assert rep["std_deflection_m"] == pytest.approx(np.std(defl), rel=1e-6)
    assert rep["min_stiffness_min_N_per_m"] == pytest.approx(min(kmin), rel=1e-7)
    assert rep["mean_stiffness_min_N_per_m"] == pytest.approx(np.mean(kmin), rel=1e-7)
    assert all(math.isfinite(v) for v in rep.values())


def test_stiffness_metrics_flag_selects_the_generic_kernel_and_the_columns():
    """Without options.stiffness_metrics the results have no stiffness columns and grid_stats is the fast path
    (its rows widened: the paper run is unchanged); with it, grid_stats equals the generic kernel over point_fields
    bitwise, and its voxel counts and LCI bands are the fast path's."""
    cols = result_columns(M, "m", 3, True, False, {})
    assert not any("deflection" in c or "stiffness_min" in c for c in cols)
    on = result_columns(M, "m", 3, True, False, {"stiffness_metrics": True})
    for c in ("max_deflection_m", "task_max_deflection_m", "min_stiffness_min_N_per_m",
              "task_min_stiffness_min_N_per_m", "mean_deflection_m"):
        assert c in on and c not in cols
    rng = np.random.default_rng(4)
    designs = [M.resolve_design(dict(m=rng.uniform(0.5, 1.5), n=rng.uniform(0.2, 1), l1=rng.uniform(0.5, 1.5),
                                     l2=rng.uniform(0.5, 1.5), c=rng.uniform(0.1, 0.5))) for _ in range(6)]
    off, flag = M.resolve_options({}), M.resolve_options({"stiffness_metrics": True})
    grids = [make_grid(M, d, off, 9) for d in designs]
    lo, step, shape = np.stack([g.lo for g in grids]), np.stack([g.step for g in grids]), grids[0].shape
    packed_off = np.stack([M.pack(d, off) for d in designs])
    packed_on = np.stack([M.pack(d, flag) for d in designs])
    fast = P.widen_rows(P.population_stats_fast(packed_off, lo, step, shape, EDGES), P.N_FIELDS, M.n_fields)
    assert np.array_equal(M.grid_stats(packed_off, lo, step, shape, EDGES), fast)
    generic = kgrid.population_stats(M.field_kernel, M.n_fields, packed_on, lo, step, shape, EDGES)
    got = M.grid_stats(packed_on, lo, step, shape, EDGES)
    assert np.array_equal(got, generic)
    assert (got[:, kgrid.COL_COUNT] > 0).sum() >= 4
    assert np.array_equal(got[:, kgrid.COL_COUNT], fast[:, kgrid.COL_COUNT])
    bands = [kgrid.band_column(M.n_fields, b) for b in range(3)]
    assert np.array_equal(got[:, bands], fast[:, bands])
    # the stiffness columns are filled: max deflection > 0 wherever a design reaches something
    reach = got[:, kgrid.COL_COUNT] > 0
    assert np.all(got[reach, kgrid.field_column(DEFL, kgrid.STAT_MAX)] > 0)


def test_a_stiffness_metric_without_the_flag_is_named_and_the_flag_is_checked():
    data = dict(SMALL, objectives=[{"metric": "volume"}, {"metric": "max_deflection", "sense": "min"}])
    with pytest.raises(ConfigError, match=r"max_deflection.*options\.stiffness_metrics \(false\)"):
        config_from_dict(data)
    cfg = config_from_dict(dict(data, options={"stiffness_metrics": True}))
    assert stiffness_map_fields(cfg) == ("deflection", "stiffness_min")
    assert stiffness_map_fields(config_from_dict(SMALL)) == ()
    with pytest.raises(InvalidParameter, match=r"options\.stiffness_metrics: expected true or false"):
        M.resolve_options({"stiffness_metrics": "yes"})


def test_near_the_forward_singularity_the_deflection_grows_with_the_reference_and_stays_finite():
    """Symmetric mode ++ at x = y = 0: the links' xz-projections are mirror images, so J_x is singular where they
    are vertical (det J_x changes sign along z; found by bisection). Approaching it the platform can move along x
    without deforming anything: the deflection under a load with an x component grows without bound, in step with
    the reference solver, while the kernel stays finite and never NaN; stiffness_min -> 0."""
    design = M.resolve_design({})
    opt = M.resolve_options({"load": [50.0, 0.0, -150.0], "stiffness_metrics": True})
    p = M.pack(design, opt)

    def det_jx(z):
        (q,) = [s.values for s in M.inverse_kinematics(design, opt, (0.0, 0.0, z)) if s.label == "++"]
        return np.linalg.det(M.jacobians(design, opt, (0.0, 0.0, z), q)["Jx"])

    lo, hi = M.bounding_box(design, opt)
    zs = [z for z in np.linspace(lo[2], hi[2], 401) if fields_at(p, (0.0, 0.0, z))[0] > 0]
    dets = np.array([det_jx(z) for z in zs])
    signs = np.sign(dets)
    # a crossing through 0 (small |det J_x| on both sides: the IK branch does not jump there)
    k = int(np.nonzero((signs[:-1] != signs[1:]) & (np.abs(dets[:-1]) < 0.5) & (np.abs(dets[1:]) < 0.5))[0][0])
    a, b = zs[k], zs[k + 1]
    for _ in range(80):
        mid = 0.5 * (a + b)
        a, b = (mid, b) if np.sign(det_jx(mid)) == signs[k] else (a, mid)
    z_s = 0.5 * (a + b)
    prev_d, prev_k = 0.0, math.inf
    for gap in (1e-2, 1e-3, 1e-4):  # deflection ~ gap^-2 (the stiffness along x ~ det(J_x)^2): 0.018, 1.8, 176 m
        pose = (0.0, 0.0, z_s - gap * np.sign(zs[k + 1] - zs[k]))  # on zs[k]'s side
        out = fields_at(p, pose)
        res = solve(M.stiffness_model(design, opt, pose))
        assert out[DEFL] > 50 * prev_d and out[KMIN] < 0.02 * prev_k
        assert out[DEFL] == pytest.approx(res.deflection_norm, rel=1e-6)
        assert out[KMIN] == pytest.approx(res.stiffness_min, rel=1e-6)
        prev_d, prev_k = out[DEFL], out[KMIN]
    assert 100.0 < prev_d < legs.DEFLECTION_CAP
    # 1e-6 away the eigenvalue ratio is below SINGULAR_RTOL: singular for the kernel (0, the cap) and the solver
    out = fields_at(p, (0.0, 0.0, z_s - 1e-6 * np.sign(zs[k + 1] - zs[k])))
    assert solve(M.stiffness_model(design, opt, (0.0, 0.0, z_s - 1e-6 * np.sign(zs[k + 1] - zs[k])))).singular
    assert (out[KMIN], out[DEFL]) == (0.0, legs.DEFLECTION_CAP) and out[0] > 0.0


def test_translational_response_singular_and_zero_load_never_nan():
    """legs.response_translational on exact cases: a diagonal K; a rank-2 K (singular: 0 and the cap, 0 under a zero
    load); a NaN entry gives the singular answer, not NaN."""
    kmin, d = legs.response_translational(2.0, 0.0, 0.0, 5.0, 0.0, 4.0, 4.0, 0.0, -2.0)
    assert kmin == pytest.approx(2.0) and d == pytest.approx(math.hypot(4.0 / 2.0, -2.0 / 4.0))
    u, v = np.array([1.0, 2.0, 0.5]), np.array([0.0, 1.0, -1.0])
    K = 3e6 * np.outer(u, u) + 1e5 * np.outer(v, v)
    assert legs.response_translational(*K[np.triu_indices(3)], 0.0, 0.0, -150.0) == (0.0, legs.DEFLECTION_CAP)
    assert legs.response_translational(*K[np.triu_indices(3)], 0.0, 0.0, 0.0) == (0.0, 0.0)
    assert legs.response_translational(math.nan, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0) == (0.0,
                                                                                              legs.DEFLECTION_CAP)


def test_a_synthesis_with_a_deflection_constraint_runs_and_its_task_statistic_is_the_cells_maximum(tmp_path):
    """A small NSGA-II run of seed 000 maximising volume and task_min_stiffness_min under task_max_deflection
    <= 0.5 m (the default slender tubes): the results carry the stiffness columns, every feasible design meets the
    constraint, and the config design's task_max_deflection is the largest deflection of the reference solver over
    the task grid's reachable cells (the uniform task grid)."""
    from scalesynth.evaluate import evaluate_config, task_grid
    from scalesynth.optimize import run

    task = {"box": {"x": [-0.4, 0.4], "y": [-0.3, 0.3], "z": [1.2, 2.0]}, "resolution": 3}
    data = dict(SMALL, options={"stiffness_metrics": True}, task=task, grid={"resolution": 8},
                algorithm={"pop_size": 8, "n_gen": 2, "seed": 3},
                objectives=[{"metric": "volume"}, {"metric": "task_min_stiffness_min", "sense": "max"}],
                constraints=[{"metric": "task_max_deflection", "max": 0.5}])
    cfg = config_from_dict(data)
    result = run(cfg, tmp_path / "out", plots=False)
    pop = result.population
    assert {"task_max_deflection_m", "task_min_stiffness_min_N_per_m", "max_deflection_m"} <= set(pop.columns)
    # null (NaN) only where nothing of the task box is reachable (a statistic over an empty set, issue 27)
    assert np.all(np.isfinite(pop["task_max_deflection_m"]) | (pop["task_coverage"] == 0))
    assert (pop["task_max_deflection_m"] > 0.5).any()  # the constraint binds (seed 3: up to 0.69 m)
    feasible = result.pareto
    assert len(feasible) and (feasible["task_max_deflection_m"] <= 0.5).all()
    rep = evaluate_config(cfg).metrics
    design, opt = cfg.resolved_design(), cfg.resolved_options()
    tg = task_grid(M, cfg.task, 8)
    defl = []
    for idx in np.ndindex(3, 3, 3):
        pose = tg.lo + (np.array(idx) + 0.5) * tg.step
        if fields_at(M.pack(design, opt), pose)[0] >= 0:
            defl.append(solve(M.stiffness_model(design, opt, pose)).deflection_norm)
    assert len(defl) >= 10
    assert rep["task_max_deflection_m"] == pytest.approx(max(defl), rel=1e-7)
