"""Batch synthesis on dask.distributed: every (config, seed) pair is one task running ``optimize.run``.

Layout of a batch directory OUT::

    OUT/batch.json                              summary of the last batch run (written atomically)
    OUT/<config name>/seed<k>/                  one results directory per task (plots off)
    OUT/<config name>/combined_pareto.csv       non-dominated merge of the seeds' fronts
    OUT/<config name>/hypervolume_by_seed.png   hypervolume per generation, one line per seed

Tasks run with ``resume=True``: re-running the same batch skips tasks whose directory holds a finished manifest
of the same config and seed, and continues unfinished ones from their checkpoints. One failing task never stops
the others; it is reported with a one-line error.

A task returns everything the summary needs (its pareto.csv text and hypervolume history), so the client needs
no access to the workers' disks; with ``--scheduler`` the task directories live where the workers write them
(the same OUT path on each worker: use a shared filesystem to have them all in one place).

dask is an optional dependency (``pip install scalesynth[dask]``): it is imported only here, lazily.
"""

from __future__ import annotations

import io
import logging
import os
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from scalesynth import io as rio
from scalesynth.config import RunConfig
from scalesynth.errors import ConfigError, RunError, ScalesynthError

SUMMARY = "batch.json"
COMBINED = "combined_pareto.csv"
HV_PLOT = "hypervolume_by_seed.png"
MAX_SEED = 2**32 - 1
CONNECT_TIMEOUT = "20s"  # for --scheduler: how long to try to reach the scheduler


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
    """Outcome of one task. ``wall_seconds`` is the time spent on it in this batch (seconds); ``run_seconds``
    the run's own wall time from its manifest (all sessions of a resumed run)."""

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

    def summary(self) -> dict[str, Any]:
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
        }


@dataclass
class BatchSummary:
    out: Path
    scheduler: str
    tasks: list[TaskRecord]
    combined: dict[str, dict[str, Any]]
    wall_seconds: float

    @property
    def n_failed(self) -> int:
        return sum(t.status == "failed" for t in self.tasks)

    def to_dict(self) -> dict[str, Any]:
        return {
            "out": str(self.out),
            "scheduler": self.scheduler,
            "wall_seconds": round(self.wall_seconds, 3),
            "n_tasks": len(self.tasks),
            "n_finished": sum(t.status == "finished" for t in self.tasks),
            "n_skipped": sum(t.status == "skipped" for t in self.tasks),
            "n_failed": self.n_failed,
            "tasks": [t.summary() for t in self.tasks],
            "combined": self.combined,
        }


def one_line(err: BaseException) -> str:
    """A one-line description of an exception: the library's own message, else 'TypeName: message'."""
    text = str(err) if isinstance(err, ScalesynthError) else f"{type(err).__name__}: {err}"
    text = " ".join(text.split())
    return text or type(err).__name__


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


def run_task(data: dict[str, Any], seed: int, out_dir: str) -> dict[str, Any]:
    """Run (or skip, or resume) one task; executed on a dask worker. Never raises: failures are returned."""
    from scalesynth import results
    from scalesynth.config import config_from_dict
    from scalesynth.optimize import config_digest, run

    t0 = time.perf_counter()
    out = Path(out_dir)
    try:
        cfg = config_from_dict(data)
        seeded = cfg.model_copy(update={"algorithm": cfg.algorithm.model_copy(update={"seed": seed})})
        if results.finished(out, config_digest(seeded)):
            result, status = results.load(out), "skipped"
        else:
            result, status = run(cfg, out, seed=seed, resume=True, progress=None, plots=False), "finished"
        m = result.manifest
        history = result.history
        return {
            "status": status,
            "wall_seconds": time.perf_counter() - t0,
            "run_seconds": float(m["wall_seconds"]),
            "hypervolume": float(m["hypervolume"]),
            "pareto_size": int(m["pareto_size"]),
            "hv_reference": [float(v) for v in m["hv_reference"]],
            "history": {
                "generation": [int(g) for g in history["generation"]],
                "hypervolume": [float(h) for h in history["hypervolume"]],
            },
            "pareto_csv": (out / results.PARETO).read_text(encoding="utf-8"),
        }
    except Exception as err:  # a task boundary: report any failure, let the other tasks go on
        return {"status": "failed", "error": one_line(err), "wall_seconds": time.perf_counter() - t0}


def local_cluster_shape(n_tasks: int, cores: int | None = None) -> tuple[int, int]:
    """(worker processes, Numba threads per worker) for an embedded cluster: workers x threads <= cores."""
    cores = max(1, cores or os.cpu_count() or 1)
    workers = max(1, min(n_tasks, cores))
    return workers, max(1, cores // workers)


@contextmanager
def dask_client(scheduler: str | None, n_tasks: int) -> Iterator[Any]:
    """A dask Client: on the cluster at ``scheduler`` (used as it is), else on an embedded LocalCluster of
    worker processes with one task thread each and NUMBA_NUM_THREADS set so the machine is not oversubscribed."""
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise RunError("batch needs dask.distributed: pip install 'scalesynth[dask]'") from None
    if scheduler:
        try:
            client = Client(scheduler, timeout=CONNECT_TIMEOUT)
        except (OSError, TimeoutError, ValueError) as err:
            raise RunError(f"--scheduler {scheduler}: cannot connect ({one_line(err)})") from None
        with client:
            yield client
        return
    workers, numba_threads = local_cluster_shape(n_tasks)
    cluster = LocalCluster(
        n_workers=workers,
        threads_per_worker=1,
        processes=True,
        # the scheduler always serves HTTP (health routes): a free port, not the default 8787; no dashboard
        dashboard_address=":0",
        scheduler_kwargs={"dashboard": False},
        silence_logs=logging.ERROR,
        env={"NUMBA_NUM_THREADS": str(numba_threads)},
    )
    with cluster, Client(cluster) as client:
        yield client


def _record(task: BatchTask, outcome: dict[str, Any]) -> TaskRecord:
    return TaskRecord(config=task.name, source=task.source, seed=task.seed, out_dir=str(task.out_dir), **outcome)


def run_tasks(tasks: Sequence[BatchTask], client, echo: Callable[[str], None] | None = None) -> list[TaskRecord]:
    """Submit every task, collect the outcomes as they complete; returned in task order."""
    from dask.distributed import as_completed

    futures = {
        client.submit(run_task, t.data, t.seed, str(t.out_dir), key=t.key, pure=False, retries=0): i
        for i, t in enumerate(tasks)
    }
    records: list[TaskRecord | None] = [None] * len(tasks)
    for done, fut in enumerate(as_completed(futures), start=1):
        i = futures[fut]
        try:
            outcome = fut.result()
        except Exception as err:  # the worker died (e.g. killed) or the task could not be shipped
            outcome = {"status": "failed", "error": one_line(err)}
        records[i] = rec = _record(tasks[i], outcome)
        if echo is not None:
            hv = f"HV {rec.hypervolume:.6g}, " if rec.hypervolume is not None else ""
            why = f": {rec.error}" if rec.error else ""
            where = f"[{done}/{len(tasks)}] {rec.config} seed {rec.seed}"
            echo(f"{where}: {rec.status}{why} ({hv}{rec.wall_seconds:.1f} s)")
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
    rows = rows[nondominated_mask(F)]
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
) -> BatchSummary:
    """Run every (config, seed) task on dask, then write the combined fronts, plots and ``OUT/batch.json``."""
    t0 = time.perf_counter()
    out = Path(out)
    tasks = plan(configs, seeds, out)  # bad input fails here, before anything is written
    with dask_client(scheduler, len(tasks)) as client:
        rio.ensure_dir(out)  # after connecting: an unreachable scheduler leaves nothing behind
        records = run_tasks(tasks, client, echo)
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
