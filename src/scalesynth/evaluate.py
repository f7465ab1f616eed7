"""Workspace, task and design metrics of designs: evaluate(mechanism, design, ...) -> WorkspaceReport.

The pipeline lives in ``scalesynth.evaluation``, one job per module (grid geometry, plans, the adaptive evaluator,
strategy choice, metric assembly, the report API, config adapters); this module re-exports its public names, so
``from scalesynth.evaluate import evaluate_config`` and the like keep working. Degenerate designs are data: an empty
workspace gives measure 0 and GCI 0; every other statistic over an empty set is NaN (null), never a number that
could read as best (stats_to_metrics).
"""

from __future__ import annotations

from scalesynth.evaluation.adaptive import (
    AdaptiveResult,
    HalfBox,
    adaptive_population_stats,
    column_axis,
    column_order,
    mirror_halves,
)
from scalesynth.evaluation.assembly import field_mean, metrics_of, stats_to_metrics
from scalesynth.evaluation.configs import (
    config_tolerance,
    evaluate_config,
    evaluate_config_population,
    evaluator_description,
)
from scalesynth.evaluation.grid import Grid, design_boxes, make_grid, task_grid
from scalesynth.evaluation.plans import (
    ADAPTIVE_PLAN,
    ColumnPlan,
    Tolerance,
    UniformPlan,
    adaptive_plan,
    uniform_resolution,
)
from scalesynth.evaluation.report import DEFAULT_BAND_EDGES, WorkspaceReport, evaluate, evaluate_population, warm_up
from scalesynth.evaluation.strategy import tolerance_population_stats
from scalesynth.paths import sample_path

__all__ = [
    "ADAPTIVE_PLAN", "DEFAULT_BAND_EDGES", "AdaptiveResult", "ColumnPlan", "Grid", "HalfBox", "Tolerance",
    "UniformPlan", "WorkspaceReport", "adaptive_plan", "adaptive_population_stats", "column_axis", "column_order",
    "config_tolerance", "design_boxes", "evaluate", "evaluate_config", "evaluate_config_population",
    "evaluate_population", "evaluator_description", "field_mean", "make_grid", "metrics_of", "mirror_halves",
    "sample_path", "stats_to_metrics", "task_grid", "tolerance_population_stats", "uniform_resolution", "warm_up",
]
