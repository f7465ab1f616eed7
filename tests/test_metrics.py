"""The metric catalogue (scalesynth.metrics): its CLI listing, the generated docs, design-level metrics with exact
formulas, bad metric choices, infeasibility diagnostics, results that flow in memory, and the five-bar
size-versus-dexterity synthesis of the issue."""

import dataclasses
import json
import math
import os
import re
import subprocess
import sys

import numpy as np
import pytest
import yaml

from scalesynth import metrics
from scalesynth.config import config_from_dict, load_config
from scalesynth.errors import ConfigError
from scalesynth.evaluate import evaluate
from scalesynth.mechanisms import _REGISTRY, available, get
from scalesynth.mechanisms.base import Field, enclosing_circle_radius
from scalesynth.optimize import run
from scalesynth.validate_results import check_results

from conftest import ROOT, SMALL

CATALOGUE_KEYS = {"name", "column", "family", "field", "statistic", "unit", "range", "better", "worst", "needs",
                  "description", "mechanisms"}


def cli(*args):
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.run([sys.executable, "-m", "scalesynth", *args], capture_output=True, text=True, env=env,
                          cwd=ROOT)


def test_metrics_command_lists_every_metric_of_the_fivebar_as_json():
    r = cli("metrics", "planar-fivebar", "--json")
    assert r.returncode == 0, r.stderr
    rows = json.loads(r.stdout)
    by_name = {row["name"]: row for row in rows}
    assert list(by_name) == list(metrics.catalogue(get("planar-fivebar")))
    assert all(set(row) == CATALOGUE_KEYS for row in rows)
    assert by_name["link_length_sum"] == {
        "name": "link_length_sum", "column": "link_length_sum_mm", "family": "design", "field": None,
        "statistic": None, "unit": "mm", "range": [0.0, None], "better": "min", "worst": "bounds_corners",
        "needs": [], "description": by_name["link_length_sum"]["description"], "mechanisms": ["planar-fivebar"],
    }
    assert by_name["mean_sigma_max"]["column"] == "mean_sigma_max_mm_per_rad"
    assert by_name["mean_sigma_max"]["unit"] == "mm/rad"
    assert by_name["task_gci"]["needs"] == ["task"] and by_name["path_mean_lci"]["needs"] == ["task", "path"]
    assert by_name["band_share"]["column"] == "band{band}_share"
    for name in ("volume", "gci", "fci", "min_lci", "max_lci", "voxels", "band_volume", "task_coverage",
                 "task_fci", "task_min_lci", "path_min_lci", "footprint_radius", "min_sigma_min", "task_max_sigma_max"):
        assert name in by_name
    text = cli("metrics")
    assert text.returncode == 0 and "link_length_sum" in text.stdout and "stroke_d" in text.stdout
    bad = cli("metrics", "no-such-robot")
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "unknown mechanism 'no-such-robot'" in bad.stderr


def test_docs_metrics_md_is_generated_from_the_catalogue():
    """docs/metrics.md equals metrics.markdown() (regenerate: `python -m scalesynth.metrics > docs/metrics.md`)."""
    assert (ROOT / "docs" / "metrics.md").read_text(encoding="utf-8") == metrics.markdown()


def test_no_other_module_lists_metric_names():
    """Metric names live in the catalogue: no other source file spells the names of the task/path metrics."""
    offenders = []
    for path in (ROOT / "src" / "scalesynth").rglob("*.py"):
        if path.name == "metrics.py":
            continue
        text = path.read_text(encoding="utf-8")
        if re.search(r"[\"'](task_fci|task_min_lci|path_mean_lci|path_reachable|band_volume)[\"']", text):
            offenders.append(path.name)
    assert offenders == []


@pytest.mark.parametrize("name", available())
def test_catalogue_entries_are_complete(name):
    cat = metrics.catalogue(get(name))
    assert {m.family for m in cat.values()} <= set(metrics.FAMILIES)
    for m in cat.values():
        assert m.description and m.unit and m.range[0] <= m.range[1]
        assert m.better in ("max", "min")
    mech = get(name)
    assert {f"mean_{f.name}" for f in mech.fields if f.name != "lci"} <= set(cat)
    assert {"link_length_sum", "footprint_radius"} <= {m.name for m in cat.values() if m.family == "design"}


# ----- design-level metrics: exact formulas ------------------------------------------------------------------
DESIGN_CASES = [
    # (mechanism, design, options, {metric: value from the formula in the mechanism's docs})
    ("planar-fivebar", {"r": 191.0, "l1": 450.0, "l2": 800.0}, {},
     {"link_length_sum": 2 * (450 + 800), "footprint_radius": 191.0}),
    ("2pauu-ppap", {"m": 0.9, "n": 0.7, "l1": 1.2, "l2": 1.4, "c": 0.2}, {},
     {"link_length_sum": 2 * (2 * 1.2 + 0.2 + 1.4), "footprint_radius": 0.9, "stroke_d": 2 * 1.4}),
    ("2pauu-ppap", {"m": 0.9, "n": 0.7, "l1": 1.2, "l2": 1.4, "c": 0.2}, {"stroke_limits": [-0.5, 3.0]},
     {"stroke_d": 1.4 + 0.5}),  # stroke limits clip the reachable |y| < l2
    ("rps-upu", {"g": 80.0, "h": 50.0, "c": 30.0, "e": 0.0}, {},
     {"link_length_sum": 2 * 50 + 2 * math.hypot(50, 30), "footprint_radius": 80.0}),  # e < g: the A1A2 diameter
    ("rps-upu", {"g": 80.0, "h": 50.0, "c": 30.0, "e": 100.0}, {},
     {"footprint_radius": (100**2 + 80**2) / (2 * 100)}),  # acute triangle: its circumradius (e^2 + g^2) / 2e = 82
    ("ups-sspr", {"a": 100.0, "b": 80.0, "c": 120.0}, {},
     {"link_length_sum": 120 + 2 * 80, "footprint_radius": math.sqrt(3) * 100 / 2}),
    ("pprs-rprs", {"r": 160.0, "R": 180.0, "L1": 100.0, "L2": 120.0, "L3": 110.0}, {},
     {"link_length_sum": 100 + 120 + 110 + 3 * math.sqrt(3) * 160, "footprint_radius": 180.0}),
]


@pytest.mark.parametrize(("name", "design", "options", "expected"), DESIGN_CASES)
def test_design_metrics_exact_formulas(name, design, options, expected):
    mech = get(name)
    rep = evaluate(mech, design, options, resolution=6)
    cat = metrics.catalogue(mech)
    for metric, value in expected.items():
        assert rep.metrics[cat[metric].column] == pytest.approx(value, rel=1e-12), metric


def test_enclosing_circle_textbook_cases():
    assert enclosing_circle_radius([(0, 0), (3, 0), (0, 4)]) == pytest.approx(2.5)  # right triangle: hypotenuse/2
    assert enclosing_circle_radius([(0, 0), (1, 0), (0.5, math.sqrt(3) / 2)]) == pytest.approx(1 / math.sqrt(3))
    assert enclosing_circle_radius([(-2, 0), (0, 0), (5, 0)]) == pytest.approx(3.5)  # collinear: half the extent
    assert enclosing_circle_radius([(1, 1), (-1, 1), (-1, -1), (1, -1), (0, 0)]) == pytest.approx(math.sqrt(2))


def test_design_metric_hypervolume_reference_is_the_worst_corner():
    data = yaml.safe_load((ROOT / "configs" / "fivebar_small_robot.yaml").read_text())
    cfg = config_from_dict(data)
    from scalesynth.problem import SynthesisProblem

    ref = SynthesisProblem(cfg).hv_reference()
    assert list(ref) == [0.0, 2 * (800 + 1400)]  # max task_gci: 0; min link_length_sum: 2 (l1 + l2) at the upper corner


# ----- bad metric choices --------------------------------------------------------------------------------------
def test_a_field_the_mechanism_does_not_provide_is_named(monkeypatch):
    """A field statistic of another mechanism's field: one line naming the field and this mechanism's fields."""
    fivebar = get("planar-fivebar")
    extra = dataclasses.replace(fivebar, name="fivebar-with-stiffness",
                                fields=(*fivebar.fields, Field("stiffness", "N/{length}", "test-only field")))
    monkeypatch.setitem(_REGISTRY, extra.name, extra)
    assert "mean_stiffness" in metrics.catalogue(extra)
    data = dict(SMALL, objectives=[{"metric": "mean_stiffness", "sense": "max"}])
    with pytest.raises(ConfigError) as err:
        config_from_dict(data)
    assert str(err.value) == ("objectives[0].metric: mean_stiffness: field 'stiffness' is not provided by 2pauu-ppap "
                              "(did you mean 'stiffness_min'?; fields: lci, sigma_min, sigma_max, clearance, "
                              "stiffness_min, deflection)")


def test_unknown_metric_lists_the_usable_choices():
    with pytest.raises(ConfigError) as err:
        config_from_dict(dict(SMALL, constraints=[{"metric": "stiffnes", "min": 1}]))
    msg = str(err.value)
    # the first usable choices and where the whole list is (issue 27: no 1 000-character list)
    assert msg.startswith("constraints[0].metric: unknown metric 'stiffnes' for 2pauu-ppap (valid: volume, gci, ")
    assert msg.endswith("in all); see `scalesynth metrics 2pauu-ppap`)") and len(msg) <= 193
    with pytest.raises(ConfigError) as err:
        config_from_dict(dict(SMALL, constraints=[{"metric": "task_gc", "min": 1}]))
    assert "task_gci" not in str(err.value)  # no task section: task metrics are not choices
    with pytest.raises(ConfigError, match=r"objectives\[1\].band: metric gci has no bands"):
        config_from_dict(dict(SMALL, objectives=[{"metric": "volume"}, {"metric": "gci", "band": 1}]))


# ----- infeasibility diagnostics, results in memory ------------------------------------------------------------
def _small(tmp_path, **changes):
    data = dict(SMALL, **changes)
    path = tmp_path / "cfg.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_unmeetable_constraints_print_one_line_each_and_the_report_says_so(tmp_path):
    """A task box beyond every design's reach (|x| <= l1 + l2 <= 3) and an impossible volume bound: optimize exits
    0, prints one line per constraint with the best value seen, and report.md says the same."""
    cfg = _small(tmp_path, task={"box": {"x": [50, 51], "y": [0, 1], "z": [0, 1]}, "resolution": 4},
                 constraints=[{"metric": "task_coverage", "min": 1.0}, {"metric": "volume", "max": 1e-6}],
                 algorithm=dict(SMALL["algorithm"], n_gen=3))
    out = tmp_path / "run"
    r = cli("optimize", str(cfg), "--out", str(out), "-q")
    assert r.returncode == 0, r.stderr
    lines = [line for line in r.stderr.splitlines() if line.startswith("no feasible design:")]
    history = __import__("pandas").read_csv(out / "history.csv")
    vol_best = history["constraint1_best_volume_m3"].min()  # the smallest volume seen in any generation
    assert lines == [
        "no feasible design: task_coverage best 0, needs >= 1.0",
        f"no feasible design: volume_m3 best {vol_best:.4g}, needs <= 1e-06",
    ]
    assert (history["constraint0_best_task_coverage"] == 0.0).all() and len(history) == 3
    population = __import__("pandas").read_csv(out / "population.csv")
    assert vol_best <= population["volume_m3"].min() and vol_best > 1e-6
    assert "0 Pareto designs" in r.stderr
    report = (out / "report.md").read_text()
    assert "## No feasible design" in report
    for line in lines:
        assert f"- {line}" in report
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["feasible_in_final_population"] == 0 and len(manifest["no_feasible_design"]) == 2


def test_report_wall_time_is_this_runs_manifest(tmp_path):
    """report.md is written from the RunResult in memory: a stale manifest.json in the directory (an earlier run)
    must not leak into it."""
    cfg = load_config(_small(tmp_path, algorithm=dict(SMALL["algorithm"], n_gen=2)))
    out = tmp_path / "run"
    out.mkdir()
    (out / "manifest.json").write_text(json.dumps({"status": "finished", "config": cfg.model_dump(mode="json"),
                                                   "wall_seconds": 9999.0, "machine": {"cores": 1}}))
    result = run(cfg, out)
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest == result.manifest and manifest["wall_seconds"] != 9999.0
    wall = re.search(r"^- wall time: ([0-9.]+) s on (\d+) cores$", (out / "report.md").read_text(), re.M)
    assert wall.group(1) == f"{manifest['wall_seconds']:.1f}"
    assert int(wall.group(2)) == manifest["machine"]["cores"]


def test_fivebar_smallest_robot_front_trades_size_for_dexterity(tmp_path):
    """configs/fivebar_small_robot.yaml (max task_gci, min link_length_sum, task_coverage >= 1): every front design
    covers the rectangle, and along the front a shorter robot always has a lower task GCI."""
    cfg = load_config(ROOT / "configs" / "fivebar_small_robot.yaml")
    result = run(cfg, tmp_path / "fsr", plots=False)
    front = result.pareto.sort_values("link_length_sum_mm")
    assert len(front) >= 5
    assert (front["task_coverage"] == 1.0).all()
    np.testing.assert_allclose(front["link_length_sum_mm"], 2 * (front["l1"] + front["l2"]), rtol=1e-12)
    gci = front["task_gci"].to_numpy()
    assert np.all(np.diff(gci) > 0)  # non-dominated: each extra millimetre of links buys task GCI
    assert gci[-1] - gci[0] > 0.05 and np.ptp(front["link_length_sum_mm"]) > 100
    assert check_results(tmp_path / "fsr", require_report=False) == []
