"""The adaptive evaluator's per-design error estimates are catalogue metrics (error_volume, error_gci): result
columns of tolerance-form configs, usable as constraints, and refused (exit 2, one line) without grid.tolerance."""

import numpy as np
import pytest

from scalesynth.config import config_from_dict
from scalesynth.errors import ConfigError
from scalesynth.evaluate import Tolerance, adaptive_population_stats, evaluate_config_population
from scalesynth.optimize import run
from scalesynth.problem import SynthesisProblem

FIVEBAR = {
    "name": "estimates",
    "mechanism": "planar-fivebar",
    "units": {"length": "mm"},
    "design": {"r": 200, "l1": 475, "l2": 875},
    "bounds": {"r": [100, 300], "l1": [300, 700], "l2": [600, 1200]},
    "grid": {"tolerance": {"volume": 0.002, "gci": 5.0e-4}},
    "objectives": [{"metric": "volume", "sense": "max"}, {"metric": "gci", "sense": "max"}],
    "constraints": [{"metric": "error_volume", "max": 0.002}],
    "algorithm": {"name": "nsga2", "pop_size": 8, "n_gen": 2, "seed": 3},
}


def test_estimates_are_the_adaptive_evaluators():
    cfg = config_from_dict(FIVEBAR)
    rng = np.random.default_rng(0)
    designs = [{"r": float(rng.uniform(100, 300)), "l1": float(rng.uniform(300, 700)),
                "l2": float(rng.uniform(600, 1200))} for _ in range(6)]
    out = evaluate_config_population(cfg, designs)
    mech, opts = cfg.mech, cfg.resolved_options()
    packed = np.stack([mech.pack(mech.resolve_design(d), opts) for d in designs])
    ad = adaptive_population_stats(mech, [mech.resolve_design(d) for d in designs], opts, packed,
                                   Tolerance(0.002, 5.0e-4), np.asarray(cfg.dexterity.band_edges))
    assert np.array_equal(out["error_volume"], ad.error_volume)
    assert np.array_equal(out["error_gci"], ad.error_gci)
    assert {"error_volume", "error_gci"} <= set(SynthesisProblem(cfg).metric_columns)  # pareto.csv columns


def test_uniform_configs_have_no_estimate_columns():
    cfg = config_from_dict({**FIVEBAR, "grid": {"resolution": 24}, "constraints": []})
    assert "error_volume" not in SynthesisProblem(cfg).metric_columns
    assert "error_volume" not in evaluate_config_population(cfg, [FIVEBAR["design"]])


def test_estimate_constraint_needs_the_tolerance_form():
    with pytest.raises(ConfigError, match=r"constraints\[0\]\.metric: error_volume needs grid.tolerance"):
        config_from_dict({**FIVEBAR, "grid": {"resolution": 24}})


def test_run_reports_and_constrains_the_estimates(tmp_path):
    res = run(config_from_dict(FIVEBAR), tmp_path / "run", plots=False)
    assert len(res.pareto) >= 1
    assert (res.pareto["error_volume"] <= 0.002).all()  # the constraint holds on the front
    assert (res.pareto["error_gci"] >= 0).all()
