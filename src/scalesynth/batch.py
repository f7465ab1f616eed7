"""Batch synthesis on dask.distributed: every (config, seed) pair is one task running ``optimize.run``.

Layout of a batch directory OUT (on the client: a relative OUT is relative to the client's working directory)::

    OUT/batch.json                              summary of the last batch run (written atomically)
    OUT/<config name>/seed<k>/                  one results directory per task (plots off)
    OUT/<config name>/.seed<k>.staging/checkpoint.pkl  an unfinished task's latest checkpoint (the client's)
    OUT/<config name>/combined_pareto.csv       non-dominated merge of the seeds' fronts
    OUT/<config name>/hypervolume_by_seed.png   hypervolume per generation, one line per seed

**The client owns the results.** A task runs on the workers as a chain of chunks (scalesynth.batch_task): each
chunk continues the run from the checkpoint the client sends it up to the run's next checkpoint generation
(``output.checkpoint_every``) and returns that checkpoint's bytes, or after the last generation the bytes of the
results files; the client writes them into OUT and sends the next chunk. No shared filesystem is needed and a
worker's disk is scratch only. A chunk lost with its worker is run again (by dask, or resubmitted by the client
after dask's KilledWorker) from the checkpoint the client holds, so the final front is byte-identical to an
uninterrupted run. Re-running the same batch skips tasks whose directory in OUT holds a finished manifest of the
same config and seed, wherever they ran, and continues unfinished ones from the checkpoints in OUT. One failing
task never stops the others; it is reported with a one-line error.

dask is an optional dependency (``pip install scalesynth[dask]``): it is imported only in scalesynth.cluster and
here, lazily.
"""

from __future__ import annotations

import io
import pickle
import time
import uuid
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from scalesynth import io as rio
from scalesynth.batch_task import one_line, run_chunk
from scalesynth.cluster import check_workers, dask_client, local_cluster_shape, version_differences
from scalesynth.config import RunConfig
from scalesynth.errors import ConfigError, RunError, ScalesynthError

__all__ = ["local_cluster_shape", "one_line", "plan", "run_batch", "run_tasks"]

SUMMARY = "batch.json"
COMBINED = "combined_pareto.csv"
HV_PLOT = "hypervolume_by_seed.png"
MAX_SEED = 2**32 - 1
MAX_RESUBMITS = 3  # times a chunk is resubmitted after dask gave up on it (KilledWorker: its workers kept dying)
PROGRESS_EVERY = 30.0  # seconds between progress lines while tasks run


@dataclass(frozen=True)
class BatchTask:
    """One (config, seed) pair. ``data`` is the validated config as plain JSON data (cheap to ship to a worker)."""

    name: str
    source: str
    seed: int
    out_dir: Path
    data: dict[str, Any] = field(repr=False)

    @property
    def key(self) -> str:
        return f"scalesynth-{self.name}-seed{self.seed}"


@dataclass
class TaskRecord:
    """Outcome of one task. ``wall_seconds`` is the time its chunks spent on workers in this batch (seconds);
    ``run_seconds`` the run's own wall time from its manifest (all sessions of a resumed run). ``worker`` ran its
    last chunk; ``workers`` lists every worker whose chunks returned (in order of first chunk) with its address,
    name, nthreads, the Numba threads the chunks used and how many chunks; ``retries`` counts chunk runs lost with
    their worker (and run again from the client's checkpoint), ``lost_workers`` those workers."""

    config: str
    source: str
    seed: int
    out_dir: str
    status: str  # finished | skipped | failed
    error: str | None = None
    wall_seconds: float = 0.0
    run_seconds: float | None = None
    hypervolume: float | None = None
    pareto_size: int | None = None
    hv_reference: list[float] | None = None
    history: dict[str, list[float]] | None = field(default=None, repr=False)
    pareto_csv: str | None = field(default=None, repr=False)
    worker: str | None = None
    worker_name: str | None = None
    worker_nthreads: int | None = None
    numba_threads: int | None = None
    workers: list[dict[str, Any]] = field(default_factory=list)
    retries: int = 0
    lost_workers: list[str] = field(default_factory=list)
    chunks: int = 0
    generation: int | None = None

    def summary(self) -> dict[str, Any]:
        out = Path(self.out_dir)
        checkpoint = client_checkpoint(out)
        return {
            "config": self.config,
            "source": self.source,
            "seed": self.seed,
            "status": self.status,
            "error": self.error,
            "wall_seconds": round(self.wall_seconds, 3),
            "run_seconds": self.run_seconds,
            "hypervolume": self.hypervolume,
            "pareto_size": self.pareto_size,
            "results": self.out_dir,
            "files": sorted(str(p) for p in out.iterdir() if p.is_file() and p.name in rio.RESULT_FILES)
            if out.is_dir() else [],
            "checkpoint": str(checkpoint) if checkpoint.is_file() else None,
            "generation": self.generation,
            "worker": self.worker,
            "worker_name": self.worker_name,
            "worker_nthreads": self.worker_nthreads,
            "numba_threads": self.numba_threads,
            "workers": self.workers,
            "chunks": self.chunks,
            "retries": self.retries,
            "lost_workers": self.lost_workers,
        }


@dataclass
class BatchSummary:
    out: Path
    scheduler: str
    tasks: list[TaskRecord]
    combined: dict[str, dict[str, Any]]
    wall_seconds: float
    workers: dict[str, dict[str, Any]] = field(default_factory=dict)

    @property
    def n_failed(self) -> int:
        return sum(t.status == "failed" for t in self.tasks)

    def to_dict(self) -> dict[str, Any]:
        return {
            "out": str(self.out),
            "scheduler": self.scheduler,
            "workers": self.workers,
            "wall_seconds": round(self.wall_seconds, 3),
            "n_tasks": len(self.tasks),
            "n_finished": sum(t.status == "finished" for t in self.tasks),
            "n_skipped": sum(t.status == "skipped" for t in self.tasks),
            "n_failed": self.n_failed,
            "tasks": [t.summary() for t in self.tasks],
            "combined": self.combined,
        }


def plan(configs: Sequence[tuple[str, RunConfig]], seeds: int, out: Path) -> list[BatchTask]:
    """Tasks for ``seeds`` seeds of every config (seed, seed+1, ...), in config then seed order.

    ``configs`` pairs each validated config with where it came from (for messages). Raises ConfigError for bad
    input: no configs, seeds < 1, two configs with the same name (their directories would collide), seeds out of
    range."""
    if not configs:
        raise ConfigError("CONFIG: give at least one config")
    if seeds < 1:
        raise ConfigError(f"--seeds: must be at least 1, got {seeds}")
    seen: dict[str, str] = {}
    tasks = []
    for source, cfg in configs:
        if cfg.name in seen:
            raise ConfigError(
                f"{source}: name: {cfg.name!r} is also the name of {seen[cfg.name]} (batch configs need distinct names)"
            )
        seen[cfg.name] = source
        first = cfg.algorithm.seed
        if first + seeds - 1 > MAX_SEED:
            raise ConfigError(f"--seeds: {source}: seeds {first}..{first + seeds - 1} exceed {MAX_SEED}")
        # the name pattern already forbids separators and leading dots; safe_child is the belt to those braces
        config_dir = rio.safe_child(out, cfg.name)
        data = cfg.model_dump(mode="json")
        for seed in range(first, first + seeds):
            tasks.append(BatchTask(cfg.name, source, seed, config_dir / f"seed{seed}", data))
    return tasks


@dataclass
class TaskRun:
    """Client-side state of one unfinished task: the latest checkpoint the client holds (None: not started) and
    what its chunks did so far."""

    index: int
    task: BatchTask
    checkpoint: bytes | None = field(default=None, repr=False)
    generation: int = 0
    record: TaskRecord | None = None  # accumulates workers, retries, ...; status set when the task ends
    resubmits: int = 0

    def key(self) -> str:
        """A fresh dask key for the next chunk: readable (config, seed, generation it starts from), unique."""
        return f"{self.task.key}-gen{self.generation}-{uuid.uuid4().hex[:8]}"


def _seeded_digest(task: BatchTask) -> str:
    from scalesynth.config import config_from_dict
    from scalesynth.optimize import config_digest

    cfg = config_from_dict(task.data)
    return config_digest(cfg.model_copy(update={"algorithm": cfg.algorithm.model_copy(update={"seed": task.seed})}))


def _results_outcome(out_dir: Path) -> dict[str, Any]:
    """What the summary needs from a finished results directory on the client."""
    from scalesynth import results

    result = results.load(out_dir)
    m, history = result.manifest, result.history
    return {
        "run_seconds": float(m["wall_seconds"]),
        "hypervolume": float(m["hypervolume"]),
        "pareto_size": int(m["pareto_size"]),
        "hv_reference": [float(v) for v in m["hv_reference"]],
        "history": {
            "generation": [int(g) for g in history["generation"]],
            "hypervolume": [float(h) for h in history["hypervolume"]],
        },
        "pareto_csv": (out_dir / "pareto.csv").read_text(encoding="utf-8"),
        "numba_threads": int(m.get("machine", {}).get("numba_threads") or 0) or None,
        "generation": int(m["generations"]),
    }


def _new_record(task: BatchTask, status: str = "running") -> TaskRecord:
    return TaskRecord(config=task.name, source=task.source, seed=task.seed, out_dir=str(task.out_dir), status=status)


def prepare(index: int, task: BatchTask) -> TaskRun | TaskRecord:
    """Look at the task's directory on the client: a TaskRecord if it is finished (skipped) or unusable (failed),
    else a TaskRun starting from the checkpoint found there (if any)."""
    from scalesynth.results import finished as _finished

    try:
        digest = _seeded_digest(task)
        if _finished(task.out_dir, digest):
            rec = _new_record(task, "skipped")
            for k, v in _results_outcome(task.out_dir).items():
                setattr(rec, k, v)
            return rec
        rio.ensure_dir(task.out_dir)
        rio.remove_stale_temps(task.out_dir)  # left by a client killed while writing
        run = TaskRun(index, task, record=_new_record(task))
        path = client_checkpoint(task.out_dir)
        if not path.is_file() and (task.out_dir / rio.CHECKPOINT).is_file():
            path = task.out_dir / rio.CHECKPOINT  # written inside the target by scalesynth < 0.2
        if path.is_file():
            blob = path.read_bytes()
            try:
                state = pickle.loads(blob)
                generation = int(state["history"][-1]["generation"]) if state["history"] else 0
            except Exception as err:  # any unpickling failure means the file is not a usable checkpoint
                raise ConfigError(f"{path}: not a readable checkpoint ({one_line(err)}); remove it to start over") \
                    from None
            if state.get("digest") != digest:
                raise ConfigError(f"{path}: cannot resume: the config differs from the checkpoint's "
                                  "(remove it to start over)")
            run.checkpoint, run.generation = blob, generation
        return run
    except (ScalesynthError, OSError) as err:
        rec = _new_record(task, "failed")
        rec.error = one_line(err)
        return rec


def client_checkpoint(out_dir: Path) -> Path:
    """Where the client keeps an unfinished task's latest checkpoint: the run's staging directory beside its
    target (``scalesynth.rundir``), as for ``optimize --resume``, so the target only ever holds a finished run."""
    from scalesynth import rundir

    return rundir.staging_path(out_dir) / rio.CHECKPOINT


def _write_checkpoint(out_dir: Path, blob: bytes) -> None:
    path = client_checkpoint(out_dir)
    rio.ensure_dir(path.parent)
    rio.write_atomic(path, lambda fh: fh.write(blob), mode="wb")


def _write_results(out_dir: Path, files: dict[str, bytes], force: bool = False) -> None:
    """The results files a finished chunk returned, into the task's staging directory (manifest.json last: it
    marks a finished run), without the checkpoint, then swapped in whole (``rundir``: locked, atomic); with
    ``force`` into a directory that is not a run's, moved in file by file."""
    from scalesynth import rundir

    with rundir.claim(out_dir, force=force) as claimed:
        work = rio.ensure_dir(claimed.work)
        (work / rio.CHECKPOINT).unlink(missing_ok=True)
        (out_dir / rio.CHECKPOINT).unlink(missing_ok=True)  # a legacy checkpoint inside the target
        for name in sorted(files, key=lambda n: n == "manifest.json"):
            if name not in rio.RESULT_FILES:  # only known names: a file name never comes from the worker unchecked
                continue
            blob = files[name]
            rio.write_atomic(work / name, lambda fh, b=blob: fh.write(b), mode="wb")
        claimed.commit()


class LostChunks:
    """Chunk runs that dask lost with a worker, from the scheduler's 'remove-worker' events (topic 'all'): dask
    runs such a chunk again elsewhere from the same checkpoint, and these events are the only trace of it. The
    events are fetched only when a worker has left (or on demand): the topic also logs every gather."""

    def __init__(self, client):
        self.client = client
        try:
            self.known: set[str] = set(client.nthreads())
        except Exception:
            self.known = set()
        self.seen: set[tuple[float, str]] = set()

    def poll(self, force: bool = False) -> list[tuple[str, str]]:
        """New (worker address, chunk key) pairs since the last poll."""
        try:
            workers = set(self.client.nthreads())
            left = bool(self.known - workers)
            self.known = workers
            if not (left or force):
                return []
            events = self.client.get_events("all")
        except Exception:  # the summary loses a retry count, the results nothing
            return []
        out = []
        for stamp, msg in events:
            if not isinstance(msg, dict) or msg.get("action") != "remove-worker" or msg.get("expected"):
                continue
            worker = str(msg.get("worker"))
            if (stamp, worker) in self.seen:
                continue
            self.seen.add((stamp, worker))
            for key in [*(msg.get("processing-tasks") or ()), *(msg.get("lost-computed-tasks") or ())]:
                out.append((worker, str(key)))
        return out


def check_targets(tasks: Sequence[BatchTask], out: Path, force: bool = False) -> None:
    """OUT and every task's directory checked before any task runs: an OUT that cannot be a directory, and unless
    ``force`` a task directory that is not empty and neither a run's nor an unfinished task's, are refused
    (ConfigError naming --out: exit 2) instead of failing that task after its run. A task directory that cannot
    be made (a file in the way) still fails that task alone."""
    from scalesynth import outpath, rundir

    outpath.check_dir(out, "--out")
    for task in tasks:
        rundir.check_own(task.out_dir, rundir.RUN, force, "--out", resuming=True)


def run_tasks(tasks: Sequence[BatchTask], client, echo: Callable[[str], None] | None = None,
              force: bool = False) -> list[TaskRecord]:
    """Drive every task's chain of chunks on the cluster, writing checkpoints and results into the tasks'
    directories on the client; returns the records in task order.

    At most one chunk per connected worker is in flight (pinned to an idle worker, allowed elsewhere if it dies),
    so a worker runs one chunk at a time with all its threads; a task's next chunk goes before other tasks'
    first ones, so tasks finish early instead of all at the end."""
    from distributed import as_completed
    from distributed.scheduler import KilledWorker

    from scalesynth.cluster import client_versions

    records: list[TaskRecord | None] = [None] * len(tasks)
    mine = client_versions()
    done = 0
    n_gen = [int(t.data["algorithm"]["n_gen"]) for t in tasks]
    generations = [0] * len(tasks)  # per task: the generation of the client's latest checkpoint (n_gen: ended)
    last_progress = time.monotonic()

    def progress() -> None:
        nonlocal last_progress
        if echo is None or time.monotonic() - last_progress < PROGRESS_EVERY:
            return
        last_progress = time.monotonic()
        share = 100.0 * sum(generations) / max(1, sum(n_gen))
        echo(f"progress: {done}/{len(tasks)} tasks ended, {len(inflight)} chunks running, generations "
             f"{sum(generations)}/{sum(n_gen)} ({share:.0f} %)")

    def finish(rec: TaskRecord, index: int) -> None:
        nonlocal done
        records[index] = rec
        done += 1
        generations[index] = n_gen[index]
        if echo is not None:
            hv = f"HV {rec.hypervolume:.6g}, " if rec.hypervolume is not None else ""
            why = f": {rec.error}" if rec.error else ""
            retried = f", {rec.retries} retr{'y' if rec.retries == 1 else 'ies'}" if rec.retries else ""
            where = f"[{done}/{len(tasks)}] {rec.config} seed {rec.seed}"
            echo(f"{where}: {rec.status}{why} ({hv}{rec.wall_seconds:.1f} s{retried})")

    def fail(run: TaskRun, error: str) -> None:
        rec = run.record
        rec.status, rec.error, rec.generation = "failed", error, run.generation
        run.checkpoint = None  # the client keeps it in OUT, not in memory
        finish(rec, run.index)

    pending: deque[TaskRun] = deque()
    for i, t in enumerate(tasks):
        prepared = prepare(i, t)
        if isinstance(prepared, TaskRecord):
            finish(prepared, i)
        else:
            pending.append(prepared)

    inflight: dict[Any, tuple[TaskRun, str | None]] = {}  # future -> (task, worker it was pinned to)
    owner: dict[str, TaskRun] = {}  # chunk key -> its task, for the scheduler's lost-worker events
    lost = LostChunks(client)
    completed = as_completed(loop=client.loop)

    def submit_ready() -> None:
        if not pending:
            return
        try:
            workers = list(client.nthreads())
        except Exception:  # the scheduler is busy or gone: submit unpinned, dask places the chunk
            workers = []
        busy = {w for _, w in inflight.values() if w}
        idle = [w for w in workers if w not in busy]
        while pending and (idle or not inflight):
            run = pending.popleft()
            worker = idle.pop(0) if idle else None
            where = {"workers": [worker], "allow_other_workers": True} if worker else {}
            key = run.key()
            fut = client.submit(run_chunk, run.task.data, run.task.seed, run.checkpoint, key=key, pure=False,
                                retries=0, **where)
            inflight[fut] = (run, worker)
            owner[key] = run
            completed.add(fut)

    def note_lost(force: bool = False) -> None:
        for worker, key in lost.poll(force):
            run = owner.get(key)
            if run is None or run.record.status != "running":
                continue
            run.record.retries += 1
            run.record.lost_workers.append(worker)
            if echo is not None:
                echo(f"{run.task.name} seed {run.task.seed}: worker {worker} lost while running generations after "
                     f"{run.generation}; running them again from the client's checkpoint")

    def accept(run: TaskRun, chunk: dict[str, Any]) -> None:
        rec = run.record
        rec.wall_seconds += float(chunk.get("seconds", 0.0))
        rec.worker, rec.worker_name = chunk.get("worker"), chunk.get("worker_name")
        rec.worker_nthreads, rec.numba_threads = chunk.get("worker_nthreads"), chunk.get("numba_threads")
        entry = next((w for w in rec.workers if w["address"] == rec.worker), None)
        if entry is None:
            entry = {"address": rec.worker, "name": rec.worker_name, "nthreads": rec.worker_nthreads,
                     "numba_threads": rec.numba_threads, "chunks": 0}
            rec.workers.append(entry)
        entry["chunks"] += 1
        rec.chunks += 1
        if chunk.get("kind") == "failed":
            return fail(run, str(chunk.get("error")))
        theirs = chunk.get("versions") or {}
        theirs = {**theirs, "python": ".".join(str(theirs.get("python", "")).split(".")[:2]) or None}
        diff = version_differences(mine, {k: theirs.get(k) for k in mine})
        if diff:
            return fail(run, f"worker {rec.worker} ({rec.worker_name}): {'; '.join(diff)}")
        try:
            if chunk.get("kind") == "checkpoint":
                blob = chunk["checkpoint"]
                _write_checkpoint(run.task.out_dir, blob)
                run.checkpoint, run.generation = blob, int(chunk["generation"])
                generations[run.index] = run.generation
                pending.appendleft(run)
                progress()
                return None
            _write_results(run.task.out_dir, chunk["files"], force)
            for k, v in _results_outcome(run.task.out_dir).items():
                setattr(rec, k, v)
        except (ScalesynthError, OSError, KeyError, ValueError) as err:
            return fail(run, one_line(err))
        rec.status = "finished"
        run.checkpoint = None
        finish(rec, run.index)
        return None

    def step() -> None:
        fut = next(completed)
        run, _ = inflight.pop(fut)
        try:
            chunk = fut.result()
        except KilledWorker:  # dask gave up after several workers died running it: try again, a few times
            note_lost(force=True)
            run.resubmits += 1
            if run.resubmits > MAX_RESUBMITS:
                fail(run, f"workers kept dying while running generations after {run.generation} (dask's "
                          f"KilledWorker {run.resubmits} times); re-run to resume from the client's checkpoint")
            else:
                pending.appendleft(run)
            return
        except Exception as err:  # cancelled, or the chunk could not be shipped / unpickled on the worker
            if getattr(client, "status", "running") != "running":
                raise  # the scheduler is gone: handled below, for the whole batch
            fail(run, one_line(err))
            return
        else:
            note_lost()  # before the record is closed: a rerun of this very chunk counts
            accept(run, chunk)
        finally:
            fut.release()
            owner.pop(fut.key, None)

    try:
        submit_ready()
        while inflight:
            step()
            submit_ready()
    except Exception as err:
        if getattr(client, "status", "running") == "running":
            raise  # not a lost scheduler: a bug, let it show
        # the scheduler went away: what is done (results, checkpoints) is in OUT
        raise RunError(f"lost the dask scheduler ({one_line(err)}); finished tasks and the latest checkpoints are "
                       "in OUT: re-run the same command to resume") from None
    return [r for r in records if r is not None]


def nondominated_mask(F: np.ndarray) -> np.ndarray:
    """True for rows of F (minimisation) that no other row weakly dominates with one strict improvement."""
    F = np.asarray(F, dtype=float)
    keep = np.ones(len(F), dtype=bool)
    for i in range(len(F)):
        keep[i] = not np.any(np.all(F <= F[i], axis=1) & np.any(F < F[i], axis=1))
    return keep


def combined_front(fronts: dict[int, Any], keys: Sequence[str], signs: np.ndarray):
    """Non-dominated merge of per-seed fronts (seed -> DataFrame): a DataFrame with a leading ``seed`` column,
    sorted by the objectives in minimisation form, objective-space duplicates kept once (lowest seed), without
    the per-seed ``rank`` column."""
    import pandas as pd

    frames = [f.assign(seed=seed) for seed, f in sorted(fronts.items()) if len(f)]
    if not frames:
        return pd.DataFrame(columns=["seed", *keys])
    rows = pd.concat(frames, ignore_index=True)
    # 'rank' is the rank within one seed's population: meaningless across seeds
    rows = rows[["seed", *[c for c in rows.columns if c not in ("seed", "rank")]]]
    F = rows[list(keys)].to_numpy(dtype=float) * signs
    rows = rows[nondominated_mask(np.where(np.isnan(F), np.inf, F))]  # a statistic over nothing: worst
    order_cols = [f"__f{j}" for j in range(len(keys))]
    Fk = rows[list(keys)].to_numpy(dtype=float) * signs
    rows = rows.assign(**{c: Fk[:, j] for j, c in enumerate(order_cols)})
    rows = rows.sort_values([*order_cols, "seed"], kind="mergesort").drop_duplicates(subset=list(keys))
    return rows.drop(columns=order_cols).reset_index(drop=True)


def hypervolume_figure(histories: dict[int, dict[str, list[float]]], title: str):
    from scalesynth.plotting import plt  # pyplot with the Agg backend selected

    fig, ax = plt.subplots(figsize=(6.5, 4))
    for seed, h in sorted(histories.items()):
        ax.plot(h["generation"], h["hypervolume"], label=f"seed {seed}")
    ax.set_xlabel("generation")
    ax.set_ylabel("hypervolume")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    return fig


def write_combined(out: Path, cfg: RunConfig, records: Sequence[TaskRecord]) -> dict[str, Any]:
    """Write ``combined_pareto.csv`` and ``hypervolume_by_seed.png`` of one config from its successful tasks."""
    import pandas as pd

    from scalesynth import plotting
    from scalesynth.optimize import hypervolume
    from scalesynth.problem import metric_key

    ok = [r for r in records if r.status != "failed"]
    failed = [r.seed for r in records if r.status == "failed"]
    info: dict[str, Any] = {"seeds": [r.seed for r in ok], "failed_seeds": failed}
    if not ok:
        info.update(pareto_size=0, hypervolume=None, files=[])
        return info
    keys = [metric_key(cfg, o) for o in cfg.objectives]
    signs = np.array([-1.0 if o.sense == "max" else 1.0 for o in cfg.objectives])
    fronts = {r.seed: pd.read_csv(io.StringIO(r.pareto_csv or "")) for r in ok}
    front = combined_front(fronts, keys, signs)
    config_dir = rio.ensure_dir(rio.safe_child(out, cfg.name))
    rio.write_csv(config_dir / COMBINED, front)
    fig = hypervolume_figure({r.seed: r.history or {"generation": [], "hypervolume": []} for r in ok},
                             f"{cfg.name}: hypervolume by seed")
    try:
        rio.save_figure(fig, config_dir / HV_PLOT)
    finally:
        plotting.close(fig)
    ref = np.array(ok[0].hv_reference or [0.0] * len(keys))
    F = front[keys].to_numpy(dtype=float) * signs if len(front) else np.zeros((0, len(keys)))
    F = np.where(np.isnan(F), ref[None, :], F)  # a statistic over an empty set counts as the reference (worst)
    info.update(
        pareto_size=int(len(front)),
        hypervolume=hypervolume(F, ref),
        files=[str(config_dir / COMBINED), str(config_dir / HV_PLOT)],
    )
    return info


def run_batch(
    configs: Sequence[tuple[str, RunConfig]],
    out: Path,
    *,
    seeds: int = 1,
    scheduler: str | None = None,
    echo: Callable[[str], None] | None = None,
    force: bool = False,
) -> BatchSummary:
    """Run every (config, seed) task on dask, then write the combined fronts, plots and ``OUT/batch.json``.

    ``out`` is a path on this machine (the client), relative to its working directory; workers never see it.
    Raises ConfigError for bad input (configs, seeds, a malformed scheduler address, a task directory that is not
    a run's unless ``force``: :func:`check_targets`) and RunError when the scheduler cannot be reached or a
    worker's scalesynth or result-relevant packages differ from the client's; all before anything is written."""
    t0 = time.perf_counter()
    out = Path(out).absolute()  # the client's directory: a relative --out is the client's
    tasks = plan(configs, seeds, out)  # bad input fails here, before anything is written
    check_targets(tasks, out, force)  # before connecting: a refused directory costs no cluster
    with dask_client(scheduler, len(tasks)) as client:
        workers = check_workers(client)  # a worker without scalesynth, or another version: nothing is written
        if not workers and echo is not None:
            echo(f"no workers on the scheduler yet: the tasks wait for workers to join ({scheduler})")
        rio.ensure_dir(out)  # after connecting: an unreachable scheduler leaves nothing behind
        records = run_tasks(tasks, client, echo, force)
        workers.update({r.worker: {"name": r.worker_name, "nthreads": r.worker_nthreads}
                        for r in records if r.worker and r.worker not in workers})
    combined = {}
    for _, cfg in configs:
        mine = [r for r in records if r.config == cfg.name]
        try:
            combined[cfg.name] = write_combined(out, cfg, mine)
        except ScalesynthError as err:  # e.g. OUT/<name> is not writable: its tasks failed too, go on
            combined[cfg.name] = {"seeds": [], "failed_seeds": [r.seed for r in mine], "error": one_line(err)}
    summary = BatchSummary(
        out=out,
        scheduler=scheduler or "local",
        tasks=records,
        combined=combined,
        wall_seconds=time.perf_counter() - t0,
        workers=workers,
    )
    rio.write_json(out / SUMMARY, summary.to_dict())
    return summary


def format_table(records: Sequence[TaskRecord]) -> str:
    """Plain-text table of the tasks: config, seed, status, wall time (s), hypervolume, results, error."""
    header = ("config", "seed", "status", "wall_s", "hypervolume", "results", "error")
    rows = [
        (
            r.config,
            str(r.seed),
            r.status,
            f"{r.wall_seconds:.1f}",
            "-" if r.hypervolume is None else f"{r.hypervolume:.6g}",
            r.out_dir,
            r.error or "",
        )
        for r in records
    ]
    widths = [max(len(h), *(len(row[j]) for row in rows)) for j, h in enumerate(header)]
    lines = ["  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip() for row in [header, *rows]]
    return "\n".join(lines)
