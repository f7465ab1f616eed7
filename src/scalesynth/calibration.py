"""Automatic calibration of the tolerance form for a mechanism with no hand-calibrated plan (issue 28).

The seed mechanisms' evaluation plans were searched by hand against 3x finer grids (each mechanism's
``node_plan``, ``interval_plan``, ``uniform_plan``). A described mechanism (or any other without one) gets no such
table; instead every design climbs a ladder of adaptive-evaluator plans (``LADDER_COLUMNS``: each rung 1.5x the
columns per cross axis and z-cells per column of the one before) until three consecutive rungs agree within half
the tolerance (``SAFETY``). This is Richardson-style: the change from a coarser rung bounds a finer rung's error
when the results converge. Two changes and half the tolerance, because convergence is not monotone: on a Delta
design the GCI stays 3e-4 low, within 5e-5, from 8 to 18 columns and moves to the reference only at 28. The finest
rung's statistics are reported, with the larger of the two changes as ``error_volume`` (relative) and
``error_gci`` (absolute); a design that still disagrees at the last rung reports the last rung and its last change
(above the tolerance), never a silent pass. The estimates are therefore not bounds: the benchmark
(benchmarks/described.py) states the errors against uniform grids.

Per design, so the result of a design does not depend on the other designs of the call (reproducible: the same
design evaluates the same alone or in a population of 200). The ladder's first rung and growth were chosen on the
rotary Delta (configs/delta.yaml, benchmarks/described.py and docs/describing.md give the numbers); nothing in it is
specific to one mechanism.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from scalesynth.kernels import grid as _grid

# columns per cross axis and z-cells per column of each rung: each rung 1.5x finer than the one before along every
# axis (rounded to even, for mirror halves), so the change between rungs sees every part of the discretisation: with
# 8 z-cells on every rung the GCI's Gauss rule along z does not change between rungs, and a Delta design 4.5e-4 off
# in GCI (against N = 384) reported 1.1e-4. Each rung: z-cells doubled up to twice where the column's fields change
# (z-levels), 5 bisections, 2 refinement levels and the box-face ghost columns (a workspace tangent to its box:
# without them a cylinder inscribed in its box, the linear Delta with base_radius = platform_radius, stays 0.3-0.4 %
# too large on every rung)
LADDER_COLUMNS = (8, 12, 18, 28, 42)
# share of the tolerance the two changes may take: the GCI does not converge monotonically in the columns; on a Delta
# design 8, 12 and 18 columns agreed within 5e-5 at 0.5500 while 28 and more (and uniform grids up to N = 384) give
# 0.5503 (the z-cells made no difference there: 1, 2 or 3 per column per rung gave the same GCI to 3e-5)
SAFETY = 0.5
# z-confirmations per rung where the columns run on nodes and bisection: a part of the workspace thinner than a
# z-cell is missed where no node falls inside it, and with one confirmation several rungs could miss the same part
# and agree. The rim of Masory and Wang's hexapod at a 40 deg joint limit (a wedge between z = 5.63 and 5.83, with
# 0.17 of its 38.2 volume in columns shorter than 0.2) lay between two nodes on the first three rungs in the box
# z in [0, 7.5]: they agreed on 0.39 % too little at a 0.2 % tolerance. Two confirmations (z-cells x 4 where
# needed) find it, at 1.75-2.1x the time per design of the Hexa and the hexapod (benchmarks/RESULTS.md). Interval
# kernels give each column's reachable set in closed form, so no node can miss a part: one confirmation there.
NODE_ZCONFIRM = 2


def ladder_plan(rung: int, nodes: bool = False):
    """The evaluate.ColumnPlan of ``rung`` (0-based) of the ladder; ``nodes``: the columns run on nodes and bisection
    (no interval kernel for these options), so each rung doubles its z-cells until two consecutive changes meet the
    tolerance instead of one (``NODE_ZCONFIRM``)."""
    from scalesynth.evaluation.plans import ColumnPlan

    return ColumnPlan(LADDER_COLUMNS[rung], LADDER_COLUMNS[rung], 5, 2, beta=1.0, zlevels=2,
                      zconfirm=NODE_ZCONFIRM if nodes else 1, faces=True)


def has_plan(mech) -> bool:
    """Whether ``mech`` has a hand-calibrated plan (then the tolerance form uses it, not this ladder)."""
    return mech.node_plan is not None or mech.interval_plan is not None or mech.uniform_plan is not None \
        or len(mech.task_axes) != 3


def _volume_gci(stats: np.ndarray, cell: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(measure, GCI) per statistics row; GCI 0 over an empty set (the catalogue's empty value)."""
    count = stats[:, _grid.COL_COUNT]
    gci = np.where(count > 0, stats[:, _grid.field_column(0, _grid.STAT_SUM)] / np.where(count > 0, count, 1.0), 0.0)
    return count * cell, gci


def _change(v0: np.ndarray, g0: np.ndarray, v1: np.ndarray, g1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(relative measure change, absolute GCI change) from a coarser (v0, g0) to a finer (v1, g1) rung; relative
    to the finer measure; nothing reachable on the finer rung: 0, or 1 if the coarser found something."""
    ev = np.where(v1 > 0.0, np.abs(v1 - v0) / np.where(v1 > 0.0, v1, 1.0), np.where(v0 > 0.0, 1.0, 0.0))
    return ev, np.abs(g1 - g0)


def calibrated_population_stats(
    mech,
    designs: Sequence[Mapping[str, float]],
    options: Mapping[str, Any],
    packed: np.ndarray,
    tolerance,
    edges: np.ndarray,
    region: Mapping[str, Sequence[float]] | None = None,
    lci_only: bool = False,
):
    """evaluate.AdaptiveResult of every design by the ladder (module docstring): statistics in the first rung's
    coarse-cell units (``cell``), ``levels`` the rung each design was accepted at (or the last), ``evaluations``
    the kernel calls of every rung the design ran."""
    from scalesynth.evaluation.adaptive import AdaptiveResult, adaptive_population_stats

    n = len(designs)
    ndim = len(mech.task_axes)
    nodes = mech.interval_kernel_for(options) is None  # the columns' reach by nodes and bisection
    first = ladder_plan(0, nodes)
    stats = cell = None
    err_v = np.full(n, np.inf)
    err_g = np.full(n, np.inf)
    rung_of = np.zeros(n, dtype=np.int64)
    calls = np.zeros(n)
    active = np.arange(n)
    prev_v = prev_g = None
    last_v = np.full(n, np.inf)  # the change into the previous rung, per design
    last_g = np.full(n, np.inf)
    for rung in range(len(LADDER_COLUMNS)):
        sub = [designs[i] for i in active]
        ad = adaptive_population_stats(mech, sub, options, packed[active], tolerance, edges, region,
                                       plan=ladder_plan(rung, nodes), lci_only=lci_only)
        calls[active] += ad.evaluations
        if stats is None:  # rung 0: every design; the unit of the rows (its coarse cell)
            stats, cell = ad.stats.copy(), ad.cell.copy()
        else:
            # rows of this rung in the first rung's coarse-cell units (extensive columns scaled by the cell ratio)
            for j, i in enumerate(active):
                stats[i] = _grid.scale_extensive(ad.stats[j : j + 1], mech.n_fields, ad.cell[j] / cell[i]
                                                 if cell[i] > 0.0 else 1.0)[0]
        rung_of[active] = rung
        v, g = _volume_gci(ad.stats, ad.cell)
        done = np.zeros(len(active), dtype=bool)
        if prev_v is not None:
            ev, eg = _change(prev_v, prev_g, v, g)
            # the estimate: the larger of the last two changes (one small change can be a crossing of a
            # non-monotone convergence; module docstring)
            err_v[active] = np.maximum(ev, last_v[active])
            err_g[active] = np.maximum(eg, last_g[active])
            last_v[active], last_g[active] = ev, eg
            done = (err_v[active] <= SAFETY * tolerance.volume) & (err_g[active] <= SAFETY * tolerance.gci)
        active, prev_v, prev_g = active[~done], v[~done], g[~done]
        if len(active) == 0:
            break
    # a design that ran out of rungs reports its last change (its last rung's, above the tolerance)
    unfinished = ~np.isfinite(err_v) | ~np.isfinite(err_g)
    err_v[unfinished] = np.nan_to_num(last_v[unfinished], posinf=1.0)
    err_g[unfinished] = np.nan_to_num(last_g[unfinished], posinf=1.0)
    return AdaptiveResult(stats, cell, err_v, err_g, rung_of, calls, first.coarse_cells(ndim))
