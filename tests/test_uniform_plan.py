"""The tolerance form on a calibrated uniform grid (Mechanism.uniform_plan: 2pauu-ppap, whose uniform fast path is
far cheaper than the adaptive evaluator at equal accuracy): which grid a tolerance picks, that the values are that
grid's, the error estimates the change to the grid twice as fine, and that a tolerance tighter than every calibrated
step goes to the adaptive evaluator."""

import numpy as np

from scalesynth.config import config_from_dict, load_config
from scalesynth.evaluate import (
    Tolerance,
    UniformPlan,
    adaptive_population_stats,
    evaluate,
    evaluate_config_population,
    evaluate_population,
    evaluator_description,
    uniform_resolution,
)
from scalesynth.mechanisms import get
from scalesynth.problem import SynthesisProblem
from test_registry import config_for

EDGES = (0.0, 0.1, 0.3, 1.0)


def test_a_tolerance_picks_the_coarsest_step_at_least_as_tight():
    plan = UniformPlan(((0.002, 5e-4, 72), (0.01, 2.5e-3, 32), (0.03, 5e-3, 24)))
    assert plan.resolution_for(Tolerance(0.03, 5e-3)) == 24
    assert plan.resolution_for(Tolerance(0.05, 0.01)) == 24  # looser than every step: the coarsest
    assert plan.resolution_for(Tolerance(0.02, 5e-3)) == 32  # the 3 % step is too loose in volume
    assert plan.resolution_for(Tolerance(0.03, 1e-3)) == 72  # ... and the 1 % step in GCI
    assert plan.resolution_for(Tolerance(0.002, 5e-4)) == 72
    assert plan.resolution_for(Tolerance(0.001, 5e-4)) is None  # tighter than every step: adaptive
    mech = get("2pauu-ppap")
    assert uniform_resolution(mech, Tolerance()) == 72  # the default tolerance (0.2 %, 5e-4)
    # the calibrated steps (the comment on 2pauu-ppap's uniform_plan: benchmarks/uniform_ladder.py on two design sets)
    assert uniform_resolution(mech, Tolerance(0.001, 2.5e-4)) == 112
    assert uniform_resolution(mech, Tolerance(0.001, 5e-4)) == 112  # the 0.2 % step is too loose in volume
    assert uniform_resolution(mech, Tolerance(0.0005, 1e-4)) == 144
    assert uniform_resolution(mech, Tolerance(0.0002, 5e-4)) is None  # tighter than every step: adaptive
    assert uniform_resolution(get("rps-upu"), Tolerance(0.03, 5e-3)) is None  # no calibrated plan


def _designs(n=5, seed=1):
    cfg = load_config(config_for("2pauu-ppap"))
    rng = np.random.default_rng(seed)
    return cfg, [{**cfg.resolved_design(), **{k: float(rng.uniform(lo, hi)) for k, (lo, hi) in cfg.bounds.items()}}
                 for _ in range(n)]


def test_values_are_the_calibrated_grids_and_estimates_the_change_to_twice_as_fine():
    """2pauu-ppap at (3 %, 5e-3): every metric equals (as bytes) the uniform 24-cell evaluation, and error_volume /
    error_gci equal |V24 - V48| / V24 and |G24 - G48| from two independent uniform evaluations."""
    cfg, designs = _designs()
    mech, options = cfg.mech, cfg.resolved_options()
    tol = Tolerance(0.03, 5e-3)
    out = evaluate_population(mech, designs, options, band_edges=EDGES, tolerance=tol)
    coarse = evaluate_population(mech, designs, options, resolution=24, band_edges=EDGES)
    fine = evaluate_population(mech, designs, options, resolution=48, band_edges=EDGES)
    assert set(out) == set(coarse) | {"error_volume", "error_gci"}
    for k, v in coarse.items():
        assert v.tobytes() == out[k].tobytes(), k
    v24, v48 = coarse["volume_m3"], fine["volume_m3"]
    assert (v24 > 0).all()
    np.testing.assert_array_equal(out["error_volume"], np.abs(v24 - v48) / v24)
    np.testing.assert_array_equal(out["error_gci"], np.abs(coarse["gci"] - fine["gci"]))
    assert (out["error_volume"] > 0).all() and (out["error_gci"] > 0).all()  # the grids differ: compared
    one = evaluate(mech, designs[0], options, band_edges=EDGES, tolerance=tol)
    assert one.metrics["volume_m3"] == v24[0] and one.metrics["error_gci"] == out["error_gci"][0]
    assert one.grid_cells == 24**3 + 48**3


def test_a_tighter_tolerance_than_every_step_runs_the_adaptive_evaluator():
    cfg, designs = _designs(3)
    mech, options = cfg.mech, cfg.resolved_options()
    tol = Tolerance(0.0002, 5e-4)  # tighter in volume than the tightest calibrated step (0.05 %)
    out = evaluate_population(mech, designs, options, band_edges=EDGES, tolerance=tol)
    packed = np.stack([mech.pack(mech.resolve_design(d), options) for d in designs])
    ad = adaptive_population_stats(mech, [mech.resolve_design(d) for d in designs], options, packed, tol,
                                   np.asarray(EDGES))
    assert out["volume_m3"].tobytes() == (ad.stats[:, 0] * ad.cell).tobytes()
    assert out["error_volume"].tobytes() == ad.error_volume.tobytes()


def test_the_search_leaves_the_estimates_to_the_final_population():
    """The estimates cost a second grid: a search of volume and GCI does not compute them (NaN columns, completed
    afterwards, equal to a full evaluation); a constraint on one makes the search compute them."""
    data = load_config(config_for("2pauu-ppap")).model_dump(mode="json", exclude_none=True)
    data["grid"] = {"tolerance": {"volume": 0.03, "gci": 0.005}}
    cfg = config_from_dict(data)
    assert evaluator_description(cfg) == "tolerance volume 0.03, GCI 0.005: calibrated uniform grid, 24 cells per axis"
    problem = SynthesisProblem(cfg)
    assert problem.searched_fields == {"lci"}
    assert {"error_volume", "error_gci"} <= set(problem.unsearched_columns())
    _, designs = _designs(4)
    X = np.array([[d[k] for k in problem.var_names] for d in designs])
    M = problem.metrics(X)
    assert np.isnan(M[:, problem.metric_columns.index("error_volume")]).all()
    done = problem.complete_metrics(X, M)
    full = evaluate_config_population(cfg, problem.designs(X))
    assert done.tobytes() == np.column_stack([full[k] for k in problem.metric_columns]).tobytes()
    data["constraints"] = [{"metric": "error_volume", "max": 0.05}]
    constrained = SynthesisProblem(config_from_dict(data))
    assert constrained.searched_fields == {"lci", "estimate"}
    assert not np.isnan(constrained.metrics(X)[:, constrained.metric_columns.index("error_volume")]).any()


def test_quick_config_uses_the_tolerance_form():
    cfg = load_config(config_for("2pauu-ppap").parent / "quick.yaml")
    assert cfg.grid.adaptive
    assert evaluator_description(cfg).endswith("calibrated uniform grid, 24 cells per axis")
