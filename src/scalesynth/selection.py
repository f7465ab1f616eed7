"""Decision support: pick one design from a Pareto front (knee, balanced, or weighted), and the one design
selector of every per-design command.

Per-design commands (evaluate, show, cycle, stiffness, ik, fk, mobility, plot-task) read their design through
:func:`load_design`: from a config (its ``design``), from a results directory with ``--design`` (:func:`choose_row`:
``knee``, ``best-<metric>`` or a row of pareto.csv), or, for the pose-level commands, from a mechanism name (its
defaults); ``--set`` overrides apply in every case.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from scalesynth.errors import InvalidParameter
from scalesynth.names import did_you_mean, hint

SELECTOR = "knee, best-<metric> or a row number"

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
    data = result.config_of(row).model_dump(mode="json")  # with the row's gear ratio, when the search varies it
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


# ----- the design selector of every per-design command ---------------------------------------------------------
@dataclass(frozen=True)
class DesignSource:
    """One design and where it came from. ``cfg``: the config (None for a bare mechanism name), with --set applied
    and ``design`` replaced by the chosen one; ``label``: 'config', 'defaults', 'knee', 'best-<metric>' or
    'row<k>' (with '-set' when --set changed the design of a results row); ``row``: of pareto.csv or None;
    ``result``: the results.RunResult of a results directory, else None."""

    mech: Any
    design: dict[str, float]
    options: dict[str, Any]
    cfg: Any = None
    label: str = "config"
    row: int | None = None
    result: Any = None


def _metric_column(result, wanted: str) -> tuple[str, str, str | None]:
    """(column of pareto.csv, name in the label, better sense or None) of ``best-<wanted>``: a catalogue metric
    name (``volume`` also as ``area`` or ``measure``) or a metric column of pareto.csv (band columns included)."""
    from scalesynth.metrics import catalogue

    cfg, pareto, problem = result.cfg, result.pareto, result.problem
    cat = catalogue(cfg.mech, cfg.units.length)
    n_bands = len(cfg.dexterity.band_edges) - 1
    by_column = {col: m for m in cat.values() for col in m.columns(n_bands)}
    name = "volume" if wanted in ("area", "measure") else wanted
    metric = cat.get(name)
    if metric is not None and "band" not in metric.needs:
        column = metric.column
    elif wanted in pareto.columns and wanted not in problem.var_names and wanted != "rank":
        column, metric = wanted, by_column.get(wanted)
    else:
        known = [m.name for m in cat.values() if "band" not in m.needs and m.column in pareto.columns]
        known += [c for c in pareto.columns if c in by_column and "band" in by_column[c].needs]
        raise InvalidParameter(f"--design: unknown metric {wanted[:40]!r} of this run "
                               + hint(wanted, known, more=f"see `scalesynth metrics {cfg.mech.name}`"))
    if column not in pareto.columns:
        raise InvalidParameter(f"--design: best-{wanted}: {column} is not a column of this run's pareto.csv (its "
                               f"config computes no {metric.family} metrics)")
    return column, name, None if metric is None else metric.better


def choose_row(result, choice: str) -> tuple[int, str]:
    """(row of pareto.csv, label) of a results.RunResult's front for a design selector: ``knee`` (:func:`choose`),
    ``best-<metric>`` (the best value of a catalogue metric or a metric column: in the objective's sense when it is
    an objective, otherwise in the catalogue's better sense) or a row number (``3`` or ``row3``)."""
    pareto, problem = result.pareto, result.problem
    if not len(pareto):
        raise InvalidParameter(f"--design: the front of {result.out_dir} is empty (no feasible design), nothing to "
                               "choose")
    choice = str(choice).strip()
    if choice == "knee":
        return choose(result.objective_matrix(), "knee"), "knee"
    if choice.startswith("best-"):
        column, name, better = _metric_column(result, choice[len("best-"):])
        sense = better
        if column in problem.objective_keys:
            sense = "min" if problem.signs[problem.objective_keys.index(column)] > 0 else "max"
        if sense not in ("min", "max"):
            raise InvalidParameter(f"--design: best-{name}: {name} has no better direction; choose a row instead")
        values = pareto[column].to_numpy(dtype=float)
        if not np.isfinite(values).any():
            raise InvalidParameter(f"--design: best-{name}: no design of the front has a value of {column}")
        row = int(np.nanargmax(values) if sense == "max" else np.nanargmin(values))
        return row, f"best-{name}"
    m = re.fullmatch(r"(?:row)?(-?\d+)", choice)
    if m is None:
        tip = did_you_mean(choice, ["knee", "best-"])
        raise InvalidParameter(f"--design: expected {SELECTOR}, got {choice[:40]!r}" + (f" ({tip})" if tip else ""))
    row = int(m.group(1))
    if not 0 <= row < len(pareto):
        raise InvalidParameter(f"--design: row {row} is not in pareto.csv (rows 0..{len(pareto) - 1})")
    return row, f"row{row}"


def _looks_like_path(text: str) -> bool:
    return any(sep in text for sep in ("/", "\\")) or text.endswith((".yaml", ".yml")) or text in (".", "..")


def load_design(source: str | Path, design: str | None = None, sets: Sequence[str] | None = None, *,
                mechanism_ok: bool = False) -> DesignSource:
    """The design a per-design command works on, from ``source``:

    * a results directory: its front row chosen by ``design`` (default knee), its config;
    * a config file: its ``design`` (``design`` must be None or 'config');
    * with ``mechanism_ok``, a registered mechanism name: its default design and options.

    ``sets`` (``--set key=value``) apply to the config in the first two cases (a design parameter overrides the
    chosen row's value) and to the design and options of a mechanism name."""
    from scalesynth.config import apply_overrides, config_from_dict, load_config

    sets = list(sets or [])
    text = str(source)
    path = Path(source)
    try:
        is_dir, is_file = path.is_dir(), path.is_file()
    except OSError:  # e.g. a name too long for a file name: not a path, maybe a (misspelt) mechanism name
        is_dir = is_file = False
    if is_dir:
        from scalesynth import results

        result = results.load(path, require_finished=False)
        mech = result.cfg.mech
        row, label = choose_row(result, design or "knee")
        chosen = result.design_of(result.pareto.iloc[row])
        cfg = result.config_of(result.pareto.iloc[row])  # the row's gear ratio, when the search varies it
        if sets:
            cfg = config_from_dict(cfg.model_dump(mode="json"), sets)
            changed = apply_overrides({}, sets, set(mech.parameter_names)).get("design") or {}
            if changed:
                chosen = mech.resolve_design({**chosen, **{k: cfg.design[k] for k in changed if k in cfg.design}})
                label += "-set"
        cfg = cfg.model_copy(update={"design": chosen})
        return DesignSource(mech, chosen, cfg.resolved_options(), cfg, label, row, result)
    if is_file or _looks_like_path(text) or not mechanism_ok:
        if design not in (None, "config"):
            raise InvalidParameter(f"--design {design[:40]}: a config uses its own design (change it with --set); "
                                   f"give a results directory to choose {SELECTOR}")
        cfg = load_config(path, sets)
        return DesignSource(cfg.mech, cfg.resolved_design(), cfg.resolved_options(), cfg, "config")
    from scalesynth.mechanisms import get

    if design is not None:
        raise InvalidParameter(f"--design {design[:40]}: a mechanism name has one design (its defaults, changed with "
                               f"--set); give a results directory to choose {SELECTOR}")
    mech = get(text)
    data = apply_overrides({}, sets, set(mech.parameter_names))
    extra = set(data) - {"design", "options"}
    if extra:
        raise InvalidParameter(f"--set {sorted(extra)[0]}: only design parameters and options apply to a mechanism "
                               "name (give a config for the other sections)")
    return DesignSource(mech, mech.resolve_design(data.get("design")), mech.resolve_options(data.get("options")),
                        None, "defaults")
