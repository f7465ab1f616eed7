"""NSGA-II scale synthesis: run(config) -> RunResult, with checkpoints, resume and per-generation history.

The loop is pymoo's ask/tell; the whole algorithm object (population, its Generator state, counters) is pickled
every ``output.checkpoint_every`` generations, so ``resume`` continues a killed run to the same final front as an
uninterrupted run with the same seed.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
import platform
import time
from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from scalesynth import io as rio
from scalesynth import memory, results, rundir
from scalesynth.config import ConstraintConfig, RunConfig
from scalesynth.errors import ConfigError, RunError
from scalesynth.evaluate import evaluator_description
from scalesynth.problem import SynthesisProblem
from scalesynth.results import RunResult

if TYPE_CHECKING:  # imported where the tables are built, after the search: the first generation does not wait
    import pandas as pd

ProgressFn = Callable[[dict[str, Any]], None]



class CanonicalX:
    """Duplicate-elimination key: designs that are the same model (e.g. equal m - n) count as duplicates."""

    def __init__(self, problem: SynthesisProblem):
        self.problem = problem

    def __call__(self, pop):
        return self.problem.canonical(pop.get("X"))


def config_digest(cfg: RunConfig) -> str:
    """Hash of everything that determines the result (not the output location)."""
    data = cfg.model_dump(mode="json")
    data.pop("output", None)
    return hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()


def make_algorithm(cfg: RunConfig, problem: SynthesisProblem):
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.core.duplicate import DefaultDuplicateElimination
    from pymoo.core.evaluator import Evaluator
    from pymoo.operators.crossover.sbx import SBX
    from pymoo.operators.mutation.pm import PM
    from pymoo.operators.sampling.rnd import FloatRandomSampling

    a = cfg.algorithm
    return NSGA2(
        pop_size=a.pop_size,
        sampling=FloatRandomSampling(),
        crossover=SBX(prob=a.prob_crossover, eta=a.eta_crossover),
        mutation=PM(prob=1.0, prob_var=a.prob_mutation, eta=a.eta_mutation),
        eliminate_duplicates=DefaultDuplicateElimination(epsilon=1e-9, func=CanonicalX(problem)),
        evaluator=Evaluator(evaluate_values_of=["F", "G", "M"]),
    )


def hypervolume(F: np.ndarray, ref: np.ndarray) -> float:
    """Hypervolume (moocore) of the points of F that strictly dominate ``ref`` (minimisation)."""
    import moocore

    if F.size == 0:
        return 0.0
    F = F[np.all(F < ref, axis=1)]
    if F.size == 0:
        return 0.0
    return float(moocore.hypervolume(F, ref=ref))


def _feasible(pop) -> np.ndarray:
    cv = pop.get("CV")
    if cv is None or len(cv) == 0:
        return np.ones(len(pop), dtype=bool)
    return (np.asarray(cv, dtype=float).reshape(len(pop), -1) <= 0).all(axis=1)


def _history_row(algorithm, problem: SynthesisProblem, ref: np.ndarray, elapsed: float) -> dict[str, Any]:
    pop = algorithm.pop
    feas = _feasible(pop)
    F = pop.get("F")[feas]
    opt = algorithm.opt
    opt_F = opt.get("F")[_feasible(opt)] if opt is not None and len(opt) else np.zeros((0, problem.n_obj))
    row = {
        "generation": int(algorithm.n_gen) - 1,  # pymoo counts the next generation
        "evaluations": int(algorithm.evaluator.n_eval),
        "n_nondominated": int(len(opt_F)),
        "n_feasible": int(feas.sum()),
        "hypervolume": hypervolume(opt_F, ref),
    }
    for key, sign in zip(problem.objective_keys, problem.signs, strict=True):
        col = problem.objective_keys.index(key)
        row[f"best_{key}"] = float((F[:, col] * sign).max() if sign < 0 else F[:, col].min()) if len(F) else 0.0
    M = pop.get("M")
    for i, (con, key) in enumerate(zip(problem.cfg.constraints, problem.constraint_keys, strict=True)):
        row[constraint_column(i, key)] = best_for_constraint(con, M[:, problem.metric_columns.index(key)])
    row["seconds"] = round(elapsed, 3)
    return row


def constraint_column(i: int, key: str) -> str:
    """history.csv column of constraint i's best value in the generation's population."""
    return f"constraint{i}_best_{key}"


def best_for_constraint(con: ConstraintConfig, values: np.ndarray) -> float:
    """The value closest to satisfying the constraint: the largest for a lower bound, the smallest for an upper
    bound, the least violating for both; statistics over empty sets (NaN) are left out, and NaN when every one is."""
    values = values[~np.isnan(values)]
    if not len(values):
        return math.nan
    if con.max is None:
        return float(values.max())
    if con.min is None:
        return float(values.min())
    violation = np.maximum(con.min - values, 0.0) + np.maximum(values - con.max, 0.0)
    return float(values[int(np.argmin(violation))])


def _needs(con: ConstraintConfig) -> str:
    if con.max is None:
        return f">= {float(con.min)!r}"
    if con.min is None:
        return f"<= {float(con.max)!r}"
    return f"in [{float(con.min)!r}, {float(con.max)!r}]"


def infeasibility(problem: SynthesisProblem, history: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per constraint: the best value seen over the whole run (from the history) and what it needs."""
    out = []
    for i, (con, key) in enumerate(zip(problem.cfg.constraints, problem.constraint_keys, strict=True)):
        seen = np.array([row[constraint_column(i, key)] for row in history], dtype=float)
        best = best_for_constraint(con, seen) if len(seen) else 0.0
        out.append({"constraint": key, "best": best, "needs": _needs(con)})
    return out



def _versions() -> dict[str, str]:
    """Versions of scalesynth, Python and its dependencies (recorded in the manifest; ``versions`` owns the list)."""
    from scalesynth.versions import installed_versions

    return installed_versions()


def _pareto_frame(problem: SynthesisProblem, algorithm) -> tuple[pd.DataFrame, pd.DataFrame, int]:
    """(pareto, population, number of objective-space duplicates dropped from the front)."""
    import pandas as pd
    from pymoo.util.nds.non_dominated_sorting import NonDominatedSorting

    cfg = problem.cfg
    pop = algorithm.pop
    X, F = pop.get("X"), pop.get("F")
    M = problem.complete_metrics(X, pop.get("M"))
    feas = _feasible(pop)
    rank = np.full(len(pop), -1, dtype=int)
    if feas.any():
        idx = np.nonzero(feas)[0]
        for r, front in enumerate(NonDominatedSorting().do(F[idx])):
            rank[idx[front]] = r
    rows = []
    for i, design in enumerate(problem.designs(X)):
        row: dict[str, Any] = dict(zip(problem.var_names, map(float, X[i]), strict=True))  # with a gear ratio
        row.update(cfg.mech.derived_columns(design))
        row.update({k: M[i, j] for j, k in enumerate(problem.metric_columns)})
        row["voxels"] = int(round(row["voxels"]))
        row["feasible"] = bool(feas[i])
        row["rank"] = int(rank[i])
        rows.append(row)
    population = pd.DataFrame(rows)
    measure = cfg.mech.measure_key(cfg.units.length)
    sort_cols = [measure, *problem.objective_keys]
    sort_cols = list(dict.fromkeys(sort_cols))
    population = population.sort_values(
        ["rank", *sort_cols], ascending=[True] + [False] * len(sort_cols), kind="mergesort"
    ).reset_index(drop=True)
    front = population[(population["rank"] == 0) & population["feasible"]]
    deduped = front.drop_duplicates(subset=problem.objective_keys, keep="first")
    pareto = deduped.drop(columns=["feasible"]).reset_index(drop=True)
    return pareto, population, len(front) - len(deduped)


def run(
    cfg: RunConfig,
    out_dir: Path | None = None,
    *,
    seed: int | None = None,
    resume: bool = False,
    progress: ProgressFn | None = None,
    plots: bool = True,
    stop_after: int | None = None,
    on_checkpoint: Callable[[Path, int], None] | None = None,
    force: bool = False,
) -> RunResult:
    """Run NSGA-II for ``cfg`` and write the results directory.

    ``stop_after`` (generations) ends the loop early without writing final results, leaving a checkpoint: it
    exists for tests of resume and for chunked runs. ``on_checkpoint(path, generation)`` is called after every
    checkpoint write (the last one too, before the results are written); an exception it raises ends the run
    there, leaving that checkpoint (the batch runner ships checkpoints to its client this way).

    The target must be new, empty or a run directory (``scalesynth.rundir``); ``force`` lets the run add its files
    to any other directory, replacing only files of the names it writes.
    """
    if seed is not None:
        cfg = cfg.model_copy(update={"algorithm": cfg.algorithm.model_copy(update={"seed": seed})})
    target = Path(out_dir) if out_dir is not None else cfg.output_dir()
    problem = SynthesisProblem(cfg)  # validates everything (bounds, objectives) before anything is written
    memory.check(memory.run_estimates(cfg, plots))  # refuse what cannot fit before allocating (issue 11)
    ref = problem.hv_reference()
    digest = config_digest(cfg)
    history: list[dict[str, Any]] = []
    elapsed_before = 0.0
    started = datetime.now(UTC).isoformat(timespec="seconds")
    fresh_algorithm = make_algorithm(cfg, problem)
    fresh_algorithm.setup(problem, termination=("n_gen", cfg.algorithm.n_gen), seed=cfg.algorithm.seed, verbose=False)
    algorithm = None
    # ---- run directory (scalesynth.rundir, issue 11): lock the target, write into its staging directory -------
    with rundir.claim(target, rundir.RUN, force, resuming=resume) as claimed:
        out = claimed.continued() if resume else None
        ckpt_path = claimed.work / rio.CHECKPOINT
        if out is not None and ckpt_path.exists():
            state = rio.read_checkpoint(ckpt_path)
            if state.get("digest") != digest:
                raise ConfigError(
                    f"{target}: cannot resume: the config differs from the checkpoint's (start without --resume)"
                )
            algorithm = state["algorithm"]
            algorithm.problem = problem
            algorithm.evaluator.evaluate_values_of = ["F", "G", "M"]
            history = state["history"]
            elapsed_before = state["elapsed"]
            started = state["started"]
        elif out is not None and results.finished(out, digest):  # killed after its last write, before the swap
            claimed.commit()
            return results.load(target)
        elif resume and results.finished(target, digest):
            return results.load(target)
        if algorithm is None:
            out = claimed.fresh()  # a fresh run: an abandoned staging directory belongs to another run
            algorithm = fresh_algorithm
        result = _run_generations(cfg, problem, algorithm, out, ckpt_path, ref, digest, history, elapsed_before,
                                  started, progress, plots, stop_after, on_checkpoint)
        claimed.commit()
    # ---- end of the run-directory block ------------------------------------------------------------------------
    return dataclasses.replace(result, out_dir=target)  # the same run, now at its target


def _run_generations(cfg, problem, algorithm, out, ckpt_path, ref, digest, history, elapsed_before, started,
                     progress, plots, stop_after, on_checkpoint=None) -> RunResult:
    """The NSGA-II loop from ``algorithm``'s state; writes checkpoints and the results into ``out``."""
    # compile the kernels before the clock starts on the first generation
    problem.metrics(np.atleast_2d((problem.xl + problem.xu) / 2))
    t0 = time.perf_counter()
    gens_this_call = 0
    while algorithm.has_next():
        pop = algorithm.ask()
        algorithm.evaluator.eval(problem, pop)
        algorithm.tell(infills=pop)
        gens_this_call += 1
        elapsed = elapsed_before + time.perf_counter() - t0
        row = _history_row(algorithm, problem, ref, elapsed)
        history.append(row)
        if progress is not None:
            progress({**row, "n_gen": cfg.algorithm.n_gen})
        done = not algorithm.has_next()
        if done or row["generation"] % cfg.output.checkpoint_every == 0 or stop_after == gens_this_call:
            rio.write_pickle(
                ckpt_path,
                {"algorithm": algorithm, "history": history, "elapsed": elapsed, "digest": digest, "started": started},
            )
            if on_checkpoint is not None:
                on_checkpoint(ckpt_path, row["generation"])
        if stop_after is not None and gens_this_call >= stop_after and not done:
            raise RunError(f"stopped after {gens_this_call} generations (checkpoint in {ckpt_path})")
    wall = elapsed_before + time.perf_counter() - t0
    pareto, population, dropped = _pareto_frame(problem, algorithm)
    import pandas as pd

    history_df = pd.DataFrame(history)
    n_feasible = int(_feasible(algorithm.pop).sum())
    manifest = {
        "name": cfg.name,
        "status": "finished",
        "mechanism": cfg.mechanism,
        "seed": cfg.algorithm.seed,
        "config_digest": digest,
        "started": started,
        "finished": datetime.now(UTC).isoformat(timespec="seconds"),
        "wall_seconds": round(wall, 3),
        "generations": int(algorithm.n_gen) - 1,
        "evaluations": int(algorithm.evaluator.n_eval),
        "pop_size": cfg.algorithm.pop_size,
        "grid_resolution": cfg.grid.resolution,
        "workspace_evaluator": evaluator_description(cfg),
        "objectives": [f"{o.sense} {k}" for o, k in zip(cfg.objectives, problem.objective_keys, strict=True)],
        "hv_reference": [float(v) for v in ref],
        "hv_reference_note": "in minimisation form: maximised objectives enter negated",
        "hypervolume": history[-1]["hypervolume"] if history else 0.0,
        "pareto_size": int(len(pareto)),
        "objective_duplicates_dropped": int(dropped),
        "feasible_in_final_population": n_feasible,
        "no_feasible_design": infeasibility(problem, history) if n_feasible == 0 and cfg.constraints else [],
        "machine": {
            "cores": os.cpu_count(),
            "platform": platform.platform(),
            "processor": platform.processor() or platform.machine(),
            "numba_threads": _numba_threads(),
        },
        "versions": _versions(),
        "config": cfg.model_dump(mode="json"),
    }
    result = RunResult(out_dir=out, cfg=cfg, pareto=pareto, history=history_df, manifest=manifest,
                       population=population, problem=problem)
    results.write_tables(result)
    if plots:
        from scalesynth.report import write_plots_and_report

        write_plots_and_report(result)  # from the run in memory: the same figures as the manifest
    manifest["files"] = [*rundir.listing(out), results.MANIFEST]  # what the next run on this directory replaces
    results.write_manifest(result)  # last: its presence marks a finished run
    if ckpt_path.exists():
        ckpt_path.unlink()
    return result


def _numba_threads() -> int:
    import numba

    return int(numba.get_num_threads())


def reproduce(
    run_dir: Path, out_dir: Path, on_versions: Callable[[list[str]], None] | None = None, force: bool = False
) -> dict[str, Any]:
    """Re-run a finished run from its manifest's config and seed into ``out_dir``; compare pareto.csv bytes.

    ``on_versions`` is called, once the run has been read and checked and before the re-run starts, with the
    recorded dependency versions that differ from the installed ones (``versions.version_differences``)."""
    from scalesynth.config import config_from_dict
    from scalesynth.versions import version_differences

    run_real, out_real = Path(run_dir).resolve(), Path(out_dir).resolve()
    if out_real == run_real or run_real in out_real.parents:
        raise ConfigError(f"--out: {out_dir} is the run being checked (or inside it); re-run somewhere else")
    original = results.load(run_dir)
    try:
        cfg = config_from_dict(original.manifest["config"])
    except ConfigError as err:
        raise ConfigError(f"{Path(run_dir) / 'manifest.json'}: config: {err}") from None
    differences = version_differences(original.manifest.get("versions"))
    if on_versions is not None:
        on_versions(differences)
    result = run(cfg, out_dir, plots=False, force=force)
    same = (Path(run_dir) / results.PARETO).read_bytes() == (Path(out_dir) / results.PARETO).read_bytes()
    return {
        "identical": same,
        "original": str(run_dir),
        "rerun": str(out_dir),
        "wall_seconds": result.manifest["wall_seconds"],
        "hypervolume": result.manifest["hypervolume"],
        "original_hypervolume": original.manifest["hypervolume"],
        "version_differences": differences,
    }
