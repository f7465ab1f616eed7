"""A user's files are sacred (issue 27): a run, `cycle`, `show`, `compare` and `select` write only into a directory
that is new, empty or their own (recognised by its manifest), refuse anything else before any work (exit 2, one
line naming --out) unless --force, and even with --force touch no file they do not write; `--out` is checked
before computing; `cycle`, `show` and `compare` stage their directory and swap it in whole, so a failure or an
interrupt leaves the previous output exactly as it was.

Every command runs through the real entry point (``cli.main``) in process; "no work" is asserted by making the
first expensive step fail loudly if it is reached."""

import copy
import errno
import json
import os
from pathlib import Path

import pytest
import yaml

from cli_main import run_main as _main
from sacred_checks import fail_on, refused, snapshot
from scalesynth import rundir
from scalesynth.config import config_from_dict
from scalesynth.optimize import run

from conftest import ROOT, SMALL

QUICK = ROOT / "configs" / "quick.yaml"
FIVEBAR = ROOT / "configs" / "fivebar_packing.yaml"  # planar five-bar with a cycle section: the cheapest views


def _no_work(monkeypatch):
    """Make the expensive step of every command fail loudly: a refusal must come before it."""
    def reached(*a, **k):
        raise AssertionError("the command computed before checking --out")

    from scalesynth import optimize, show
    from scalesynth.cycle import analysis

    monkeypatch.setattr(optimize, "_run_generations", reached)
    monkeypatch.setattr(analysis, "analyse", reached)
    monkeypatch.setattr(show.wv, "sample_fields", reached)


def _users_directory(path: Path) -> Path:
    """A directory of the user's that happens to hold names scalesynth writes (the issue's `--out .` case)."""
    path.mkdir(parents=True, exist_ok=True)
    (path / "config.yaml").write_text("# my config, with comments\nname: mine\n")
    (path / "report.md").write_text("# my report\n")
    (path / "plots").mkdir(exist_ok=True)
    (path / "plots" / "front.png").write_bytes(b"my own figure")
    (path / "plots" / "mine.png").write_bytes(b"another of mine")
    (path / "selected_knee.yaml").write_text("name: my selection\n")
    (path / "cycle.csv").write_text("t\n0\n")
    (path / "show.json").write_text('{"mine": true}\n')
    (path / "compare.csv").write_text("a,b\n1,2\n")
    return path


# ----- a directory that is not the command's own: refused before any work --------------------------------------

def test_optimize_into_the_current_directory_keeps_the_users_files(tmp_path, capsys, monkeypatch):
    """The issue's first case: `optimize config.yaml --out .` in a directory holding the user's config.yaml,
    report.md and plots/ overwrote the config and deleted the rest; now exit 2 before any work, nothing touched."""
    work = _users_directory(tmp_path / "w")
    (work / "config.yaml").write_text(QUICK.read_text())  # the user's own config, run from where it lives
    _no_work(monkeypatch)
    line = refused(["optimize", "config.yaml", "--out", ".", "-q"], "not a scalesynth run directory", work, capsys,
                   monkeypatch)
    assert "--force" in line and "manifest.json" in line


@pytest.mark.parametrize(("command", "needle"), [
    (["optimize", QUICK, "-q"], "not a scalesynth run directory (no manifest.json)"),
    (["cycle", FIVEBAR], "not a scalesynth cycle directory (no cycle.json)"),
    (["show", FIVEBAR, "--resolution", "8"], "not a scalesynth show directory (no show.json)"),
    (["compare", "r1", "r2"], "not a scalesynth compare directory (no compare.json)"),
], ids=["optimize", "cycle", "show", "compare"])
def test_a_foreign_directory_is_refused_before_any_work(command, needle, tmp_path, capsys, monkeypatch):
    """A non-empty directory without the command's manifest (the user's, or another command's output) is refused
    with exit 2 and one line; before, each command replaced or deleted the files it found there."""
    _users_directory(tmp_path / "mine")
    _no_work(monkeypatch)
    refused([*command, "--out", "mine"], needle, tmp_path, capsys, monkeypatch)


def test_another_commands_output_is_not_own(tmp_path, capsys, monkeypatch):
    """A cycle directory is not a show directory, nor a run directory: each command knows only its manifest."""
    other = tmp_path / "c"
    other.mkdir()
    (other / "cycle.json").write_text(json.dumps({"cycle": {}, "metrics": {}, "units": {}, "files": []}))
    _no_work(monkeypatch)
    refused(["show", FIVEBAR, "--resolution", "8", "--out", "c"], "not a scalesynth show directory", tmp_path, capsys,
            monkeypatch)
    refused(["optimize", QUICK, "-q", "--out", "c"], "not a scalesynth run directory", tmp_path, capsys, monkeypatch)


def _bad_out(tmp_path: Path) -> dict[str, tuple[Path, str]]:
    (tmp_path / "file").write_text("a file\n")
    os.symlink("loop", tmp_path / "loop")
    os.symlink("nowhere", tmp_path / "dangling")
    return {
        "/proc": (Path("/proc"), "is on the proc pseudo file system"),
        "under /proc": (Path("/proc/scalesynth-out"), "is on the proc pseudo file system"),
        "/sys": (Path("/sys/scalesynth-out"), "is on the sysfs pseudo file system"),
        "link loop": (tmp_path / "loop", "symbolic link loop"),
        "under a link loop": (tmp_path / "loop" / "run", "symbolic link loop"),
        "dangling link": (tmp_path / "dangling", "is a dangling symbolic link"),
        "under a dangling link": (tmp_path / "dangling" / "run", "is a dangling symbolic link"),
        "a file": (tmp_path / "file", "a file of that name exists"),
        "under a file": (tmp_path / "file" / "run", "a part of the path is a file"),
    }


BAD_OUT = ["/proc", "under /proc", "/sys", "link loop", "under a link loop", "dangling link",
           "under a dangling link", "a file", "under a file"]


@pytest.mark.parametrize("case", BAD_OUT)
@pytest.mark.parametrize("command", [["optimize", QUICK, "-q"], ["cycle", FIVEBAR],
                                     ["show", FIVEBAR, "--resolution", "8"]], ids=["optimize", "cycle", "show"])
def test_a_bad_out_is_refused_before_computing(command, case, tmp_path, capsys, monkeypatch):
    """`--out /proc` ran the whole search and then copied its files into /.proc.staging; a link loop or a dangling
    link failed only after the run. Now each is exit 2 with one line before any work, --force or not."""
    if ("proc" in case and not Path("/proc/self").exists()) or ("sys" in case and not Path("/sys/kernel").exists()):
        pytest.skip("no /proc or /sys here")
    work = tmp_path / "w"
    work.mkdir()
    target, needle = _bad_out(work)[case]
    _no_work(monkeypatch)
    for force in ([], ["--force"]):
        refused([*command, "--out", target, *force], needle, work, capsys, monkeypatch)


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write anywhere: the mode restricts nothing")
def test_an_unwritable_parent_is_refused_before_computing(tmp_path, capsys, monkeypatch):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o555)
    try:
        _no_work(monkeypatch)
        refused(["optimize", QUICK, "-q", "--out", locked / "run"], "is not writable", tmp_path, capsys,
                monkeypatch)
    finally:
        locked.chmod(0o755)


# ----- new, empty, own: accepted; --force: only the command's own files change ----------------------------------

def _cycle(capsys, *args) -> int:
    code, _, err = _main(["cycle", FIVEBAR, *args], capsys)
    assert code == 0 or "error" in err, err
    return code


def test_cycle_reuses_its_own_directory_and_keeps_the_users_notes(tmp_path, capsys):
    """An empty directory and a cycle directory are accepted without --force; a second cycle replaces the first's
    files (the payload doubled changes cycle.csv) and carries the user's note over."""
    out = tmp_path / "c"
    out.mkdir()
    assert _cycle(capsys, "--out", out) == 0
    first = snapshot(out)
    assert sorted(first) == ["actuators.png", "cycle.csv", "cycle.json", "path.png", "quality.png"]
    files = json.loads((out / "cycle.json").read_text())["files"]
    assert sorted(files) == sorted(first)  # the manifest lists its directory
    (out / "notes.txt").write_text("mine\n")
    assert _cycle(capsys, "--out", out, "--set", "cycle.payload=2.0") == 0
    assert (out / "notes.txt").read_text() == "mine\n"
    assert (out / "cycle.csv").read_bytes() != first["cycle.csv"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c"]  # no lock or staging directory left


def test_force_into_a_foreign_directory_touches_only_the_files_it_writes(tmp_path, capsys):
    """`cycle --force` into the user's directory: cycle.csv (a name cycle writes) is replaced, every other file,
    plots/front.png and the user's config.yaml and report.md included, stays byte for byte."""
    mine = _users_directory(tmp_path / "mine")
    before = snapshot(mine)
    assert _cycle(capsys, "--out", mine, "--force") == 0
    after = snapshot(mine)
    written = {"actuators.png", "cycle.csv", "cycle.json", "path.png", "quality.png"}
    assert {k: v for k, v in after.items() if k not in written} == {k: v for k, v in before.items()
                                                                     if k not in written}
    assert after["cycle.csv"] != before["cycle.csv"] and written <= set(after)
    # the directory now holds a cycle output: a second cycle needs no --force and still keeps the user's files
    assert _cycle(capsys, "--out", mine, "--set", "cycle.payload=2.0") == 0
    again = snapshot(mine)
    assert {k: v for k, v in again.items() if k not in written} == {k: v for k, v in before.items()
                                                                     if k not in written}


# ----- staged and swapped whole: a failure or an interrupt leaves the previous output as it was -----------------

@pytest.mark.parametrize(("failure", "code", "needle"), [
    (OSError(errno.ENOSPC, os.strerror(errno.ENOSPC)), 1, "quality.png: cannot write (No space left on device)"),
    (KeyboardInterrupt(), 1, "interrupted"),  # what SIGINT raises
], ids=["disk full", "SIGINT"])
def test_a_failed_cycle_leaves_the_previous_one_whole(failure, code, needle, tmp_path, capsys, monkeypatch):
    """Before, cycle wrote in place: a failure after cycle.csv (a full disk at the last plot, an interrupt) left a
    new cycle.csv beside the old cycle.json and plots. Now the directory is byte-identical to the previous cycle."""
    out = tmp_path / "c"
    assert _cycle(capsys, "--out", out) == 0
    (out / "notes.txt").write_text("mine\n")
    before = snapshot(tmp_path)
    fail_on(monkeypatch, "quality.png", failure)
    got, _, err = _main(["cycle", FIVEBAR, "--out", out, "--set", "cycle.payload=2.0"], capsys)
    assert got == code and needle in err and len(err.strip().splitlines()) == 1, err
    assert snapshot(tmp_path) == before  # the old cycle, whole, and no staging directory left beside it


@pytest.mark.parametrize(("failure", "code", "needle"), [
    (OSError(errno.EIO, os.strerror(errno.EIO)), 1, "robot.png: cannot write (Input/output error)"),
    (KeyboardInterrupt(), 1, "interrupted"),
], ids=["I/O error", "SIGINT"])
def test_a_failed_show_leaves_the_previous_one_whole(failure, code, needle, tmp_path, capsys, monkeypatch):
    """An I/O error in show used to leave new sections beside an old show.json (the planar five-bar writes
    sections.png, then robot.png, then show.json)."""
    out = tmp_path / "s"
    got, _, err = _main(["show", FIVEBAR, "--resolution", "12", "--out", out], capsys)
    assert got == 0, err
    before = snapshot(tmp_path)
    fail_on(monkeypatch, "robot.png", failure)
    got, _, err = _main(["show", FIVEBAR, "--resolution", "16", "--field", "lci", "--out", out], capsys)
    assert got == code and needle in err and len(err.strip().splitlines()) == 1, err
    assert snapshot(tmp_path) == before


# os.replace is the last step of every file's atomic write: signal ourselves there, once `name` is complete
_SIGNAL_AT = """
import os, signal, sys
real = os.replace
def replace(src, dst, *a, **k):
    if os.path.basename(dst) == sys.argv[1]:
        os.kill(os.getpid(), getattr(signal, sys.argv[2]))
    return real(src, dst, *a, **k)
os.replace = replace
from scalesynth.cli import main
main(sys.argv[3:])
"""


@pytest.mark.parametrize(("first", "second", "name"), [
    (["cycle", FIVEBAR], ["cycle", FIVEBAR, "--set", "cycle.payload=2.0"], "path.png"),
    (["show", FIVEBAR, "--resolution", "12"], ["show", FIVEBAR, "--resolution", "16"], "robot.png"),
], ids=["cycle", "show"])
@pytest.mark.parametrize("sig", ["SIGTERM", "SIGINT"])
def test_a_signal_mid_write_leaves_the_previous_output_whole(first, second, name, sig, tmp_path, capsys):
    """A real process signalled while it writes its files (after cycle.csv, or after show's sections): the target
    is byte-identical to the previous output; SIGINT ends with exit 1 and removes its staging directory, SIGTERM
    kills the process and the next run discards what it left."""
    import signal
    import subprocess
    import sys

    out = tmp_path / "o"
    got, _, err = _main([*first, "--out", out], capsys)
    assert got == 0, err
    before = snapshot(out)
    env = dict(os.environ, MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, "-c", _SIGNAL_AT, name, sig, *map(str, second), "--out", str(out)],
                          capture_output=True, text=True, env=env, timeout=600)
    if sig == "SIGTERM":
        assert proc.returncode == -signal.SIGTERM, proc.stderr
    else:
        assert proc.returncode == 1 and proc.stderr.strip() == "error: interrupted", proc.stderr
        assert not rundir.staging_path(out).exists()
    assert snapshot(out) == before
    got, _, err = _main([*second, "--out", out], capsys)  # the next run: whole, nothing of the killed one left
    assert got == 0, err
    assert not rundir.staging_path(out).exists() and snapshot(out) != before


def test_show_reuses_its_own_directory_and_drops_the_old_views(tmp_path, capsys):
    """A second show in another format replaces the first's views (png) whole: no stale sections.png beside the
    new sections.svg; the user's note stays."""
    out = tmp_path / "s"
    assert _main(["show", FIVEBAR, "--resolution", "12", "--out", out], capsys)[0] == 0
    assert (out / "sections.png").is_file()
    (out / "notes.txt").write_text("mine\n")
    got, _, err = _main(["show", FIVEBAR, "--resolution", "12", "--format", "svg", "--out", out], capsys)
    assert got == 0, err
    info = json.loads((out / "show.json").read_text())
    assert sorted(p.name for p in out.iterdir()) == sorted([*info["files"], "show.json", "notes.txt"])
    assert "sections.svg" in info["files"] and not (out / "sections.png").exists()


# ----- compare and select ---------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def two_runs(tmp_path_factory):
    base = tmp_path_factory.mktemp("runs")
    data = copy.deepcopy(SMALL)
    data["algorithm"] = {**data["algorithm"], "n_gen": 2}
    return [run(config_from_dict(data), base / f"r{seed}", seed=seed, plots=False).out_dir for seed in (1, 2)]


def test_compare_writes_its_manifest_reuses_its_directory_and_leaves_it_whole_on_failure(two_runs, tmp_path, capsys,
                                                                                          monkeypatch):
    out = tmp_path / "cmp"
    args = ["compare", *two_runs, "--out", out]
    assert _main(args, capsys)[0] == 0
    manifest = json.loads((out / "compare.json").read_text())
    assert manifest["files"] == ["compare.csv", "compare.png", "compare.json"]
    assert manifest["runs"] == [str(d) for d in two_runs]
    assert _main([*args, "--format", "svg"], capsys)[0] == 0  # its own directory: no --force needed
    assert sorted(p.name for p in out.iterdir()) == ["compare.csv", "compare.json", "compare.svg"]
    before = snapshot(tmp_path)
    fail_on(monkeypatch, "compare.png", OSError(errno.ENOSPC, os.strerror(errno.ENOSPC)))
    got, _, err = _main(args, capsys)
    assert got == 1 and "compare.png: cannot write" in err, err
    assert snapshot(tmp_path) == before


def test_select_replaces_only_its_own_files(two_runs, tmp_path, capsys, monkeypatch):
    """`select --out FILE` overwrote any file; now a file select did not write is refused (exit 2) unless --force,
    and one it wrote (its first line says so) is replaced."""
    monkeypatch.chdir(tmp_path)
    mine = tmp_path / "design.yaml"
    mine.write_text("# my hand-made design\nname: mine\n")
    refused(["select", two_runs[0], "--out", mine], "was not written by select", tmp_path, capsys, monkeypatch)
    refused(["select", two_runs[0], "--out", tmp_path], "is a directory", tmp_path, capsys, monkeypatch)
    got, _, err = _main(["select", two_runs[0], "--out", mine, "--force"], capsys)
    assert got == 0, err
    written = yaml.safe_load(mine.read_text())
    assert written["name"] == "small-knee"
    got, _, err = _main(["select", two_runs[1], "--out", mine, "--method", "balanced"], capsys)  # its own now
    assert got == 0, err
    assert yaml.safe_load(mine.read_text())["name"] == "small-balanced"


# ----- the staging machinery itself ----------------------------------------------------------------------------

def _fake_run(directory: Path, files: dict[str, str], listed: bool = True) -> None:
    """A run directory as optimize leaves it (a manifest listing its files, or an older one without the list)."""
    for name, text in files.items():
        (directory / name).parent.mkdir(parents=True, exist_ok=True)
        (directory / name).write_text(text)
    manifest = {"config": {}, "status": "finished"}
    if listed:
        manifest["files"] = [*files, "manifest.json"]
    (directory / "manifest.json").write_text(json.dumps(manifest))


@pytest.mark.parametrize("listed", [True, False], ids=["manifest lists files", "older manifest"])
def test_the_swap_replaces_the_previous_outputs_files_and_carries_the_users_down_to_single_files(tmp_path, listed):
    """The next run replaces what the previous one wrote (report.html and bands/ too: a run without plots no
    longer keeps the old run's report.html beside its new pareto.csv) and keeps the user's files, even inside
    plots/. An older manifest without "files" owns plots/ whole, as before."""
    out = tmp_path / "run"
    out.mkdir()
    _fake_run(out, {"pareto.csv": "old\n", "report.html": "old\n", "bands/pareto_band0.csv": "old\n",
                    "plots/front.png": "old\n"}, listed)
    (out / "plots" / "mine.png").write_text("mine\n")
    (out / "notes").mkdir()
    (out / "notes" / "n.txt").write_text("mine\n")
    with rundir.claim(out) as rd:
        work = rd.fresh()
        _fake_run(work, {"pareto.csv": "new\n"})
        rd.commit()
    got = snapshot(out)
    expected = {"pareto.csv": b"new\n", "notes": b"<dir>", "notes/n.txt": b"mine\n"}
    if listed:
        expected.update({"plots": b"<dir>", "plots/mine.png": b"mine\n"})
    assert {k: v for k, v in got.items() if k != "manifest.json"} == expected


def test_force_merge_refuses_a_type_clash_before_moving_anything(tmp_path):
    """--force into a directory where a name the command writes is a directory of the user's: nothing moves."""
    from scalesynth.errors import RunError

    out = tmp_path / "mine"
    (out / "pareto.csv").mkdir(parents=True)
    (out / "keep.txt").write_text("mine\n")
    before = snapshot(out)
    with rundir.claim(out, force=True) as rd:
        assert rd.merge
        work = rd.fresh()
        _fake_run(work, {"history.csv": "new\n", "pareto.csv": "new\n"})
        with pytest.raises(RunError, match="pareto.csv: cannot replace a directory"):
            rd.commit()
    assert snapshot(out) == before


def test_resuming_a_forced_run_needs_force_again_and_keeps_the_users_files(tmp_path):
    """A run forced into the user's directory and stopped: resuming it without --force is refused (the swap would
    drop the user's report.md and plots/, names a run owns), with --force it moves only its own files in."""
    from scalesynth.errors import ConfigError, RunError

    mine = _users_directory(tmp_path / "mine")
    before = snapshot(mine)
    cfg = config_from_dict(copy.deepcopy(SMALL))
    with pytest.raises(RunError, match="stopped after 2 generations"):
        run(cfg, mine, plots=False, stop_after=2, force=True)
    with pytest.raises(ConfigError, match="not a scalesynth run directory"):
        run(cfg, mine, plots=False, resume=True)
    assert snapshot(mine) == before
    run(cfg, mine, plots=False, resume=True, force=True)
    after = snapshot(mine)
    written = set(json.loads(after["manifest.json"])["files"])
    assert written == {"pareto.csv", "population.csv", "history.csv", "config.yaml", "manifest.json"}
    assert {k: v for k, v in after.items() if k not in written} == {k: v for k, v in before.items()
                                                                     if k not in written}
