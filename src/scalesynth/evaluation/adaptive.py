"""The adaptive column evaluator over a population (kernels.adaptive): per-design boxes, column axis and order,
the half box of mirror symmetries, and the statistics rows it returns."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from scalesynth.evaluation.grid import Grid, design_boxes
from scalesynth.evaluation.plans import ColumnPlan, Tolerance, adaptive_plan
from scalesynth.kernels import grid as _grid

if TYPE_CHECKING:  # annotations only: nothing here imports the mechanisms
    from scalesynth.mechanisms.base import Mechanism


@dataclass
class AdaptiveResult:
    """Statistics of designs from ``adaptive_population_stats`` (or ``tolerance_population_stats``): counts in
    coarse-cell units (``cell`` the coarse cell measure per design; a calibrated uniform grid's cell), per-design
    error estimates and cost (kernel calls; a calibrated uniform grid: its cells, and those of the estimate's)."""

    stats: np.ndarray
    cell: np.ndarray
    error_volume: np.ndarray  # relative
    error_gci: np.ndarray  # absolute
    levels: np.ndarray  # refinement levels used per design (int64)
    evaluations: np.ndarray  # field-kernel calls per design
    coarse_cells: int  # cells of the coarse grid (coverage = count / coarse_cells)


def adaptive_population_stats(
    mech: Mechanism,
    designs: Sequence[Mapping[str, float]],
    options: Mapping[str, Any],
    packed: np.ndarray,
    tolerance: Tolerance,
    edges: np.ndarray,
    region: Mapping[str, Sequence[float]] | None = None,
    boxes: Grid | None = None,
    plan: ColumnPlan | None = None,
    lci_only: bool = False,
    mirror: bool = True,
    intervals: bool = True,
) -> AdaptiveResult:
    """Statistics of every design by the adaptive column evaluator (kernels.adaptive), refined per design until
    its error estimate (change from the previous level) meets ``tolerance`` or the plan's last level is reached.
    ``boxes``: one fixed box for every design (the task box) instead of each design's bounding box. ``lci_only``:
    the Gauss points run ``Mechanism.lci_kernel`` (only the count, LCI statistics, bands and estimates are
    meaningful; they equal the full kernel's bit for bit: the refinement reads slot 0 alone). ``mirror``: on each of
    the mechanism's mirror axes (``mirror_halves``) only the half box >= 0 is evaluated, with half the plan's
    columns (or z-cells) there, and the extensive statistics are doubled: the same columns and nodes as the full
    box, to rounding (tests/test_mirror.py). ``intervals``: columns whose reachable set the mechanism gives in
    closed form (``Mechanism.interval_kernel_for`` the options) skip the nodes and bisections, the columns run along
    the mechanism's ``column_axis`` (``column_axis`` here), and the default plan is the mechanism's interval plan
    (``adaptive_plan``); False: nodes everywhere, columns along the last axis, with the node plan (A/B)."""
    from scalesynth.kernels.adaptive import column_stats

    n = len(designs)
    ndim = len(mech.task_axes)
    plan = plan or adaptive_plan(mech, options if intervals else None)  # without intervals: the node plan
    if boxes is None:
        lo, hi = design_boxes(mech, designs, options, region)
    else:
        lo = np.tile(boxes.lo, (n, 1))
        hi = np.tile(boxes.lo + boxes.step * boxes.shape, (n, 1))
    cell = np.prod((hi - lo)[:, :ndim], axis=1) / plan.coarse_cells(ndim)
    interval_kernel = mech.interval_kernel_for(options) if intervals else None
    axis = column_axis(mech, options, intervals)
    half = HalfBox.of(mech, options, lo, hi, plan, mirror, axis)
    kernel = mech.stats_kernel(packed, lci_only)
    reach = mech.reach_kernel
    box_lo, box_hi = half.lo, hi
    if axis != ndim - 1:
        # the kernels take the task coordinates in column order (the cross axes, then the column axis); the
        # statistics rows and estimates do not depend on the order of the axes
        order = column_order(ndim, axis)
        kernel, reach = mech.column_order_kernel(kernel, options), mech.column_order_kernel(reach, options)
        box_lo, box_hi = half.lo[:, order], hi[:, order]
    stats, err_v, err_g, levels, evals = column_stats(kernel, mech.n_fields, packed, box_lo, box_hi, ndim,
                                                      half.columns, half.cells, plan.bisections, plan.levels,
                                                      tolerance.volume, tolerance.gci, edges, plan.beta,
                                                      plan.zlevels, plan.zconfirm, plan.faces, reach,
                                                      ny=half.ny, mirror=half.mirror,
                                                      interval_kernel=interval_kernel,
                                                      field_levels=plan.field_levels,
                                                      gauss_points=plan.gauss_points)
    stats = half.whole(stats, mech.n_fields)
    return AdaptiveResult(stats, cell, err_v, err_g, levels, evals, plan.coarse_cells(ndim))


def column_axis(mech: Mechanism, options: Mapping[str, Any], intervals: bool = True) -> int:
    """The task axis the adaptive evaluator runs its columns along: the mechanism's ``column_axis`` where its interval
    kernel is used (``intervals`` and ``interval_kernel_for`` the options), else the last task axis."""
    if intervals and mech.interval_kernel_for(options) is not None:
        return mech.column_axis(options)
    return len(mech.task_axes) - 1


def column_order(ndim: int, axis: int) -> list[int]:
    """Task axes in column order: the cross axes in task order, then the column axis ``axis``."""
    return [a for a in range(ndim) if a != axis] + [axis] + list(range(ndim, 3))


def mirror_halves(mech: Mechanism, options: Mapping[str, Any], lo: np.ndarray, hi: np.ndarray,
                  plan: ColumnPlan, axis: int | None = None) -> tuple[int, ...]:
    """The task axes the adaptive evaluator halves: the mechanism's mirror axes (``Mechanism.mirror_axes``) on
    which every design's box (lo, hi: (n, 3)) is symmetric about 0 exactly and the plan's column count (or, on the
    column axis ``axis``, default the last, its z-cells) is even, so the half box holds exactly half of the full
    box's columns and nodes."""
    ndim = len(mech.task_axes)
    axis = ndim - 1 if axis is None else axis
    out = []
    for a in mech.mirror_axes(options):
        count = plan.cells if a == axis else plan.columns
        if count % 2 == 0 and np.all(lo[:, a] == -hi[:, a]):  # a degenerate design's empty box (0, 0) halves too
            out.append(a)
    return tuple(out)


@dataclass(frozen=True)
class HalfBox:
    """What the adaptive evaluator computes on the mirror axes (``mirror_halves``): every design's box with lo = 0
    on them (lo: (n, 3), task order), the coarse columns per cross axis (``columns``, ``ny``: kernels.adaptive's n
    and ny, cross axes in column order; None for planar tasks) and z-cells, the kernel's mirror planes per cross
    axis (column order), and ``factor`` = 2^(halved axes). ``axis``: the column axis (default the last)."""

    lo: np.ndarray
    columns: int
    ny: int | None
    cells: int
    mirror: tuple[bool, bool]
    factor: float

    @classmethod
    def of(cls, mech: Mechanism, options: Mapping[str, Any], lo: np.ndarray, hi: np.ndarray, plan: ColumnPlan,
           mirror: bool = True, axis: int | None = None) -> HalfBox:
        ndim = len(mech.task_axes)
        axis = ndim - 1 if axis is None else axis
        counts = [plan.columns, plan.columns, plan.cells]  # cross axes 0, 1 (3-D only), the column axis
        order = column_order(ndim, axis)
        slot = {a: (k if ndim == 3 or k == 0 else 2) for k, a in enumerate(order[:ndim])}  # task axis -> entry
        planes = [False, False]
        lo = lo.copy()
        halves = mirror_halves(mech, options, lo, hi, plan, axis) if mirror else ()
        for a in halves:
            lo[:, a] = 0.0
            counts[slot[a]] //= 2
            if slot[a] < 2:
                planes[slot[a]] = True
        return cls(lo, counts[0], counts[1] if ndim == 3 else None, counts[2], (planes[0], planes[1]),
                   float(2 ** len(halves)))

    def whole(self, stats: np.ndarray, n_fields: int) -> np.ndarray:
        """Statistics rows of the half box -> those of the whole box (extensive columns times ``factor``)."""
        return stats if self.factor == 1.0 else _grid.scale_extensive(stats, n_fields, self.factor)
