"""Evaluation plans: the accuracy target (Tolerance), the adaptive column evaluator's resolution (ColumnPlan) and
a calibrated uniform grid per tolerance (UniformPlan), and which one a mechanism runs. Each mechanism carries its
own hand-tuned plans (``Mechanism.node_plan``, ``interval_plan``, ``uniform_plan``); the defaults are here."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # annotations only: nothing here imports the mechanisms
    from scalesynth.mechanisms.base import Mechanism


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



# the default plan per task dimension, for a mechanism without its own (Mechanism.node_plan; chosen with
# `python benchmarks/bench.py adaptive`, which checks the tolerance against a 3x finer uniform grid on 20 random
# designs): planar workspaces have parts thinner than 1/64 of the box along y; 3-D workspaces have shells thinner
# than the 8 coarse z-cells and walls between the edge columns and the box, hence z-levels confirmed twice and
# box-face columns. The mechanisms' own plans, and why each, live with the mechanisms (node_plan, interval_plan,
# uniform_plan)
ADAPTIVE_PLAN = {2: ColumnPlan(64, 128, 8, 6),
                 3: ColumnPlan(24, 8, 5, 3, beta=1.0, zlevels=5, zconfirm=2, faces=True)}


def adaptive_plan(mech: Mechanism, options: Mapping[str, Any] | None = None) -> ColumnPlan:
    """The mechanism's plan: its interval plan (``Mechanism.interval_plan``) when its interval kernel handles these
    resolved options, else its node plan (``Mechanism.node_plan``, or the default per task dimension)."""
    if options is not None and mech.interval_plan is not None and mech.interval_kernel_for(options) is not None:
        return mech.interval_plan
    return mech.node_plan or ADAPTIVE_PLAN[len(mech.task_axes)]


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


@dataclass(frozen=True)
class CalibratedPlan:
    """An adaptive-evaluator plan calibrated for a tolerance (a description's ``evaluation`` block): run at
    ``tolerance`` itself it met that tolerance against 3x finer uniform grids on random designs."""

    tolerance: Tolerance
    plan: ColumnPlan


def calibrated_plan(mech: Mechanism, tolerance: Tolerance) -> CalibratedPlan | None:
    """The mechanism's calibrated plan (``Mechanism.calibrated_plans``) for ``tolerance``: of those calibrated at a
    tolerance at least as tight on both counts, the one calibrated at the loosest (volume, then GCI); None when none
    is (the per-design ladder of scalesynth.calibration then meets it)."""
    ok = [c for c in mech.calibrated_plans
          if c.tolerance.volume <= tolerance.volume and c.tolerance.gci <= tolerance.gci]
    return max(ok, key=lambda c: (c.tolerance.volume, c.tolerance.gci)) if ok else None


def uniform_resolution(mech: Mechanism, tolerance: Tolerance) -> int | None:
    """The uniform grid the tolerance form uses for ``mech`` (``Mechanism.uniform_plan``), or None: the adaptive
    evaluator."""
    plan = mech.uniform_plan
    return None if plan is None else plan.resolution_for(tolerance)
