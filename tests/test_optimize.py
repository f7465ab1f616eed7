"""NSGA-II synthesis end to end on small configs: outputs, invariants, determinism, resume."""

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pandas as pd
import pytest
import yaml

from scalesynth.config import config_from_dict, load_config
from scalesynth.errors import RunError
from scalesynth.optimize import run
from scalesynth.rundir import staging_path

from conftest import SMALL


def small_cfg(**changes):
    data = json.loads(json.dumps(SMALL))
    for key, value in changes.items():
        data[key] = value
    return config_from_dict(data)


def nondominated(F):
    """True where no other row is <= everywhere and < somewhere (minimisation), by brute force."""
    n = len(F)
    keep = np.ones(n, dtype=bool)
    for i in range(n):
        dom = np.all(F <= F[i], axis=1) & np.any(F < F[i], axis=1)
        keep[i] = not dom.any()
    return keep


@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("run")
    return run(small_cfg(), out, plots=False)


def test_outputs_and_invariants(small_run):
    out = small_run.out_dir
    for name in ("pareto.csv", "population.csv", "history.csv", "manifest.json", "config.yaml"):
        assert (out / name).is_file()
    assert not (out / "checkpoint.pkl").exists()
    p = pd.read_csv(out / "pareto.csv")
    for col in ("m", "n", "l1", "l2", "c", "m_minus_n", "volume_m3", "gci", "fci", "min_lci", "band0_share",
                "band2_volume_m3", "rank"):
        assert col in p.columns
    assert len(p) >= 2
    np.testing.assert_allclose(p["m_minus_n"], p["m"] - p["n"], atol=1e-9)
    F = -p[["volume_m3", "gci"]].to_numpy()
    assert nondominated(F).all()
    assert len(np.unique(F, axis=0)) == len(F)  # no duplicates in objective space
    assert (p["volume_m3"].diff().dropna() <= 0).all()  # sorted by volume
    assert ((p["gci"] >= 0) & (p["gci"] <= 1)).all() and ((p["min_lci"] >= 0) & (p["min_lci"] <= p["gci"])).all()
    np.testing.assert_allclose(p[["band0_share", "band1_share", "band2_share"]].sum(axis=1), 1.0, atol=1e-12)
    for k in SMALL["bounds"]:
        lo, hi = SMALL["bounds"][k]
        assert p[k].between(lo, hi).all()
    assert not p.isna().any().any()
    h = pd.read_csv(out / "history.csv")
    assert list(h["generation"]) == list(range(1, 7))
    assert list(h["evaluations"]) == [16 * g for g in range(1, 7)]
    # while the front is smaller than the population, elitism keeps every non-dominated design: HV cannot drop
    # (once the front fills the population, crowding truncation may lose a little; see validate_results)
    assert (h["n_nondominated"] < 16).all() and (np.diff(h["hypervolume"]) >= -1e-12).all()
    m = json.loads((out / "manifest.json").read_text())
    assert m["status"] == "finished" and m["seed"] == 3 and m["evaluations"] == 96 and m["grid_resolution"] == 12
    assert m["hv_reference"] == [0.0, 0.0] and m["machine"]["cores"] >= 1
    assert set(m["versions"]) >= {"scalesynth", "numpy", "numba", "pymoo", "moocore"}
    assert load_config(out / "config.yaml").model_dump() == small_cfg().model_dump()


def test_hypervolume_matches_independent_2d_sweep(small_run):
    """History HV (moocore) equals the area dominated by the front w.r.t. the origin, by a 2-D sweep."""
    p = small_run.pareto
    pts = sorted(zip(p["volume_m3"], p["gci"], strict=True), reverse=True)  # volume descending
    area, best_gci = 0.0, 0.0
    for i, (v, g) in enumerate(pts):
        v_next = pts[i + 1][0] if i + 1 < len(pts) else 0.0
        best_gci = max(best_gci, g)
        area += (v - v_next) * best_gci
    assert small_run.history["hypervolume"].iloc[-1] == pytest.approx(area, rel=1e-12)


def test_same_seed_gives_identical_bytes(small_run, tmp_path):
    again = run(small_cfg(), tmp_path, plots=False)
    assert (again.out_dir / "pareto.csv").read_bytes() == (small_run.out_dir / "pareto.csv").read_bytes()
    other = run(small_cfg(), tmp_path / "s4", seed=4, plots=False)
    assert (other.out_dir / "pareto.csv").read_bytes() != (small_run.out_dir / "pareto.csv").read_bytes()


def test_resume_after_interruption_gives_same_front(small_run, tmp_path):
    with pytest.raises(RunError):
        run(small_cfg(), tmp_path, plots=False, stop_after=3)
    # the unfinished run lives in the staging directory beside the target (scalesynth.rundir)
    assert (staging_path(tmp_path) / "checkpoint.pkl").exists() and not (tmp_path / "pareto.csv").exists()
    resumed = run(small_cfg(), tmp_path, resume=True, plots=False)
    assert (tmp_path / "pareto.csv").read_bytes() == (small_run.out_dir / "pareto.csv").read_bytes()
    assert list(resumed.history["generation"]) == list(range(1, 7))


def test_resume_refuses_a_changed_config(tmp_path):
    with pytest.raises(RunError):
        run(small_cfg(), tmp_path, plots=False, stop_after=2)
    from scalesynth.errors import ConfigError

    with pytest.raises(ConfigError, match="cannot resume"):
        run(small_cfg(grid={"resolution": 14}), tmp_path, resume=True, plots=False)


def test_constraints_are_respected(tmp_path):
    cfg = small_cfg(constraints=[{"metric": "volume", "min": 30.0}, {"metric": "gci", "min": 0.3}])
    res = run(cfg, tmp_path, plots=False)
    assert len(res.pareto) > 0
    assert (res.pareto["volume_m3"] >= 30.0).all() and (res.pareto["gci"] >= 0.3).all()


def test_other_objectives(tmp_path):
    cfg = small_cfg(objectives=[{"metric": "band_volume", "band": 2}, {"metric": "fci", "sense": "min"}])
    res = run(cfg, tmp_path, plots=False)
    F = np.column_stack([-res.pareto["band2_volume_m3"], res.pareto["fci"]])
    assert nondominated(F).all()
    assert res.manifest["hv_reference"] == [0.0, 0.5]


def _cli(*args, **kw):
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.run([sys.executable, "-m", "scalesynth", *args], capture_output=True, text=True, env=env, **kw)


def test_kill_9_then_resume_gives_same_front(tmp_path):
    data = json.loads(json.dumps(SMALL))
    data["algorithm"]["n_gen"] = 30
    data["output"]["checkpoint_every"] = 1
    cfg_path = tmp_path / "cfg.yaml"
    cfg_path.write_text(yaml.safe_dump(data))
    ref = run(config_from_dict(data), tmp_path / "ref", plots=False)
    out = tmp_path / "killed"
    env = dict(os.environ, MPLBACKEND="Agg")
    proc = subprocess.Popen([sys.executable, "-m", "scalesynth", "optimize", str(cfg_path), "--out", str(out),
                             "--no-plots", "-q"], env=env)
    ckpt = staging_path(out) / "checkpoint.pkl"
    deadline = time.time() + 120
    while not ckpt.exists() and time.time() < deadline and proc.poll() is None:
        time.sleep(0.01)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert not (out / "manifest.json").exists(), "the run finished before it could be killed"
    r = _cli("optimize", str(cfg_path), "--out", str(out), "--resume", "--no-plots", "-q")
    assert r.returncode == 0, r.stderr
    assert (out / "pareto.csv").read_bytes() == (ref.out_dir / "pareto.csv").read_bytes()


def test_cli_optimize_plots_select_evaluate(tmp_path):
    cfg_path = tmp_path / "cfg.yaml"
    data = json.loads(json.dumps(SMALL))
    data["references"] = {"T4-1": SMALL["design"]}
    cfg_path.write_text(yaml.safe_dump(data))
    out = tmp_path / "run"
    r = _cli("optimize", str(cfg_path), "--out", str(out))
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == str(out)
    for f in ("front.png", "hypervolume.png", "bands_front.png", "band_shares.png", "sections_knee.png"):
        assert (out / "plots" / f).stat().st_size > 1000
    report = (out / "report.md").read_text()
    assert "T4-1" in report and "plots/front.png" in report
    r = _cli("select", str(out), "--method", "balanced", "--json")
    assert r.returncode == 0, r.stderr
    chosen = json.loads(r.stdout)
    r = _cli("evaluate", chosen["config"], "--json")
    assert r.returncode == 0, r.stderr
    ev = json.loads(r.stdout)
    assert ev["volume_m3"] == pytest.approx(chosen["metrics"]["volume_m3"], rel=1e-9)
    assert ev["gci"] == pytest.approx(chosen["metrics"]["gci"], rel=1e-9)
    r = _cli("select", str(out), "--method", "weights", "--weights", "1,x")
    assert r.returncode == 2 and "--weights" in r.stderr
    r = _cli("plot-front", str(tmp_path))
    assert r.returncode == 2 and "not a scalesynth results directory" in r.stderr


def test_reproduce_from_manifest(small_run, tmp_path):
    r = _cli("reproduce", str(small_run.out_dir), "--out", str(tmp_path / "again"))
    assert r.returncode == 0, r.stderr
    assert "pareto.csv identical" in r.stdout


def test_results_validator_accepts_a_run_and_catches_damage(tmp_path):
    import shutil

    from scalesynth.validate_results import check_results

    res = run(small_cfg(), tmp_path / "ok")  # with plots and report
    assert check_results(res.out_dir) == []
    bad = tmp_path / "bad"
    shutil.copytree(res.out_dir, bad)
    p = pd.read_csv(bad / "pareto.csv")
    p.loc[1, "gci"] = p["gci"].min() - 0.01  # worse than every row in both objectives: dominated
    p.loc[1, "volume_m3"] = p["volume_m3"].min() - 0.01
    p.to_csv(bad / "pareto.csv", index=False)
    assert any("dominated" in msg for msg in check_results(bad))


def test_designs_equal_up_to_m_minus_n_are_duplicates():
    """Spec §1.1: the model depends on m, n only through m - n, so NSGA-II must treat such designs as one."""
    from pymoo.core.population import Population

    from scalesynth.optimize import CanonicalX, make_algorithm
    from scalesynth.problem import SynthesisProblem

    problem = SynthesisProblem(small_cfg())
    X = np.array([[0.9, 0.7, 1.2, 1.4, 0.2],   # m - n = 0.2
                  [1.1, 0.9, 1.2, 1.4, 0.2],   # same model
                  [1.1, 0.8, 1.2, 1.4, 0.2]])  # m - n = 0.3: different
    key = CanonicalX(problem)(Population.new("X", X))
    assert np.array_equal(key[0], key[1]) and not np.array_equal(key[0], key[2])
    elim = make_algorithm(small_cfg(), problem).eliminate_duplicates
    kept = elim.do(Population.new("X", X))
    assert len(kept) == 2
    M = problem.complete_metrics(X, problem.metrics(X))  # every column, not only the searched families
    # identical kinematic metrics, as the invariance says; design-level ones may see m itself (the base radius)
    design = [i for i, c in enumerate(problem.metric_columns) if c in ("link_length_sum_m", "footprint_radius_m",
                                                                        "stroke_d_m")]
    assert len(design) == 3
    kinematic = [i for i in range(M.shape[1]) if i not in design]
    assert np.array_equal(M[0, kinematic], M[1, kinematic])
    assert M[0, problem.metric_columns.index("footprint_radius_m")] == 0.9  # = m
    assert M[1, problem.metric_columns.index("footprint_radius_m")] == 1.1
