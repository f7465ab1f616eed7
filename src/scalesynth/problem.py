"""The pymoo Problem: design vectors -> objectives F and constraints G (G <= 0 feasible), vectorised.

Each generation's designs go to the Numba evaluator in one call (``evaluate_config_population``). Besides F and
G the problem returns ``M``, the matrix of every metric (columns ``metric_columns``), so results can report
all of them without re-evaluating.
"""

from __future__ import annotations

import numpy as np
from pymoo.core.problem import Problem

from scalesynth.config import ConstraintConfig, ObjectiveConfig, RunConfig
from scalesynth.evaluate import evaluate_config_population, metric_names

# Worst possible value of each metric for a minimised objective (hypervolume reference); maximised metrics are
# all >= 0, so their worst value is 0.
_WORST_IF_MIN = {"fci": 0.5, "task_fci": 0.5}


def metric_key(cfg: RunConfig, item: ObjectiveConfig | ConstraintConfig) -> str:
    """Column name of an objective's or constraint's metric, e.g. 'volume_m3', 'band2_share'."""
    mkey = cfg.mech.measure_key(cfg.units.length)
    if item.metric == "volume":
        return mkey
    if item.metric == "band_share":
        return f"band{item.band}_share"
    if item.metric == "band_volume":
        return f"band{item.band}_{mkey}"
    return item.metric


def objective_label(cfg: RunConfig, obj: ObjectiveConfig) -> str:
    return f"{obj.sense} {metric_key(cfg, obj)}"


class SynthesisProblem(Problem):
    """Design variables = the config's ``bounds`` keys, in the mechanism's parameter order (so YAML key order cannot
    change a result); other parameters stay at ``design``."""

    def __init__(self, cfg: RunConfig):
        if not cfg.bounds:
            from scalesynth.errors import ConfigError

            raise ConfigError("bounds: at least one design variable needs bounds to optimise")
        self.cfg = cfg
        self.var_names = [p for p in cfg.mech.parameter_names if p in cfg.bounds]
        self.base_design = cfg.resolved_design()
        self.objective_keys = [metric_key(cfg, o) for o in cfg.objectives]
        self.signs = np.array([-1.0 if o.sense == "max" else 1.0 for o in cfg.objectives])
        self.constraint_keys = [metric_key(cfg, c) for c in cfg.constraints]
        names = metric_names(cfg.mech, cfg.units.length, cfg.dexterity.band_edges)
        if cfg.task is not None:
            names += ["task_coverage", "task_gci", "task_fci", "task_min_lci"]
            if cfg.task.path is not None:
                names += ["path_reachable", "path_min_lci", "path_mean_lci"]
        # stiffness metrics (issue 12) only when an objective or constraint asks for them (their kernels cost)
        from scalesynth.stiffness.fields import TASK_METRICS, WORKSPACE_METRICS

        used = set(self.objective_keys) | set(self.constraint_keys)
        self.stiffness = bool(used & set(WORKSPACE_METRICS + TASK_METRICS))
        if self.stiffness:
            names += list(WORKSPACE_METRICS) + (list(TASK_METRICS) if cfg.task is not None else [])
        self.metric_columns = names
        n_constr = sum((c.min is not None) + (c.max is not None) for c in cfg.constraints)
        xl = np.array([cfg.bounds[k][0] for k in self.var_names], dtype=float)
        xu = np.array([cfg.bounds[k][1] for k in self.var_names], dtype=float)
        super().__init__(n_var=len(xl), n_obj=len(cfg.objectives), n_ieq_constr=n_constr, xl=xl, xu=xu)

    def designs(self, X: np.ndarray) -> list[dict[str, float]]:
        out = []
        for row in np.atleast_2d(X):
            d = dict(self.base_design)
            d.update({k: float(v) for k, v in zip(self.var_names, row, strict=True)})
            out.append(d)
        return out

    def metrics(self, X: np.ndarray) -> np.ndarray:
        """All metrics, shape (n, len(metric_columns))."""
        values = evaluate_config_population(self.cfg, self.designs(X), stiffness=self.stiffness)
        return np.column_stack([np.asarray(values[k], dtype=float) for k in self.metric_columns])

    def objectives_from_metrics(self, M: np.ndarray) -> np.ndarray:
        cols = [self.metric_columns.index(k) for k in self.objective_keys]
        return M[:, cols] * self.signs

    def constraints_from_metrics(self, M: np.ndarray) -> np.ndarray:
        """G <= 0 feasible; each row scaled by its bound so violations of different metrics are commensurate."""
        rows = []
        for con, key in zip(self.cfg.constraints, self.constraint_keys, strict=True):
            v = M[:, self.metric_columns.index(key)]
            if con.min is not None:
                rows.append((con.min - v) / max(abs(con.min), 1e-12))
            if con.max is not None:
                rows.append((v - con.max) / max(abs(con.max), 1e-12))
        return np.column_stack(rows) if rows else np.zeros((M.shape[0], 0))

    def _evaluate(self, X, out, *args, **kwargs):
        M = self.metrics(X)
        out["F"] = self.objectives_from_metrics(M)
        if self.n_ieq_constr:
            out["G"] = self.constraints_from_metrics(M)
        out["M"] = M

    def hv_reference(self) -> np.ndarray:
        """Fixed hypervolume reference point in the minimisation form of F (written to the manifest).

        Maximised metrics are >= 0, so 0 is their worst value; minimised ones use their largest possible value
        (1 for LCI-type shares and indices, 0.5 for FCI, the bounding-box measure of the largest design for
        volumes)."""
        ref = []
        for obj, key in zip(self.cfg.objectives, self.objective_keys, strict=True):
            if obj.sense == "max":
                ref.append(0.0)
            elif obj.metric in ("volume", "band_volume"):
                upper = dict(self.base_design)
                upper.update({k: self.cfg.bounds[k][1] for k in self.var_names})
                lo, hi = self.cfg.mech.bounding_box(upper, self.cfg.resolved_options())
                n = len(self.cfg.mech.task_axes)
                ref.append(float(np.prod((hi - lo)[:n])))
            else:
                ref.append(_WORST_IF_MIN.get(key, 1.0))
        return np.array(ref, dtype=float)

    def canonical(self, X: np.ndarray) -> np.ndarray:
        """Design vectors mapped to the mechanism's canonical parameters (identical models -> identical rows)."""
        return self.cfg.mech.canonical_vectors(self.var_names, np.atleast_2d(X))
