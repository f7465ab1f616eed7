"""Workspace, task and design metrics of designs: evaluate(mechanism, design, ...) -> WorkspaceReport.

Plain functions over the Numba kernels in ``kernels.grid``; which metrics exist and how each is named comes from
the catalogue (``scalesynth.metrics``). Degenerate designs are data: an empty workspace gives measure 0 and GCI 0;
every other statistic over an empty set is NaN (null), never a number that could read as best (stats_to_metrics).
"""

from __future__ import annotations

import math
import time
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from scalesynth import metrics as _metrics
from scalesynth.errors import InvalidParameter
from scalesynth.kernels import grid as _grid
from scalesynth.mechanisms.base import Mechanism
from scalesynth.names import hint
from scalesynth.paths import sample_path  # noqa: F401 - re-exported for callers of evaluate

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


@dataclass(frozen=True)
class Tolerance:
    """Accuracy target of the adaptive evaluator: relative workspace-measure error and absolute GCI error."""

    volume: float = 0.002
    gci: float = 5.0e-4


@dataclass(frozen=True)
class ColumnPlan:
    """Resolution of the adaptive (column) evaluator (kernels.adaptive): coarse columns per cross axis, z-cells
    per column, bisection steps per boundary crossing, most refinement levels (each triples the columns per cross
    axis where the column measures curve), and the share of the tolerance one coarse column's error indicator may
    take before it is refined (larger: fewer refined columns)."""

    columns: int
    cells: int
    bisections: int
    levels: int
    beta: float = 1.0
    zlevels: int = 0  # most doublings of the z-cells on the coarse grid (z-levels, kernels.adaptive step 0)
    zconfirm: int = 1  # consecutive z-level changes within the tolerance before the z-cells are trusted
    faces: bool = False  # box-face columns as ghost neighbours of the edge columns (kernels.adaptive step 3)
    # the last level whose new columns evaluate the fields at their Gauss points; deeper ones refine the measure
    # alone and inherit their parent's fields per unit measure (kernels.adaptive step 3b); -1: every level
    field_levels: int = -1
    gauss_points: int = 2  # fields per piece: 2 (Gauss-Legendre) or 1 (midpoint rule; kernels.adaptive step 2)

    def coarse_cells(self, ndim: int) -> int:
        """Cells of the coarse grid (the unit of the statistics rows' counts)."""
        return self.columns ** (ndim - 1) * self.cells


# per task dimension, and per mechanism where its workspaces need less (chosen with
# `python benchmarks/bench.py adaptive`, which checks the tolerance against a 3x finer uniform grid on 20 random
# designs): planar workspaces have parts thinner than 1/64 of the box along y; 3-D workspaces have shells thinner
# than the 8 coarse z-cells (2pauu-ppap's lobe tips, pprs-rprs's and rps-upu-tool's thin slabs) and walls between
# the edge columns and the box (rps-upu-tool's task box), hence z-levels confirmed twice and box-face columns;
# rps-upu's and ups-sspr's workspaces are smooth and thick (the benchmark meets the tolerance without either).
# ups-sspr's and rps-upu's plans: the cheapest of a grid search (columns, cells, bisections, levels, beta: 2160 and
# 870 plans) whose worst errors on the benchmark's 20 designs (seed 0) are <= 80 % of the tolerance and which also
# meets the tolerance on 20 other random designs (seed 1; where the N = 96 reference itself was off, the check was
# against N = 192). ups-sspr: (6, 4, 8, 3, beta 1): 0.79x / 0.80x the volume tolerance on seed 0 / 1, GCI 0.29x /
# 0.53x; the plan before, (8, 6, 5, 3, beta 3), was 1.02x on seed 1 (against N = 384 too). Bisections are cheap
# (reach kernel), hence 8. rps-upu: no cheaper plan passes both sets ((15, 8, 6, 3, beta 3.5): 0.61x on seed 0,
# 1.4-1.6x on seed-1 designs against N = 192), so (24, 8, 5, 3, beta 3) stays (0.82x / 0.80x on seed 0; 0.56x /
# 0.75x on seed 1 without the design whose N = 96 reference is 2.45x off N = 192's); since its z-column intervals
# (INTERVAL_PLAN_OF) this psi-column node plan runs only for the C-model and interference_free
ADAPTIVE_PLAN = {2: ColumnPlan(64, 128, 8, 6),
                 3: ColumnPlan(24, 8, 5, 3, beta=1.0, zlevels=5, zconfirm=2, faces=True)}
ADAPTIVE_PLAN_OF: dict[str, ColumnPlan] = {
    "ups-sspr": ColumnPlan(6, 4, 8, 3, beta=1.0),  # with interference_free; else INTERVAL_PLAN_OF's
    "rps-upu": ColumnPlan(24, 8, 5, 3, beta=3.0),
    "2pauu-ppap": ColumnPlan(24, 8, 5, 3, beta=3.0, zlevels=5, zconfirm=2, faces=True),
    # rps-upu-tool's node plan (with interference_free; else INTERVAL_PLAN_OF's): from benchmarks/plan_search.py's
    # 1926 plans (LCI kernel; benchmarks/notes/adaptive_plans.md), the
    # one with the widest margin against the better reference N = 192 (N = 96 is 0.2-0.6x the volume tolerance off
    # it on most designs) among the cheap ones: 10 x 10 columns of 8 z-cells (up to 3 doublings, confirmed twice),
    # 5 bisections, 2 levels, face columns: 122 299 calls/design, 4.4x fewer than the 3-D default's 533 892. Errors x
    # tolerance (volume, GCI) against N = 192, seeds 0 / 1 / 2: 0.50, 0.73 / 0.46, 0.47 / 0.43, 0.40. The cheapest
    # plan passing the rule, (12, 12, 4, 2, beta 1, 2 z-levels confirmed once): 93 874 calls, but 0.80x in GCI on
    # seed 1. Both are more accurate at 2 levels than at 3 (0.82-1.02x: a third level refines part of the boundary
    # and loses a cancellation), so the margin, not the level count, is the safety here. Their own estimates stop
    # above the tolerance (the reported error_volume is conservative, up to 4.6x, as ups-sspr's). Without face
    # columns or z-levels no plan passes seed 0 (the task box's wall and thin slabs).
    "rps-upu-tool": ColumnPlan(10, 8, 5, 2, beta=1.0, zlevels=3, zconfirm=2, faces=True),
    # pprs-rprs's node plan (interference_free only: else its interval plan, INTERVAL_PLAN_OF) is the 3-D default;
    # searched before its box pad (bounding_box) and column intervals: none of 332 plans (against N = 192) was within
    # 0.8x on seed 0, the default included (0.96x); N = 192 is itself up to 1.35x off N = 384 on seed-0 designs, and
    # the default is 1.9x off N = 768 on a seed-1 design (0.36 % too large, its own estimate 0.88x: it stops early;
    # benchmarks/notes/adaptive_plans.md)
}


# plans for the mechanisms whose columns come in closed form (Mechanism.interval_kernel_for the options): the
# reachable length of a column is exact, so no z-levels are needed to find thin shells; the z-cells only serve the
# Gauss rule of the fields. rps-upu-tool: benchmarks/plan_search.py's 14 plans against N = 192 on seeds 0, 1, 2
# (benchmarks/notes/adaptive_plans.md): (10, 16, 5, 2, beta 1, faces) is within 0.60x (volume) and 0.52x (GCI) of the
# tolerance on all three at 7 320 calls per design, against its node plan's 19 512 (with intervals) or 61 150 (without);
# 8 columns or 12 z-cells miss (8.5x the volume tolerance on a seed-0 design; 1.65x in GCI), and 8 z-cells with no
# z-levels are 12x off in GCI (the fields' Gauss rule needs the 16)
# rps-upu (P-model; its columns run along z, Mechanism.column_axis): (8, 6, 5, 2, beta 3, 2 z-levels confirmed once)
# is within 0.77x of the tolerance against N = 192 on seeds 0-3 and N = 384 on seed 4 (N = 192 is off there) at
# 2 988 calls per design (seed 0), 0.44x the time of (8, 8, 5, 2, beta 1, 3 z-levels), which was within 0.58x at
# 7 186 calls: its 200 x 200 loop had reached 30 s, the goal. The psi-column node plan took 23 958. Without z-levels
# the fields' Gauss rule along z misses the GCI (16-48 fixed z-cells: 1.1-4.4x; the LCI varies along z more than
# the coarse cells resolve on some designs); more z-levels are not safer here (3 instead of 2: 2.02x in GCI on seed
# 0 against N = 384), so only the searched plan is trusted (benchmarks/notes/adaptive_plans.md)
# pprs-rprs: its workspaces are thin slabs (median 27-28 mm of a 215-256 mm box) whose columns hold one interval,
# so 1 z-cell and the midpoint rule serve the fields; its refinement is driven by walls (vertical planes of the
# rail and link limits), where the measure jumps but the LCI does not, so the refined columns inherit their fields
# (field_levels 0, kernels.adaptive step 3b) and refine 4 times less eagerly (beta 4): (24, 1, 5, 3, beta 4, no
# faces, fields on level 0, 1 Gauss point) is within 0.68x / 0.54x / 0.76x / 0.78x / 0.63x (volume, against the
# exact volume of the column intervals on a 2400^2 cross grid) and 0.47x / 0.51x / 0.50x / 0.56x / 0.76x (GCI,
# against 324^2 columns of exact intervals with fields everywhere) on seeds 0-4 at 2 056-2 609 calls per design,
# where the plan before, (24, 2, 5, 3, beta 1, faces), took 5 341-6 793 and was 1.14x off on a seed-3 design; 12
# or 16 columns miss small workspaces (1.52x, 1.16x on seed 1) (benchmarks/pprs_columns.py,
# benchmarks/notes/pprs_rprs.md)
INTERVAL_PLAN_OF: dict[str, ColumnPlan] = {
    # rps-upu-tool: inherited fields (step 3b) on the same plan: 3 132 calls per design against 7 320, 0.43x the time
    # (plan_search.py --ab), with the same worst errors against N = 192 on seeds 0-4 (volume 0.60 / 0.91x, GCI
    # 0.50 / 0.46x; before 0.60 / 0.91x, 0.52 / 0.62x); rps-upu's GCI does not allow it (1.19x on seed 1)
    "rps-upu-tool": ColumnPlan(10, 16, 5, 2, beta=1.0, faces=True, field_levels=0),
    # ups-sspr (Y-columns in closed form, ups_sspr.column_intervals): benchmarks/plan_search.py's 864 plans against
    # N = 192 (columns 4-8, cells 1-4, levels 3, beta 1-3, z-levels, faces), the cheapest within 0.8x of the
    # tolerance on seeds 0, 1, 2: 0.74x (volume) and 0.64x (GCI) at worst, 0.75x on seeds 3, 4; 562 calls per design
    # (LCI kernel) against the node plan's 2534 (with the same columns, 4 z-cells and every call a node or bisection)
    "ups-sspr": ColumnPlan(6, 2, 8, 3, beta=2.0, faces=True),
    "rps-upu": ColumnPlan(8, 6, 5, 2, beta=3.0, zlevels=2, zconfirm=1),
    "pprs-rprs": ColumnPlan(24, 1, 5, 3, beta=4.0, field_levels=0, gauss_points=1),
}


def adaptive_plan(mech: Mechanism, options: Mapping[str, Any] | None = None) -> ColumnPlan:
    """The mechanism's plan: its interval plan (INTERVAL_PLAN_OF) when its interval kernel handles these resolved
    options, else its node plan (ADAPTIVE_PLAN_OF, or the default per task dimension)."""
    if options is not None and mech.name in INTERVAL_PLAN_OF and mech.interval_kernel_for(options) is not None:
        return INTERVAL_PLAN_OF[mech.name]
    return ADAPTIVE_PLAN_OF.get(mech.name, ADAPTIVE_PLAN[len(mech.task_axes)])


@dataclass(frozen=True)
class UniformPlan:
    """The tolerance form on a uniform grid, for a mechanism whose uniform evaluator is far cheaper than the adaptive
    one at equal accuracy: ``steps`` (volume tolerance, GCI tolerance, N), each N the coarsest of a ladder whose
    worst errors on two sets of 20 random designs within the config's bounds stayed within 0.8x that tolerance
    against the benchmark's 3x finer reference (``benchmarks/uniform_ladder.py``, seeds 0 and 1)."""

    steps: tuple[tuple[float, float, int], ...]

    def resolution_for(self, tolerance: Tolerance) -> int | None:
        """N of the coarsest step calibrated for a tolerance at least as tight as ``tolerance``; None when no step
        is (the adaptive evaluator then meets it)."""
        ok = [n for tv, tg, n in self.steps if tv <= tolerance.volume and tg <= tolerance.gci]
        return min(ok) if ok else None


# 2pauu-ppap: its uniform fast path (column intervals, mirror symmetries) costs about 1/15 of the adaptive evaluator
# at (0.2 %, 5e-4) (N = 72: 0.96 ms against 15 ms per design on the quarter box of its symmetries, one thread).
# Ladders on the config's bounds (paper_2pauu_ppap.yaml; quick.yaml has the same), worst volume / GCI error as
# multiples of the tolerance on seed 0 | seed 1 (benchmarks/notes/uniform_plans.md): N = 72 at (0.2 %, 5e-4): 0.41,
# 0.44 | 0.50, 0.48 (N = 56: 0.67, 0.70 | 1.06, 1.04; N = 64: 1.04 on seed 0); N = 32 at (1 %, 2.5e-3): 0.68, 0.32 |
# 0.51, 0.52; N = 24 at (3 %, 5e-3): 0.57, 0.46 | 0.50, 0.74 (N = 20: 0.85, 0.88 on seed 0). Tighter steps, against
# N = 448 (`uniform_ladder.py 2pauu-ppap SEED ... --ref 448`): N = 112 at (0.1 %, 2.5e-4): 0.53, 0.60 | 0.58, 0.76
# (N = 96: 0.88x in GCI on seed 1); N = 144 at (0.05 %, 1e-4): 0.28, 0.59 | 0.60, 0.72 (N = 128: 0.93x on seed 1).
# Without them such a tolerance ran the adaptive evaluator: 0.12 s per design at (0.05 %, 1e-4), where N = 144
# takes about 4 ms
UNIFORM_PLAN_OF: dict[str, UniformPlan] = {
    "2pauu-ppap": UniformPlan(((0.0005, 1.0e-4, 144), (0.001, 2.5e-4, 112), (0.002, 5.0e-4, 72), (0.01, 2.5e-3, 32),
                               (0.03, 5.0e-3, 24))),
}


def uniform_resolution(mech: Mechanism, tolerance: Tolerance) -> int | None:
    """The uniform grid the tolerance form uses for ``mech`` (UNIFORM_PLAN_OF), or None: the adaptive evaluator."""
    plan = UNIFORM_PLAN_OF.get(mech.name)
    return None if plan is None else plan.resolution_for(tolerance)


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
    kernel = mech.lci_kernel if lci_only else mech.field_kernel
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


def tolerance_population_stats(
    mech: Mechanism,
    designs: Sequence[Mapping[str, float]],
    options: Mapping[str, Any],
    packed: np.ndarray,
    tolerance: Tolerance,
    edges: np.ndarray,
    region: Mapping[str, Sequence[float]] | None = None,
    lci_only: bool = False,
    estimates: bool = True,
) -> AdaptiveResult:
    """Statistics of every design under the tolerance form: the adaptive evaluator, or, for a mechanism with a
    calibrated uniform plan (UNIFORM_PLAN_OF), its uniform grid for ``tolerance``. There the error estimates are
    the change to the grid twice as fine (relative for the measure, absolute for the GCI), computed only with
    ``estimates`` (NaN without); the adaptive evaluator's come with its statistics."""
    n_uniform = uniform_resolution(mech, tolerance)
    from scalesynth import calibration  # no hand-calibrated plan: the per-design ladder (calibration.py)

    if n_uniform is None and not calibration.has_plan(mech):
        return calibration.calibrated_population_stats(mech, designs, options, packed, tolerance, edges, region,
                                                       lci_only=lci_only)
    if n_uniform is None:
        return adaptive_population_stats(mech, designs, options, packed, tolerance, edges, region, lci_only=lci_only)
    ndim = len(mech.task_axes)

    def on_grid(n: int, lci: bool) -> tuple[np.ndarray, np.ndarray]:
        grids = [make_grid(mech, d, options, n, region) for d in designs]
        lo = np.stack([g.lo for g in grids])
        step = np.stack([g.step for g in grids])
        return mech.grid_stats(packed, lo, step, grids[0].shape, edges, lci_only=lci), np.array(
            [g.cell_measure for g in grids])

    stats, cell = on_grid(n_uniform, lci_only)
    n = len(designs)
    err_v = np.full(n, np.nan)
    err_g = np.full(n, np.nan)
    calls = float(n_uniform**ndim)
    if estimates:
        fine, fine_cell = on_grid(2 * n_uniform, True)
        vol, vol_f = stats[:, _grid.COL_COUNT] * cell, fine[:, _grid.COL_COUNT] * fine_cell
        # relative to the reported measure, as the adaptive evaluator's; nothing reachable: 0, or 1 if the finer
        # grid finds something
        err_v = np.where(vol > 0.0, np.abs(vol - vol_f) / np.where(vol > 0.0, vol, 1.0),
                         np.where(vol_f > 0.0, 1.0, 0.0))
        # the GCI of an empty grid is 0 here, as the reported GCI (the catalogue's empty value)
        err_g = np.abs(np.nan_to_num(_field_mean(stats, 0)) - np.nan_to_num(_field_mean(fine, 0)))
        calls += float((2 * n_uniform) ** ndim)
    return AdaptiveResult(stats, cell, err_v, err_g, np.zeros(n, dtype=np.int64), np.full(n, calls),
                          n_uniform**ndim)


def _field_mean(stats: np.ndarray, f: int) -> np.ndarray:
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
            mean = _field_mean(stats, f)
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


def _metrics_of(
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
        values = _metrics_of(mech, [design], options, packed, ad.stats, ad.cell, resolution, band_edges, unit, task,
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
        values = _metrics_of(mech, [design], options, packed, stats, np.array([g.cell_measure]), resolution,
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
        return _metrics_of(mech, resolved, options, packed, None, None, *args)
    lci_only = fields is not None and set(fields) <= {"lci", "estimate"}
    if tolerance is not None:
        estimates = fields is None or "estimate" in fields
        ad = tolerance_population_stats(mech, resolved, options, packed, tolerance, edges, region,
                                        lci_only=lci_only, estimates=estimates)
        out = _metrics_of(mech, resolved, options, packed, ad.stats, ad.cell, *args)
        if estimates:
            out["error_volume"] = ad.error_volume
            out["error_gci"] = ad.error_gci
        return out
    grids = [make_grid(mech, d, options, resolution, region) for d in resolved]
    lo = np.stack([g.lo for g in grids])
    step = np.stack([g.step for g in grids])
    stats = mech.grid_stats(packed, lo, step, grids[0].shape, edges, lci_only=lci_only)
    cell = np.array([g.cell_measure for g in grids])
    return _metrics_of(mech, resolved, options, packed, stats, cell, *args)


def _check_selection(what: str, names: Collection[str] | None, known: Sequence[str]) -> None:
    """Raise InvalidParameter naming the first of ``names`` not in ``known`` (a misspelt family or field would
    otherwise just select nothing)."""
    for name in names or ():
        if name not in known:
            raise InvalidParameter(f"{what}: unknown name {name!r} " + hint(str(name), known))


def evaluator_description(cfg) -> str:
    """One line naming the workspace evaluator a config runs (reports and manifests): the uniform grid, or the
    tolerance form's adaptive evaluator or calibrated uniform grid."""
    tol = config_tolerance(cfg)
    if tol is None:
        return f"uniform grid, {cfg.grid.resolution} cells per axis"
    mech, options = cfg.mech, cfg.resolved_options()
    n = uniform_resolution(mech, tol)
    how = f"calibrated uniform grid, {n} cells per axis" if n is not None else "adaptive evaluator"
    if n is None:
        # what the config's own design runs: the half box of a mirror symmetry, closed-form column intervals
        lo, hi = design_boxes(mech, [cfg.resolved_design()], options, cfg.grid.region)
        halves = mirror_halves(mech, options, lo, hi, adaptive_plan(mech, options), column_axis(mech, options))
        extras = ([f"half box of the mirror symmetry in {' and '.join(mech.task_axes[a] for a in halves)}"]
                  if halves else []) + (["column intervals"] if mech.interval_kernel_for(options) is not None else [])
        if extras:
            how += f" ({'; '.join(extras)})"
    return f"tolerance volume {tol.volume:g}, GCI {tol.gci:g}: {how}"


def config_tolerance(cfg) -> Tolerance | None:
    """The config's accuracy target when it is in the tolerance form (``GridConfig.adaptive``), else None."""
    if not cfg.grid.adaptive:
        return None
    return Tolerance(volume=cfg.grid.tolerance.volume, gci=cfg.grid.tolerance.gci)


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
        cycle=cfg.cycle,
        tolerance=config_tolerance(cfg),
    )


def evaluate_config_population(cfg, designs: Sequence[Mapping[str, float]],
                               families: Collection[str] | None = None,
                               fields: Collection[str] | None = None) -> dict[str, np.ndarray]:
    """All metrics of many designs under one config (of ``families`` only, when given), in one parallel kernel
    call per grid. The cycle metrics (batched over the designs: cycle.population) only when an objective or
    constraint uses one
    (``cycle.config.searched``)."""
    from scalesynth.cycle.config import searched

    return evaluate_population(
        cfg.mech,
        designs,
        cfg.resolved_options(),
        resolution=cfg.grid.resolution,
        region=cfg.grid.region,
        band_edges=cfg.dexterity.band_edges,
        length_unit=cfg.units.length,
        task=cfg.task,
        cycle=searched(cfg),
        tolerance=config_tolerance(cfg),
        families=families,
        fields=fields,
    )
