"""A user's files are sacred (issue 27), for the commands that used to write in place: `plot-front`, `plot-bands`,
`plot-task` and `drives` check --out before computing, refuse a foreign non-empty directory (exit 2, one line)
unless --force, touch with --force only the files they write, and stage their directory and swap it in whole (a
failure leaves the previous output exactly as it was). Figures written into a run's own plots/ are listed in the
run's manifest, so the next run on that directory replaces them. `batch` refuses a task directory that is not a
run's before any task runs, and takes --force.

Commands run through the real entry point (``cli.main``) in process; "no work" is asserted by making the first
expensive step fail loudly if it is reached."""

import errno
import json
import os
from pathlib import Path

import pytest

from cli_main import error_lines
from cli_main import run_main as _main
from sacred_checks import fail_on, refused, snapshot
from scalesynth import rundir
from scalesynth.config import load_config
from scalesynth.optimize import run

from conftest import ROOT

QUICK = ROOT / "configs" / "quick.yaml"
TINY = ["grid.resolution=8", "algorithm.pop_size=8", "algorithm.n_gen=2"]  # quick.yaml in seconds
FIVEBAR = ROOT / "configs" / "fivebar_packing.yaml"  # plot-task: the planar five-bar with a task box
PPRS = ROOT / "configs" / "pprs_rprs.yaml"  # drives needs pprs-rprs
TASK = ["--resolution", "12"]
DRIVES = ["--samples", "41"]


def _ok(argv, capsys) -> str:
    code, out, err = _main(argv, capsys)
    assert code == 0, err
    return out


def _no_work(monkeypatch):
    """Make the first expensive step of each command fail loudly: a refusal must come before it."""
    def reached(*a, **k):
        raise AssertionError("the command computed before checking --out")

    from scalesynth import report
    from scalesynth.commands import fivebar
    from scalesynth.cycle import analysis

    monkeypatch.setattr(report, "reference_points", reached)  # plot-front's first evaluation
    monkeypatch.setattr(report, "band_sections", reached)  # plot-bands'
    monkeypatch.setattr(fivebar, "task_map", reached)  # plot-task's
    monkeypatch.setattr(analysis, "analyse", reached)  # drives'


def _users_directory(path: Path) -> Path:
    """The user's directory, holding names the figure commands write (front.png, task_lci.png, drives.csv)."""
    path.mkdir(parents=True, exist_ok=True)
    (path / "notes.md").write_text("# my notes\n")
    (path / "front.png").write_bytes(b"my own front")
    (path / "task_lci.png").write_bytes(b"my own task map")
    (path / "drives.csv").write_text("t\n0\n")
    (path / "bands").mkdir(exist_ok=True)
    (path / "bands" / "mine.csv").write_text("a\n1\n")
    return path


@pytest.fixture(scope="module")
def a_run(tmp_path_factory) -> Path:
    """A finished run without plots (its manifest lists its files)."""
    out = tmp_path_factory.mktemp("runs") / "run"
    run(load_config(QUICK, TINY), out, plots=False)
    return out


@pytest.fixture
def my_run(a_run, tmp_path) -> Path:
    """A private copy of ``a_run`` (hard links would share inodes with the module's run: copy the bytes)."""
    import shutil

    out = tmp_path / "run"
    shutil.copytree(a_run, out)
    return out


def _commands(run_dir: Path) -> dict[str, list]:
    return {
        "plot-front": ["plot-front", run_dir],
        "plot-bands": ["plot-bands", run_dir],
        "plot-task": ["plot-task", FIVEBAR, *TASK],
        "drives": ["drives", PPRS, *DRIVES],
    }


COMMANDS = ["plot-front", "plot-bands", "plot-task", "drives"]
NEEDLES = {"plot-front": "not a scalesynth figures directory (no plots.json)",
           "plot-bands": "not a scalesynth figures directory (no plots.json)",
           "plot-task": "not a scalesynth figures directory (no plots.json)",
           "drives": "not a scalesynth drives directory (no drives.json)"}


# ----- a foreign directory: refused before any work; --force touches only what the command writes -----------------

@pytest.mark.parametrize("command", COMMANDS)
def test_a_foreign_directory_is_refused_before_any_work(command, a_run, tmp_path, capsys, monkeypatch):
    """Before, each of these commands wrote into any --out, replacing the user's front.png, task_lci.png or
    drives.csv; now exit 2 with one line before any evaluation, and nothing changes."""
    _users_directory(tmp_path / "mine")
    _no_work(monkeypatch)
    line = refused([*_commands(a_run)[command], "--out", "mine"], NEEDLES[command], tmp_path, capsys, monkeypatch)
    assert "--force" in line


@pytest.mark.parametrize(("command", "written"), [
    ("plot-front", {"front.png", "hypervolume.png", "plots.json"}),
    ("plot-task", {"task_lci.png", "plots.json"}),
    ("drives", {"drives.csv", "drives.png", "drives.json"}),
])
def test_force_touches_only_the_files_the_command_writes(command, written, a_run, tmp_path, capsys):
    """With --force the user's directory gets the command's files (the user's front.png, task_lci.png or
    drives.csv of that name replaced: the user asked for it) and every other file stays byte for byte."""
    mine = _users_directory(tmp_path / "mine")
    before = snapshot(mine)
    _ok([*_commands(a_run)[command], "--out", mine, "--force"], capsys)
    after = snapshot(mine)
    assert written <= set(after)
    assert {k: v for k, v in after.items() if k not in written} == {k: v for k, v in before.items()
                                                                     if k not in written}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine"]  # no lock or staging directory left beside it


def _bad_out(tmp_path: Path) -> dict[str, tuple[Path, str]]:
    (tmp_path / "file").write_text("a file\n")
    os.symlink("nowhere", tmp_path / "dangling")
    os.symlink("loop", tmp_path / "loop")
    return {
        "a file": (tmp_path / "file", "a file of that name exists"),
        "dangling link": (tmp_path / "dangling" / "figs", "is a dangling symbolic link"),
        "link loop": (tmp_path / "loop", "symbolic link loop"),
        "under /proc": (Path("/proc/scalesynth-figs"), "is on the proc pseudo file system"),
    }


@pytest.mark.parametrize("case", ["a file", "dangling link", "link loop", "under /proc"])
@pytest.mark.parametrize("command", COMMANDS)
def test_a_bad_out_is_refused_before_computing(command, case, a_run, tmp_path, capsys, monkeypatch):
    """Before, a bad --out failed only when the first figure was written (after the evaluations), with exit 1;
    now exit 2 with one line before any work, --force or not."""
    if "proc" in case and not Path("/proc/self").exists():
        pytest.skip("no /proc here")
    work = tmp_path / "w"
    work.mkdir()
    target, needle = _bad_out(work)[case]
    _no_work(monkeypatch)
    for force in ([], ["--force"]):
        refused([*_commands(a_run)[command], "--out", target, *force], needle, work, capsys, monkeypatch)


def _drop_column(path: Path, column: str) -> None:
    import csv

    rows = list(csv.reader(path.open(newline="")))
    k = rows[0].index(column)
    with path.open("w", newline="") as fh:
        csv.writer(fh).writerows([r[:k] + r[k + 1:] for r in rows])


# a damage of the run directory, and what the one-line refusal names
DAMAGES = {
    "no history": (lambda run: (run / "history.csv").unlink(), "(missing history.csv)"),
    "empty history": (lambda run: (run / "history.csv").write_text("generation,evaluations,hypervolume\n"),
                      "history.csv: no generations"),
    "no band share": (lambda run: _drop_column(run / "pareto.csv", "band0_share"),
                      "pareto.csv: column 'band0_share' is missing"),
    "damaged population": (lambda run: (run / "population.csv").write_text("a,b\n1,2\n"),
                           "population.csv: column "),
    "damaged manifest": (lambda run: (run / "manifest.json").write_text("{"), "manifest.json: not valid JSON"),
}


@pytest.mark.parametrize("damage", list(DAMAGES))
def test_plot_bands_refuses_a_damaged_run_before_evaluating(damage, my_run, tmp_path, capsys, monkeypatch):
    """plot-bands evaluates its sections from config.yaml and pareto.csv read without pandas; a run directory
    that results.load refuses (another table missing or damaged) is refused before that evaluation, exit 2."""
    spoil, needle = DAMAGES[damage]
    spoil(my_run)
    _no_work(monkeypatch)
    code, out, err = _main(["plot-bands", my_run, "--out", tmp_path / "figs"], capsys)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and needle in lines[0], err
    assert not (tmp_path / "figs").exists()


def test_plot_task_file_form_replaces_only_its_own_file(tmp_path, capsys, monkeypatch):
    """`plot-task --out FILE.png` overwrote any file; now a file plot-task did not write is refused before the
    map (exit 2) unless --force, and one it wrote (marked in its metadata) is replaced."""
    mine = tmp_path / "map.png"
    mine.write_bytes(b"\x89PNG my own picture")
    refused(["plot-task", FIVEBAR, *TASK, "--out", mine], "exists and was not written by plot-task", tmp_path,
            capsys, monkeypatch)
    _ok(["plot-task", FIVEBAR, *TASK, "--out", mine, "--force"], capsys)
    first = mine.read_bytes()
    assert first[:8] == b"\x89PNG\r\n\x1a\n" and b"scalesynth plot-task" in first
    _ok(["plot-task", FIVEBAR, "--resolution", "16", "--out", mine], capsys)  # its own now: no --force needed
    assert mine.read_bytes() != first
    assert sorted(p.name for p in tmp_path.iterdir()) == ["map.png"]


# ----- staged and swapped whole -----------------------------------------------------------------------------------

@pytest.mark.parametrize(("command", "fails_at"), [
    ("plot-front", "hypervolume.png"),  # after front.png
    ("plot-bands", "band_shares.png"),  # after bands/ and bands_front.png
])
@pytest.mark.parametrize("failure", [OSError(errno.ENOSPC, os.strerror(errno.ENOSPC)), KeyboardInterrupt()],
                         ids=["disk full", "SIGINT"])
def test_a_failed_plot_into_the_run_leaves_the_run_whole(command, fails_at, failure, my_run, tmp_path, capsys,
                                                         monkeypatch):
    """Before, plot-front wrote plots/front.png in place and then failed at hypervolume.png (plot-bands: bands/
    and bands_front.png before band_shares.png), leaving a run with half its new figures. Now the run directory
    and its surroundings are byte-identical to before: exit 1, one line."""
    before = snapshot(tmp_path)
    fail_on(monkeypatch, fails_at, failure)
    code, _, err = _main([command, my_run], capsys)
    lines = error_lines(err)
    assert code == 1 and len(lines) == 1, err
    want = f"{fails_at}: cannot write"
    assert (want in lines[0]) if isinstance(failure, OSError) else lines == ["error: interrupted"]
    assert snapshot(tmp_path) == before


def test_figures_in_the_run_join_its_manifest_and_the_next_run_replaces_them(my_run, capsys):
    """plot-front into RUN/plots adds its figures to the run's manifest: the next run on that directory (without
    plots) replaces them like the run's own, instead of keeping an older front.svg beside a new pareto.csv; the
    user's plots/mine.png survives both, and an unfinished run staged beside RUN (waiting for --resume) is not
    touched by plot-front."""
    (my_run / "plots").mkdir()
    (my_run / "plots" / "mine.png").write_bytes(b"mine")
    waiting = rundir.staging_path(my_run) / "checkpoint.pkl"
    waiting.parent.mkdir()
    waiting.write_bytes(b"an unfinished run's checkpoint")
    manifest = json.loads((my_run / "manifest.json").read_text())
    out = _ok(["plot-front", my_run, "--format", "svg"], capsys)
    assert out.split() == [str(my_run / "plots" / "front.svg"), str(my_run / "plots" / "hypervolume.svg")]
    after = json.loads((my_run / "manifest.json").read_text())
    assert after["files"] == [*sorted({*manifest["files"], "plots/front.svg", "plots/hypervolume.svg"}
                                      - {"manifest.json"}), "manifest.json"]
    assert {k: v for k, v in after.items() if k != "files"} == {k: v for k, v in manifest.items() if k != "files"}
    assert waiting.read_bytes() == b"an unfinished run's checkpoint"
    waiting.parent.joinpath("checkpoint.pkl").unlink()
    waiting.parent.rmdir()
    run(load_config(QUICK, [*TINY, "algorithm.seed=2"]), my_run, plots=False)
    assert sorted(p.name for p in (my_run / "plots").iterdir()) == ["mine.png"]


def test_a_figures_directory_is_shared_by_the_plot_commands(a_run, tmp_path, capsys):
    """plots.json marks a figures directory: plot-front and plot-task write into the same --out without --force,
    each replacing only what it wrote there before (front.png goes when plot-front draws svg; task_lci.png
    stays) and keeping the user's notes."""
    figs = tmp_path / "figs"
    _ok(["plot-front", a_run, "--out", figs], capsys)
    _ok(["plot-task", FIVEBAR, *TASK, "--out", figs], capsys)
    (figs / "notes.md").write_text("mine\n")
    _ok(["plot-front", a_run, "--out", figs, "--format", "svg"], capsys)
    assert sorted(p.name for p in figs.iterdir()) == ["front.svg", "hypervolume.svg", "notes.md", "plots.json",
                                                      "task_lci.png"]
    info = json.loads((figs / "plots.json").read_text())
    assert info["commands"]["plot-front"]["files"] == ["front.svg", "hypervolume.svg"]
    assert info["commands"]["plot-task"]["files"] == ["task_lci.png"]
    assert info["files"] == ["front.svg", "hypervolume.svg", "task_lci.png", "plots.json"]


def test_a_failed_drives_leaves_the_previous_one_whole(tmp_path, capsys, monkeypatch):
    """drives wrote drives.csv, then drives.png, in place: a failure at the plot left the new table beside the old
    plot. Now the directory is byte-identical to the previous drives output (41 samples, not 81)."""
    out = tmp_path / "d"
    _ok(["drives", PPRS, *DRIVES, "--out", out], capsys)
    assert len((out / "drives.csv").read_text().splitlines()) == 1 + 41
    (out / "notes.md").write_text("mine\n")
    before = snapshot(tmp_path)
    fail_on(monkeypatch, "drives.png", OSError(errno.EIO, os.strerror(errno.EIO)))
    code, _, err = _main(["drives", PPRS, "--samples", "81", "--out", out], capsys)
    assert code == 1 and "drives.png: cannot write (Input/output error)" in err, err
    assert snapshot(tmp_path) == before
    monkeypatch.undo()
    _ok(["drives", PPRS, "--samples", "81", "--out", out], capsys)  # its own directory: no --force needed
    assert len((out / "drives.csv").read_text().splitlines()) == 1 + 81
    assert (out / "notes.md").read_text() == "mine\n"
    assert json.loads((out / "drives.json").read_text())["files"] == ["drives.csv", "drives.png", "drives.json"]


# ----- batch ------------------------------------------------------------------------------------------------------

def _batch_config(tmp_path: Path) -> Path:
    import yaml

    data = yaml.safe_load(QUICK.read_text())
    data["grid"] = {"resolution": 8}
    data["algorithm"].update(pop_size=8, n_gen=2)
    data["output"] = {"checkpoint_every": 2}
    path = tmp_path / "quick.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_batch_refuses_a_foreign_task_directory_before_any_task_runs(tmp_path, capsys, monkeypatch):
    """A task directory OUT/<name>/seed<k> holding the user's files was refused only when its finished run was
    swapped in (the task failed after its run, exit 1); now the batch stops before connecting to a scheduler,
    exit 2 with one line naming the directory. A run's directory or an unfinished task's is not refused."""
    from scalesynth import batch

    def reached(*a, **k):
        raise AssertionError("the batch started before checking its task directories")

    cfg = _batch_config(tmp_path)
    out = tmp_path / "out"
    _users_directory(out / "quick" / "seed2")
    monkeypatch.setattr(batch, "dask_client", reached)
    line = refused(["batch", cfg, "--seeds", "2", "--out", "out"], "not a scalesynth run directory", tmp_path,
                   capsys, monkeypatch)
    assert "seed2" in line and "--force" in line
    # with --force, or with only a run's or an unfinished task's directories, the batch goes on to the scheduler
    for args in (["--force"], []):
        if not args:
            (out / "quick").rename(tmp_path / "moved")
            (out / "quick" / "seed1").mkdir(parents=True)
            (out / "quick" / "seed1" / "checkpoint.pkl").write_bytes(b"")  # scalesynth < 0.2 kept it inside
        code, _, err = _main(["batch", cfg, "--seeds", "2", "--out", out, *args], capsys)
        assert code == 1 and "the batch started before checking" in err, err  # reached the (stubbed) scheduler


def test_batch_force_moves_only_its_files_into_the_users_directory(tmp_path, monkeypatch):
    """batch --force: the finished task's files join the user's directory, whose own files stay byte for byte
    (the chunks run in this process on a stand-in for dask)."""
    from fake_dask import InlineClient, use_inline_dask
    from scalesynth import batch

    cfg = load_config(_batch_config(tmp_path))
    out = tmp_path / "out"
    tasks = batch.plan([("quick.yaml", cfg)], 1, out)
    mine = _users_directory(tasks[0].out_dir)
    before = snapshot(mine)
    batch.check_targets(tasks, out, force=True)
    use_inline_dask(monkeypatch)
    records = batch.run_tasks(tasks, InlineClient(), force=True)
    assert [r.status for r in records] == ["finished"], records[0].error
    after = snapshot(mine)
    written = set(json.loads(after["manifest.json"])["files"])
    assert {"pareto.csv", "history.csv", "manifest.json"} <= written
    assert {k: v for k, v in after.items() if k not in written} == before
