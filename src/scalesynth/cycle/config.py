"""The ``cycle:`` config section (pydantic) and its checks against the mechanism.

```yaml
cycle:
  path: [[x, y], ...]        # closed polyline in task axes (joined back to the first point; angles in rad), or:
  preset: adept              # 25 mm up, 305 mm across, 25 mm down and back (mechanisms with 2 Cartesian axes)
                             # or abb-cycle-1: the same path (ABB's "Cycle 1", 25-305-25 mm), 90 deg of tool
                             # rotation over the across move where the task axes have a rotation, dwell_s 0.035
  start: [x, y]              # adept: start point (task coordinates, the config's length unit)
  direction: [1, 0]          # adept: the 'across' direction (task axes; default: the first Cartesian axis
                             #        that is not vertical); it must be perpendicular to gravity
  law: poly345               # or modified_trapezoid, constant, or one law per segment
  cycles_per_minute: 60      # or period: 1.0 (s); exactly one of the two
  payload: 1.0               # kg, > 0
  gravity: null              # m/s^2 per task axis (angular task axes: per x, y, z of the mechanism frame);
                             # null = 9.81 down the last Cartesian task axis (angular task axes: down -z)
  samples: 400               # time intervals over one cycle
  speed_limits: null         # per actuator (or one number): |qd| limit, length unit/s or rad/s
  force_limits: null         # per actuator (or one number): |force| limit, N or N m
```
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, PrivateAttr, field_validator, model_validator

from scalesynth.cycle.trajectory import LAWS
from scalesynth.names import hint

PRESETS = ("adept", "abb-cycle-1")
G0 = 9.80665  # standard gravity, m/s^2
# adept cycle (mm): 25 up, 305 across, 25 down, then back the same way
ADEPT_UP_MM = 25.0
ADEPT_ACROSS_MM = 305.0
# ABB IRB 360 "Cycle 1": the adept path with 90 degrees of tool rotation and 35 ms of vacuum at pick and at place
ABB_ROTATION_RAD = 0.5 * math.pi
ABB_DWELL_S = 0.035
METRES_PER_UNIT = {"m": 1.0, "dm": 0.1, "cm": 0.01, "mm": 0.001}


def _within_magnitude(*values: float) -> None:
    """ValueError for a value beyond +-MAX_MAGNITUDE or subnormal (as every other number of a config)."""
    from scalesynth.mechanisms.base import MAX_MAGNITUDE, SUBNORMAL, is_subnormal

    for i, v in enumerate(values):
        where = f"{i}: " if len(values) > 1 else ""
        if abs(v) > MAX_MAGNITUDE:
            raise ValueError(f"{where}{v:g} is beyond +-{MAX_MAGNITUDE:g}, the largest magnitude scalesynth computes "
                             "with (products of such values overflow)")
        if is_subnormal(v):
            raise ValueError(f"{where}{v:g} is {SUBNORMAL}")


class CycleConfig(BaseModel):
    model_config = ConfigDict(extra="forbid")

    path: list[list[float]] | None = Field(None, description="closed polyline in task axes")
    preset: str | None = Field(None, description="'adept'")
    start: list[float] | None = Field(None, description="adept start point (task coordinates)")
    direction: list[float] | None = Field(None, description="adept 'across' direction (task axes)")
    law: str | list[str] = Field("poly345", description="motion law, or one per segment")
    cycles_per_minute: float | None = None
    period: float | None = Field(None, description="cycle time, s")
    payload: float = Field(1.0, description="payload mass, kg")
    gravity: list[float] | None = Field(None, description="m/s^2 per task axis; null = down the vertical axis")
    samples: int = Field(400, ge=8, le=100_000, description="time intervals over one cycle")
    speed_limits: float | list[float] | None = None
    force_limits: float | list[float] | None = None
    dwell_s: float = Field(0.0, ge=0.0, le=3600.0, description="s at rest at pick and at place (motors' cycle time)")
    # the run config's dynamics and motors sections (RunConfig attaches them; None: tube links, no motors)
    _dynamics: Any = PrivateAttr(None)
    _motors: Any = PrivateAttr(None)
    _base_dir: Any = PrivateAttr(None)  # where a relative motors.catalogue is read from
    # (n_designs,) the gear ratio of each design of a population (a search over bounds.gear_ratio), else None:
    # replaces motors.gear_ratio in cycle.population (set by problem.SynthesisProblem on a copy of the cycle)
    _gear_ratios: Any = PrivateAttr(None)

    @field_validator("path")
    @classmethod
    def _path_ok(cls, v):
        from scalesynth.paths import check_polyline

        return None if v is None else check_polyline(v, closed=True)

    @field_validator("preset")
    @classmethod
    def _preset_ok(cls, v):
        if v is not None and v not in PRESETS:
            raise ValueError(f"unknown preset {v!r} " + hint(str(v), PRESETS))
        return v

    @field_validator("law")
    @classmethod
    def _law_ok(cls, v):
        for law in [v] if isinstance(v, str) else v:
            if law not in LAWS:
                raise ValueError(f"unknown motion law {law!r} " + hint(str(law), LAWS))
        if not isinstance(v, str) and "constant" in v and len(set(v)) > 1:
            raise ValueError("'constant' applies to the whole loop, not to single segments")
        return v

    @field_validator("cycles_per_minute", "period", "payload")
    @classmethod
    def _positive(cls, v):
        if v is not None and not (math.isfinite(v) and v > 0):
            raise ValueError(f"must be a finite number > 0, got {v}")
        if v is not None:
            _within_magnitude(v)
        return v

    @field_validator("start", "direction", "gravity")
    @classmethod
    def _finite(cls, v):
        if v is not None and not all(math.isfinite(c) for c in v):
            raise ValueError("must be finite")
        if v is not None:
            _within_magnitude(*v)
        return v

    @field_validator("speed_limits", "force_limits")
    @classmethod
    def _limits(cls, v):
        for x in [] if v is None else [v] if isinstance(v, (int, float)) else v:
            if not (math.isfinite(x) and x > 0):
                raise ValueError(f"limits must be finite numbers > 0, got {x}")
            _within_magnitude(x)
        return v

    @model_validator(mode="after")
    def _one_of(self):
        if (self.path is None) == (self.preset is None):
            raise ValueError("give either path or preset")
        if self.preset is not None and self.start is None:
            raise ValueError(f"start: required by preset {self.preset!r}")
        if self.path is not None and (self.start is not None or self.direction is not None):
            raise ValueError("start/direction: only with a preset")
        if (self.cycles_per_minute is None) == (self.period is None):
            raise ValueError("give either cycles_per_minute or period")
        if self.preset == "abb-cycle-1" and "dwell_s" not in self.model_fields_set:
            self.dwell_s = ABB_DWELL_S  # the vacuum time of ABB's cycle, unless the config sets its own
        return self

    # ----- derived values ---------------------------------------------------------------------------------
    @property
    def cycle_time(self) -> float:
        """Period in s."""
        return float(self.period if self.period is not None else 60.0 / self.cycles_per_minute)


def _cartesian(mech) -> list[int]:
    return [a for a, u in enumerate(mech.task_units) if u == "length"]


def cartesian_task(mech) -> bool:
    """Whether every task axis is a length (the payload then sits at the task point)."""
    return all(u == "length" for u in mech.task_units)


def payload_axes(mech) -> tuple[str, ...]:
    """Axes of the payload's position and of ``gravity``: the task axes when they are all Cartesian, else the
    mechanism frame's x, y, z (the payload sits at ``mech.payload_point``, z up)."""
    return tuple(mech.task_axes) if cartesian_task(mech) else ("x", "y", "z")


def gravity_vector(cyc: CycleConfig, mech) -> np.ndarray:
    """Gravity (m/s^2) per payload axis (``payload_axes``); default -9.80665 along the last Cartesian task axis,
    or along -z of the mechanism frame when a task axis is an angle."""
    if cyc.gravity is not None:
        return np.asarray(cyc.gravity, dtype=float)
    if not cartesian_task(mech):
        return np.array([0.0, 0.0, -G0])
    g = np.zeros(len(mech.task_axes))
    g[_cartesian(mech)[-1]] = -G0
    return g


def vertices(cyc: CycleConfig, mech, length_unit: str) -> np.ndarray:
    """The polyline's points (m, k) in task units: the path as given, or the adept cycle's six vertices
    S, S + u h, S + u h + d w, S + d w, S + u h + d w, S + u h (the loop closes back to S), with h = 25 mm and
    w = 305 mm in the length unit, u = up (against gravity), d = the across direction. abb-cycle-1: the same, and
    where the task axes include an angle (a tool rotation) the first one turns by +90 degrees over the across
    move (vertices 2 to 4 at S's angle + pi/2) and back over the return."""
    if cyc.path is not None:
        return np.asarray(cyc.path, dtype=float)
    scale = 0.001 / METRES_PER_UNIT[length_unit]
    up, across = adept_axes(cyc, mech)
    s = np.asarray(cyc.start, dtype=float)
    h, w = ADEPT_UP_MM * scale * up, ADEPT_ACROSS_MM * scale * across
    out = np.array([s, s + h, s + h + w, s + w, s + h + w, s + h])
    angles = [a for a, u in enumerate(mech.task_units) if u == "angle"]
    if cyc.preset == "abb-cycle-1" and angles:
        out[2:5, angles[0]] += ABB_ROTATION_RAD
    return out


def adept_axes(cyc: CycleConfig, mech) -> tuple[np.ndarray, np.ndarray]:
    """Unit 'up' and 'across' vectors in task axes for the adept preset (checked by ``check``)."""
    k = len(mech.task_axes)
    g = gravity_vector(cyc, mech)
    up = -g / np.linalg.norm(g)
    if cyc.direction is not None:
        d = np.asarray(cyc.direction, dtype=float)
    else:
        d = np.zeros(k)
        d[next(a for a in _cartesian(mech) if abs(up[a]) < 0.5)] = 1.0
    return up, d / np.linalg.norm(d)


def check(cyc: CycleConfig, mech) -> None:
    """Checks that need the mechanism; raise ValueError('cycle.<field>: ...') naming the field."""
    from scalesynth.mechanisms.base import Mechanism

    k = len(mech.task_axes)
    axes = ", ".join(mech.task_axes)
    if cyc.preset is not None and (len(_cartesian(mech)) < 2 or not cartesian_task(mech)):
        raise ValueError(
            f"cycle.preset: {cyc.preset} needs two Cartesian task axes; {mech.name} has {axes} "
            f"({', '.join(mech.task_units)})"
        )
    needed = ("link_geometry", "velocity_map") + (() if cartesian_task(mech) else ("payload_point",))
    for method in needed:
        if getattr(type(mech), method) is getattr(Mechanism, method):
            raise ValueError(f"cycle: {mech.name} has no {method.replace('_', ' ')} yet (cycles need it)")
    if cyc.path is not None and len(cyc.path[0]) != k:
        raise ValueError(f"cycle.path: points need {k} coordinates ({axes}) for {mech.name}")
    g_axes = payload_axes(mech)
    if cyc.gravity is not None and len(cyc.gravity) != len(g_axes):
        frame = "" if cartesian_task(mech) else " of the mechanism frame (the task axes include an angle)"
        raise ValueError(f"cycle.gravity: need {len(g_axes)} components ({', '.join(g_axes)}){frame}")
    n = len(mech.joints)
    for name in ("speed_limits", "force_limits"):
        v = getattr(cyc, name)
        if isinstance(v, list) and len(v) != n:
            raise ValueError(f"cycle.{name}: need one number or {n} (one per actuator: {', '.join(mech.joints)})")
    if not isinstance(cyc.law, str):
        n_seg = len(vertices_count(cyc))
        if len(cyc.law) != n_seg:
            raise ValueError(f"cycle.law: need one law or {n_seg} (one per segment of the closed path)")
    if cyc.preset is None:
        return
    cart = _cartesian(mech)
    if len(cyc.start) != k:
        raise ValueError(f"cycle.start: need {k} coordinates ({axes})")
    if cyc.direction is not None and len(cyc.direction) != k:
        raise ValueError(f"cycle.direction: need {k} components ({axes})")
    g = gravity_vector(cyc, mech)
    if not np.any(g[cart]) or np.any(g[[a for a in range(k) if a not in cart]]):
        raise ValueError("cycle.gravity: the adept preset needs gravity along the Cartesian task axes")
    up = -g / np.linalg.norm(g)
    if cyc.direction is None:
        if not any(abs(up[a]) < 0.5 for a in cart):
            raise ValueError("cycle.direction: required (no Cartesian axis is horizontal)")
        return
    d = np.asarray(cyc.direction, dtype=float)
    norm = float(np.linalg.norm(d))
    if norm == 0.0 or np.any(d[[a for a in range(k) if a not in cart]]):
        raise ValueError("cycle.direction: need a non-zero vector along the Cartesian task axes")
    if abs(float(d @ up)) > 1e-9 * norm:
        raise ValueError("cycle.direction: must be perpendicular to gravity (the adept moves are up and across)")


def vertices_count(cyc: CycleConfig) -> list[Any]:
    """Segments of the closed path (one per vertex): the adept preset has 6."""
    if cyc.path is None:
        return [None] * 6
    pts = cyc.path
    return [None] * (len(pts) - 1 if len(pts) > 2 and pts[-1] == pts[0] else len(pts))


def limit_vector(value, n: int) -> np.ndarray | None:
    """speed_limits / force_limits as an (n,) array, or None."""
    if value is None:
        return None
    return np.full(n, float(value)) if isinstance(value, (int, float)) else np.asarray(value, dtype=float)


# actuator kinds by joint unit: a mechanism with both has its peaks per kind (one unit each), never mixed
ACTUATOR_KINDS = {"angle": "revolute", "length": "prismatic"}
ACTUATOR_PEAKS = ("speed", "accel", "force")


def peak_names(joint_units) -> dict[str, tuple[str, ...]]:
    """Catalogue name of each actuator peak metric -> the joint kinds ('angle', 'length') it is taken over:
    ``cycle_max_actuator_speed`` (all actuators) for a mechanism with one actuator kind,
    ``cycle_max_actuator_speed_revolute`` and ``..._prismatic`` for one with both (a maximum over rad/s and mm/s
    together would mix units)."""
    kinds = sorted(set(joint_units))
    suffixes = {"": tuple(kinds)} if len(kinds) == 1 else {f"_{ACTUATOR_KINDS[k]}": (k,) for k in kinds}
    return {f"cycle_max_actuator_{peak}{suffix}": ks for peak in ACTUATOR_PEAKS for suffix, ks in suffixes.items()}


CYCLE_METRICS = (
    "cycle_feasible",
    "cycle_max_actuator_speed",
    "cycle_max_actuator_accel",
    "cycle_max_actuator_force",
    *(f"cycle_max_actuator_{peak}_{kind}" for peak in ACTUATOR_PEAKS for kind in ACTUATOR_KINDS.values()),
    "cycle_min_lci",
    "cycle_min_clearance",
    "cycle_max_deflection",
    "max_cycles_per_minute",
    "picks_per_minute",
    "cycle_time_s",
    "motor_peak_torque_ratio",
    "motor_rms_torque_ratio",
    "motor_speed_ratio",
)


def searched(cfg) -> CycleConfig | None:
    """The config's cycle when an objective or constraint is a cycle metric (the optimisation then evaluates the
    cycle of every design), else None: a cycle costs 0.2 to a few ms per design, so it is not analysed for results
    columns nobody optimises (``scalesynth evaluate`` and ``scalesynth cycle`` always report it)."""
    used = {item.metric for item in [*cfg.objectives, *cfg.constraints]}
    return cfg.cycle if used & set(CYCLE_METRICS) else None
