"""Metric assembly: statistics rows -> catalogue metric columns (stats_to_metrics), and every catalogue metric
of designs from the workspace statistics, the task grid and the computed families (metrics_of)."""

from __future__ import annotations

from collections.abc import Collection, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from scalesynth import metrics as _metrics
from scalesynth.evaluation.grid import task_grid
from scalesynth.kernels import grid as _grid

if TYPE_CHECKING:  # annotations only: nothing here imports the mechanisms
    from scalesynth.mechanisms.base import Mechanism


def field_mean(stats: np.ndarray, f: int) -> np.ndarray:
    """Mean of field slot ``f`` over the reachable cells of statistics rows (slot 0: the GCI); NaN where nothing is
    reachable (a statistic over nothing; ``stats_to_metrics``)."""
    count = stats[:, _grid.COL_COUNT]
    has = count > 0
    return np.where(has, stats[:, _grid.field_column(f, _grid.STAT_SUM)] / np.where(has, count, 1.0), np.nan)


def stats_to_metrics(
    mech: Mechanism,
    stats: np.ndarray,
    cell_measure: np.ndarray,
    total_cells: float,
    entries: Sequence[_metrics.Metric],
    n_bands: int,
) -> dict[str, np.ndarray]:
    """Metric arrays of the catalogue ``entries`` (one family) from statistics rows (n, stat_columns). Over an
    empty region the measure, count and coverage are 0, and every statistic over its cells (mean, std, min, max of
    a field, band shares) is NaN: null in JSON, an empty CSV cell, the worst value in the search (problem.py);
    never a number that could read as best (issue 27: an unreachable task box gave task_max_deflection 0). The one
    exception is the metric's ``empty`` value (the GCI: 0 over an empty set, the documented convention)."""
    count = stats[:, _grid.COL_COUNT]
    has = count > 0
    safe = np.where(has, count, 1.0)
    slots = {name: i for i, name in enumerate(mech.field_names)}
    nf = mech.n_fields
    out: dict[str, np.ndarray] = {}
    for m in entries:
        st = m.statistic
        if st == "measure":
            out[m.column] = count * cell_measure
        elif st == "count":
            out[m.column] = count.astype(np.int64)
        elif st == "coverage":
            out[m.column] = count / total_cells
        elif st in ("band_share", "band_measure"):
            for b in range(n_bands):
                band = stats[:, _grid.band_column(nf, b)]
                out[m.column_for(b)] = np.where(has, band / safe, np.nan) if st == "band_share" else band * cell_measure
        else:
            f = slots[m.field]
            mean = field_mean(stats, f)
            if st == "mean":
                out[m.column] = mean
            elif st == "std":
                var = np.where(has, stats[:, _grid.field_column(f, _grid.STAT_SUMSQ)] / safe - mean * mean, np.nan)
                out[m.column] = np.sqrt(np.maximum(var, 0.0))  # NaN stays NaN
            else:
                col = _grid.field_column(f, _grid.STAT_MIN if st == "min" else _grid.STAT_MAX)
                out[m.column] = np.where(has, stats[:, col], np.nan)
        if m.empty is not None:
            for col in m.columns(n_bands):
                out[col] = np.where(has, out[col], m.empty)
    return out


def metrics_of(
    mech: Mechanism,
    resolved: list[dict[str, float]],
    options: dict[str, Any],
    packed: np.ndarray,
    workspace_stats: np.ndarray | None,
    cell: np.ndarray | None,
    resolution: int,
    band_edges: Sequence[float],
    unit: str,
    task: Any,
    cycle: Any = None,
    families: Collection[str] | None = None,
    fields: Collection[str] | None = None,
) -> dict[str, np.ndarray]:
    """Every catalogue metric of the designs (of ``families`` only, when given): workspace statistics given (None
    when the workspace family is not asked for; of ``fields`` only, when given), task statistics (on the uniform
    task grid) and the computed families (design, path, cycle) evaluated here."""
    has_path = task is not None and task.path is not None
    # the adaptive evaluator's error estimates (statistic "estimate") come with its statistics, from the caller
    entries = [m for m in _metrics.result_metrics(mech, unit, task is not None, has_path, options, cycle)
               if m.statistic != "estimate"]
    if families is not None:
        entries = [m for m in entries if m.family in families]
    n_bands = len(band_edges) - 1
    out = {}
    if workspace_stats is not None:
        out.update(stats_to_metrics(mech, workspace_stats, cell, 0.0,
                                    [m for m in entries if m.family == "workspace"
                                     and (fields is None or _metrics.field_of(m) in fields)], n_bands))
    n = packed.shape[0]
    if task is not None and any(m.family == "task" for m in entries):
        tg = task_grid(mech, task, resolution)
        edges = np.asarray(band_edges, dtype=float)
        # the task box always on the uniform grid (task.resolution, else grid.resolution): the column evaluator on
        # the task box (boxes=) misses sliver coverages entirely (fivebar_stiffness, 20 random designs: one design
        # at 0.2 % coverage read as 0, task_gci 0.05 off; the others within 1e-4 of a 384^2 grid) and costs more
        # than the 32^2-64^2 grids the five-bar configs need (about 5 ms/design against under 1 ms, one-off
        # measurement on a loaded machine)
        tstats = mech.grid_stats(packed, np.tile(tg.lo, (n, 1)), np.tile(tg.step, (n, 1)), tg.shape, edges)
        tcell, tcells = np.full(n, tg.cell_measure), float(tg.n_cells)
        out.update(stats_to_metrics(mech, tstats, tcell, tcells,
                                    [m for m in entries if m.family == "task" and m.compute is None], n_bands))
    ctx = _metrics.EvalContext(mech, resolved, options, packed, task, resolution, band_edges, unit, cycle)
    for m in entries:
        if m.compute is not None:
            out[m.column] = np.asarray(m.compute(ctx), dtype=float)
    return out
