"""The metric catalogue: every metric a config can optimise or constrain and every metric column of the results.

One place lists metric names. Config validation, the problem's columns, the report, the results validator,
``docs/metrics.md`` and ``scalesynth metrics [MECH] [--json]`` all read :func:`catalogue`.

Families:

* ``workspace``: a statistic of a per-voxel field over the reachable workspace (the grid over the mechanism's
  bounding box): its measure, count, dexterity bands, and mean / std / min / max of every field the mechanism's
  field kernel writes (``Mechanism.fields``; LCI's are named gci, fci, min_lci, max_lci);
* ``task``: the same statistics over the reachable part of the config's task box, plus its coverage;
* ``path``: along the config's task path;
* ``design``: from the design parameters alone (``Mechanism.design_metrics``: link_length_sum, footprint_radius,
  strokes);
* ``cycle``: along the config's pick-and-place cycle (``scalesynth.cycle``; needs a ``cycle`` section).

Per-voxel field statistics are generated from each mechanism's ``fields``: adding a field to a mechanism (its
field kernel and its ``fields`` entry) adds ``mean_<f>``, ``std_<f>``, ``min_<f>``, ``max_<f>`` and their
``task_`` twins here without editing this module. Other families are entries with a ``compute(ctx)`` function.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from scalesynth.mechanisms.base import Field, Mechanism, option_set
from scalesynth.names import hint
from scalesynth.paths import sample_path

FAMILIES = ("workspace", "task", "path", "design", "cycle")
STATISTICS = ("mean", "std", "min", "max")
# worst-value keywords (see Metric.worst)
WORST_BOUNDING_BOX = "bounding_box"  # measure of the bounding box of the largest design within the bounds
WORST_BOUNDS_CORNERS = "bounds_corners"  # largest value over the corners of the optimisation bounds

# what `scalesynth design` compares and its datasheet shows (scalesynth.design): requirement -> (metric, sense of
# the bound, label); the columns of a comparison, metric -> (label, is a length); the datasheet's dexterity rows
DESIGN_REQUIREMENTS = {
    "envelope": ("task_coverage", "min", "reaches the whole working zone"),
    "cycle": ("cycle_feasible", "min", "follows the cycle without singularity"),
    "rate": ("picks_per_minute", "min", "picks per minute"),
    "deflection": ("task_max_deflection", "max", "deflection under the spec's force"),
}
DESIGN_COLUMNS = {"link_length_sum": ("link length sum", True), "footprint_radius": ("footprint radius", True),
                  "task_gci": ("task GCI", False), "task_min_lci": ("task min LCI", False),
                  "task_max_deflection": ("max deflection", True), "picks_per_minute": ("picks/min", False),
                  "cycle_time_s": ("cycle time s", False),
                  "motor_peak_torque_ratio": ("peak torque / motor peak", False),
                  "motor_rms_torque_ratio": ("RMS torque / motor rated", False),
                  "motor_speed_ratio": ("speed / motor max", False)}
DATASHEET_DEXTERITY = (("task_gci", "task GCI (mean LCI over the zone)"),
                       ("task_min_lci", "smallest LCI over the zone"), ("gci", "workspace GCI"))

# the LCI statistics keep the names the dexterity literature uses
_LCI_NAMES = {"mean": "gci", "std": "fci", "min": "min_lci", "max": "max_lci"}
_STAT_WORDS = {"mean": "mean", "std": "standard deviation", "min": "minimum", "max": "maximum"}


@dataclass
class EvalContext:
    """What a ``compute`` function of a non-voxel metric gets: n resolved designs under one config."""

    mech: Mechanism
    designs: list[dict[str, float]]
    options: dict[str, Any]
    packed: np.ndarray  # (n, k) Mechanism.pack of every design
    task: Any  # config TaskConfig or None
    resolution: int
    band_edges: Sequence[float]
    length_unit: str
    cycle: Any = None  # config CycleConfig or None
    cache: dict[str, Any] = field(default_factory=dict)  # shared between compute functions (e.g. path samples)


@dataclass(frozen=True)
class Metric:
    """One catalogue entry (per mechanism and length unit).

    ``column``: result column (units in the name; band metrics contain ``{band}``). ``field``/``statistic``: the
    per-voxel field and the statistic over it (workspace, task, path families). ``range``: values it can take.
    ``better``: the sense an engineer usually prefers. ``worst``: worst value of a *minimised* objective (the
    hypervolume reference): a number, WORST_BOUNDING_BOX, WORST_BOUNDS_CORNERS, or None when unbounded (it can
    then be maximised or constrained, not minimised); a maximised objective's worst value is ``range[0]``.
    ``needs``: 'task', 'path', 'band' or 'options.<name>'. ``compute(ctx) -> (n,) array`` for metrics that are
    not statistics of the voxel grids. ``empty``: the value reported where the statistic's set (the reachable
    workspace or task cells) is empty; None (every statistic but the GCI) = NaN, null in JSON and empty in CSV,
    and the worst value where it is an objective or constraint (``problem.py``).
    """

    name: str
    column: str
    family: str
    field: str | None
    statistic: str | None
    unit: str
    range: tuple[float, float]
    better: str | None
    worst: float | str | None
    needs: tuple[str, ...]
    description: str
    compute: Callable[[EvalContext], np.ndarray] | None = field(default=None, compare=False, repr=False)
    empty: float | None = None

    def columns(self, n_bands: int) -> list[str]:
        """Every result column of the metric (one per band for band metrics)."""
        if "band" in self.needs:
            return [self.column.format(band=b) for b in range(n_bands)]
        return [self.column]

    def column_for(self, band: int | None = None) -> str:
        return self.column.format(band=band) if "band" in self.needs else self.column

    def to_dict(self) -> dict[str, Any]:
        def num(v):
            return None if v is None else (v if isinstance(v, str) else (None if math.isinf(v) else float(v)))

        return {
            "name": self.name,
            "column": self.column,
            "family": self.family,
            "field": self.field,
            "statistic": self.statistic,
            "unit": self.unit,
            "range": [num(self.range[0]), num(self.range[1])],  # null = unbounded
            "better": self.better,
            "worst": num(self.worst),
            "needs": list(self.needs),
            "description": self.description,
        }


def unit_text(unit: str, length_unit: str) -> str:
    return unit.replace("{length}", length_unit)


def unit_slug(unit: str) -> str:
    """Unit as a column-name suffix: 'mm/rad' -> 'mm_per_rad'; '' for dimensionless ('1')."""
    if unit in ("1", ""):
        return ""
    return unit.replace("/", "_per_").replace("^", "").replace(" ", "_")


def _with_unit(base: str, unit: str) -> str:
    slug = unit_slug(unit)
    return f"{base}_{slug}" if slug else base


def _std_range(f: Field) -> tuple[float, float]:
    lo, hi = f.range
    return (0.0, 0.5 * (hi - lo)) if math.isfinite(hi) and math.isfinite(lo) else (0.0, math.inf)


def _field_entries(mech: Mechanism, f: Field, length_unit: str, family: str) -> list[Metric]:
    """mean/std/min/max of one field over the workspace or the task box."""
    unit = unit_text(f.unit, length_unit)
    region = "the reachable workspace" if family == "workspace" else "the reachable part of the task box"
    needs = (("task",) if family == "task" else ()) + tuple(f"options.{o}" for o in f.needs_options)
    out = []
    for stat in STATISTICS:
        if f.name == "lci":
            name = _LCI_NAMES[stat]
            column = name
        else:
            name = f"{stat}_{f.name}"
            column = _with_unit(name, unit)
        if family == "task":
            name, column = f"task_{name}", f"task_{column}"
        rng = _std_range(f) if stat == "std" else f.range
        gci = f.name == "lci" and stat == "mean"
        better = ("min" if stat == "std" else f.better)
        out.append(Metric(
            name=name, column=column, family=family, field=f.name, statistic=stat, unit=unit, range=rng,
            better=better, worst=rng[1] if math.isfinite(rng[1]) else None, needs=needs,
            description=f"{_STAT_WORDS[stat]} of {f.name} over {region}" + (f" ({unit})" if unit != "1" else "")
            + ("; 0 if that is empty" if gci else "; null if that is empty"),
            # the GCI of an empty set is 0 by convention (volume 0, GCI 0); any other statistic over nothing is null
            empty=0.0 if gci else None,
        ))
    return out


def _design_entry(mech: Mechanism, dm, length_unit: str) -> Metric:
    unit = unit_text(dm.unit, length_unit)
    value = dm.value

    def compute(ctx: EvalContext, value=value) -> np.ndarray:
        return np.array([float(value(d, ctx.options)) for d in ctx.designs], dtype=float)

    return Metric(
        name=dm.name, column=_with_unit(dm.name, unit), family="design", field=None, statistic=None, unit=unit,
        range=dm.range, better=dm.better, worst=WORST_BOUNDS_CORNERS, needs=(),
        description=f"{dm.description} ({unit})", compute=compute,
    )


def _path_fields(ctx: EvalContext) -> np.ndarray:
    """Fields of every design at the path samples, (n, samples, n_fields), computed once per context."""
    if "path_fields" not in ctx.cache:
        from scalesynth.kernels import grid as _grid

        pts = sample_path(ctx.task.path, ctx.task.path_samples)
        ctx.cache["path_fields"] = _grid.population_points_fields(
            ctx.mech.field_kernel, ctx.mech.n_fields, ctx.packed, pts
        )
    return ctx.cache["path_fields"]


def _path_reachable(ctx: EvalContext) -> np.ndarray:
    return (_path_fields(ctx)[:, :, 0] >= 0).mean(axis=1)


def _path_min_lci(ctx: EvalContext) -> np.ndarray:
    lci = _path_fields(ctx)[:, :, 0]
    reach = lci >= 0
    return np.where(reach.all(axis=1), lci.min(axis=1), 0.0)


def _path_mean_lci(ctx: EvalContext) -> np.ndarray:
    lci = _path_fields(ctx)[:, :, 0]
    return np.where(lci >= 0, lci, 0.0).mean(axis=1)


def _cycle_values(ctx: EvalContext) -> dict[str, np.ndarray]:
    """Every cycle metric of every design (scalesynth.cycle.analysis.metrics, batched over the population by
    scalesynth.cycle.population), computed once per context."""
    if "cycle" not in ctx.cache:
        from scalesynth.cycle.population import population_metrics

        ctx.cache["cycle"] = population_metrics(ctx.mech, ctx.designs, ctx.options, ctx.cycle, ctx.length_unit)
    return ctx.cache["cycle"]


def _cycle_entries(mech: Mechanism, length_unit: str) -> list[Metric]:
    from scalesynth.cycle.analysis import CYCLE_PENALTY, deflection_field, has_deflection

    def entry(name, unit, rng, better, worst, needs, description, plain=False):
        def compute(ctx: EvalContext, name=name) -> np.ndarray:
            return _cycle_values(ctx)[name]

        column = name if plain else _with_unit(name, unit)
        return Metric(name, column, "cycle", None, None, unit, rng, better, worst, needs, description,
                      compute=compute)

    from scalesynth.cycle.config import ACTUATOR_KINDS, peak_names

    lu = length_unit
    failed = f"; {CYCLE_PENALTY:g} if the cycle cannot be followed"
    # one unit per metric: a mechanism with revolute and prismatic actuators gets each peak per kind
    units = {"angle": ("rad/s", "rad/s^2", "N m"), "length": (f"{lu}/s", f"{lu}/s^2", "N")}
    words = {"speed": ("|qd_i|", 0, ""), "accel": ("|qdd_i|", 1, ""),
             "force": ("actuator force or torque", 2, " for the payload, quasi-static plus payload inertia")}
    peaks = []
    for name, kinds in peak_names(mech.joint_units).items():
        what, slot, how = words[name.split("_")[3]]
        unit = units[kinds[0]][slot]
        over = "the actuators" if len(set(mech.joint_units)) == 1 else f"the {ACTUATOR_KINDS[kinds[0]]} actuators"
        peaks.append(entry(name, unit, (0.0, math.inf), "min", CYCLE_PENALTY, ("cycle",),
                           f"largest {what} over the cycle and {over}{how} ({unit}){failed}"))
    return [
        entry("cycle_feasible", "1", (0.0, 1.0), "max", 1.0, ("cycle",),
              "1 if the cycle stays in the workspace without branch jump or singularity, with clearance >= 0 and "
              "within the cycle's speed and force limits, else 0"),
        *peaks,
        entry("cycle_min_lci", "1", (0.0, 1.0), "max", 1.0, ("cycle",),
              "smallest LCI along the cycle (0 if it cannot be followed)"),
        entry("cycle_min_clearance", lu, (-CYCLE_PENALTY, math.inf), "max", None,
              ("cycle",), f"smallest distance between non-adjacent link capsules along the cycle ({lu}; < 0: "
              f"interference; -{CYCLE_PENALTY:g} if the cycle cannot be followed)"),
        *([entry("cycle_max_deflection", lu, (0.0, CYCLE_PENALTY), "min", CYCLE_PENALTY,
                 ("cycle", *(f"options.{o}" for o in deflection_field(mech).needs_options)),
                 f"largest deflection of the payload point along the cycle under the payload's weight and inertia "
                 f"m (g - a) ({lu}; stiffness model with ideal joints, docs/cycles.md){failed}")]
          if has_deflection(mech) else []),
        entry("max_cycles_per_minute", "1/min", (0.0, math.inf), "max", None, ("cycle", "cycle.limits"),
              "highest cycle rate within the actuator speed and force limits of the cycle section (cycles per "
              "minute; 0 if gravity alone exceeds a force limit or the cycle cannot be followed)", plain=True),
        entry("picks_per_minute", "1/min", (0.0, math.inf), "max", None, ("cycle", "cycle.motors"),
              "picks per minute within every motor limit (peak and rated torque, speed; links, payload, rotor "
              "inertia and gravity): 60 / cycle_time_s; 0 if the motors cannot hold the payload or the cycle "
              "cannot be followed", plain=True),
        entry("cycle_time_s", "s", (0.0, CYCLE_PENALTY), "min", CYCLE_PENALTY, ("cycle", "cycle.motors"),
              f"shortest period of the cycle's motion law within every motor limit plus 2 cycle.dwell_s (s){failed} "
              "or the motors cannot hold the payload", plain=True),
        *(entry(f"motor_{what}_ratio", "1", (0.0, math.inf), "min", CYCLE_PENALTY, ("cycle", "cycle.motors"),
                f"largest {desc} over the actuators at the configured rate (1 = at the limit){failed}", plain=True)
          for what, desc in (("peak_torque", "peak motor torque / peak_torque"),
                             ("rms_torque", "RMS motor torque (motion and dwell) / rated_torque"),
                             ("speed", "peak motor speed / max_speed"))),
    ]


# (name, unit) -> (the mechanism, its catalogue): two users' descriptions may share a name, so the entry is checked
# to be this very mechanism's
_CACHE: dict[tuple[str, str], tuple[Mechanism, dict[str, Metric]]] = {}


def catalogue(mech: Mechanism, length_unit: str | None = None) -> dict[str, Metric]:
    """Every metric of ``mech`` with columns in ``length_unit`` (default the mechanism's), in result-column order."""
    unit = mech.length_unit(length_unit, "length_unit")
    key = (mech.name, unit)
    if key in _CACHE and _CACHE[key][0] is mech:
        return _CACHE[key][1]
    mkey = mech.measure_key(unit)
    munit = mech.measure_unit(unit)
    mname = mech.measure_name()
    lci = next(f for f in mech.fields if f.name == "lci")
    entries: list[Metric] = [
        Metric("volume", mkey, "workspace", None, "measure", munit, (0.0, math.inf), "max", WORST_BOUNDING_BOX, (),
               f"workspace {mname}: reachable cells x cell {mname} ({munit})"),
    ]
    entries += _field_entries(mech, lci, unit, "workspace")
    entries += [
        Metric("voxels", "voxels", "workspace", None, "count", "1", (0.0, math.inf), "max", None, (),
               "number of reachable grid cells"),
        Metric("band_share", "band{band}_share", "workspace", "lci", "band_share", "1", (0.0, 1.0), "max", 1.0,
               ("band",), "share of the reachable workspace whose LCI lies in dexterity band k; null if that is "
               "empty"),
        Metric("band_volume", f"band{{band}}_{mkey}", "workspace", "lci", "band_measure", munit, (0.0, math.inf),
               "max", WORST_BOUNDING_BOX, ("band",), f"workspace {mname} whose LCI lies in dexterity band k ({munit})"),
    ]
    for f in mech.fields:
        if f.name != "lci":
            entries += _field_entries(mech, f, unit, "workspace")
    entries += [
        Metric("error_volume", "error_volume", "workspace", None, "estimate", "1", (0.0, math.inf), "min", None,
               ("grid.tolerance",), f"the tolerance form's estimate of the relative error of the workspace "
               f"{mname} (adaptive evaluator: change from its previous refinement level; calibrated uniform grid: "
               "change to the grid twice as fine)"),
        Metric("error_gci", "error_gci", "workspace", None, "estimate", "1", (0.0, math.inf), "min", None,
               ("grid.tolerance",), "the tolerance form's estimate of the absolute error of the GCI (adaptive "
               "evaluator: change from its previous refinement level; calibrated uniform grid: change to the grid "
               "twice as fine)"),
    ]
    entries.append(Metric("task_coverage", "task_coverage", "task", None, "coverage", "1", (0.0, 1.0), "max", 1.0,
                          ("task",), "share of the task box's cells reachable within all limits"))
    for f in mech.fields:
        entries += _field_entries(mech, f, unit, "task")
    entries += [
        Metric("path_reachable", "path_reachable", "path", "lci", "reachable", "1", (0.0, 1.0), "max", 1.0,
               ("task", "path"), "share of the task path's samples inside the workspace", compute=_path_reachable),
        Metric("path_min_lci", "path_min_lci", "path", "lci", "min", "1", (0.0, 1.0), "max", 1.0, ("task", "path"),
               "minimum LCI along the task path (0 if the path leaves the workspace)", compute=_path_min_lci),
        Metric("path_mean_lci", "path_mean_lci", "path", "lci", "mean", "1", (0.0, 1.0), "max", 1.0,
               ("task", "path"), "mean LCI along the task path, samples outside the workspace counted as 0",
               compute=_path_mean_lci),
    ]
    entries += [_design_entry(mech, dm, unit) for dm in mech.design_metrics]
    entries += _cycle_entries(mech, unit)
    out = {}
    for m in entries:
        if m.name in out:
            raise ValueError(f"metric {m.name!r} defined twice for {mech.name}")
        out[m.name] = m
    _CACHE[key] = (mech, out)
    return out


NULLABLE_STATISTICS = (*STATISTICS, "band_share")


def nullable_columns(mech: Mechanism, length_unit: str, n_bands: int) -> set[str]:
    """Result columns that are null (NaN, an empty CSV cell) for a design whose set is empty: the statistics over
    the reachable workspace or task cells without an ``empty`` value."""
    return {c for m in catalogue(mech, length_unit).values()
            if m.family in ("workspace", "task") and m.statistic in NULLABLE_STATISTICS and m.empty is None
            for c in m.columns(n_bands)}


def field_of(m: Metric) -> str | None:
    """What a workspace or task metric needs from the evaluator: its per-voxel field, the LCI for the measure, count
    and coverage (reachability is the LCI's sign), "estimate" for the error estimates (evaluate_population's
    ``fields``); None for the computed families."""
    if m.family not in ("workspace", "task"):
        return None
    if m.statistic == "estimate":
        return "estimate"
    return m.field or "lci"


def applicable(m: Metric, has_task: bool, has_path: bool, options: Mapping[str, Any] | None = None,
               cycle: Any = None, adaptive: bool = False) -> str | None:
    """Why ``m`` cannot be evaluated under a config (a phrase), or None if it can. ``cycle``: the config's
    CycleConfig or None; ``adaptive``: whether the workspace goes through the adaptive evaluator (grid.tolerance
    without a resolution)."""
    for need in m.needs:
        if need == "grid.tolerance" and not adaptive:
            return "needs grid.tolerance without grid.resolution (the tolerance form's estimate)"
        if need == "cycle" and cycle is None:
            return "needs a cycle section"
        if need == "cycle.limits" and cycle is not None and cycle.speed_limits is None and cycle.force_limits is None:
            return "needs cycle.speed_limits or cycle.force_limits"
        if need == "cycle.motors" and cycle is not None and getattr(cycle, "_motors", None) is None:
            return "needs a motors section"
        if need == "task" and not has_task:
            return "needs a task section"
        if need == "path" and not has_path:
            return "needs task.path"
        if need.startswith("options.") and options is not None and not option_set(options, need[8:]):
            return f"needs {need} ({'false' if options.get(need[8:]) is False else 'null'})"
    return None


def result_metrics(mech: Mechanism, length_unit: str, has_task: bool, has_path: bool,
                   options: Mapping[str, Any] | None = None, cycle: Any = None,
                   adaptive: bool = False) -> list[Metric]:
    """The metrics evaluated for a config (catalogue order)."""
    return [m for m in catalogue(mech, length_unit).values()
            if applicable(m, has_task, has_path, options, cycle, adaptive) is None]


def result_columns(mech: Mechanism, length_unit: str, n_bands: int, has_task: bool, has_path: bool,
                   options: Mapping[str, Any] | None = None, cycle: Any = None,
                   adaptive: bool = False) -> list[str]:
    """Every metric column of a config's results, in a fixed order."""
    return [c for m in result_metrics(mech, length_unit, has_task, has_path, options, cycle, adaptive)
            for c in m.columns(n_bands)]


def all_field_names() -> set[str]:
    from scalesynth.mechanisms import available, get

    return {f.name for name in available() for f in get(name).fields}


def resolve(mech: Mechanism, length_unit: str, name: str, band: int | None, n_bands: int, has_task: bool,
            has_path: bool, options: Mapping[str, Any] | None = None, cycle: Any = None,
            adaptive: bool = False) -> Metric:
    """The catalogue entry of a config's objective/constraint. Raises ValueError with a message that starts with
    the sub-field it is about ('metric: ...' or 'band: ...') and lists the valid choices."""
    cat = catalogue(mech, length_unit)
    if name not in cat:
        for prefix in ("task_", ""):
            for stat in STATISTICS:
                head = f"{prefix}{stat}_"
                fname = name[len(head):]
                if name.startswith(head) and fname in all_field_names():
                    raise ValueError(f"metric: {name}: field {fname!r} is not provided by {mech.name} "
                                     + hint(fname, mech.field_names, "fields"))
        split = [n for n in cat if n.startswith(f"{name}_") and n.split("_")[-1] in ("revolute", "prismatic")]
        if split:  # an actuator peak of a mechanism with both kinds: one unit per metric, so one per kind
            raise ValueError(f"metric: {name} mixes units on {mech.name} (revolute and prismatic actuators); "
                             f"did you mean {' or '.join(split)}?")
        usable = [m.name for m in cat.values() if applicable(m, has_task, has_path, options, cycle, adaptive) is None]
        raise ValueError(f"metric: unknown metric {name!r} for {mech.name} "
                         + hint(name, usable, "valid", more=f"see `scalesynth metrics {mech.name}`"))
    m = cat[name]
    why = applicable(m, has_task, has_path, options, cycle, adaptive)
    if why is not None:
        raise ValueError(f"metric: {name} {why}")
    if "band" in m.needs:
        if band is None:
            raise ValueError(f"band: required for metric {name} (0..{n_bands - 1})")
        if not 0 <= band < n_bands:
            raise ValueError(f"band: {band} out of range (valid: 0..{n_bands - 1})")
    elif band is not None:
        raise ValueError(f"band: metric {name} has no bands (only band_share, band_volume)")
    return m


# ----- listings ----------------------------------------------------------------------------------------------
def listing(mech_name: str | None = None) -> list[dict[str, Any]]:
    """Catalogue entries as dicts: of one mechanism (its default length unit), or of every mechanism with a
    ``mechanisms`` list per entry (columns and units then shown for each mechanism's default unit)."""
    from scalesynth.mechanisms import available, get

    if mech_name is not None:
        mech = get(mech_name)
        return [dict(m.to_dict(), mechanisms=[mech.name]) for m in catalogue(mech).values()]
    merged: dict[str, dict[str, Any]] = {}
    for name in available():
        for m in catalogue(get(name)).values():
            entry = merged.setdefault(m.name, dict(m.to_dict(), mechanisms=[], columns={}, units={}))
            entry["mechanisms"].append(name)
            entry["columns"][name] = m.column
            entry["units"][name] = m.unit
    return list(merged.values())


def to_json(mech_name: str | None = None) -> str:
    return json.dumps(listing(mech_name), indent=None)


def markdown() -> str:
    """docs/metrics.md (generated: ``python -m scalesynth.metrics > docs/metrics.md``; a test checks it)."""
    from scalesynth.mechanisms import available, get

    lines = [
        "# Metrics",
        "",
        "<!-- generated from src/scalesynth/metrics.py by `python -m scalesynth.metrics > docs/metrics.md`; "
        "do not edit -->",
        "",
        "Every metric below can be an objective (`objectives: [{metric: NAME, sense: max|min}]`) or a constraint",
        "(`constraints: [{metric: NAME, min: .., max: ..}]`), and appears in `pareto.csv` / `population.csv` under",
        "its column name (units in the name; `{band}` is the band index k, chosen with `band: k`). Families:",
        "`workspace` (statistic of a per-voxel field over the reachable workspace), `task` (over the reachable part",
        "of `task.box`; needs a task), `path` (along `task.path`), `design` (from the design parameters), `cycle`",
        "(along the config's `cycle`, docs/cycles.md). A",
        "minimised objective needs a finite worst value for the hypervolume reference: `bounding_box` is the",
        "bounding-box measure of the largest design in the bounds, `bounds_corners` the largest value over the",
        "corners of the bounds; metrics without one can be maximised or constrained.",
        "",
        "A statistic over an empty set (the reachable workspace or task cells) is null: `null` in JSON, an empty",
        "CSV cell; as an objective it takes its worst value and it violates every constraint on it (the GCI of an",
        "empty set is 0, and counts as worst where it is minimised or bounded above). No metric mixes units: a",
        "mechanism with revolute and prismatic actuators has its actuator peaks per kind (`_revolute`,",
        "`_prismatic`). Lengths are in the mechanism's own unit (`units.length` must name it).",
        "",
        "`scalesynth metrics [MECH] [--json]` prints the same catalogue.",
        "",
    ]
    for name in available():
        mech = get(name)
        lines += [f"## `{name}` (lengths in {mech.default_length_unit})", ""]
        lines.append("Per-voxel fields: " + "; ".join(
            f"`{f.name}` ({unit_text(f.unit, mech.default_length_unit)}): {f.description}" for f in mech.fields) + ".")
        lines += ["", "| metric | column | family | unit | range | better | worst if minimised | needs | description |",
                  "|---|---|---|---|---|---|---|---|---|"]
        for m in catalogue(mech).values():
            d = m.to_dict()
            rng = "[" + ", ".join("inf" if v is None else f"{v:g}" for v in d["range"]) + "]"
            worst = "-" if d["worst"] is None else (d["worst"] if isinstance(d["worst"], str) else f"{d['worst']:g}")
            lines.append(f"| `{m.name}` | `{m.column}` | {m.family} | {m.unit} | {rng} | {m.better or '-'} | "
                         f"{worst} | {', '.join(m.needs) or '-'} | {m.description} |")
        lines.append("")
    return "\n".join(lines)


if __name__ == "__main__":
    import sys

    sys.stdout.write(markdown())
