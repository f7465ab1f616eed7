"""Hostile input across every command (issue 11 item 7): each case runs the real entry point (``cli.main``, the
function behind ``scalesynth`` and ``python -m scalesynth``) in process, and asserts the exit code, exactly one
line on stderr starting with ``error:`` and naming the field, nothing on stdout, and nothing written: the
working directory (which holds the inputs, and a finished run for the damaged-results cases) is byte-identical
afterwards."""

import copy
import pickle
import shutil
from pathlib import Path

import pytest
import yaml

from cli_main import run_main as _run_main
from scalesynth.config import config_from_dict
from scalesynth.optimize import run
from scalesynth.rundir import staging_path

from conftest import SMALL

ROOT = Path(__file__).resolve().parents[1]
QUICK = str(ROOT / "configs" / "quick.yaml")
FIVEBAR = str(ROOT / "configs" / "fivebar_packing.yaml")
PPRS = str(ROOT / "configs" / "pprs_rprs.yaml")


def _snapshot(directory: Path) -> dict[str, bytes]:
    return {str(p.relative_to(directory)): (p.read_bytes() if p.is_file() else b"<dir>")
            for p in sorted(directory.rglob("*"))}



def _assert_refused(argv, code, needle, workdir, capsys, monkeypatch):
    monkeypatch.chdir(workdir)
    before = _snapshot(workdir)
    got, out, err = _run_main(argv, capsys)
    # a process whose cache lacks a kernel says so once before it compiles (plot-bands evaluates its sections
    # before it reads the whole directory, issue 15); that progress line is not part of the error
    lines = [line for line in err.strip().splitlines() if not line.startswith("note: compiling ")]
    assert got == code, (argv, got, err)
    assert len(lines) == 1, err
    assert lines[0].startswith("error: ") and needle in lines[0], lines[0]
    assert "Traceback" not in err and out == ""
    assert _snapshot(workdir) == before, "something was written"


# ----- evaluate: one bad --set value each (config, options, grid, algorithm, objectives, ...) ------------------

SET_CASES = [
    ("l1=1e300", "design.l1: 1e+300 is beyond"),
    ("l1=-1", "design.l1: must be > 0"),
    ("l1=.nan", "design.l1: must be finite"),
    ("l1=.inf", "design.l1: must be finite"),
    ("l1=nan", "design.l1:"),
    ("m=true", "design.m: expected a number, got true"),
    ("m=[1, 2]", "design.m:"),
    ("m={a: 1}", "design.m:"),
    ("..=1", "--set '..': empty field name"),
    ("a..b=1", "--set 'a..b': empty field name"),
    ("grid.=1", "empty field name"),
    ("noequals", "--set noequals: expected key=value"),
    ("=1", "empty key"),
    ("grid.resolution=3", "grid.resolution:"),
    ("grid.resolution=1025", "grid.resolution:"),
    ("grid.resolution=2e-1", "grid.resolution:"),
    ("grid.resolution=true", "grid.resolution:"),
    ("grid.region.x=[-1e308, 1e308]", "grid.region.x: -1e+308 is beyond"),
    ("grid.region.q=[0, 1]", "grid.region.q: not a task axis"),
    ("grid.region.x=[1, 0]", "grid.region.x:"),
    ("grid.region.x=[0, .inf]", "grid.region.x:"),
    ("mode=+*", "options.mode:"),
    ("theta1_limits=[0]", "options.theta1_limits:"),
    ("theta1_limits=[1e300, 1e301]", "options.theta1_limits[0]: 1e+300 is beyond"),
    ("theta1_limits=[1, 0]", "options.theta1_limits:"),
    ("stroke_limits=[-1e308, 1e308]", "options.stroke_limits[0]"),
    ("e=1e200", "options.e: 1e+200 is beyond"),
    ("e=yes", "options.e:"),
    ("z_min=[1]", "options.z_min:"),
    ("speed=1", "options.speed: unknown option"),
    ("algorithm.pop_size=3", "algorithm.pop_size:"),
    ("algorithm.pop_size=1e9", "algorithm.pop_size:"),
    ("algorithm.seed=-1", "algorithm.seed:"),
    ("algorithm.seed=99999999999999999999", "algorithm.seed:"),
    ("algorithm.name=cmaes", "algorithm.name:"),
    ("algorithm.prob_crossover=2", "algorithm.prob_crossover:"),
    ("algorithm.eta_mutation=-1", "algorithm.eta_mutation:"),
    ("dexterity.band_edges=[0, 0.5]", "dexterity.band_edges:"),
    ("dexterity.band_edges=[0, 0.5, 0.4, 1]", "dexterity.band_edges:"),
    ("units.length=furlong", "units.length:"),
    ("name=../x", "name:"),
    ("name=.hidden", "name:"),
    ("mechanism=nope", "mechanism: unknown mechanism 'nope'"),
    ("objectives=[]", "objectives:"),
    ("objectives=[{metric: gci}, {metric: gci}]", "objectives[1]: duplicate of objectives[0] (gci)"),
    ("objectives=[{metric: band_share, band: 1}, {metric: band_share, band: 1}]", "objectives[1]: duplicate"),
    ("objectives=[{metric: speed}]", "objectives[0].metric: unknown metric 'speed'"),
    ("objectives=[{metric: band_share, band: 9}]", "objectives[0].band:"),
    ("constraints=[{metric: gci, min: .nan}]", "constraints.0.min: must be finite"),
    ("constraints=[{metric: gci, max: .inf}]", "constraints.0.max: must be finite"),
    ("constraints=[{metric: gci, max: -.inf}]", "constraints.0.max: must be finite"),
    ("constraints=[{metric: gci}]", "constraints.0: give min, max or both"),
    ("constraints=[{metric: gci, min: 2, max: 1}]", "constraints.0: min 2.0 must not exceed max 1.0"),
    ("constraints=[{metric: task_coverage, min: 1}]", "constraints[0].metric: task_coverage needs a task"),
    ("bounds.l1=[0.5, 1e308]", "bounds.l1: 1e+308 is beyond"),
    ("bounds.l1=[2, 1]", "bounds.l1: lower bound 2.0 must be below"),
    ("bounds.l1=[.nan, 1]", "bounds.l1:"),
    ("bounds.l1=[true, 2]", "bounds.l1: expected a number, got true"),
    ("bounds.q=[0, 1]", "bounds.q: unknown parameter"),
    ("bounds.c=[-1, 1]", "bounds.c: lower bound must be > 0"),
    ("task.box.x=[0, 1]", "task.box.y: missing"),
    ("references.r.l1=1e155", "references.r: design.l1: 1e+155 is beyond"),
    ("references.r.q=1", "references.r: design.q: unknown parameter"),
    ("output.checkpoint_every=0", "output.checkpoint_every:"),
    ("colour=red", "options.colour: unknown option"),
    ("extra.key=1", "extra: unknown key"),
]


@pytest.mark.parametrize(("setting", "needle"), SET_CASES, ids=[c[0] for c in SET_CASES])
def test_evaluate_refuses_a_bad_setting(setting, needle, tmp_path, capsys, monkeypatch):
    _assert_refused(["evaluate", QUICK, "--set", setting, "--json"], 2, needle, tmp_path, capsys, monkeypatch)


# ----- config files -------------------------------------------------------------------------------------------

def _bomb(depth: int) -> str:
    lines = ["a0: &a0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
    for i in range(1, depth + 1):
        lines.append(f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]")
    return "name: q\nmechanism: 2pauu-ppap\nanchors:\n" + "\n".join("  " + ln for ln in lines) + \
        f"\noptions: {{mode: *a{depth}}}\n"


FILE_CASES = [
    # the expanded node counts of the bombs: sum over levels of 9^k lists of 9 items (computed by the loader)
    ("alias bomb depth 8", lambda: _bomb(8), "the document expands to 9.26e+08 nodes (aliases), more than"),
    ("alias bomb depth 9", lambda: _bomb(9), "the document expands to 8.34e+09 nodes (aliases), more than"),
    ("alias bomb depth 4", lambda: _bomb(4), "the document expands to 1.41e+05 nodes"),
    ("alias bomb depth 3", lambda: _bomb(3), "anchors: unknown key"),  # small enough to load: then refused
    ("duplicate top-level key", lambda: "name: a\nname: b\nmechanism: 2pauu-ppap\n", "line 2: duplicate key 'name'"),
    ("duplicate nested key", lambda: "name: a\nmechanism: 2pauu-ppap\ndesign: {l1: 1, l1: 2}\n",
     "line 3: duplicate key 'l1'"),
    ("python tag", lambda: "!!python/object/apply:os.system ['true']\n", "invalid YAML"),
    ("top-level list", lambda: "- name: a\n", "config: top level must be a mapping"),
    ("scalar document", lambda: "just text\n", "config: top level must be a mapping"),
    ("empty document", lambda: "", "config: top level must be a mapping"),
    ("unclosed bracket", lambda: "name: [a\n", "invalid YAML (line 2)"),
    ("tab indentation", lambda: "name: a\n\tmechanism: x\n", "invalid YAML"),
    ("deep nesting", lambda: "name: a\nx: " + "[" * 5000 + "]" * 5000 + "\n", "nested too deeply"),
    ("oversized file", lambda: "name: a\n# " + "x" * 1_100_000 + "\n", "more than the 1000000 a config may have"),
    ("float in option 2e-1 accepted, then the mode refused",
     lambda: "name: a\nmechanism: 2pauu-ppap\noptions: {z_min: 2e-1, mode: bad}\n", "options.mode:"),
    ("boolean design value", lambda: "name: a\nmechanism: 2pauu-ppap\ndesign: {m: yes}\n",
     "design.m: expected a number, got true"),
    ("missing mechanism", lambda: "name: a\n", "mechanism: Field required"),
]


@pytest.mark.parametrize(("label", "text", "needle"), FILE_CASES, ids=[c[0] for c in FILE_CASES])
def test_optimize_refuses_a_bad_config_file(label, text, needle, tmp_path, capsys, monkeypatch):
    cfg = tmp_path / "c.yaml"
    cfg.write_text(text(), encoding="utf-8")
    _assert_refused(["optimize", cfg, "--out", tmp_path / "out", "-q"], 2, needle, tmp_path, capsys, monkeypatch)


def test_a_large_quoted_value_keeps_the_message_short(tmp_path, capsys, monkeypatch):
    """An alias-expanded option value (6 561 strings) is quoted in the error, cut to a short line."""
    lines = ["name: q", "mechanism: 2pauu-ppap", "options:", "  mode: &a2 [&a1 [&a0 [" + ", ".join(["lol"] * 9) + "]"
             + ", *a0" * 8 + "]" + ", *a1" * 8 + "]"]
    (tmp_path / "c.yaml").write_text("\n".join(lines) + "\n")
    _assert_refused(["evaluate", "c.yaml"], 2, "options.mode: must be one of", tmp_path, capsys, monkeypatch)
    _, _, err = _run_main(["evaluate", "c.yaml"], capsys)
    assert len(err) < 450 and err.rstrip().endswith("...")


def test_unreadable_bytes_and_directories(tmp_path, capsys, monkeypatch):
    (tmp_path / "bin.yaml").write_bytes(b"name: \xff\xfe\n")
    (tmp_path / "dir.yaml").mkdir()
    _assert_refused(["evaluate", "bin.yaml"], 2, "bin.yaml: cannot read (UnicodeDecodeError)", tmp_path, capsys,
                    monkeypatch)
    # a directory is read as a results directory (evaluate takes one with --design)
    _assert_refused(["evaluate", "dir.yaml"], 2, "dir.yaml: not a scalesynth results directory", tmp_path, capsys,
                    monkeypatch)
    _assert_refused(["evaluate", "missing.yaml"], 2, "missing.yaml: no such config file", tmp_path, capsys,
                    monkeypatch)


# ----- optimize flags -----------------------------------------------------------------------------------------

OPTIMIZE_CASES = [
    (["--seed", "99999999999999999999"], 2, "Invalid value for '--seed'"),
    (["--seed", "-1"], 2, "Invalid value for '--seed'"),
    (["--seed", "2e-1"], 2, "Invalid value for '--seed'"),
    (["--bogus"], 2, "No such option: --bogus"),
    (["--set", "algorithm.pop_size=100000"], 2, "algorithm.pop_size: pymoo's duplicate-elimination"),
    (["--set", "bounds={}"], 2, "bounds: at least one design variable needs bounds"),
    (["--set", "algorithm.n_gen=0"], 2, "algorithm.n_gen:"),
    (["--set", "output.dir=1"], 2, "output.dir:"),
]


@pytest.mark.parametrize(("flags", "code", "needle"), OPTIMIZE_CASES, ids=[" ".join(c[0]) for c in OPTIMIZE_CASES])
def test_optimize_refuses_bad_flags(flags, code, needle, tmp_path, capsys, monkeypatch):
    _assert_refused(["optimize", QUICK, "--out", tmp_path / "out", "-q", *flags], code, needle, tmp_path, capsys,
                    monkeypatch)


def test_optimize_into_a_file_is_exit_2(tmp_path, capsys, monkeypatch):
    (tmp_path / "f").write_text("x")  # a bad --out, refused before any work (issue 27)
    _assert_refused(["optimize", QUICK, "--out", tmp_path / "f", "-q"], 2, "cannot create output directory",
                    tmp_path, capsys, monkeypatch)


# ----- damaged checkpoints (resume) ---------------------------------------------------------------------------

class Foreign:  # a pickled object of a class that does not exist at load time
    pass


def _foreign_pickle() -> bytes:
    """Protocol 0 names the class's module in plain text: point it at a module that does not exist."""
    return pickle.dumps(Foreign(), protocol=0).replace(Foreign.__module__.encode(), b"no_such_module_xyz")


CHECKPOINT_CASES = [
    ("empty", lambda: b"", "empty or truncated checkpoint"),
    ("truncated", lambda: pickle.dumps({"algorithm": 1, "history": [2] * 100})[:40], "checkpoint"),
    ("garbage", lambda: b"not a pickle at all", "not a scalesynth checkpoint"),
    ("foreign class", _foreign_pickle, "not a scalesynth checkpoint (ModuleNotFoundError"),
    ("wrong keys", lambda: pickle.dumps({"a": 1}), "not a scalesynth checkpoint (unexpected content"),
    ("a list", lambda: pickle.dumps([1, 2]), "not a scalesynth checkpoint (unexpected content"),
    ("no algorithm", lambda: pickle.dumps({k: 1 for k in ("algorithm", "history", "elapsed", "digest", "started")}),
     "not a scalesynth checkpoint (no NSGA-II state"),
]


@pytest.mark.parametrize(("label", "content", "needle"), CHECKPOINT_CASES, ids=[c[0] for c in CHECKPOINT_CASES])
def test_resume_refuses_a_damaged_checkpoint(label, content, needle, tmp_path, capsys, monkeypatch):
    work = tmp_path / "w"
    work.mkdir()
    cfg = work / "c.yaml"
    cfg.write_text(yaml.safe_dump(SMALL))
    staged = staging_path(work / "out")
    staged.mkdir()
    (staged / "checkpoint.pkl").write_bytes(content())
    _assert_refused(["optimize", cfg, "--out", work / "out", "-q", "--resume", "--no-plots"], 2, needle, work,
                    capsys, monkeypatch)


# ----- other commands -----------------------------------------------------------------------------------------

COMMAND_CASES = [
    (["evaluate", QUICK, "--resolution", "2e-1"], 2, "Invalid value for '--resolution'"),
    (["evaluate", QUICK, "--resolution", "3"], 2, "grid.resolution:"),
    (["evaluate"], 2, "Missing argument"),
    (["no-such-command"], 2, "No such command 'no-such-command'"),
    (["ik", "2pauu-ppap", "--pose=1e308,0,0"], 2, "--pose: values beyond +-1e+12"),
    (["ik", "2pauu-ppap", "--pose=nan,0,0"], 2, "--pose: expected 3 finite"),
    (["ik", "2pauu-ppap", "--pose=1,2"], 2, "--pose: expected 3 finite"),
    (["ik", "2pauu-ppap", "--pose=a,b,c"], 2, "--pose: expected 3 comma-separated numbers"),
    (["ik", "2pauu-ppap", "--pose=" + ",".join(["1"] * 10000)], 2, "..."),
    (["ik", "nope", "--pose=0,0,0"], 2, "unknown mechanism 'nope'"),
    (["ik", "2pauu-ppap", "--pose=0,0,0", "--set", "l1=1e300"], 2, "design.l1: 1e+300 is beyond"),
    (["ik", "2pauu-ppap", "--pose=0,0,0", "--set", "grid.resolution=8"], 2, "only design parameters and options"),
    (["ik", "2pauu-ppap"], 2, "Missing option '--pose'"),
    (["fk", "2pauu-ppap", "--inputs=1e308,0,0"], 2, "--inputs: values beyond +-1e+12"),
    (["fk", "2pauu-ppap", "--inputs=1,2"], 2, "--inputs: expected 3 finite"),
    (["fk", "planar-fivebar", "--inputs=0,0", "--set", "l1=1e155"], 2, "design.l1: 1e+155 is beyond"),
    (["mobility", "2pauu-ppap", "--samples", "0"], 2, "--samples: expected an integer in [1, 10000]"),
    (["mobility", "2pauu-ppap", "--samples", "100000000"], 2, "--samples: expected an integer in [1, 10000]"),
    (["mobility", "nope"], 2, "unknown mechanism 'nope'"),
    (["mobility", "2pauu-ppap", "--set", "l1=-1"], 2, "design.l1: must be > 0"),
    (["plot-task", FIVEBAR, "--resolution", "100000"], 2, "--resolution: a 100000 x 100000 LCI map needs about"),
    (["plot-task", FIVEBAR, "--resolution", "1"], 2, "--resolution: need at least 2"),
    (["plot-task", QUICK], 2, "mechanism: plot-task needs a planar mechanism"),
    (["plot-task", FIVEBAR, "--set", "l1=1e155"], 2, "design.l1: 1e+155 is beyond"),
    (["drives", QUICK], 2, "mechanism: drives needs pprs-rprs"),
    (["drives", PPRS, "--side", "-1"], 2, "--side: must be a positive length"),
    (["drives", PPRS, "--center", "a,b"], 2, "--center: expected x,y"),
    (["drives", PPRS, "--samples", "1"], 2, "--samples: need 9 to 100001 samples"),
    (["drives", PPRS, "--z", "nan"], 2, "--z: must be finite"),
    (["batch", QUICK, "--scheduler", "not a url", "--out", "b"], 2, "'not a url': expected SCHEME://HOST:PORT"),
    (["batch", QUICK, "--scheduler", "tcp://host:99999", "--out", "b"], 2, "port '99999' is not a number in 1..65535"),
    (["batch", QUICK, "--seeds", "0", "--out", "b"], 2, "--seeds: must be at least 1"),
    (["batch", QUICK, "--set", "l1=1e300", "--out", "b"], 2, "design.l1: 1e+300 is beyond"),
    (["select", "no-such-dir"], 2, "not a scalesynth results directory"),
    (["plot-front", "no-such-dir"], 2, "not a scalesynth results directory"),
    (["reproduce", "no-such-dir"], 2, "not a finished scalesynth run"),
]


@pytest.mark.parametrize(("argv", "code", "needle"), COMMAND_CASES, ids=[" ".join(c[0])[:60] for c in COMMAND_CASES])
def test_commands_refuse_bad_input(argv, code, needle, tmp_path, capsys, monkeypatch):
    _assert_refused(argv, code, needle, tmp_path, capsys, monkeypatch)


# ----- damaged results directories ----------------------------------------------------------------------------

@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    out = tmp_path_factory.mktemp("finished") / "run"
    run(config_from_dict(copy.deepcopy(SMALL)), out, plots=False)
    return out


def _edit_csv(name, edit):
    def damage(run_dir: Path):
        lines = (run_dir / name).read_text().splitlines()
        (run_dir / name).write_text("\n".join(edit(lines)) + "\n")
    return damage


def _write(name, text):
    def damage(run_dir: Path):
        if text is None:
            (run_dir / name).unlink()
        else:
            (run_dir / name).write_text(text)
    return damage


def _drop_column(name, column):
    def edit(lines):
        header = lines[0].split(",")
        k = header.index(column)
        return [",".join(v for i, v in enumerate(line.split(",")) if i != k) for line in lines]
    return _edit_csv(name, edit)


def _set_cell(name, column, value):
    def edit(lines):
        k = lines[0].split(",").index(column)
        row = lines[1].split(",")
        row[k] = value
        return [lines[0], ",".join(row), *lines[2:]]
    return _edit_csv(name, edit)


LOAD_RUN_DAMAGE = [
    ("empty pareto.csv", _write("pareto.csv", ""), "pareto.csv: not a scalesynth results table (EmptyDataError)"),
    ("non-numeric pareto.csv", _set_cell("pareto.csv", "gci", "abc"), "pareto.csv: column 'gci', row 1: not a finite"),
    ("NaN in pareto.csv", _set_cell("pareto.csv", "volume_m3", "nan"), "column 'volume_m3', row 1: not a finite"),
    ("missing column", _drop_column("pareto.csv", "gci"), "pareto.csv: column 'gci' is missing"),
    ("missing design column", _drop_column("pareto.csv", "l1"), "pareto.csv: column 'l1' is missing"),
    ("binary pareto.csv", lambda d: (d / "pareto.csv").write_bytes(b"\xff\xfe\x00\x01"),
     "pareto.csv: not a scalesynth"),
    ("missing config.yaml", _write("config.yaml", None), "missing config.yaml"),
    ("bad config.yaml", _write("config.yaml", "name: [x\n"), "config.yaml: invalid YAML"),
    ("invalid config.yaml", _write("config.yaml", "name: x\nmechanism: nope\n"), "mechanism: unknown mechanism"),
    ("empty history.csv", _write("history.csv", "generation,evaluations,hypervolume\n"), "history.csv: no generations"),
    ("history without hypervolume", _drop_column("history.csv", "hypervolume"), "column 'hypervolume' is missing"),
]


@pytest.mark.parametrize("command", ["select", "plot-front", "plot-bands"])
@pytest.mark.parametrize(("label", "damage", "needle"), LOAD_RUN_DAMAGE, ids=[c[0] for c in LOAD_RUN_DAMAGE])
def test_damaged_results_are_refused(command, label, damage, needle, finished, tmp_path, capsys, monkeypatch):
    run_dir = tmp_path / "run"
    shutil.copytree(finished, run_dir)
    damage(run_dir)
    _assert_refused([command, "run"], 2, needle, tmp_path, capsys, monkeypatch)


MANIFEST_DAMAGE = [
    ("manifest not JSON", _write("manifest.json", "{not json"), "manifest.json: not valid JSON (JSONDecodeError)"),
    ("manifest a list", _write("manifest.json", "[1, 2]"), "manifest.json: expected a JSON object, got list"),
    ("manifest without config", _write("manifest.json", '{"status": "finished", "hypervolume": 1, '
                                                        '"wall_seconds": 1}'), "field 'config' is missing"),
    ("manifest with a bad config", _write("manifest.json", '{"status": "finished", "hypervolume": 1, '
                                                           '"wall_seconds": 1, "config": {"name": "x"}}'),
     "manifest.json: config: mechanism: Field required"),
    ("manifest empty", _write("manifest.json", ""), "manifest.json: not valid JSON"),
    ("pareto.csv empty", _write("pareto.csv", ""), "pareto.csv: not a scalesynth results table"),
    ("history without hypervolume", _drop_column("history.csv", "hypervolume"), "column 'hypervolume' is missing"),
    ("no pareto.csv", _write("pareto.csv", None), "not a scalesynth results directory (missing pareto.csv)"),
]


@pytest.mark.parametrize(("label", "damage", "needle"), MANIFEST_DAMAGE, ids=[c[0] for c in MANIFEST_DAMAGE])
def test_reproduce_refuses_damaged_results(label, damage, needle, finished, tmp_path, capsys, monkeypatch):
    run_dir = tmp_path / "run"
    shutil.copytree(finished, run_dir)
    damage(run_dir)
    _assert_refused(["reproduce", "run", "--out", tmp_path / "again"], 2, needle, tmp_path, capsys, monkeypatch)


@pytest.mark.parametrize("out", ["run", "run/sub", "run/../run"])
def test_reproduce_refuses_to_overwrite_the_run_it_checks(out, finished, tmp_path, capsys, monkeypatch):
    shutil.copytree(finished, tmp_path / "run")
    _assert_refused(["reproduce", "run", "--out", out], 2, "--out:", tmp_path, capsys, monkeypatch)


def test_select_with_bad_method_and_weights(finished, tmp_path, capsys, monkeypatch):
    shutil.copytree(finished, tmp_path / "run")
    _assert_refused(["select", "run", "--method", "nope"], 2, "--method: must be one of", tmp_path, capsys,
                    monkeypatch)
    _assert_refused(["select", "run", "--method", "weights", "--weights", "1,x"], 2, "--weights: expected",
                    tmp_path, capsys, monkeypatch)
    _assert_refused(["select", "run", "--method", "weights", "--weights", "1,2,3"], 2, "--weights: need 2",
                    tmp_path, capsys, monkeypatch)


def test_plot_task_write_error_names_the_target(tmp_path, capsys, monkeypatch):
    import errno
    import os

    real_replace = os.replace

    def full(src, dst, *a, **k):
        if str(dst).endswith("task.png"):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(dst))
        return real_replace(src, dst, *a, **k)

    monkeypatch.setattr(os, "replace", full)
    (tmp_path / "plots").mkdir()
    target = tmp_path / "plots" / "task.png"
    _assert_refused(["plot-task", FIVEBAR, "--out", target, "--resolution", "8"], 1,
                    f"{target}: cannot write (No space left on device)", tmp_path, capsys, monkeypatch)
