"""The adaptive evaluator's per-design error estimates are catalogue metrics (error_volume, error_gci): result
columns of tolerance-form configs, usable as constraints, and refused (exit 2, one line) without grid.tolerance."""

import numpy as np
import pytest

from scalesynth.config import config_from_dict
from scalesynth.errors import ConfigError
from scalesynth.evaluate import Tolerance, adaptive_population_stats, evaluate_config_population
from scalesynth.optimize import run
from scalesynth.problem import SynthesisProblem
from scalesynth.validate_results import check_results

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
    assert check_results(tmp_path / "run", require_report=False) == []  # the results schema has the columns
    assert len(res.pareto) >= 1
    assert (res.pareto["error_volume"] <= 0.002).all()  # the constraint holds on the front
    assert (res.pareto["error_gci"] >= 0).all()


def test_written_config_of_a_tolerance_form_run_stays_adaptive(tmp_path):
    """Every dump of a config that is loaded again (results/<name>/config.yaml and the manifest's config, batch
    tasks, `select`, API overrides) keeps the adaptive evaluator: the grid is dumped without its default
    resolution, which would force the uniform grid when loaded again."""
    from scalesynth.config import dump_config, load_config

    cfg = config_from_dict(FIVEBAR)
    assert cfg.grid.adaptive
    assert "resolution" not in cfg.model_dump(mode="json")["grid"]
    assert config_from_dict(cfg.model_dump(mode="json")).grid.adaptive
    path = tmp_path / "config.yaml"
    path.write_text(dump_config(cfg))
    again = load_config(path)
    assert again.grid.adaptive and again.grid.tolerance == cfg.grid.tolerance
    assert again.grid.resolution == cfg.grid.resolution == 64  # the default, still used by plots and sections
    uniform = config_from_dict({**FIVEBAR, "grid": {"resolution": 24, "tolerance": {"volume": 0.002, "gci": 5e-4}},
                                "constraints": []})
    path.write_text(dump_config(uniform))
    assert not load_config(path).grid.adaptive  # a given resolution still wins after the round trip
    assert load_config(path).grid.resolution == 24


def test_reproduce_of_a_tolerance_form_run(tmp_path):
    """`scalesynth reproduce` re-runs the manifest's config: the same adaptive evaluator, byte-identical front."""
    from typer.testing import CliRunner

    from scalesynth.cli import app

    run(config_from_dict(FIVEBAR), tmp_path / "run", plots=False)
    res = CliRunner().invoke(app, ["reproduce", str(tmp_path / "run")])
    assert res.exit_code == 0, res.output
