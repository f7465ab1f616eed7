"""Run-directory integrity (scalesynth.rundir, issue 11 items 1-2): a results directory is the old finished run,
untouched, or the new run, whole. Real processes for the lock and the kills; disk-full cases are in
test_reliability."""

import copy
import json
import os
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from scalesynth import rundir
from scalesynth.config import config_from_dict
from scalesynth.errors import ConfigError, RunError
from scalesynth.optimize import reproduce, run
from scalesynth.rundir import lock_path, staging_path

from conftest import SMALL


def small(**changes):
    data = copy.deepcopy(SMALL)
    for key, value in changes.items():
        data[key] = {**data[key], **value} if isinstance(value, dict) and key in data else value
    return data


def _snapshot(directory: Path) -> dict[str, bytes]:
    return {str(p.relative_to(directory)): p.read_bytes() for p in sorted(directory.rglob("*")) if p.is_file()}


def _optimize(cfg_path: Path, out: Path, *extra: str) -> subprocess.Popen:
    env = dict(os.environ, MPLBACKEND="Agg")
    cmd = [sys.executable, "-m", "scalesynth", "optimize", str(cfg_path), "--out", str(out), "-q", *extra]
    return subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _wait_for(predicate, proc: subprocess.Popen, timeout: float = 120) -> None:
    deadline = time.time() + timeout
    while time.time() < deadline and proc.poll() is None:
        if predicate():
            return
        time.sleep(0.005)
    raise AssertionError(f"condition not reached (process exit {proc.poll()})")


def _holder_pid(out: Path) -> int | None:
    try:
        text = lock_path(out).read_text().strip()
    except OSError:
        return None
    return int(text) if text.isdigit() else None


@pytest.fixture(scope="module")
def reference_runs(tmp_path_factory):
    """Uninterrupted runs of the long config with seeds 3 and 8 (what a run on the shared target must equal)."""
    tmp = tmp_path_factory.mktemp("ref")
    data = small(algorithm={"n_gen": 60}, output={"checkpoint_every": 1})
    return data, {s: _snapshot(run(config_from_dict(data), tmp / f"s{s}", seed=s, plots=False).out_dir)
                  for s in (3, 8)}


def _results(snapshot):
    return {k: v for k, v in snapshot.items() if k in ("pareto.csv", "population.csv")}


def test_second_run_on_a_locked_directory_exits_1_naming_the_holder(tmp_path, reference_runs):
    """Two optimize processes on one --out (the first paused by SIGSTOP while it holds the lock): the second
    exits 1 at once with one line naming the first's pid; the first finishes alone and its results equal an
    uninterrupted run of its seed, byte for byte."""
    data, refs = reference_runs
    cfg_path = tmp_path / "cfg.yaml"
    cfg_path.write_text(yaml.safe_dump(data))
    out = tmp_path / "one_out"  # the one --out directory both runs are given
    first = _optimize(cfg_path, out, "--no-plots", "--seed", "3")
    _wait_for(lambda: _holder_pid(out) == first.pid, first)
    first.send_signal(signal.SIGSTOP)  # keep it mid-run, holding the lock, however fast the machine
    try:
        second = _optimize(cfg_path, out, "--no-plots", "--seed", "8")
        _, err = second.communicate(timeout=120)
    finally:
        first.send_signal(signal.SIGCONT)
    assert second.returncode == 1, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    assert f"(pid {first.pid})" in lines[0] and str(out) in lines[0]
    assert first.wait(timeout=300) == 0, first.stderr.read()
    assert _results(_snapshot(out)) == _results(refs[3])
    assert json.loads((out / "manifest.json").read_text())["seed"] == 3
    assert not lock_path(out).exists() and not staging_path(out).exists()


def test_kill_9_of_a_second_run_mid_write_leaves_the_finished_run_untouched(tmp_path, reference_runs):
    """A finished run (seed 3); a second run (seed 8, with plots) is SIGKILLed while it writes its results (its
    pareto.csv is staged, its plots are being drawn): the directory is still the first run, byte for byte, and
    `select` reads it; `--resume` then completes the seed-8 run, whole."""
    data, refs = reference_runs
    cfg_path = tmp_path / "cfg.yaml"
    cfg_path.write_text(yaml.safe_dump(data))
    out = tmp_path / "run"
    run(config_from_dict(data), out, seed=3, plots=False)
    before = _snapshot(out)
    proc = _optimize(cfg_path, out, "--seed", "8")
    _wait_for(lambda: (staging_path(out) / "pareto.csv").exists(), proc)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert _snapshot(out) == before
    env = dict(os.environ, MPLBACKEND="Agg")
    r = subprocess.run([sys.executable, "-m", "scalesynth", "select", str(out), "--json"], capture_output=True,
                       text=True, env=env, timeout=120)
    assert r.returncode == 0, r.stderr
    r = subprocess.run([sys.executable, "-m", "scalesynth", "optimize", str(cfg_path), "--out", str(out), "-q",
                        "--seed", "8", "--resume", "--no-plots"], capture_output=True, text=True, env=env,
                       timeout=300)
    assert r.returncode == 0, r.stderr
    after = _snapshot(out)
    assert _results(after) == _results(refs[8])
    assert json.loads(after["manifest.json"])["seed"] == 8
    assert "selected_knee.yaml" not in after  # the old run's selection went with it: nothing mixed
    assert not staging_path(out).exists()


def test_interrupted_fresh_run_never_mixes_with_the_finished_one(tmp_path):
    """Issue 11 item 2 in process: a fresh run (seed 2) stopped after some generations leaves the finished run
    (seed 1) exactly as it was; the next fresh run discards the abandoned staging directory."""
    data = small()
    out = tmp_path / "d"
    run(config_from_dict(data), out, seed=1, plots=False)
    before = _snapshot(out)
    with pytest.raises(RunError, match="stopped after 2 generations"):
        run(config_from_dict(data), out, seed=2, plots=False, stop_after=2)
    assert _snapshot(out) == before and (staging_path(out) / "checkpoint.pkl").exists()
    result = run(config_from_dict(data), out, seed=5, plots=False)
    assert result.manifest["seed"] == 5 and json.loads((out / "manifest.json").read_text())["seed"] == 5
    assert not staging_path(out).exists()


def test_user_files_survive_the_swap_and_old_run_files_do_not(tmp_path):
    out = tmp_path / "d"
    run(config_from_dict(small()), out, seed=1, plots=False)
    (out / "notes.txt").write_text("mine\n")
    (out / "drives").mkdir()
    (out / "drives" / "drives.csv").write_text("t\n0\n")
    (out / "selected_knee.yaml").write_text("name: old\n")
    run(config_from_dict(small()), out, seed=2, plots=False)
    assert (out / "notes.txt").read_text() == "mine\n" and (out / "drives" / "drives.csv").read_text() == "t\n0\n"
    assert not (out / "selected_knee.yaml").exists()


def test_fallback_swap_without_renameat2_and_repair_after_a_kill_between_renames(tmp_path, monkeypatch):
    """Where RENAME_EXCHANGE is unsupported the swap is two renames through .<name>.old; a kill between them leaves
    no target and the old run in .<name>.old, which the next claim restores before anything else."""
    out = tmp_path / "d"
    run(config_from_dict(small()), out, seed=1, plots=False)
    before = _snapshot(out)
    monkeypatch.setattr(rundir, "_exchange", lambda a, b: False)
    run(config_from_dict(small()), out, seed=2, plots=False)
    assert json.loads((out / "manifest.json").read_text())["seed"] == 2
    assert not (tmp_path / ".d.old").exists() and not staging_path(out).exists()
    # simulate the kill: the old run renamed away, the new one not yet in place
    os.rename(out, tmp_path / ".d.old")
    with rundir.claim(out):
        assert out.is_dir() and not (tmp_path / ".d.old").exists()
    assert json.loads((out / "manifest.json").read_text())["seed"] == 2
    assert before != _snapshot(out)


def test_result_files_honour_the_umask(tmp_path):
    old = os.umask(0o022)
    try:
        out = run(config_from_dict(small()), tmp_path / "d", plots=False).out_dir
    finally:
        os.umask(old)
    for name in ("pareto.csv", "population.csv", "history.csv", "manifest.json", "config.yaml"):
        assert stat.S_IMODE((out / name).stat().st_mode) == 0o644, name


def test_bad_input_writes_nothing_and_keeps_an_unfinished_run(tmp_path):
    """bounds: {} fails before any directory or lock exists; a fresh run whose config is refused does not touch
    the staged checkpoint of an earlier run."""
    out = tmp_path / "d"
    with pytest.raises(ConfigError, match="bounds"):
        run(config_from_dict({**small(), "bounds": {}}), out, plots=False)
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(RunError):
        run(config_from_dict(small()), out, plots=False, stop_after=2)
    ckpt = (staging_path(out) / "checkpoint.pkl").read_bytes()
    with pytest.raises(ConfigError):
        run(config_from_dict({**small(), "bounds": {}}), out, plots=False)
    assert (staging_path(out) / "checkpoint.pkl").read_bytes() == ckpt
    from scalesynth.memory import MemoryLimitError

    with pytest.raises(MemoryLimitError, match="algorithm.pop_size"):  # the late check of issue 11 item 11
        run(config_from_dict(small(algorithm={"pop_size": 100_000})), out, plots=False)
    assert (staging_path(out) / "checkpoint.pkl").read_bytes() == ckpt


def test_reproduce_refuses_an_out_inside_the_run(tmp_path):
    out = tmp_path / "d"
    run(config_from_dict(small()), out, plots=False)
    before = _snapshot(out)
    for target in (out, out / "again", out / ".." / "d"):
        with pytest.raises(ConfigError, match="--out"):
            reproduce(out, target)
    assert _snapshot(out) == before
