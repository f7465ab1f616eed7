"""The report API: evaluate one design (WorkspaceReport) or many (evaluate_population, column -> array)."""

from __future__ import annotations

import math
import time
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from scalesynth import metrics as _metrics
from scalesynth.errors import InvalidParameter
from scalesynth.evaluation.assembly import metrics_of
from scalesynth.evaluation.grid import Grid, make_grid
from scalesynth.evaluation.plans import Tolerance, uniform_resolution
from scalesynth.evaluation.strategy import tolerance_population_stats
from scalesynth.kernels import grid as _grid
from scalesynth.names import hint

if TYPE_CHECKING:  # annotations only: nothing here imports the mechanisms
    from scalesynth.mechanisms.base import Mechanism

DEFAULT_BAND_EDGES = (0.0, 0.1, 0.3, 1.0)


@dataclass
class WorkspaceReport:
    """Metrics of one design (from ``evaluate``). ``measure_key`` is e.g. 'volume_m3'; band k covers
    (edges[k], edges[k+1]].

    Attributes:
        metrics: {column name: value}, every metric of the catalogue that applies (``scalesynth metrics MECH``): the
            measure (``measure_key``, volume or area in the length unit), ``gci``, ``fci``, field statistics,
            ``voxels`` (reachable cells), band shares and volumes; with a task, ``task_*`` and ``path_*``.
            Empty workspace: measure and counts 0, GCI 0, every other statistic over it NaN (null in JSON).
        field_names: names of the per-voxel fields, in slot order (``lci``, ``sigma_min``, ``sigma_max``, ...).
        field_grid: only with ``keep_grid=True``: float64 array of shape (nx, ny, nz, n_fields) (nz = 1 for planar
            mechanisms), every field at each cell centre; ``field(name)`` gives one (nx, ny, nz) slice and
            ``lci_grid`` the LCI. **An LCI of -1 marks an unreachable cell** (no inverse kinematic solution in the
            selected working mode, or outside a joint limit); the other fields are 0 there. Cell (i, j, k) has
            centre ``(grid.axis(0)[i], grid.axis(1)[j], grid.axis(2)[k])`` in task-space units
            (``Mechanism.task_axes``).
        grid: only with ``keep_grid=True``: the :class:`Grid` (``lo``, ``step``, ``shape``, ``cell_measure``).
        seconds: kernel wall time of the metrics (without JIT compilation and without the per-voxel pass).
        resolution: cells per axis of the uniform grid behind the metrics (with a tolerance on a calibrated
            uniform grid, its N); with the adaptive evaluator, the grid that ``keep_grid`` samples.
        grid_cells: cells of that grid; with a tolerance, kernel calls (a calibrated grid: its cells and those
            of the 2x finer grid behind the estimates).
    """

    mechanism: str
    design: dict[str, float]
    measure_key: str
    metrics: dict[str, float]
    band_edges: list[float]
    resolution: int
    grid_cells: int
    seconds: float
    field_names: tuple[str, ...] = ()
    field_grid: np.ndarray | None = field(default=None, repr=False)
    grid: Grid | None = field(default=None, repr=False)

    @property
    def measure(self) -> float:
        return self.metrics[self.measure_key]

    @property
    def gci(self) -> float:
        return self.metrics["gci"]

    @property
    def lci_grid(self) -> np.ndarray | None:
        return None if self.field_grid is None else self.field_grid[..., 0]

    def field(self, name: str) -> np.ndarray:
        """Per-voxel values of field ``name`` (needs keep_grid=True), shape (nx, ny, nz)."""
        if self.field_grid is None:
            raise ValueError("field: evaluate with keep_grid=True to keep the per-voxel fields")
        if name not in self.field_names:
            raise KeyError(f"field: {name!r} is not a field of {self.mechanism} ({', '.join(self.field_names)})")
        return self.field_grid[..., self.field_names.index(name)]

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"mechanism": self.mechanism, "design": self.design}
        # a statistic over an empty set is NaN in memory and null in JSON (json.dumps would write NaN, not JSON)
        out.update({k: (int(v) if k == "voxels" else None if math.isnan(v) else float(v))
                    for k, v in self.metrics.items()})
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
    cycle: Any = None,
    tolerance: Tolerance | None = None,
) -> WorkspaceReport:
    """Evaluate one design on a ``resolution``-per-axis grid, or with ``tolerance`` by the adaptive evaluator
    (metrics then include ``error_volume`` and ``error_gci``). ``seconds`` (the workspace evaluation alone)
    excludes JIT compilation. ``keep_grid``: keep every per-voxel field of the uniform ``resolution`` grid
    (WorkspaceReport.field_grid). ``cycle`` (a config CycleConfig): also the cycle metrics."""
    design = mech.resolve_design(design)
    options = mech.resolve_options(options)
    unit = mech.length_unit(length_unit, "length_unit")
    g = make_grid(mech, design, options, resolution, region)
    edges = np.asarray(band_edges, dtype=float)
    packed = mech.pack(design, options)[None, :]
    if tolerance is not None:
        tolerance_population_stats(mech, [design], options, packed, tolerance, edges, region)  # compile or load
        t0 = time.perf_counter()
        ad = tolerance_population_stats(mech, [design], options, packed, tolerance, edges, region)
        seconds = time.perf_counter() - t0
        values = metrics_of(mech, [design], options, packed, ad.stats, ad.cell, resolution, band_edges, unit, task,
                             cycle)
        values.update(error_volume=ad.error_volume, error_gci=ad.error_gci)
        n_cells = int(ad.evaluations[0])
        # a calibrated uniform grid reports its own N (not the grid that keep_grid samples)
        reported_resolution = uniform_resolution(mech, tolerance) or resolution
    else:
        warm_up(mech, packed, edges)
        t0 = time.perf_counter()
        stats = mech.grid_stats(packed, g.lo[None, :], g.step[None, :], g.shape, edges)
        seconds = time.perf_counter() - t0
        values = metrics_of(mech, [design], options, packed, stats, np.array([g.cell_measure]), resolution,
                             band_edges, unit, task, cycle)
        n_cells = g.n_cells
        reported_resolution = resolution
    metrics = {k: v[0].item() for k, v in values.items()}
    fields = None
    if keep_grid:
        fields = _grid.sample_fields(mech.field_kernel, mech.n_fields, packed[0], g.lo, g.step, g.shape)
    return WorkspaceReport(
        mechanism=mech.name,
        design=dict(design),
        measure_key=mech.measure_key(unit),
        metrics=metrics,
        band_edges=[float(e) for e in band_edges],
        resolution=reported_resolution,
        grid_cells=n_cells,
        seconds=seconds,
        field_names=mech.field_names,
        field_grid=fields,
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
    cycle: Any = None,
    tolerance: Tolerance | None = None,
    families: Collection[str] | None = None,
    fields: Collection[str] | None = None,
) -> dict[str, np.ndarray]:
    """Every catalogue metric of many designs, column name -> (n,) array; the workspace grids in one parallel
    kernel call (no Python work per voxel); with ``task`` (a config TaskConfig) also the task-box and path
    metrics, with ``cycle`` (a config CycleConfig) the cycle metrics. With ``tolerance`` the adaptive evaluator
    replaces the uniform ``resolution`` grid and the result also has ``error_volume`` (relative) and
    ``error_gci`` (its per-design error estimates). ``families`` (catalogue families, e.g. {"task", "cycle"}):
    only their metrics, and no workspace grid when "workspace" is not among them (the search evaluates only what
    its objectives and constraints use). ``fields`` (per-voxel field names and "estimate", e.g. {"lci"}): the
    workspace metrics that need only those (``metrics.field_of``); within {"lci", "estimate"} the mechanism's cheaper
    ``lci_kernel`` runs, whose measure, LCI statistics, bands and error estimates equal the field kernel's bit for
    bit; the error estimates only with "estimate" (a calibrated uniform grid computes them on a second grid)."""
    options = mech.resolve_options(options)
    _check_selection("families", families, _metrics.FAMILIES)
    _check_selection("fields", fields, (*mech.field_names, "estimate"))
    unit = mech.length_unit(length_unit, "length_unit")
    resolved = [mech.resolve_design(d) for d in designs]
    n = len(resolved)
    if n == 0:
        has_path = task is not None and task.path is not None
        entries = _metrics.result_metrics(mech, unit, task is not None, has_path, options, cycle,
                                          tolerance is not None)
        cols = [c for m in entries if (families is None or m.family in families)
                and (fields is None or m.family != "workspace" or _metrics.field_of(m) in fields)
                for c in m.columns(len(band_edges) - 1)]
        return {k: np.zeros(0) for k in cols}
    packed = np.stack([mech.pack(d, options) for d in resolved])
    edges = np.asarray(band_edges, dtype=float)
    args = (resolution, band_edges, unit, task, cycle, families, fields)
    if families is not None and "workspace" not in families:
        return metrics_of(mech, resolved, options, packed, None, None, *args)
    lci_only = fields is not None and set(fields) <= {"lci", "estimate"}
    if tolerance is not None:
        estimates = fields is None or "estimate" in fields
        ad = tolerance_population_stats(mech, resolved, options, packed, tolerance, edges, region,
                                        lci_only=lci_only, estimates=estimates)
        out = metrics_of(mech, resolved, options, packed, ad.stats, ad.cell, *args)
        if estimates:
            out["error_volume"] = ad.error_volume
            out["error_gci"] = ad.error_gci
        return out
    grids = [make_grid(mech, d, options, resolution, region) for d in resolved]
    lo = np.stack([g.lo for g in grids])
    step = np.stack([g.step for g in grids])
    stats = mech.grid_stats(packed, lo, step, grids[0].shape, edges, lci_only=lci_only)
    cell = np.array([g.cell_measure for g in grids])
    return metrics_of(mech, resolved, options, packed, stats, cell, *args)


def _check_selection(what: str, names: Collection[str] | None, known: Sequence[str]) -> None:
    """Raise InvalidParameter naming the first of ``names`` not in ``known`` (a misspelt family or field would
    otherwise just select nothing)."""
    for name in names or ():
        if name not in known:
            raise InvalidParameter(f"{what}: unknown name {name!r} " + hint(str(name), known))
