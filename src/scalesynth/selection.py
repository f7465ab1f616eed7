"""Decision support: pick one design from a Pareto front (knee, balanced, or weighted)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from scalesynth.errors import InvalidParameter

METHODS = ("knee", "balanced", "weights")


def normalised(F: np.ndarray) -> np.ndarray:
    """Objectives (minimisation form) scaled to [0, 1] per column by the front's ideal and nadir points."""
    lo, hi = F.min(axis=0), F.max(axis=0)
    span = np.where(hi > lo, hi - lo, 1.0)
    return (F - lo) / span


def choose(F: np.ndarray, method: str = "knee", weights: Sequence[float] | None = None) -> int:
    """Index of the chosen row of F (minimisation form).

    knee: the point farthest below the hyperplane through the front's extreme points (for two objectives, the
    line joining the two ends), i.e. where a small gain in one objective costs most in the others.
    balanced: the point closest to the ideal point in normalised objective space.
    weights: the smallest weighted sum of normalised objectives (weights >= 0, not all 0).
    """
    F = np.asarray(F, dtype=float)
    if F.ndim != 2 or len(F) == 0:
        raise InvalidParameter("front: empty, nothing to select")
    if method not in METHODS:
        raise InvalidParameter(f"--method: must be one of {', '.join(METHODS)}, got {method!r}")
    if len(F) == 1:
        return 0
    N = normalised(F)
    if method == "balanced":
        return int(np.argmin(np.linalg.norm(N, axis=1)))
    if method == "weights":
        w = np.asarray(weights if weights is not None else [1.0] * F.shape[1], dtype=float)
        if w.shape != (F.shape[1],) or np.any(w < 0) or not np.any(w > 0) or not np.all(np.isfinite(w)):
            raise InvalidParameter(f"--weights: need {F.shape[1]} non-negative numbers, not all zero")
        return int(np.argmin(N @ (w / w.sum())))
    # knee: hyperplane through the extreme points e_k (argmin of objective k) -> n . f = 1
    ext = N[np.argmin(N, axis=0)]
    try:
        normal = np.linalg.solve(ext, np.ones(F.shape[1]))
    except np.linalg.LinAlgError:
        return int(np.argmin(np.linalg.norm(N, axis=1)))
    if not np.all(np.isfinite(normal)) or np.linalg.norm(normal) == 0:
        return int(np.argmin(np.linalg.norm(N, axis=1)))
    dist = (1.0 - N @ normal) / np.linalg.norm(normal)  # > 0: on the ideal side of the plane
    return int(np.argmax(dist))


def extremes(F: np.ndarray) -> list[int]:
    """Row index of the best point of each objective (minimisation form), without repeats."""
    return list(dict.fromkeys(int(i) for i in np.argmin(np.asarray(F), axis=0)))


SIGNATURE = "written by `scalesynth select`"  # in the first line of every config select writes


def select_design(run_dir, method: str = "knee", weights: Sequence[float] | None = None, out=None,
                  force: bool = False) -> dict:
    """Choose a design of a finished run's front and write it as an evaluate-ready config.

    Returns {"method", "design", "metrics", "config"}; the config is the run's config with ``design`` replaced.
    An existing file at ``out`` is replaced only if select wrote it (its first line says so) or with ``force``.
    """
    from pathlib import Path

    import yaml

    from scalesynth import io as rio
    from scalesynth import results

    run_dir = Path(run_dir)
    given = Path(out) if out is not None else run_dir / f"selected_{method}.yaml"
    target = check_target(given, force)
    result = results.load(run_dir, require_finished=False)
    cfg, pareto, problem = result.cfg, result.pareto, result.problem
    if not len(pareto):
        raise InvalidParameter(f"{run_dir}: the front is empty (no feasible design), nothing to select")
    i = choose(result.objective_matrix(), method, weights)
    row = pareto.iloc[i]
    design = result.design_of(row)
    metrics = {k: float(row[k]) for k in problem.metric_columns if k in row.index}
    data = cfg.model_dump(mode="json")
    data["design"] = design
    data["name"] = f"{cfg.name}-{method}"
    header = f"# {method} design of {run_dir} (row {i} of pareto.csv), {SIGNATURE}\n"
    rio.ensure_dir(target.parent)
    rio.write_text(target, header + yaml.safe_dump(data, sort_keys=False))
    return {"method": method, "row": int(i), "design": design, "metrics": metrics, "config": str(given)}


def check_target(target, force: bool = False):
    """The resolved file ``select`` may write (``scalesynth.outpath.check_file``); an existing file that select did
    not write is refused (ConfigError naming --out) unless ``force``."""
    from scalesynth import outpath

    real, exists = outpath.check_file(target)
    if exists and not force:
        try:
            with open(real, "rb") as fh:
                first = fh.readline(4096).decode("utf-8", errors="replace")
        except OSError as err:
            raise InvalidParameter(f"--out: {outpath.shown(target)}: cannot read ({err.strerror or err})") from None
        if not first.startswith("#") or SIGNATURE not in first:
            raise InvalidParameter(f"--out: {outpath.shown(target)}: exists and was not written by select; "
                                   "give a new file name, or --force to replace it")
    return real
