"""Config adapters: evaluate a RunConfig's design or designs with its options, grid, bands, task and cycle; the
config's tolerance and a one-line description of the evaluator it runs."""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence

import numpy as np

from scalesynth.evaluation.adaptive import column_axis, mirror_halves
from scalesynth.evaluation.grid import design_boxes
from scalesynth.evaluation.plans import Tolerance, adaptive_plan, calibrated_plan, uniform_resolution
from scalesynth.evaluation.report import WorkspaceReport, evaluate, evaluate_population


def evaluator_description(cfg) -> str:
    """One line naming the workspace evaluator a config runs (reports and manifests): the uniform grid, or the
    tolerance form's adaptive evaluator or calibrated uniform grid."""
    tol = config_tolerance(cfg)
    if tol is None:
        return f"uniform grid, {cfg.grid.resolution} cells per axis"
    mech, options = cfg.mech, cfg.resolved_options()
    calibrated = calibrated_plan(mech, tol)
    n = None if calibrated is not None else uniform_resolution(mech, tol)
    how = f"calibrated uniform grid, {n} cells per axis" if n is not None else "adaptive evaluator"
    if calibrated is not None:
        how += (f" with the description's plan calibrated at volume {calibrated.tolerance.volume:g}, GCI "
                f"{calibrated.tolerance.gci:g}")
    if n is None:
        # what the config's own design runs: the half box of a mirror symmetry, closed-form column intervals
        lo, hi = design_boxes(mech, [cfg.resolved_design()], options, cfg.grid.region)
        plan = calibrated.plan if calibrated is not None else adaptive_plan(mech, options)
        halves = mirror_halves(mech, options, lo, hi, plan, column_axis(mech, options))
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
