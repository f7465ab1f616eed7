"""Reliability: degenerate designs never give NaN/inf, SIGKILL at random generations then resume gives the
uninterrupted front with no corrupt or temporary files, determinism, and I/O failures (disk full, output under a
regular file) give a clear error, exit 1, and leave earlier results untouched."""

import copy
import errno
import itertools
import json
import os
import pickle
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from scalesynth import io as rio
from scalesynth.cli import app
from scalesynth.config import TaskConfig, config_from_dict
from scalesynth.errors import RunError
from scalesynth.evaluate import evaluate, evaluate_population
from scalesynth.mechanisms import available, get
from scalesynth.metrics import nullable_columns
from scalesynth.optimize import run
from scalesynth.rundir import staging_path

from conftest import SMALL


def small(**changes):
    data = copy.deepcopy(SMALL)
    data.update(copy.deepcopy(changes))
    return data


# ----- degenerate designs ---------------------------------------------------------------------------------------

def _task_for(mech):
    """A task box (the middle half of the default design's bounding box) and its diagonal as the path."""
    design = mech.resolve_design({})
    lo, hi = mech.bounding_box(design, mech.resolve_options({}))
    n = len(mech.task_axes)
    mid, half = (lo[:n] + hi[:n]) / 2, np.maximum((hi[:n] - lo[:n]) / 4, 1e-6)
    box = {a: (float(mid[i] - half[i]), float(mid[i] + half[i])) for i, a in enumerate(mech.task_axes)}
    path = [list(map(float, mid - half)), list(map(float, mid)), list(map(float, mid + half))]
    return TaskConfig(box=box, resolution=5, path=path, path_samples=15)


def degenerate_designs(mech) -> list[dict[str, float]]:
    """Designs at and near degenerate geometry: every pair of parameters equal (l1 = l2, m = n, ...) or equal up
    to 1e-12, every parameter tiny (1e-9 x) or huge (1e6 x) alone and all together, zero and negative values of
    the parameters that may be <= 0."""
    base = mech.resolve_design({})
    names = list(base)
    positive = {p.name: p.positive for p in mech.parameters}
    out = [dict(base)]
    for a, b in itertools.permutations(names, 2):
        if base[a] > 0 or not positive[b]:
            out.append({**base, b: base[a]})
            out.append({**base, b: base[a] * (1 + 1e-12) + 1e-300})
    for scale in (1e-9, 1e-3, 1e3, 1e6):
        out.append({k: (v * scale if v != 0 else scale) for k, v in base.items()})
        for k in names:
            out.append({**base, k: base[k] * scale if base[k] != 0 else scale})
    for p in mech.parameters:
        if not p.positive:
            for v in (0.0, -1e-9, -1.0, -1e6):
                out.append({**base, p.name: v})
    return [mech.resolve_design(d) for d in out]


def _assert_all_finite(metrics: dict, label: str, mech=None) -> None:
    """Every value finite; with ``mech``, NaN is allowed where a statistic is over an empty set (issue 27: the
    nullable columns, and only where the workspace or the task box has no reachable cell)."""
    nullable = set() if mech is None else nullable_columns(mech, mech.default_length_unit, 3)
    for key, values in metrics.items():
        arr = np.asarray(values, dtype=float)
        bad = ~np.isfinite(arr)
        if key in nullable:
            empty = np.asarray(metrics["task_coverage" if key.startswith("task_") else "voxels"]) == 0
            bad &= ~(np.isnan(arr) & empty)
        assert not bad.any(), f"{label}: {key} is not finite for design(s) {np.nonzero(bad)[0].tolist()}"


@pytest.mark.parametrize("name", available())
def test_degenerate_designs_never_give_nan_or_inf(name):
    mech = get(name)
    designs = degenerate_designs(mech)
    task = _task_for(mech)
    metrics = evaluate_population(mech, designs, resolution=8, task=task)
    _assert_all_finite(metrics, name, mech)
    assert (metrics["gci"] >= 0).all() and (metrics["gci"] <= 1).all()
    assert (np.nan_to_num(metrics["min_lci"]) >= 0).all() and (metrics["voxels"] >= 0).all()
    # the single-design path (evaluate) agrees on the same designs
    for i in (0, 1, len(designs) - 1):
        single = evaluate(mech, designs[i], resolution=8, task=task).metrics
        _assert_all_finite(single, f"{name} design {i}", mech)
        assert single["gci"] == pytest.approx(metrics["gci"][i], rel=1e-12, abs=1e-12)


@settings(max_examples=15)
@given(data=st.data())
def test_random_extreme_ratios_never_give_nan_or_inf(data):
    """Log-uniform scalings of every parameter over 15 decades, 6 designs per example, every mechanism."""
    for name in available():
        mech = get(name)
        base = mech.resolve_design({})
        designs = []
        for _ in range(6):
            exps = data.draw(st.lists(st.floats(-9, 6), min_size=len(base), max_size=len(base)))
            designs.append({k: (v if v != 0 else 1.0) * 10.0**e for (k, v), e in zip(base.items(), exps, strict=True)})
        _assert_all_finite(evaluate_population(mech, designs, resolution=6), name, mech)


# ----- SIGKILL and resume ---------------------------------------------------------------------------------------

def _ckpt_generation(path: Path) -> int | None:
    """Generation of the checkpoint on disk (None if absent or being replaced right now)."""
    try:
        with open(path, "rb") as fh:
            state = pickle.load(fh)
    except (OSError, EOFError, pickle.UnpicklingError):
        return None
    return int(state["history"][-1]["generation"])


def _assert_results_intact(out: Path) -> None:
    """Every CSV parses, the manifest and config parse, no temp file or checkpoint is left over."""
    for name in ("pareto.csv", "population.csv", "history.csv"):
        frame = pd.read_csv(out / name)
        assert len(frame) > 0 and not frame.isna().any().any(), name
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["status"] == "finished"
    assert yaml.safe_load((out / "config.yaml").read_text())["name"] == manifest["name"]
    leftovers = [p.name for p in out.rglob("*") if p.name.endswith(".tmp") or p.name == rio.CHECKPOINT]
    assert leftovers == []


def test_sigkill_at_random_generations_then_resume(tmp_path):
    """Three SIGKILLs at generations drawn at random (fixed seed), each after a later checkpoint than the last;
    the final resume completes with the front of an uninterrupted run, byte for byte."""
    data = small(algorithm={"pop_size": 16, "n_gen": 40, "seed": 5}, output={"checkpoint_every": 1})
    data["grid"] = {"resolution": 16}
    cfg_path = tmp_path / "cfg.yaml"
    cfg_path.write_text(yaml.safe_dump(data))
    ref = run(config_from_dict(data), tmp_path / "ref", plots=False)
    out = tmp_path / "killed"
    ckpt = staging_path(out) / rio.CHECKPOINT  # an unfinished run lives beside its target
    rng = random.Random(2026)
    env = dict(os.environ, MPLBACKEND="Agg")
    cmd = [sys.executable, "-m", "scalesynth", "optimize", str(cfg_path), "--out", str(out), "--no-plots", "-q"]
    killed_at = []
    for i in range(3):
        # a random generation a few past the last kill's checkpoint, so every kill is at a new checkpoint
        target = (killed_at[-1] if killed_at else 0) + rng.randint(2, 8)
        proc = subprocess.Popen(cmd + (["--resume"] if i else []), env=env)
        deadline = time.time() + 120
        gen = None
        while time.time() < deadline and proc.poll() is None:
            gen = _ckpt_generation(ckpt) if ckpt.exists() else None
            if gen is not None and gen >= target:
                break
            time.sleep(0.005)
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        assert not (out / "manifest.json").exists(), f"the run finished before kill {i + 1} (target {target})"
        killed_at.append(_ckpt_generation(ckpt))
    assert killed_at == sorted(killed_at) and len(set(killed_at)) == 3, killed_at  # three distinct checkpoints
    # whatever the kills left (a checkpoint, perhaps a temp file from an interrupted write) must not matter
    r = subprocess.run(cmd + ["--resume"], env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    for name in ("pareto.csv", "population.csv"):
        assert (out / name).read_bytes() == (ref.out_dir / name).read_bytes(), name
    h = pd.read_csv(out / "history.csv")
    assert list(h["generation"]) == list(range(1, 41))
    pd.testing.assert_frame_equal(h.drop(columns="seconds"), ref.history.drop(columns="seconds"))
    _assert_results_intact(out)


def test_temp_files_of_an_interrupted_write_are_removed_by_resume(tmp_path):
    """A SIGKILL during a write leaves '.<name>.<random>.tmp' next to the file (in the staging directory, and in
    the target from older versions): the resumed run removes them; a user's file in the target is kept."""
    cfg = config_from_dict(small())
    with pytest.raises(RunError):
        run(cfg, tmp_path, plots=False, stop_after=3)
    for where in (tmp_path, staging_path(tmp_path)):
        for name in (".checkpoint.pkl.x1y2z3_4.tmp", ".pareto.csv.abc123de.tmp"):
            (where / name).write_bytes(b"half a fi")
        (where / "plots").mkdir()
        (where / "plots" / ".front.png.q9w8e7r6.tmp").write_bytes(b"\x89PN")
    (tmp_path / "notes.tmp").write_text("not ours: kept\n")
    run(cfg, tmp_path, resume=True, plots=False)
    assert (tmp_path / "notes.tmp").read_text() == "not ours: kept\n"
    assert sorted(p.name for p in tmp_path.rglob("*.tmp")) == ["notes.tmp"]
    (tmp_path / "notes.tmp").unlink()
    _assert_results_intact(tmp_path)


# ----- determinism ----------------------------------------------------------------------------------------------

def test_same_config_and_seed_give_identical_bytes_for_a_task_config(tmp_path):
    """A planar mechanism with task-box and path metrics and constraints: two runs, identical results."""
    data = {
        "name": "fivebar_small",
        "mechanism": "planar-fivebar",
        "units": {"length": "mm"},
        "design": {"r": 200, "l1": 475, "l2": 875},
        "options": {"mode": "+-"},
        "bounds": {"r": [50, 400], "l1": [250, 800], "l2": [500, 1400]},
        "grid": {"resolution": 16},
        "task": {"box": {"x": [-500, 500], "y": [-850, -600]}, "resolution": 8,
                 "path": [[500, -600], [-500, -600], [-500, -850]], "path_samples": 20},
        "objectives": [{"metric": "task_gci"}, {"metric": "task_fci", "sense": "min"}],
        "constraints": [{"metric": "task_coverage", "min": 0.5}],
        "algorithm": {"pop_size": 12, "n_gen": 4, "seed": 9},
    }
    a = run(config_from_dict(data), tmp_path / "a", plots=False)
    b = run(config_from_dict(data), tmp_path / "b", plots=False)
    for name in ("pareto.csv", "population.csv", "config.yaml"):
        assert (a.out_dir / name).read_bytes() == (b.out_dir / name).read_bytes(), name


# ----- I/O failures ---------------------------------------------------------------------------------------------

def _cli(*args):
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.run([sys.executable, "-m", "scalesynth", *args], capture_output=True, text=True, env=env,
                          timeout=120)


def test_output_under_a_regular_file_is_a_clear_error_exit_2(tmp_path):
    cfg_path = tmp_path / "cfg.yaml"
    cfg_path.write_text(yaml.safe_dump(small()))
    blocker = tmp_path / "results"
    blocker.write_text("I am a file\n")
    r = _cli("optimize", str(cfg_path), "--out", str(blocker / "run"), "--no-plots", "-q")
    assert r.returncode == 2, r.stderr  # a bad --out, refused before any work (issue 27)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "cannot create output directory" in lines[0]
    from scalesynth.outpath import shown

    assert shown(blocker / "run") in lines[0]  # the path, its start cut when long (error lines stay short)
    assert lines[0].rstrip().endswith("results/run: cannot create output directory (a part of the path is a file)")
    assert blocker.read_text() == "I am a file\n"


@pytest.fixture()
def finished_run(tmp_path):
    out = tmp_path / "run"
    run(config_from_dict(small()), out, plots=False)
    snapshot = {p.name: p.read_bytes() for p in out.iterdir()}
    return out, snapshot


def _disk_full_inside(monkeypatch, directory: Path):
    """os.replace (the commit step of every atomic write) fails with ENOSPC for targets inside ``directory``."""
    real_replace = os.replace

    def replace(src, dst, *args, **kwargs):
        if Path(dst).resolve().is_relative_to(directory.resolve()):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(dst))
        return real_replace(src, dst, *args, **kwargs)

    monkeypatch.setattr(os, "replace", replace)


def test_disk_full_is_a_clear_error_and_earlier_results_survive(finished_run, monkeypatch):
    """A new run (another seed) into a directory of finished results on a full disk: exit 1, one line naming
    the file and 'No space left on device', every earlier file byte-identical, no temp file left."""
    out, snapshot = finished_run
    cfg_path = out.parent / "cfg.yaml"
    cfg_path.write_text(yaml.safe_dump(small()))
    _disk_full_inside(monkeypatch, out.parent)  # the file system is full: the staging directory beside it too
    r = CliRunner().invoke(app, ["optimize", str(cfg_path), "--out", str(out), "--seed", "8", "--no-plots", "-q"])
    assert r.exit_code == 1, r.output
    lines = r.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "No space left on device" in lines[0], lines
    assert str(staging_path(out) / rio.CHECKPOINT) in lines[0]  # the file that could not be written
    after = {p.name: p.read_bytes() for p in out.iterdir()}
    assert after == snapshot
    assert not list(out.parent.rglob("*.tmp"))


def test_disk_full_while_writing_results_keeps_every_earlier_file(finished_run, monkeypatch):
    """The run itself succeeds but the final writes fail (the checkpoint commit is allowed): exit 1, earlier
    results intact, and the checkpoint kept so the run can be resumed once there is space."""
    out, snapshot = finished_run
    real_replace = os.replace

    def replace(src, dst, *args, **kwargs):
        if Path(dst).name != rio.CHECKPOINT and Path(dst).parent.resolve() == staging_path(out).resolve():
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(dst))
        return real_replace(src, dst, *args, **kwargs)

    monkeypatch.setattr(os, "replace", replace)
    with pytest.raises(RunError, match="No space left on device"):
        run(config_from_dict(small()), out, seed=8, plots=False)
    after = {p.name: p.read_bytes() for p in out.iterdir()}
    assert after == snapshot and (staging_path(out) / rio.CHECKPOINT).exists()
    monkeypatch.setattr(os, "replace", real_replace)
    resumed = run(config_from_dict(small()), out, seed=8, resume=True, plots=False)
    assert resumed.manifest["seed"] == 8
    _assert_results_intact(out)


def test_disk_full_in_batch_summary_is_exit_1(tmp_path, monkeypatch):
    """The batch's summary cannot be written: a one-line error, exit 1 (the tasks' own results are complete)."""
    from scalesynth import batch

    cfg = config_from_dict(small(name="solo", algorithm={"pop_size": 8, "n_gen": 2}))

    from contextlib import contextmanager

    from fake_dask import InlineClient, use_inline_dask

    @contextmanager
    def inline(scheduler, n_tasks):  # runs tasks in this process: the failure under test is on the client side
        yield InlineClient()

    monkeypatch.setattr(batch, "dask_client", inline)
    monkeypatch.setattr(batch, "check_workers", lambda client: {})
    use_inline_dask(monkeypatch)
    _disk_full_inside(monkeypatch, tmp_path / "batch.json")
    with pytest.raises(RunError, match=r"batch\.json: cannot write \(No space left on device\)"):
        batch.run_batch([("solo.yaml", cfg)], tmp_path, seeds=1)
    assert (tmp_path / "solo" / "seed1" / "manifest.json").exists() and not (tmp_path / "batch.json").exists()
    assert not list(tmp_path.glob(".*.tmp"))
