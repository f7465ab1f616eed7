"""The search evaluates only the catalogue families its objectives and constraints use; the final population's
other columns are filled in afterwards and equal a full evaluation of the same designs."""

import numpy as np
import pandas as pd

from scalesynth import metrics as _metrics
from scalesynth.config import config_from_dict
from scalesynth.evaluate import evaluate_config_population
from scalesynth.optimize import run
from scalesynth.problem import SynthesisProblem

FIVEBAR = {  # a task-only five-bar study: no objective or constraint reads the workspace grid
    "name": "families",
    "mechanism": "planar-fivebar",
    "units": {"length": "mm"},
    "design": {"r": 200, "l1": 475, "l2": 875},
    "bounds": {"r": [100, 300], "l1": [300, 700], "l2": [600, 1200]},
    "grid": {"resolution": 24},
    "task": {"box": {"x": [-300, 300], "y": [-850, -650]}, "resolution": 12,
             "path": [[-200, -800], [200, -800]], "path_samples": 20},
    "objectives": [{"metric": "task_gci", "sense": "max"}, {"metric": "link_length_sum", "sense": "min"}],
    "constraints": [{"metric": "task_coverage", "min": 0.5}],
    "algorithm": {"name": "nsga2", "pop_size": 12, "n_gen": 3, "seed": 4},
}


def designs(n=9, seed=0):
    rng = np.random.default_rng(seed)
    return [{"r": float(rng.uniform(100, 300)), "l1": float(rng.uniform(300, 700)),
             "l2": float(rng.uniform(600, 1200))} for _ in range(n)]


def test_families_give_exactly_their_columns_with_the_full_values():
    cfg = config_from_dict(FIVEBAR)
    full = evaluate_config_population(cfg, designs())
    part = evaluate_config_population(cfg, designs(), frozenset({"task", "design"}))
    entries = _metrics.catalogue(cfg.mech, "mm").values()
    family = {c: m.family for m in entries for c in m.columns(3)}
    assert set(part) == {k for k in full if family[k] in ("task", "design")}
    assert {"task_gci", "task_coverage", "link_length_sum_mm"} <= set(part)
    for k, v in part.items():
        assert np.array_equal(v, full[k]), k


def test_families_skip_the_workspace_grid(monkeypatch):
    """No workspace grid is evaluated: make_grid (the per-design workspace box) is never called."""
    import scalesynth.evaluate as ev

    cfg = config_from_dict(FIVEBAR)

    def boom(*a, **k):
        raise AssertionError("workspace grid built")

    monkeypatch.setattr(ev, "make_grid", boom)
    out = evaluate_config_population(cfg, designs(), frozenset({"task"}))
    assert "task_gci" in out and "area_mm2" not in out


def test_problem_searches_its_families_and_completes_the_rest():
    cfg = config_from_dict(FIVEBAR)
    problem = SynthesisProblem(cfg)
    assert problem.searched_families == {"task", "design"}
    X = np.array([[d["r"], d["l1"], d["l2"]] for d in designs()])
    M = problem.metrics(X)
    missing = problem.unsearched_columns()
    assert "area_mm2" in missing and "gci" in missing and "path_min_lci" in missing
    cols = [problem.metric_columns.index(k) for k in missing]
    assert np.isnan(M[:, cols]).all()
    assert not np.isnan(np.delete(M, cols, axis=1)).any()
    done = problem.complete_metrics(X, M)
    full = evaluate_config_population(cfg, problem.designs(X))
    expected = np.column_stack([full[k] for k in problem.metric_columns])
    assert np.array_equal(done, expected)


def test_run_results_equal_a_full_evaluation_of_the_front(tmp_path):
    cfg = config_from_dict(FIVEBAR)
    res = run(cfg, tmp_path / "run", plots=False)
    pareto = res.pareto  # full-precision designs (pareto.csv rounds to 12 digits)
    assert len(pareto) >= 1 and not pareto.isna().any().any()
    assert not pd.read_csv(tmp_path / "run" / "pareto.csv").isna().any().any()
    full = evaluate_config_population(cfg, [{"r": r, "l1": a, "l2": b} for r, a, b in
                                            pareto[["r", "l1", "l2"]].to_numpy()])
    for k in ("area_mm2", "gci", "path_min_lci", "task_gci"):
        assert np.array_equal(pareto[k].to_numpy(), full[k]), k
    assert res.manifest["evaluations"] == 36


def test_unknown_family_or_field_names_are_one_line_errors():
    """A misspelt family or field would select no metric at all; evaluate_population names it instead."""
    import pytest

    from scalesynth.errors import InvalidParameter
    from scalesynth.evaluate import evaluate_population

    cfg = config_from_dict(FIVEBAR)
    with pytest.raises(InvalidParameter,
                       match=r"^families: unknown name 'tasks' \(did you mean 'task'\?; known: workspace, task, "):
        evaluate_population(cfg.mech, designs(2), families={"tasks"})
    with pytest.raises(InvalidParameter,
                       match=r"^fields: unknown name 'LCI' \(did you mean 'lci'\?; known: lci, sigma_min, "):
        evaluate_population(cfg.mech, designs(2), fields={"LCI"})
