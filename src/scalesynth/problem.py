"""The pymoo Problem: design vectors -> objectives F and constraints G (G <= 0 feasible), vectorised.

Each generation's designs go to the Numba evaluator in one call (``evaluate_config_population``), for the
catalogue families the objectives and constraints use, and, when their workspace metrics are the LCI's alone
(measure, GCI, bands), with the mechanism's LCI kernel (no clearance, stiffness or sigma per point). Besides F and
G the problem returns ``M``, the matrix of every metric (columns ``metric_columns``; NaN in the columns the search
does not evaluate), and ``complete_metrics`` fills those columns in for the final population, so results report
every metric.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping

import numpy as np
from pymoo.core.problem import Problem

from scalesynth import metrics as _metrics
from scalesynth.config import ConstraintConfig, ObjectiveConfig, RunConfig
from scalesynth.dynamics.config import GEAR_RATIO
from scalesynth.evaluate import evaluate_config_population


def metric_entry(cfg: RunConfig, item: ObjectiveConfig | ConstraintConfig) -> _metrics.Metric:
    """Catalogue entry of an objective's or constraint's metric (the config was validated against it)."""
    return _metrics.catalogue(cfg.mech, cfg.units.length)[item.metric]


def metric_key(cfg: RunConfig, item: ObjectiveConfig | ConstraintConfig) -> str:
    """Column name of an objective's or constraint's metric, e.g. 'volume_m3', 'band2_share'."""
    return metric_entry(cfg, item).column_for(item.band)


def result_columns(cfg: RunConfig) -> list[str]:
    """Every metric column of the config's results (catalogue order)."""
    from scalesynth.cycle.config import searched

    has_task = cfg.task is not None
    return _metrics.result_columns(cfg.mech, cfg.units.length, len(cfg.dexterity.band_edges) - 1, has_task,
                                   has_task and cfg.task.path is not None, cfg.resolved_options(), searched(cfg),
                                   cfg.grid.adaptive)


def objective_label(cfg: RunConfig, obj: ObjectiveConfig) -> str:
    return f"{obj.sense} {metric_key(cfg, obj)}"


class SynthesisProblem(Problem):
    """Design variables = the config's ``bounds`` keys, in the mechanism's parameter order (so YAML key order cannot
    change a result); other parameters stay at ``design``. ``bounds.gear_ratio`` (with motors) adds the motors'
    shared gear ratio as the last variable: ``var_names`` ends with it, ``design_names`` are the mechanism's."""

    def __init__(self, cfg: RunConfig):
        if not cfg.bounds:
            from scalesynth.errors import ConfigError

            raise ConfigError("bounds: at least one design variable needs bounds to optimise")
        self.cfg = cfg
        self.design_names = [p for p in cfg.mech.parameter_names if p in cfg.bounds]
        self.searches_gear_ratio = GEAR_RATIO in cfg.bounds and GEAR_RATIO not in cfg.mech.parameter_names
        self.var_names = [*self.design_names, *([GEAR_RATIO] if self.searches_gear_ratio else [])]
        self.base_design = cfg.resolved_design()
        self.objective_keys = [metric_key(cfg, o) for o in cfg.objectives]
        self.signs = np.array([-1.0 if o.sense == "max" else 1.0 for o in cfg.objectives])
        self.constraint_keys = [metric_key(cfg, c) for c in cfg.constraints]
        self.metric_columns = result_columns(cfg)
        # the search evaluates only the catalogue families its objectives and constraints use (a five-bar's task
        # and cycle metrics need no workspace grid); the final population gets the other columns (complete_metrics)
        entries = [metric_entry(cfg, item) for item in [*cfg.objectives, *cfg.constraints]]
        self.searched_families = frozenset(m.family for m in entries)
        # what the searched workspace metrics need: None (every field) unless the LCI (and the error estimates) alone
        wfields = {_metrics.field_of(m) for m in entries if m.family == "workspace"}
        self.searched_fields = frozenset(wfields) if wfields <= {"lci", "estimate"} else None
        n_constr = sum((c.min is not None) + (c.max is not None) for c in cfg.constraints)
        xl = np.array([cfg.bounds[k][0] for k in self.var_names], dtype=float)
        xu = np.array([cfg.bounds[k][1] for k in self.var_names], dtype=float)
        super().__init__(n_var=len(xl), n_obj=len(cfg.objectives), n_ieq_constr=n_constr, xl=xl, xu=xu)

    def designs(self, X: np.ndarray) -> list[dict[str, float]]:
        """The mechanism's designs of the rows of X (a searched gear ratio is not a design parameter:
        ``config_of``)."""
        out = []
        for row in np.atleast_2d(X):
            d = dict(self.base_design)
            d.update({k: float(v) for k, v in zip(self.design_names, row, strict=False)})
            out.append(d)
        return out

    def config_of(self, values: Mapping[str, float]) -> RunConfig:
        """The config of one row (a results row or a design vector as a name -> value mapping): the run's config
        with motors.gear_ratio set to the row's gear ratio when the search varies it, else the run's config."""
        if not self.searches_gear_ratio:
            return self.cfg
        from scalesynth.config import config_from_dict

        data = self.cfg.model_dump(mode="json")
        data["motors"] = {**data["motors"], GEAR_RATIO: float(values[GEAR_RATIO])}
        return config_from_dict(data, base_dir=getattr(self.cfg.cycle, "_base_dir", None))

    def _evaluate_population(self, X: np.ndarray, families, fields=None) -> dict[str, np.ndarray]:
        """evaluate_config_population of the rows of X; with a searched gear ratio, each design's cycle uses its
        own (a copy of the cycle carries the ratios to cycle.population)."""
        cfg = self.cfg
        if self.searches_gear_ratio and cfg.cycle is not None:
            cycle = cfg.cycle.model_copy()
            cycle._gear_ratios = np.atleast_2d(X)[:, len(self.design_names)].astype(float)
            cfg = cfg.model_copy(update={"cycle": cycle})
        return evaluate_config_population(cfg, self.designs(X), families, fields)

    def metrics(self, X: np.ndarray) -> np.ndarray:
        """Metrics of the designs X (n, n_var), shape (n, len(metric_columns)): the searched families' columns,
        NaN in the others (``complete_metrics``)."""
        values = self._evaluate_population(X, self.searched_families, self.searched_fields)
        n = np.atleast_2d(X).shape[0]
        return np.column_stack([np.asarray(values[k], dtype=float) if k in values else np.full(n, np.nan)
                                for k in self.metric_columns])

    def _entry_of(self) -> dict[str, _metrics.Metric]:
        """Catalogue entry of every metric column."""
        n_bands = len(self.cfg.dexterity.band_edges) - 1
        return {c: m for m in _metrics.catalogue(self.cfg.mech, self.cfg.units.length).values()
                for c in m.columns(n_bands)}

    def _family_of(self) -> dict[str, str]:
        """Catalogue family of every metric column."""
        return {c: m.family for c, m in self._entry_of().items()}

    def unsearched_columns(self) -> list[str]:
        """The metric columns the search does not evaluate: those of the families it does not use and, when it
        runs the LCI kernel, the workspace statistics of the other fields."""
        entry_of = self._entry_of()

        def searched(m: _metrics.Metric) -> bool:
            if m.family not in self.searched_families:
                return False
            fields = self.searched_fields
            return m.family != "workspace" or fields is None or _metrics.field_of(m) in fields

        return [k for k in self.metric_columns if not searched(entry_of[k])]

    def complete_metrics(self, X: np.ndarray, M: np.ndarray) -> np.ndarray:
        """M (from ``metrics``) with the unsearched columns evaluated for the designs X; a copy. A design's
        metrics do not depend on the designs evaluated with it, so the values equal a full evaluation's."""
        missing = self.unsearched_columns()
        if not missing or not len(M):
            return M
        family_of = self._family_of()
        values = self._evaluate_population(X, frozenset(family_of[k] for k in missing))
        out = np.array(M, dtype=float, copy=True)
        for k in missing:
            out[:, self.metric_columns.index(k)] = np.asarray(values[k], dtype=float)
        return out

    def _searched_values(self, M: np.ndarray, item: ObjectiveConfig | ConstraintConfig) -> np.ndarray:
        """An objective's or constraint's column of M, NaN where its statistic is over an empty set: NaN already
        (statistics without an ``empty`` value), or the GCI's conventional 0 where the measure of its set (the
        workspace measure, task_coverage) is 0."""
        m = metric_entry(self.cfg, item)
        v = np.array(M[:, self.metric_columns.index(m.column_for(item.band))], dtype=float)
        if m.empty is not None:
            size = self.cfg.mech.measure_key(self.cfg.units.length) if m.family == "workspace" else "task_coverage"
            if size in self.metric_columns:
                v[M[:, self.metric_columns.index(size)] == 0.0] = np.nan
        return v

    def worst_objectives(self) -> np.ndarray:
        """The worst value of each objective in minimisation form (the hypervolume reference), computed once."""
        if getattr(self, "_worst", None) is None:
            self._worst = self.hv_reference()
        return self._worst

    def minimisation_form(self, values: np.ndarray) -> np.ndarray:
        """Objective values (n, n_obj) in minimisation form; a statistic over an empty set (NaN) counts as the
        objective's worst value, never as best (issue 27)."""
        F = np.asarray(values, dtype=float) * self.signs
        return np.where(np.isnan(F), self.worst_objectives()[None, :], F)

    def objectives_from_metrics(self, M: np.ndarray) -> np.ndarray:
        values = [self._searched_values(M, obj) for obj in self.cfg.objectives]
        return self.minimisation_form(np.column_stack(values) if values else np.zeros((M.shape[0], 0)))

    def constraints_from_metrics(self, M: np.ndarray) -> np.ndarray:
        """G <= 0 feasible; each row scaled by its bound so violations of different metrics are commensurate. A
        statistic over an empty set (NaN) satisfies no bound: it violates each by at least 1 (the bound's scale),
        or by more where the metric's worst value would."""
        rows = []
        for con in self.cfg.constraints:
            v = self._searched_values(M, con)
            m = metric_entry(self.cfg, con)
            for bound, sign, worst in ((con.min, -1.0, m.range[0]),
                                       (con.max, 1.0, m.worst if isinstance(m.worst, float) else m.range[1])):
                if bound is None:
                    continue
                g = sign * (v - bound) / max(abs(bound), 1e-12)
                at_worst = sign * (worst - bound) / max(abs(bound), 1e-12)
                empty = max(1.0, at_worst) if np.isfinite(at_worst) else 1.0
                rows.append(np.where(np.isnan(g), empty, g))
        return np.column_stack(rows) if rows else np.zeros((M.shape[0], 0))

    def _evaluate(self, X, out, *args, **kwargs):
        M = self.metrics(X)
        out["F"] = self.objectives_from_metrics(M)
        if self.n_ieq_constr:
            out["G"] = self.constraints_from_metrics(M)
        out["M"] = M

    def hv_reference(self) -> np.ndarray:
        """Fixed hypervolume reference point in the minimisation form of F (written to the manifest).

        A maximised metric's worst value is the lower end of its catalogue range (0 for all of them, entering
        negated); a minimised one uses the catalogue's worst value: a number (1 for LCI-type shares and indices,
        0.5 for FCI), the bounding-box measure of the largest design (volumes), or the largest value over the
        corners of the bounds (design-level metrics)."""
        ref = []
        for obj in self.cfg.objectives:
            m = metric_entry(self.cfg, obj)
            if obj.sense == "max":
                ref.append(-float(m.range[0]) if m.range[0] != 0 else 0.0)
            elif m.worst == _metrics.WORST_BOUNDING_BOX:
                upper = dict(self.base_design)
                upper.update({k: self.cfg.bounds[k][1] for k in self.design_names})
                lo, hi = self.cfg.mech.bounding_box(upper, self.cfg.resolved_options())
                n = len(self.cfg.mech.task_axes)
                ref.append(float(np.prod((hi - lo)[:n])))
            elif m.worst == _metrics.WORST_BOUNDS_CORNERS:
                ref.append(float(max(m.compute(self._corner_context()))))
            else:
                ref.append(float(m.worst))
        return np.array(ref, dtype=float)

    def _corner_context(self) -> _metrics.EvalContext:
        """The designs at every corner of the optimisation bounds, for design-level worst values."""
        corners = []
        for combo in itertools.product(*[self.cfg.bounds[k] for k in self.design_names]):
            d = dict(self.base_design)
            d.update({k: float(v) for k, v in zip(self.design_names, combo, strict=True)})
            corners.append(d)
        options = self.cfg.resolved_options()
        packed = np.stack([self.cfg.mech.pack(d, options) for d in corners])
        return _metrics.EvalContext(self.cfg.mech, corners, options, packed, self.cfg.task, self.cfg.grid.resolution,
                                    self.cfg.dexterity.band_edges, self.cfg.units.length)

    def canonical(self, X: np.ndarray) -> np.ndarray:
        """Design vectors mapped to the mechanism's canonical parameters (identical models -> identical rows).

        The canonical map describes the kinematics; a design-level objective or constraint (e.g. footprint_radius
        = m for seed 000) may tell such designs apart, so then the vectors are kept as they are."""
        X = np.atleast_2d(X)
        items = [*self.cfg.objectives, *self.cfg.constraints]
        if any(metric_entry(self.cfg, item).family == "design" for item in items):
            return np.asarray(X, dtype=float)
        nd = len(self.design_names)
        canonical = self.cfg.mech.canonical_vectors(self.design_names, X[:, :nd])
        return np.column_stack([canonical, X[:, nd:]]) if X.shape[1] > nd else canonical
