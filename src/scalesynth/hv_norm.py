"""The hypervolume history as a share of its reference box, for plots and reports.

A run's hypervolume is measured in the product of its objectives' units (m³ × 1, or mm⁶ for two volumes in mm³), so
its raw value can read 2.6×10¹⁵. Divided by the volume of the reference box, the box spanned by the fixed reference
point (manifest ``hv_reference``) and the run's ideal point (per objective the best value any feasible design of the
run reached, from history.csv's ``best_<objective>`` columns), it lies in [0, 1]: every point counted in the
hypervolume lies in that box. The same denominator serves every generation, so the curve keeps its shape.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

AXIS_LABEL = "hypervolume / reference-box volume [-]"
RAW_LABEL = "hypervolume [product of the objectives' units]"


def reference_box(history, ref: Sequence[float], keys: Sequence[str], signs: Sequence[float]) -> np.ndarray | None:
    """(2, n_obj) corners of the reference box in minimisation form (ideal point, reference point), or None when
    history.csv lacks a ``best_<key>`` column or an objective appears twice (one column for two senses)."""
    if len(set(keys)) != len(keys) or any(f"best_{k}" not in history.columns for k in keys):
        return None
    import pandas as pd

    def column(name: str) -> np.ndarray:  # a damaged cell reads NaN and counts for nothing
        return pd.to_numeric(history[name], errors="coerce").to_numpy(dtype=float)

    # a generation without a feasible design wrote best_<key> 0: no value reached, not a best one
    feasible = column("n_feasible") > 0 if "n_feasible" in history.columns else np.ones(len(history), dtype=bool)
    ideal = []
    for key, sign in zip(keys, signs, strict=True):
        best = column(f"best_{key}")[feasible] * float(sign)  # minimisation form
        best = best[np.isfinite(best)]
        ideal.append(best.min() if best.size else np.inf)
    return np.vstack([np.array(ideal, dtype=float), np.asarray(ref, dtype=float)])


def normalised(history, ref: Sequence[float], keys: Sequence[str], signs: Sequence[float]) -> np.ndarray | None:
    """history's hypervolume divided by the reference box volume (in [0, 1]; 0 where no design dominates the
    reference point), or None when the box is unknown (see reference_box)."""
    import pandas as pd

    box = reference_box(history, ref, keys, signs)
    if box is None:
        return None
    hv = pd.to_numeric(history["hypervolume"], errors="coerce").to_numpy(dtype=float)
    volume = float(np.prod(np.clip(box[1] - box[0], 0.0, None))) if np.all(np.isfinite(box)) else 0.0
    if volume <= 0.0 or not np.isfinite(volume):
        return np.zeros_like(hv)  # no feasible design beats the reference point: nothing is dominated
    # mathematically at most 1; the hypervolume library and the product here round differently in the last bit
    return np.clip(hv / volume, 0.0, 1.0)


def of_result(result) -> tuple[np.ndarray, str]:
    """(values, axis label) of a results.RunResult's hypervolume history: normalised when it can be, else raw."""
    problem = result.problem
    ref = (result.manifest or {}).get("hv_reference") or problem.hv_reference()
    values = normalised(result.history, ref, problem.objective_keys, problem.signs)
    if values is None:
        return result.history["hypervolume"].to_numpy(dtype=float), RAW_LABEL
    return values, AXIS_LABEL


def share_text(result) -> str:
    """' (0.83 of the reference box)': the final hypervolume normalised, or '' when it cannot be."""
    values, label = of_result(result)
    return f" ({values[-1]:.4g} of the reference box)" if label == AXIS_LABEL and len(values) else ""
