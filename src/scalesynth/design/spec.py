"""The spec sheet of ``scalesynth design`` (pydantic, like ``scalesynth.config``): ``load_spec(path)``.

Every validation problem is one SpecError line naming the field, e.g. ``envelope.cylinder.diameter: must be a
finite number > 0, got -4``. Lengths are in ``units.length`` (default mm); the robot frame has z up with the base
plane at z = 0 (planar mechanisms: y up).

```yaml
name: case_packer
units: {length: mm}
envelope:                       # one of box, cylinder, task
  box: {x: 400, y: 300, z: 80}  # sizes of the working zone (z: its height; omit z, or 0, for a planar zone)
  depth: 300                    # distance from the base plane to the near face of the zone
payloads: [1.0]                 # kg; the largest is the rated payload the robot is designed for
cycle: {preset: adept, picks_per_minute: 120, dwell_s: 0.0, law: modified_trapezoid}
stiffness: {max_deflection: 0.1, force: 150}   # length unit, N (downward)
links: {tube: [50, 3], youngs_modulus: 135, density: 1600}   # optional: length unit, GPa, kg/m^3
motors: {catalogue: builtin, model: SGM7J-08A, gear_ratio: 20}
mechanisms: null                # null = every registered mechanism that can do the task
search: {population: 16, generations: 6, seed: 1}
```
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from scalesynth.errors import ConfigError

LENGTH_UNITS = ("m", "dm", "cm", "mm")


class SpecError(ConfigError):
    """A malformed spec sheet (one line naming the field; exit code 2)."""


def _positive(name: str, v: float | None) -> float | None:
    if v is None:
        return v
    if isinstance(v, bool) or not math.isfinite(v) or v <= 0:
        raise ValueError(f"must be a finite number > 0, got {v}")
    return v


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class BoxZone(_Strict):
    """A rectangular working zone: sizes along x, y (horizontal) and z (height; 0 or absent: a planar zone in the
    x-z plane... of a planar mechanism, whose vertical axis is y)."""

    x: float = Field(..., description="width along x")
    y: float = Field(..., description="depth along y (planar zone: its height)")
    z: float = Field(0.0, description="height along z; 0 = planar zone (x by y, y vertical)")

    @field_validator("x", "y")
    @classmethod
    def _pos(cls, v):
        return _positive("", v)

    @field_validator("z")
    @classmethod
    def _non_negative(cls, v):
        if isinstance(v, bool) or not math.isfinite(v) or v < 0:
            raise ValueError(f"must be a finite number >= 0, got {v}")
        return v


class CylinderZone(_Strict):
    diameter: float
    height: float

    @field_validator("diameter", "height")
    @classmethod
    def _pos(cls, v):
        return _positive("", v)


class EnvelopeSpec(_Strict):
    """The working zone: a ``box`` or a ``cylinder`` ``depth`` below the base plane (on the side each mechanism
    works on), or a config's ``task`` section verbatim (robot frame, the spec's length unit)."""

    box: BoxZone | None = None
    cylinder: CylinderZone | None = None
    task: dict[str, Any] | None = Field(None, description="a run config's task section (box per axis, path)")
    depth: float | None = Field(None, description="distance from the base plane to the zone's near face")

    @field_validator("depth")
    @classmethod
    def _depth(cls, v):
        if v is not None and (isinstance(v, bool) or not math.isfinite(v) or v < 0):
            raise ValueError(f"must be a finite number >= 0, got {v}")
        return v

    @model_validator(mode="after")
    def _one_form(self):
        forms = [k for k in ("box", "cylinder", "task") if getattr(self, k) is not None]
        if len(forms) != 1:
            raise ValueError("give exactly one of box, cylinder, task" + (f" (got {', '.join(forms)})" if forms
                                                                          else ""))
        if forms[0] != "task" and self.depth is None:
            raise ValueError(f"depth: required with {forms[0]} (distance from the base plane to the zone)")
        if forms[0] == "task":
            from scalesynth.config import TaskConfig

            if self.depth is not None:
                raise ValueError("depth: only with box or cylinder (a task is in robot coordinates)")
            try:
                TaskConfig.model_validate(self.task)
            except ValidationError as err:
                first = err.errors()[0]
                loc = ".".join(str(p) for p in first["loc"])
                msg = first["msg"].removeprefix("Value error, ")
                raise ValueError(f"task.{loc}: {msg}" if loc else f"task: {msg}") from None
        return self

    @property
    def form(self) -> str:
        return next(k for k in ("box", "cylinder", "task") if getattr(self, k) is not None)

    @property
    def planar(self) -> bool:
        """Whether the zone is planar: a box without height, or a task box of two axes."""
        if self.box is not None:
            return self.box.z == 0
        if self.task is not None:
            return len(self.task.get("box") or {}) == 2
        return False


class CycleSpec(_Strict):
    """The pick-and-place cycle: ``preset`` (adept: 25 up, 305 across, 25 down and back, through the zone's
    centre) or ``path`` (closed polyline, relative to the zone's centre on its near face; z up), the target rate
    and dwell."""

    preset: Literal["adept"] | None = "adept"
    path: list[list[float]] | None = None
    picks_per_minute: float = Field(..., description="target rate")
    dwell_s: float = Field(0.0, ge=0.0, le=3600.0, description="s at rest at pick and at place")
    law: str = "modified_trapezoid"

    @field_validator("picks_per_minute")
    @classmethod
    def _rate(cls, v):
        _positive("", v)
        if v > 6000:
            raise ValueError(f"{v:g} picks per minute is beyond any robot (at most 6000)")
        return v

    @field_validator("law")
    @classmethod
    def _law(cls, v):
        from scalesynth.cycle.trajectory import LAWS
        from scalesynth.names import hint

        if v not in LAWS:
            raise ValueError(f"unknown motion law {v!r} " + hint(v, LAWS))
        return v

    @field_validator("path")
    @classmethod
    def _path(cls, v):
        from scalesynth.paths import check_polyline

        return None if v is None else check_polyline(v, closed=True)

    @model_validator(mode="before")
    @classmethod
    def _path_replaces_preset(cls, data):
        if isinstance(data, dict) and data.get("path") is not None and "preset" not in data:
            data = {**data, "preset": None}
        return data

    @model_validator(mode="after")
    def _one(self):
        if (self.preset is None) == (self.path is None):
            raise ValueError("give either preset or path")
        return self


class StiffnessSpec(_Strict):
    max_deflection: float = Field(..., description="largest deflection of the tool point (length unit)")
    force: float = Field(..., description="N, downward, at the tool point")

    @field_validator("max_deflection", "force")
    @classmethod
    def _pos(cls, v):
        return _positive("", v)


class LinksSpec(_Strict):
    """The links every candidate is built from: a round tube and its material, for the stiffness model (section,
    Young's modulus) and the mass model of the cycle (section, density). Null fields keep each mechanism's defaults
    (aluminium 70 GPa, 2700 kg/m^3, a 40 x 3 mm tube)."""

    tube: list[float] | None = Field(None, description="[outer diameter, wall] in the spec's length unit")
    youngs_modulus: float | None = Field(None, description="GPa")
    density: float | None = Field(None, description="kg/m^3")

    @field_validator("tube")
    @classmethod
    def _tube(cls, v):
        if v is None:
            return v
        if len(v) != 2:
            raise ValueError(f"expected [outer diameter, wall], got {len(v)} numbers")
        d, t = (_positive("", x) for x in v)
        if 2.0 * t > d:
            raise ValueError(f"the wall ({t:g}) is more than half the outer diameter ({d:g})")
        return [d, t]

    @field_validator("youngs_modulus", "density")
    @classmethod
    def _material(cls, v, info):
        v = _positive("", v)
        # the largest of any structural material: diamond's modulus, osmium's density
        limit, unit = {"youngs_modulus": (2000.0, "GPa"), "density": (25_000.0, "kg/m^3")}[info.field_name]
        if v is not None and v > limit:
            raise ValueError(f"{v:g} {unit} is beyond any structural material (at most {limit:g} {unit})")
        return v


class SearchSpec(_Strict):
    """The budget of each candidate's search (NSGA-II): small by default, so a spec runs in minutes."""

    population: int = Field(16, ge=4, le=10_000)
    generations: int = Field(6, ge=1, le=10_000)
    seed: int = Field(1, ge=0, le=2**32 - 1)
    task_resolution: int = Field(10, ge=2, le=256, description="task-box cells per axis")
    cycle_samples: int = Field(48, ge=8, le=100_000, description="time intervals of the cycle per design")


class UnitsSpec(_Strict):
    length: Literal[LENGTH_UNITS] = "mm"  # type: ignore[valid-type]


class DesignSpec(_Strict):
    name: str = Field(..., min_length=1, max_length=100, pattern=r"^[A-Za-z0-9_][A-Za-z0-9_.-]*$")
    units: UnitsSpec = Field(default_factory=UnitsSpec)
    envelope: EnvelopeSpec
    payloads: list[float] = Field(default_factory=lambda: [1.0], min_length=1, max_length=16)
    cycle: CycleSpec
    stiffness: StiffnessSpec | None = None
    links: LinksSpec | None = Field(None, description="tube section and material of every candidate's links")
    motors: dict[str, Any] | None = Field(None, description="a run config's motors section (catalogue, model, gear)")
    mechanisms: list[str] | None = Field(None, min_length=1, description="null = every one that can do the task")
    search: SearchSpec = Field(default_factory=SearchSpec)

    @field_validator("payloads")
    @classmethod
    def _payloads(cls, v):
        for i, p in enumerate(v):
            if isinstance(p, bool) or not math.isfinite(p) or p <= 0:
                raise ValueError(f"{i}: must be a finite mass > 0 (kg), got {p}")
            if p > 10_000:
                raise ValueError(f"{i}: {p:g} kg is beyond any parallel robot's payload (at most 10000 kg)")
        return v

    @field_validator("mechanisms")
    @classmethod
    def _known(cls, v):
        if v is None:
            return v
        from scalesynth.mechanisms import available
        from scalesynth.names import hint

        names = available()
        for i, name in enumerate(v):
            if name not in names:
                raise ValueError(f"{i}: unknown mechanism {str(name)[:40]!r} " + hint(str(name), names))
        if len(set(v)) != len(v):
            raise ValueError("each mechanism once")
        return v

    @model_validator(mode="after")
    def _path_dims(self):
        if self.cycle.path is not None:
            dims = 2 if self.envelope.planar else 3
            if len(self.cycle.path[0]) != dims:
                raise ValueError(f"cycle.path: points need {dims} coordinates for a "
                                 f"{'planar' if dims == 2 else '3-D'} zone")
        return self

    @property
    def rated_payload(self) -> float:
        return max(self.payloads)


def _format(err: ValidationError) -> str:
    first = err.errors()[0]
    loc = ".".join(str(p) for p in first["loc"])
    msg = first["msg"].removeprefix("Value error, ")
    if first["type"] == "extra_forbidden":
        msg = "unknown key"
    import re

    if loc and re.match(r"^[\w.\[\]-]+: ", msg):
        return f"{loc}.{msg}"
    return f"{loc}: {msg}" if loc else msg


def spec_from_dict(data: Any) -> DesignSpec:
    """Validate a spec mapping; SpecError (one line) otherwise."""
    from scalesynth.config import _one_line

    if not isinstance(data, dict):
        raise SpecError("spec: top level must be a mapping")
    try:
        return DesignSpec.model_validate(data)
    except ValidationError as err:
        raise SpecError(_one_line(_format(err))[:190]) from None


def load_spec(path: str | Path) -> DesignSpec:
    """Read and validate a spec sheet (YAML, safe loader)."""
    from scalesynth.yamlfile import MAX_YAML_BYTES, read_limited, safe_yaml

    path = Path(path)
    try:
        is_file = path.is_file()
    except OSError as err:
        raise SpecError(f"{path}: {err.strerror or err}") from None
    if not is_file:
        raise SpecError(f"{path}: no such spec file")
    return spec_from_dict(safe_yaml(read_limited(path, MAX_YAML_BYTES), str(path)))
