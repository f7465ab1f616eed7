"""Grid geometry of the evaluator: cell-centred grids over a design's bounding box or a task box, and every
design's box of a population in one array pass."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # annotations only: nothing here imports the mechanisms
    from scalesynth.mechanisms.base import Mechanism


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


def design_boxes(
    mech: Mechanism,
    designs: Sequence[Mapping[str, float]],
    options: Mapping[str, Any],
    region: Mapping[str, Sequence[float]] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi), each (n, 3): every design's box as ``make_grid(..., 1, region)`` gives it (lo, and lo + step x
    shape; the axes beyond the task's: 0 and 1), in one array pass instead of a Grid per design."""
    n = len(designs)
    ndim = len(mech.task_axes)
    lo, hi = np.zeros((n, 3)), np.zeros((n, 3))
    for k, d in enumerate(designs):
        lo[k], hi[k] = mech.bounding_box(d, options)
    for a, name in enumerate(mech.task_axes):
        if region and name in region:
            lo[:, a], hi[:, a] = float(region[name][0]), float(region[name][1])
    # make_grid: step = (hi - lo) / 1, hi = lo + step x 1 (not hi itself: the same rounding)
    top = np.ones((n, 3))
    top[:, :ndim] = lo[:, :ndim] + (hi[:, :ndim] - lo[:, :ndim])
    lo[:, ndim:] = 0.0
    return lo, top


def task_grid(mech: Mechanism, task: Any, resolution: int) -> Grid:
    """The cell-centred grid over a config's task box (``task.resolution`` cells per axis, else ``resolution``)."""
    ndim = len(mech.task_axes)
    lo = np.zeros(3)
    hi = np.zeros(3)
    shape = np.ones(3, dtype=np.int64)
    res = task.resolution or resolution
    for a, name in enumerate(mech.task_axes):  # config validation guarantees every axis is in the box
        lo[a], hi[a] = task.box[name]
        shape[a] = res
    step = np.ones(3)
    step[:ndim] = (hi[:ndim] - lo[:ndim]) / shape[:ndim]
    return Grid(lo=lo, step=step, shape=shape, ndim=ndim)
