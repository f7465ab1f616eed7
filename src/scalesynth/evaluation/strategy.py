"""Strategy choice under the tolerance form: the adaptive evaluator, or a mechanism's calibrated uniform grid with
its error estimates against the grid twice as fine."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from scalesynth.evaluation.adaptive import AdaptiveResult, adaptive_population_stats
from scalesynth.evaluation.assembly import field_mean
from scalesynth.evaluation.grid import make_grid
from scalesynth.evaluation.plans import Tolerance, calibrated_plan, uniform_resolution
from scalesynth.evaluation.sector import sector_plan, sector_population_stats
from scalesynth.kernels import grid as _grid

if TYPE_CHECKING:  # annotations only: nothing here imports the mechanisms
    from scalesynth.mechanisms.base import Mechanism


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
    """Statistics of every design under the tolerance form: a sector plan calibrated for it (evaluation.sector;
    rotationally symmetric legs only), an adaptive-evaluator plan calibrated for it
    (``Mechanism.calibrated_plans``, run at its calibration tolerance), the adaptive evaluator, or, for a mechanism
    with a calibrated uniform plan (``Mechanism.uniform_plan``), its uniform grid for ``tolerance``. There the error
    estimates are the change to the grid twice as fine (relative for the measure, absolute for the GCI), computed
    only with ``estimates`` (NaN without); the adaptive evaluator's come with its statistics. A mechanism with
    none of these climbs the per-design ladder (scalesynth.calibration)."""
    sector = sector_plan(mech, tolerance)
    if sector is not None:
        # a description's sector plan (evaluation.sector), where the legs' rotational symmetry admits it
        result = sector_population_stats(mech, designs, options, packed, edges, region, sector[1])
        if result is not None:
            return result
    calibrated = calibrated_plan(mech, tolerance)
    if calibrated is not None:
        # a plan calibrated at a tolerance at least as tight (a description's evaluation block), run at that
        # tolerance: what was measured against the finer grids is what runs
        return adaptive_population_stats(mech, designs, options, packed, calibrated.tolerance, edges, region,
                                         plan=calibrated.plan, lci_only=lci_only)
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
        err_g = np.abs(np.nan_to_num(field_mean(stats, 0)) - np.nan_to_num(field_mean(fine, 0)))
        calls += float((2 * n_uniform) ** ndim)
    return AdaptiveResult(stats, cell, err_v, err_g, np.zeros(n, dtype=np.int64), np.full(n, calls),
                          n_uniform**ndim)
