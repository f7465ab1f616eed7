"""Per dexterity band k: the designs of the final population that are non-dominated when the workspace measure
objective is replaced by band k's measure (the run's other objectives kept), written to bands/pareto_band<k>.csv
with a plot of each.

If the run has no workspace-measure objective (e.g. task GCI and task FCI), band k's measure (maximised) is added
to the run's objectives. Only feasible designs take part. Objective-space duplicates keep their first row.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from scalesynth import io as rio
from scalesynth import labels as lab


def nondominated_mask(F: np.ndarray) -> np.ndarray:
    """Rows of F (minimisation) that no other row dominates (pymoo's non-dominated sorting, first front)."""
    from pymoo.util.nds.non_dominated_sorting import NonDominatedSorting

    keep = np.zeros(len(F), dtype=bool)
    if len(F):
        keep[NonDominatedSorting().do(F, only_non_dominated_front=True)] = True
    return keep


def band_objectives(problem, band: int) -> tuple[list[str], np.ndarray]:
    """(columns, signs) of the band-k problem: measure objectives -> band k's measure, the others unchanged."""
    cfg = problem.cfg
    mkey = cfg.mech.measure_key(cfg.units.length)
    bkey = f"band{band}_{mkey}"
    cols, signs = [], []
    replaced = False
    for obj, key, sign in zip(cfg.objectives, problem.objective_keys, problem.signs, strict=True):
        if obj.metric == "volume" and not replaced:
            cols.append(bkey)
            signs.append(-1.0)
            replaced = True
        else:
            cols.append(key)
            signs.append(float(sign))
    if not replaced:
        cols.insert(0, bkey)
        signs.insert(0, -1.0)
    keep = list(dict.fromkeys(cols))  # a band volume that was already an objective appears once
    return keep, np.array([signs[cols.index(c)] for c in keep])


def band_pareto(problem, population: pd.DataFrame, band: int) -> tuple[pd.DataFrame, list[str]]:
    """Band-k Pareto set of a final population (feasible rows), sorted by band-k measure descending."""
    cols, signs = band_objectives(problem, band)
    feas = population[population["feasible"].astype(bool)] if "feasible" in population.columns else population
    F = feas[cols].to_numpy(dtype=float) * signs
    F = np.where(np.isnan(F), np.inf, F)  # a statistic over an empty set is the worst value, never best
    front = feas[nondominated_mask(F)].drop_duplicates(subset=cols, keep="first")
    front = front.sort_values(cols[0], ascending=bool(signs[0] > 0), kind="mergesort").reset_index(drop=True)
    return front, cols


def write_band_fronts(run_dir: Path, cfg, problem, population: pd.DataFrame | None, fmt: str = "png",
                      out_dir: Path | None = None) -> dict[str, Any]:
    """bands/pareto_band<k>.csv and bands/pareto_band<k>.<fmt> for every band; returns their paths and sizes."""
    from scalesynth import plotting

    if population is None:
        return {"paths": [], "sizes": []}
    bands_dir = rio.ensure_dir(Path(out_dir) if out_dir is not None else Path(run_dir) / "bands")
    paths, sizes = [], []
    edges = cfg.dexterity.band_edges
    feas = population[population["feasible"].astype(bool)] if "feasible" in population.columns else population
    label = lab.labeller(cfg)
    for k in range(len(edges) - 1):
        front, cols = band_pareto(problem, population, k)
        name = f"pareto_band{k}"
        rio.write_csv(bands_dir / f"{name}.csv", front.drop(columns=["feasible"], errors="ignore"))
        paths.append(bands_dir / f"{name}.csv")
        sizes.append(len(front))
        ycol = cols[1] if len(cols) > 1 else cols[0]
        fig = plotting.band_pareto_figure(
            feas[cols[0]].to_numpy(), feas[ycol].to_numpy(), front[cols[0]].to_numpy(), front[ycol].to_numpy(),
            label(cols[0]), label(ycol),
            f"{cfg.name}: Pareto set of LCI band {k} {_band_label(edges, k)} ({', '.join(cols)})")
        rio.save_figure(fig, bands_dir / f"{name}.{fmt}")
        plotting.close(fig)
        paths.append(bands_dir / f"{name}.{fmt}")
    return {"paths": paths, "sizes": sizes}


def _band_label(edges, k: int) -> str:
    return f"{'[' if k == 0 else '('}{edges[k]:g}, {edges[k + 1]:g}]"
