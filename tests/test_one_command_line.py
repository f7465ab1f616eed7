"""Issue 27, "one command line": one design selector for every per-design command (a config, a results directory
with --design, or a mechanism name; --set in every case), compare matching metrics by catalogue name across
length units, "did you mean" for unknown names, error lines of at most 200 characters, and one line on stderr
when a process compiles Numba kernels. Runs on the planar five-bar (the cheapest mechanism to compile)."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from cli_main import run_main as _main
from scalesynth.compare import conversion
from scalesynth.config import load_config
from scalesynth.optimize import run

ROOT = Path(__file__).resolve().parents[1]
PNP = ROOT / "configs" / "fivebar_pnp_cycle.yaml"
QUICK = ROOT / "configs" / "quick.yaml"
FIVEBAR = ROOT / "configs" / "fivebar_packing.yaml"
POSE = "--pose=0,-700"  # mm: inside every five-bar workspace of these runs (the packing rectangle's middle)



@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """A tiny five-bar synthesis in mm with a pick-and-place cycle (its front has cycle metrics), and a tiny
    2pauu-ppap one (quick.yaml), whose lengths are in m (each mechanism computes in its own length unit)."""
    base = tmp_path_factory.mktemp("one_command_line")
    run(load_config(PNP, ["algorithm.pop_size=8", "algorithm.n_gen=2"]), base / "mm", plots=False)
    run(load_config(QUICK, ["algorithm.pop_size=8", "algorithm.n_gen=2"]), base / "m", plots=False)
    return base



def _ok_json(argv, capsys) -> dict:
    code, out, err = _main([*argv, "--json"], capsys)
    assert code == 0, err
    return json.loads(out)


def _row_design(run_dir: Path, row: int) -> dict[str, float]:
    front = pd.read_csv(run_dir / "pareto.csv")
    return {k: float(front[k].iloc[row]) for k in ("r", "l1", "l2")}


# ----- one design selector -------------------------------------------------------------------------------------
def test_show_takes_best_of_any_catalogue_metric_like_cycle(runs, tmp_path, capsys):
    """The case of the issue: `show --design best-cycle_max_actuator_force` was refused while `cycle` took it. The
    row expected is the front's smallest cycle_max_actuator_force_N_m (the catalogue's better sense, 'min')."""
    front = pd.read_csv(runs / "mm" / "pareto.csv")
    expected = int(front["cycle_max_actuator_force_N_m"].idxmin())
    info = _ok_json(["show", runs / "mm", "--design", "best-cycle_max_actuator_force", "--resolution", "8",
                     "--out", tmp_path / "show"], capsys)
    assert info["pareto_row"] == expected and info["design_choice"] == "best-cycle_max_actuator_force"
    assert info["design"] == pytest.approx(_row_design(runs / "mm", expected), rel=1e-12)
    cyc = _ok_json(["cycle", runs / "mm", "--design", "best-cycle_max_actuator_force", "--out", tmp_path / "c"],
                   capsys)
    assert cyc["design"] == pytest.approx(info["design"], rel=1e-12)


@pytest.mark.parametrize("selector", ["knee", "best-task_gci", "best-cycle_max_actuator_speed", "1", "row1"])
def test_evaluate_takes_a_run_directory_with_the_same_selector(runs, selector, capsys):
    """evaluate accepts a results directory: its design is the front row the selector names (best-: the largest
    task_gci, an objective maximised; the smallest cycle_max_actuator_speed, an objective minimised)."""
    front = pd.read_csv(runs / "mm" / "pareto.csv")
    from scalesynth import results
    from scalesynth.selection import choose

    row = {"knee": lambda: choose(results.load(runs / "mm").objective_matrix(), "knee"),
           "best-task_gci": lambda: int(front["task_gci"].idxmax()),
           "best-cycle_max_actuator_speed": lambda: int(front["cycle_max_actuator_speed_rad_per_s"].idxmin()),
           "1": lambda: 1, "row1": lambda: 1}[selector]()
    info = _ok_json(["evaluate", runs / "mm", "--design", selector, "--resolution", "8"], capsys)
    assert info["design"] == pytest.approx(_row_design(runs / "mm", row), rel=1e-12)


def test_stiffness_takes_a_config_and_a_run_directory_and_set(runs, capsys):
    """stiffness of a run's row 1 = stiffness of the run's config with that row's design given by --set = the
    library's pose_stiffness of that design with the config's options (the reference)."""
    from scalesynth.stiffness.report import pose_stiffness

    d = _row_design(runs / "mm", 1)
    by_row = _ok_json(["stiffness", runs / "mm", "--design", "1", POSE], capsys)
    sets = [a for k, v in d.items() for a in ("--set", f"{k}={v!r}")]
    by_config = _ok_json(["stiffness", runs / "mm" / "config.yaml", POSE, *sets], capsys)
    cfg = load_config(runs / "mm" / "config.yaml")
    mech = cfg.mech
    ref = pose_stiffness(mech, mech.resolve_design(d), cfg.resolved_options(), [0.0, -700.0], "ideal")
    for got in (by_row, by_config):
        np.testing.assert_allclose(got["deflection"], ref["deflection"], rtol=1e-12, atol=0)
    # --set on a results directory overrides the chosen row's design (refused before)
    moved = _ok_json(["stiffness", runs / "mm", "--design", "1", POSE, "--set", "l1=600"], capsys)
    ref = pose_stiffness(mech, mech.resolve_design({**d, "l1": 600.0}), cfg.resolved_options(), [0.0, -700.0],
                         "ideal")
    np.testing.assert_allclose(moved["deflection"], ref["deflection"], rtol=1e-12, atol=0)


def test_cycle_takes_set_on_a_run_directory(runs, tmp_path, capsys):
    d = _row_design(runs / "mm", 0)
    info = _ok_json(["cycle", runs / "mm", "--design", "0", "--set", "l1=600", "--out", tmp_path / "c"], capsys)
    assert info["design"] == pytest.approx({**d, "l1": 600.0}, rel=1e-12)


@pytest.mark.parametrize("argv", [
    ["ik", "{run}", "--design", "1", POSE],
    ["fk", "{run}", "--design", "1", "--inputs=0,3"],
    ["mobility", "{run}", "--design", "1", "--samples", "2"],
    ["plot-task", "{run}", "--design", "1", "--resolution", "8", "--out", "{tmp}/task.png"],
], ids=["ik", "fk", "mobility", "plot-task"])
def test_every_per_design_command_takes_a_run_directory(runs, tmp_path, argv, capsys):
    argv = [a.format(run=runs / "mm", tmp=tmp_path) for a in argv]
    code, out, err = _main(argv, capsys)
    assert code == 0, err


@pytest.mark.parametrize(("argv", "needle"), [
    (["stiffness", QUICK, "--design", "knee", "--pose=0,0,1"], "a config uses its own design"),
    (["stiffness", "planar-fivebar", "--design", "knee", POSE], "a mechanism name has one design"),
    (["evaluate", "{run}", "--design", "kne"], "(did you mean 'knee'?)"),
    (["evaluate", "{run}", "--design", "best-task_gc"], "did you mean 'task_gci'"),
    (["evaluate", "{run}", "--design", "99"], "--design: row 99 is not in pareto.csv"),
    (["evaluate", "{m}", "--design", "best-cycle_max_actuator_force_revolute"],
     "is not a column of this run's pareto.csv"),
])
def test_selector_errors_are_one_line(runs, argv, needle, capsys):
    argv = [str(a).format(run=runs / "mm", m=runs / "m") for a in argv]
    code, out, err = _main(argv, capsys)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1 and needle in err, err


# ----- compare across length units ---------------------------------------------------------------------------
def test_compare_matches_metrics_by_catalogue_name_across_units(runs, tmp_path, capsys):
    """A run in mm (five-bar) and one in m (2pauu-ppap) share link_length_sum (link_length_sum_mm /
    link_length_sum_m): the table and the figure use the first run's mm, the m run's values times 1000, and stderr
    says which values were converted. An area (mm2) and a volume (m3) differ by more than the length unit: not
    shared."""
    for x in ("link_length_sum", "link_length_sum_m"):  # the catalogue name, or either run's column
        code, out, err = _main(["compare", runs / "mm", runs / "m", "--x", x, "--y", "gci", "--out",
                                tmp_path / "cmp", "--json"], capsys)
        assert code == 0, err
        info = json.loads(out)
        assert info["axes"] == ["link_length_sum_mm", "gci"]
        assert "note: quick: converted to the first run's units: link_length_sum m -> mm" in err
        converted = {c["metric"]: c for c in info["converted"]}
        assert converted["link_length_sum"]["factor"] == pytest.approx(1000.0, rel=1e-15)
        assert "volume" not in converted and "volume" not in info["shared_metrics"]
        assert "gci" not in converted  # dimensionless: nothing to convert
    metres = pd.read_csv(runs / "m" / "pareto.csv")
    rows = [r for r in info["rows"] if r["run"] == "quick"]
    assert rows
    for r in rows:
        assert r["link_length_sum_mm"] == pytest.approx(1000.0 * metres["link_length_sum_m"].iloc[r["pareto_row"]],
                                                        rel=1e-12)
    table = pd.read_csv(tmp_path / "cmp" / "compare.csv")
    assert "link_length_sum_mm" in table.columns and "link_length_sum_m" not in table.columns


def test_unit_conversions_by_length_power():
    assert conversion("m", "mm") == pytest.approx(1e3, rel=1e-15)
    assert conversion("m3", "mm3") == pytest.approx(1e9, rel=1e-15)
    assert conversion("N/m", "N/mm") == pytest.approx(1e-3, rel=1e-15)
    assert conversion("mm/s^2", "m/s^2") == pytest.approx(1e-3, rel=1e-15)
    assert conversion("mm_rad2", "m_rad2") == pytest.approx(1e-3, rel=1e-15)
    assert conversion("N m", "N m") == 1.0
    assert conversion("mm2", "mm_rad") is None  # not the same quantity
    assert conversion("rad/s or mm/s", "rad/s or m/s") is None  # a value in either unit: not convertible


# ----- did you mean, error lines of at most 200 characters ---------------------------------------------------
LONG = "x" * 300
ERROR_CASES = [
    (["evaluate", FIVEBAR, "--set", "objectives=[{metric: volum}]"], "did you mean 'volume'"),
    (["evaluate", FIVEBAR, "--set", "objectives=[{metric: " + LONG + "}]"], "unknown metric"),
    (["evaluate", QUICK, "--set", "design.l=1"], "'l1'"),
    (["evaluate", QUICK, "--set", "e2=1"], "did you mean 'e'"),
    (["evaluate", QUICK, "--set", f"{LONG}=1"], "unknown option"),
    (["evaluate", "a/" * 150 + "c.yaml"], "no such config file"),
    (["evaluate", f"{LONG}.yaml"], "File name too long"),
    (["evaluate", QUICK, "--set", "bounds.cc=[0.1, 0.5]"], "did you mean 'c'"),
    (["ik", "planar-fivebr", POSE], "did you mean 'planar-fivebar'"),
    (["ik", LONG, POSE], "unknown mechanism"),
    (["example", "quik"], "did you mean 'quick'"),
    (["show", FIVEBAR, "--field", "lcii"], "did you mean 'lci'"),
    (["cycle", PNP, "--set", "cycle.preset=adep"], "did you mean 'adept'"),
    (["cycle", PNP, "--set", "cycle.law=poly34"], "did you mean 'poly345'"),
    (["evalute", QUICK], "Did you mean 'evaluate'"),
    ([LONG], "No such command"),
    (["ik", "planar-fivebar", "--pose=" + "1," * 200], "--pose"),
]


@pytest.mark.parametrize(("argv", "needle"), ERROR_CASES, ids=[" ".join(map(str, c[0]))[:50] for c in ERROR_CASES])
def test_errors_are_one_line_of_at_most_200_characters(argv, needle, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, err = _main(argv, capsys)
    lines = err.strip().splitlines()
    assert code == 2 and out == "" and len(lines) == 1, err
    assert lines[0].startswith("error: ") and needle in lines[0] and len(lines[0]) <= 200, (len(lines[0]), lines[0])


def test_compare_axis_and_run_directory_errors_say_did_you_mean(runs, capsys):
    code, out, err = _main(["compare", runs / "mm", runs / "m", "--x", "link_length_su"], capsys)
    assert code == 2 and "did you mean 'link_length_sum'" in err and len(err.strip()) <= 200, err
    code, out, err = _main(["stiffness", runs / "mm", "--design", "best-cycle_max_actuator_forc", POSE], capsys)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and len(lines[0]) <= 200, err
    assert "did you mean 'cycle_max_actuator_force'" in lines[0]


def test_the_guard_cuts_any_error_line_to_200_characters():
    from scalesynth.cliapp import error_line

    assert error_line("a" * 300) == "error: " + "a" * 20 + "..." + "a" * 17  # a long word: shortened inside
    assert error_line("ab " * 100) == "error: " + ("ab " * 100)[:190] + "..."  # short words: the line is cut
    assert error_line("line\nbreak") == "error: line\\nbreak"


# ----- the compile notice ------------------------------------------------------------------------------------
def _cli(args, cache: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache), NUMBA_NUM_THREADS="1", PYTHONPATH=str(ROOT / "src"))
    return subprocess.run([sys.executable, "-m", "scalesynth", *args], capture_output=True, text=True, env=env,
                          timeout=900)


def test_a_first_process_says_once_that_it_compiles_and_a_cached_one_says_nothing(tmp_path):
    """An empty Numba cache: one note line naming the planar-fivebar kernels and the cache; the same cache again:
    nothing on stderr (everything loaded); another empty cache with -q: nothing."""
    args = ["stiffness", "planar-fivebar", POSE, "--json"]
    first = _cli(args, tmp_path / "cache")
    assert first.returncode == 0, first.stderr
    lines = first.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("note: compiling the planar-fivebar kernels with Numba"), lines
    assert str(tmp_path / "cache") in lines[0] and "first run only" in lines[0] and len(lines[0]) <= 200
    again = _cli(args, tmp_path / "cache")
    assert again.returncode == 0 and again.stderr == "", again.stderr
    assert json.loads(again.stdout)["deflection"] == json.loads(first.stdout)["deflection"]
    quiet = _cli(["-q", *args], tmp_path / "quiet")
    assert quiet.returncode == 0 and quiet.stderr == "", quiet.stderr
