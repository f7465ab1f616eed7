"""bounds.gear_ratio (issue 29): the motors' shared gear ratio as a design variable of the search. Each design's
motor metrics use its own ratio: a front row's equal a fresh `scalesynth cycle` of that row's design with
motors.gear_ratio set to the row's ratio (the single-design analysis, cycle.analysis, not the batched path)."""

from __future__ import annotations

import html
import json
import re
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from scalesynth.cli import app

ROOT = Path(__file__).resolve().parents[1]
# a 750 W servo's ratings (as tests/test_dynamics.py MOTOR); the gear ratio is searched
MOTOR = {"peak_torque": 4.46, "rated_torque": 1.27, "max_speed": 628.3, "rotor_inertia": 0.486e-4, "gear_ratio": 20}
MOTOR_METRICS = ("picks_per_minute", "cycle_time_s", "motor_peak_torque_ratio", "motor_rms_torque_ratio",
                 "motor_speed_ratio")


def _config(tmp_path: Path, **changes) -> Path:
    data = yaml.safe_load((ROOT / "configs" / "fivebar_pnp_cycle.yaml").read_text())
    data.update(name="gear", grid={"resolution": 16}, task=None, motors=MOTOR,
                objectives=[{"metric": "picks_per_minute", "sense": "max"},
                            {"metric": "motor_rms_torque_ratio", "sense": "min"}],
                constraints=[], algorithm={"pop_size": 6, "n_gen": 2, "seed": 3}, output={"checkpoint_every": 1})
    data["bounds"]["gear_ratio"] = [10.0, 60.0]
    data["cycle"]["samples"] = 24
    data.update(changes)
    path = tmp_path / "c.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def _design_set(row) -> str:
    return "design={" + ", ".join(f"{k}: {float(row[k])!r}" for k in ("r", "l1", "l2")) + "}"


@pytest.fixture(scope="module")
def gear_run(tmp_path_factory) -> tuple[Path, Path]:
    """(config, results directory) of a small search over the gear ratio."""
    tmp = tmp_path_factory.mktemp("gear")
    path = _config(tmp)
    res = CliRunner().invoke(app, ["optimize", str(path), "--out", str(tmp / "run"), "--no-plots"])
    assert res.exit_code == 0, res.output
    return path, tmp / "run"


def test_searched_gear_ratio_is_a_column_and_each_row_uses_its_own(gear_run, tmp_path):
    import pandas as pd

    path, run = gear_run
    front = pd.read_csv(run / "pareto.csv")
    assert len(front) >= 1
    assert front["gear_ratio"].between(10.0, 60.0).all()
    row = front.iloc[0]
    assert row["picks_per_minute"] > 0  # a followed cycle: the comparison below is not of two failures
    runs = {}
    for label, args in (("row", [str(run), "--design", "0"]),
                        ("set", [str(path), "--set", f"motors.gear_ratio={float(row['gear_ratio'])!r}",
                                 "--set", _design_set(row)])):
        res = CliRunner().invoke(app, ["cycle", *args, "--out", str(tmp_path / label), "--json"])
        assert res.exit_code == 0, res.output
        runs[label] = json.loads(res.stdout)["metrics"]
    for name in MOTOR_METRICS:
        assert runs["row"][name] == pytest.approx(runs["set"][name], rel=1e-9, abs=1e-12), name
        assert row[name] == pytest.approx(runs["set"][name], rel=1e-9, abs=1e-12), name
    # the config's own ratio (20) gives other motor metrics: the row's ratio is the one used
    if abs(row["gear_ratio"] - 20.0) > 1e-6:
        res = CliRunner().invoke(app, ["cycle", str(path), "--out", str(tmp_path / "cfg"), "--json", "--set",
                                       _design_set(row)])
        assert json.loads(res.stdout)["metrics"]["motor_speed_ratio"] != pytest.approx(runs["set"]["motor_speed_ratio"])
    # select writes the row's ratio as motors.gear_ratio
    res = CliRunner().invoke(app, ["select", str(run), "--out", str(tmp_path / "sel.yaml")])
    assert res.exit_code == 0, res.output
    chosen = yaml.safe_load((tmp_path / "sel.yaml").read_text())
    match = front[front["r"] == chosen["design"]["r"]]
    assert len(match) >= 1 and chosen["motors"]["gear_ratio"] == pytest.approx(match["gear_ratio"].iloc[0], rel=1e-12)


def _cell(page: str, label: str) -> str:
    """The value cell of the datasheet row labelled ``label``."""
    found = re.search(f"<tr><th>{re.escape(html.escape(label))}</th><td>([^<]*)</td>", page)
    assert found, label
    return found.group(1)


def test_datasheet_uses_the_rows_searched_gear_ratio(gear_run, tmp_path):
    """The datasheet of a row of a gear-ratio search states that row's ratio, and its rated-payload rate (evaluated
    afresh by the datasheet) is the row's picks_per_minute from the search, not the rate at the config's ratio (20);
    its torque margins are the row's (1 - motor_*_torque_ratio)."""
    import pandas as pd

    from scalesynth import results
    from scalesynth.cycle.population import population_metrics
    from scalesynth.design.datasheet import _fmt

    _, run = gear_run
    row = pd.read_csv(run / "pareto.csv").iloc[0]
    assert abs(row["gear_ratio"] - MOTOR["gear_ratio"]) > 1.0  # else the check below could not tell them apart
    page = tmp_path / "ds.html"
    res = CliRunner().invoke(app, ["datasheet", str(run), "--design", "0", "--out", str(page), "--print", "none"])
    assert res.exit_code == 0, res.output
    text = page.read_text()
    assert _cell(text, "gear ratio (searched: this design's own)") == _fmt(float(row["gear_ratio"]))
    rated = _cell(text, "1 kg (rated)")
    assert rated == _fmt(float(row["picks_per_minute"]))
    result = results.load(run)  # the same design at the config's own ratio runs at another rate
    cfg = result.cfg
    at_config = population_metrics(cfg.mech, [result.design_of(row)], cfg.resolved_options(), cfg.cycle,
                                   cfg.units.length)["picks_per_minute"][0]
    assert rated != _fmt(float(at_config))
    for name in ("peak torque", "rms torque"):
        expected = 100 * (1 - float(row[f"motor_{name.replace(' ', '_')}_ratio"]))
        assert _cell(text, f"{name} margin") == _fmt(expected, "%")


def test_report_datasheet_uses_the_rows_searched_gear_ratio(gear_run):
    """The run report's datasheet (cycle.datasheet.of_featured) of a row of a gear-ratio search: that row's ratio,
    and at the cycle's own payload the row's picks_per_minute from the search."""
    from scalesynth import results
    from scalesynth.cycle.datasheet import of_featured

    _, run = gear_run
    result = results.load(run)
    row = result.pareto.iloc[0]
    label, sheet = of_featured(result, [("knee", 0)])
    assert label == "knee" and isinstance(sheet, dict), sheet
    assert sheet["gear_ratio"] == pytest.approx([float(row["gear_ratio"])] * 2, rel=1e-12)
    (rated,) = [r for r in sheet["rows"] if r["payload_kg"] == result.cfg.cycle.payload]
    assert rated["picks_per_minute"] == pytest.approx(float(row["picks_per_minute"]), rel=1e-9)


@pytest.mark.parametrize("changes, message", [
    ({"motors": None}, "bounds.gear_ratio: needs a motors section"),
    ({"bounds": {"r": [50, 400], "gear_ratio": [0.0, 60.0]}}, "bounds.gear_ratio: lower bound must be > 0"),
])
def test_bad_gear_ratio_bounds_are_one_line_errors(tmp_path, changes, message):
    res = CliRunner().invoke(app, ["optimize", str(_config(tmp_path, **changes)), "--out", str(tmp_path / "run")])
    assert res.exit_code == 2
    assert message in res.output and len(res.output.strip().splitlines()) == 1, res.output
    assert not (tmp_path / "run").exists()
