"""Workspace and dexterity of designs on voxel grids: evaluate(mechanism, design, ...) -> WorkspaceReport.

Plain functions over the Numba kernels in ``kernels.grid``. Degenerate designs are data: an empty workspace
gives measure 0 and GCI/FCI/min/max LCI 0, never NaN.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from scalesynth.kernels import grid as _grid
from scalesynth.mechanisms.base import Mechanism

DEFAULT_BAND_EDGES = (0.0, 0.1, 0.3, 1.0)


@dataclass(frozen=True)
class Grid:
    """Cell-centred grid: node i of axis a at lo[a] + (i + 0.5) * step[a]."""

    lo: np.ndarray
    step: np.ndarray
    shape: np.ndarray  # int64[3]; planar grids have shape[2] == 1
    ndim: int

    @property
    def cell_measure(self) -> float:
        return float(np.prod(self.step[: self.ndim]))

    @property
    def n_cells(self) -> int:
        return int(np.prod(self.shape))

    def axis(self, a: int) -> np.ndarray:
        return self.lo[a] + (np.arange(self.shape[a]) + 0.5) * self.step[a]


def make_grid(
    mech: Mechanism,
    design: Mapping[str, float],
    options: Mapping[str, Any],
    resolution: int,
    region: Mapping[str, Sequence[float]] | None = None,
) -> Grid:
    """Grid of ``resolution`` cells per task axis over the mechanism's bounding box (or ``region``)."""
    lo, hi = mech.bounding_box(design, options)
    lo, hi = np.array(lo, dtype=float), np.array(hi, dtype=float)
    if region:
        for a, name in enumerate(mech.task_axes):
            if name in region:
                lo[a], hi[a] = float(region[name][0]), float(region[name][1])
    ndim = len(mech.task_axes)
    shape = np.array([resolution] * ndim + [1] * (3 - ndim), dtype=np.int64)
    step = np.ones(3)
    step[:ndim] = (hi[:ndim] - lo[:ndim]) / resolution
    lo[ndim:] = 0.0
    return Grid(lo=lo, step=step, shape=shape, ndim=ndim)


def metric_names(mech: Mechanism, length_unit: str, band_edges: Sequence[float]) -> list[str]:
    """Column names of the metrics, in a fixed order (units in the names)."""
    mkey = mech.measure_key(length_unit)
    names = [mkey, "gci", "fci", "min_lci", "max_lci", "voxels"]
    for b in range(len(band_edges) - 1):
        names.append(f"band{b}_share")
    for b in range(len(band_edges) - 1):
        names.append(f"band{b}_{mkey}")
    return names


def stats_to_metrics(stats: np.ndarray, cell_measure: np.ndarray, names: list[str]) -> dict[str, np.ndarray]:
    """Turn raw kernel sums (n, N_FIXED + bands) into metric arrays; empty workspaces give 0, never NaN."""
    count = stats[:, _grid.COL_COUNT]
    safe = np.where(count > 0, count, 1.0)
    gci = np.where(count > 0, stats[:, _grid.COL_SUM] / safe, 0.0)
    var = np.where(count > 0, stats[:, _grid.COL_SUMSQ] / safe - gci * gci, 0.0)
    fci = np.sqrt(np.maximum(var, 0.0))
    bands = stats[:, _grid.N_FIXED :]
    nb = bands.shape[1]
    out = {
        names[0]: count * cell_measure,
        "gci": gci,
        "fci": fci,
        "min_lci": np.where(count > 0, stats[:, _grid.COL_MIN], 0.0),
        "max_lci": np.where(count > 0, stats[:, _grid.COL_MAX], 0.0),
        "voxels": count.astype(np.int64),
    }
    for b in range(nb):
        out[names[6 + b]] = np.where(count > 0, bands[:, b] / safe, 0.0)
    for b in range(nb):
        out[names[6 + nb + b]] = bands[:, b] * cell_measure
    return out


@dataclass
class WorkspaceReport:
    """Metrics of one design. ``measure_key`` is e.g. 'volume_m3'; band k covers (edges[k], edges[k+1]]."""

    mechanism: str
    design: dict[str, float]
    measure_key: str
    metrics: dict[str, float]
    band_edges: list[float]
    resolution: int
    grid_cells: int
    seconds: float
    lci_grid: np.ndarray | None = field(default=None, repr=False)
    grid: Grid | None = field(default=None, repr=False)

    @property
    def measure(self) -> float:
        return self.metrics[self.measure_key]

    @property
    def gci(self) -> float:
        return self.metrics["gci"]

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"mechanism": self.mechanism, "design": self.design}
        out.update({k: (int(v) if k == "voxels" else float(v)) for k, v in self.metrics.items()})
        out["band_edges"] = list(self.band_edges)
        out["resolution"] = self.resolution
        out["grid_cells"] = self.grid_cells
        out["seconds"] = self.seconds
        return out


def evaluate(
    mech: Mechanism,
    design: Mapping[str, float],
    options: Mapping[str, Any] | None = None,
    *,
    resolution: int = 64,
    region: Mapping[str, Sequence[float]] | None = None,
    band_edges: Sequence[float] = DEFAULT_BAND_EDGES,
    length_unit: str | None = None,
    keep_grid: bool = False,
    task: Any = None,
) -> WorkspaceReport:
    """Evaluate one design on a ``resolution``-per-axis grid. ``seconds`` excludes JIT compilation."""
    design = mech.resolve_design(design)
    options = mech.resolve_options(options)
    unit = length_unit or mech.default_length_unit
    g = make_grid(mech, design, options, resolution, region)
    edges = np.asarray(band_edges, dtype=float)
    packed = mech.pack(design, options)[None, :]
    warm_up(mech, packed, edges)
    t0 = time.perf_counter()
    stats = mech.grid_stats(packed, g.lo[None, :], g.step[None, :], g.shape, edges)
    seconds = time.perf_counter() - t0
    names = metric_names(mech, unit, band_edges)
    metrics = {k: v[0].item() for k, v in stats_to_metrics(stats, np.array([g.cell_measure]), names).items()}
    if task is not None:
        metrics.update({k: v[0].item() for k, v in task_metrics(mech, packed, task, resolution, band_edges).items()})
    metrics.update({k: v[0].item() for k, v in _stiffness(mech, options, packed, g.lo[None], g.step[None],
                                                            g.shape, task, resolution, always=False).items()})
    lci = _grid.sample_grid(mech.point_kernel, packed[0], g.lo, g.step, g.shape) if keep_grid else None
    return WorkspaceReport(
        mechanism=mech.name,
        design=dict(design),
        measure_key=names[0],
        metrics=metrics,
        band_edges=[float(e) for e in band_edges],
        resolution=resolution,
        grid_cells=g.n_cells,
        seconds=seconds,
        lci_grid=lci,
        grid=g if keep_grid else None,
    )


_WARM: set[tuple[str, int]] = set()


def warm_up(mech: Mechanism, packed: np.ndarray, edges: np.ndarray) -> None:
    """Compile (or load from cache) the grid kernel for this mechanism, outside any timed region."""
    key = (mech.name, len(edges))
    if key in _WARM:
        return
    lo = np.zeros((1, 3))
    step = np.ones((1, 3))
    mech.grid_stats(packed[:1], lo, step, np.array([1, 1, 1], dtype=np.int64), edges)
    _WARM.add(key)


def sample_path(points: Sequence[Sequence[float]], samples: int) -> np.ndarray:
    """``samples`` points evenly spaced by arc length along a polyline (ends included), padded to 3 columns."""
    pts = np.asarray(points, dtype=float)
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    if s[-1] == 0.0:
        out = np.repeat(pts[:1], samples, axis=0)
    else:
        t = np.linspace(0.0, s[-1], samples)
        out = np.stack([np.interp(t, s, pts[:, a]) for a in range(pts.shape[1])], axis=1)
    return np.pad(out, ((0, 0), (0, 3 - out.shape[1])))


def task_metrics(
    mech: Mechanism,
    packed: np.ndarray,
    task: Any,
    resolution: int,
    band_edges: Sequence[float],
) -> dict[str, np.ndarray]:
    """Coverage of the task box (share of its cells reachable within all limits), GCI/FCI/min LCI over the
    reachable part of the box, and the LCI along the task path (0 where the path leaves the workspace)."""
    n = packed.shape[0]
    box = task.box
    ndim = len(mech.task_axes)
    lo = np.zeros(3)
    hi = np.zeros(3)
    shape = np.ones(3, dtype=np.int64)
    res = task.resolution or resolution
    for a, name in enumerate(mech.task_axes):  # config validation guarantees every axis is in the box
        lo[a], hi[a] = box[name]
        shape[a] = res
    step = np.ones(3)
    step[:ndim] = (hi[:ndim] - lo[:ndim]) / shape[:ndim]
    edges = np.asarray(band_edges, dtype=float)
    stats = mech.grid_stats(packed, np.tile(lo, (n, 1)), np.tile(step, (n, 1)), shape, edges)
    count = stats[:, _grid.COL_COUNT]
    total = float(np.prod(shape))
    safe = np.where(count > 0, count, 1.0)
    gci = np.where(count > 0, stats[:, _grid.COL_SUM] / safe, 0.0)
    var = np.where(count > 0, stats[:, _grid.COL_SUMSQ] / safe - gci * gci, 0.0)
    out = {
        "task_coverage": count / total,
        "task_gci": gci,
        "task_fci": np.sqrt(np.maximum(var, 0.0)),
        "task_min_lci": np.where(count > 0, stats[:, _grid.COL_MIN], 0.0),
    }
    if task.path is not None:
        pts = sample_path(task.path, task.path_samples)
        lci = _grid.population_points_lci(mech.point_kernel, packed, pts)
        reach = lci >= 0
        out["path_reachable"] = reach.mean(axis=1)
        out["path_min_lci"] = np.where(reach.all(axis=1), lci.min(axis=1), 0.0)
        out["path_mean_lci"] = np.where(reach, lci, 0.0).mean(axis=1)
    return out


def _stiffness(mech, options, packed, lo, step, shape, task, resolution, always: bool) -> dict[str, np.ndarray]:
    """Stiffness metrics (issue 12) where the mechanism has per-voxel fields for these options; with ``always``
    raise when it has none, else return {}."""
    from scalesynth.stiffness import fields

    if not always and fields.field_or_none(mech, options) is None:
        return {}
    box = None if task is None else task.box
    res = None if task is None else (task.resolution or resolution)
    return fields.stiffness_metrics(mech, options, packed, lo, step, shape, box, res)


def evaluate_population(
    mech: Mechanism,
    designs: Sequence[Mapping[str, float]],
    options: Mapping[str, Any] | None = None,
    *,
    resolution: int = 64,
    region: Mapping[str, Sequence[float]] | None = None,
    band_edges: Sequence[float] = DEFAULT_BAND_EDGES,
    length_unit: str | None = None,
    task: Any = None,
    stiffness: bool = False,
) -> dict[str, np.ndarray]:
    """Metrics of many designs in one parallel kernel call (no Python work per voxel); with ``task`` (a
    config TaskConfig) also the task-box and path metrics; with ``stiffness`` the stiffness metrics."""
    options = mech.resolve_options(options)
    unit = length_unit or mech.default_length_unit
    resolved = [mech.resolve_design(d) for d in designs]
    n = len(resolved)
    names = metric_names(mech, unit, band_edges)
    if n == 0:
        return {k: np.zeros(0) for k in names}
    packed = np.stack([mech.pack(d, options) for d in resolved])
    grids = [make_grid(mech, d, options, resolution, region) for d in resolved]
    lo = np.stack([g.lo for g in grids])
    step = np.stack([g.step for g in grids])
    edges = np.asarray(band_edges, dtype=float)
    stats = mech.grid_stats(packed, lo, step, grids[0].shape, edges)
    cell = np.array([g.cell_measure for g in grids])
    out = stats_to_metrics(stats, cell, names)
    if task is not None:
        out.update(task_metrics(mech, packed, task, resolution, band_edges))
    if stiffness:
        out.update(_stiffness(mech, options, packed, lo, step, grids[0].shape, task, resolution, always=True))
    return out


def evaluate_config(cfg, design: Mapping[str, float] | None = None, *, keep_grid: bool = False) -> WorkspaceReport:
    """Evaluate ``design`` (default: the config's design) with the config's options, grid, bands and task."""
    return evaluate(
        cfg.mech,
        cfg.resolved_design() if design is None else design,
        cfg.resolved_options(),
        resolution=cfg.grid.resolution,
        region=cfg.grid.region,
        band_edges=cfg.dexterity.band_edges,
        length_unit=cfg.units.length,
        keep_grid=keep_grid,
        task=cfg.task,
    )


def evaluate_config_population(cfg, designs: Sequence[Mapping[str, float]], *, stiffness: bool = False
                               ) -> dict[str, np.ndarray]:
    """All metrics of many designs under one config, in one parallel kernel call per metric family (the
    stiffness ones with ``stiffness``)."""
    return evaluate_population(
        cfg.mech,
        designs,
        cfg.resolved_options(),
        resolution=cfg.grid.resolution,
        region=cfg.grid.region,
        band_edges=cfg.dexterity.band_edges,
        length_unit=cfg.units.length,
        task=cfg.task,
        stiffness=stiffness,
    )
