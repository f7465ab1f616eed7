"""The sector evaluator over a population (mechanisms/describe/sector.py): described 3T mechanisms whose legs are
rotationally symmetric about z (describe/symmetry.py) and whose columns have closed-form intervals; the volume is
the polar integral of the exact column lengths over one fundamental sector, the field statistics Gauss-Legendre
sums (docs/describing.md, "Evaluation plans")."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from scalesynth.evaluation.adaptive import AdaptiveResult
from scalesynth.evaluation.grid import design_boxes
from scalesynth.evaluation.plans import Tolerance
from scalesynth.kernels import grid as _grid

if TYPE_CHECKING:  # annotations only: nothing here imports the mechanisms
    from scalesynth.mechanisms.base import Mechanism

# counts are reported in cells of the design box's 64^3 grid (coverage = count / COARSE_CELLS)
COARSE_CELLS = 64**3


@dataclass(frozen=True)
class SectorPlan:
    """Gauss-Legendre nodes over the sector's angle (``angles``), over the radius (``radii``, in s with r = R (1 -
    s^2)) and on a reachable z-interval as long as the box's z-range (``z_points``; a shorter interval gets
    proportionally fewer, at least ``min_z_points``: about the same spacing everywhere); ``scan`` steps and
    ``bisections`` for the boundary radius of each ray."""

    angles: int
    radii: int
    z_points: int
    min_z_points: int = 1
    scan: int = 8
    bisections: int = 12


def gauss_tables(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights on [-1, 1] of every k <= n: row k of each (n + 1, n) table holds the
    k-point rule in its first k entries."""
    xz, wz = np.zeros((n + 1, n)), np.zeros((n + 1, n))
    for k in range(1, n + 1):
        xz[k, :k], wz[k, :k] = np.polynomial.legendre.leggauss(k)
    return xz, wz


def sector_plan(mech: Mechanism, tolerance: Tolerance) -> tuple[Tolerance, SectorPlan] | None:
    """The mechanism's sector plan for ``tolerance``: of those calibrated at a tolerance at least as tight, the
    loosest; None when none is (or the mechanism has none)."""
    ok = [(t, p) for t, p in getattr(mech, "sector_plans", ())
          if t.volume <= tolerance.volume and t.gci <= tolerance.gci]
    return max(ok, key=lambda tp: (tp[0].volume, tp[0].gci)) if ok else None


def sector_population_stats(
    mech: Mechanism,
    designs: Sequence[Mapping[str, float]],
    options: Mapping[str, Any],
    packed: np.ndarray,
    edges: np.ndarray,
    region: Mapping[str, Sequence[float]] | None,
    plan: SectorPlan,
) -> AdaptiveResult | None:
    """Statistics rows of every design by the sector evaluator, or None where it does not apply: the mechanism has
    other fields than the 3T template's, some design's legs (with the stiffness fields on: their sections,
    springs and load) are not rotationally symmetric about z, or a
    column is not handled in closed form. No error estimates (NaN): the plan's accuracy is its calibration's."""
    # the mechanism's hooks (DescribedMechanism.sector_angle, .sector_kernel): nothing here imports the mechanisms
    sector_angle = getattr(mech, "sector_angle", None)
    if sector_angle is None or tuple(mech.task_axes) != ("x", "y", "z"):
        return None
    angle = sector_angle(packed)
    if angle is None:
        return None
    n = len(designs)
    lo, hi = design_boxes(mech, designs, options, region)
    rmax = np.sqrt(np.maximum(lo[:, 0] ** 2, hi[:, 0] ** 2) + np.maximum(lo[:, 1] ** 2, hi[:, 1] ** 2))
    cell = np.prod(hi - lo, axis=1) / COARSE_CELLS
    safe_cell = np.where(cell > 0.0, cell, 1.0)  # an empty box: nothing reachable, count 0 in any unit
    xp, wp = np.polynomial.legendre.leggauss(plan.angles)
    xs, ws = np.polynomial.legendre.leggauss(plan.radii)
    xz, wz = gauss_tables(plan.z_points)
    rows = np.zeros((n, _grid.stat_columns(mech.n_fields, len(edges) - 1)))
    calls = np.zeros(n, dtype=np.int64)
    mech.sector_kernel(packed, 0.0, angle, np.where(cell > 0.0, rmax, 0.0), lo[:, 2], hi[:, 2],
                       plan.scan, plan.bisections, xp, wp, xs, ws, xz, wz,
                       min(plan.min_z_points, plan.z_points), edges, safe_cell, rows, calls)
    if np.any(calls < 0):
        return None
    stats = _grid.scale_extensive(rows, mech.n_fields, 2.0 * math.pi / angle)
    nan = np.full(n, np.nan)
    return AdaptiveResult(stats, cell, nan, nan.copy(), np.zeros(n, dtype=np.int64), calls.astype(float),
                          COARSE_CELLS)
