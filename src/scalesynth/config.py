"""Run configuration: pydantic models and ``load_config(path, overrides)``.

Every validation problem becomes a one-line ConfigError that names the field path, e.g.
``bounds.l1: lower bound 1.5 must be below upper bound 0.5``.
"""

from __future__ import annotations

import math
import re
import sys
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    PrivateAttr,
    ValidationError,
    ValidationInfo,
    field_serializer,
    field_validator,
    model_serializer,
    model_validator,
)

from scalesynth.cycle import config as cycle_config
from scalesynth.dynamics import config as dynamics_config
from scalesynth.dynamics.config import GEAR_RATIO
from scalesynth.errors import ConfigError, ScalesynthError
from scalesynth.names import hint
from scalesynth.yamlfile import MAX_YAML_BYTES, quoted, read_limited, safe_yaml

LENGTH_UNITS = ("m", "mm", "cm", "dm")


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=False)


class ToleranceConfig(_Strict):
    """Accuracy target of the tolerance form: the adaptive evaluator (per design, from its own error estimate), or a
    mechanism's calibrated uniform grid (Mechanism.uniform_plan)."""

    volume: float = Field(0.002, gt=0.0, le=0.5, description="relative error of the workspace measure")
    gci: float = Field(5.0e-4, gt=0.0, le=0.5, description="absolute error of the GCI")


class GridConfig(_Strict):
    """Either ``tolerance`` (the tolerance form: adaptive evaluator or calibrated grid) or ``resolution`` (uniform
    grid). A given ``resolution`` wins (``--resolution N`` forces the uniform reference grid); ``resolution`` also
    sets the uniform grids of plots, the report's sections and task boxes without their own resolution."""

    resolution: int = Field(64, ge=4, le=1024, description="cells per axis")
    tolerance: ToleranceConfig | None = Field(None, description="accuracy target (tolerance form)")
    region: dict[str, tuple[float, float]] | None = Field(
        None, description="override of the mechanism's bounding box, per task axis name: [lo, hi]"
    )

    @field_validator("region")
    @classmethod
    def _region_ok(cls, v):
        return v if v is None else _axis_ranges(v)

    @property
    def adaptive(self) -> bool:
        """Whether the tolerance form runs (adaptive evaluator or calibrated grid): a tolerance is given and no
        resolution is."""
        return self.tolerance is not None and "resolution" not in self.model_fields_set

    @model_serializer(mode="wrap")
    def _dump(self, handler):
        # a tolerance-form grid is dumped without its default resolution: every dump that is loaded again (the
        # run's config.yaml and manifest, batch tasks, `select`, API overrides) must stay adaptive
        data = handler(self)
        if self.adaptive:
            data.pop("resolution", None)
        return data


def _magnitude(key: str, *values: float) -> None:
    """ValueError naming ``key`` for a value beyond MAX_MAGNITUDE (mechanisms.base: where arithmetic overflows) or
    a subnormal one (where it underflows)."""
    from scalesynth.mechanisms.base import MAX_MAGNITUDE, SUBNORMAL, is_subnormal

    for v in values:
        if abs(v) > MAX_MAGNITUDE:
            raise ValueError(f"{key}: {v:g} is beyond +-{MAX_MAGNITUDE:g}, the largest magnitude scalesynth "
                             "computes with (products of such values overflow)")
        if is_subnormal(v):
            raise ValueError(f"{key}: {v:g} is {SUBNORMAL}")


# A range [lo, hi] must hold more than this many floats: the optimiser's operators (pymoo's SBX and polynomial
# mutation) divide by hi - lo and by differences of values inside the range, and a grid splits it into cells, so a
# range of one or two representable numbers gives 0/0 there
MIN_RANGE_ULPS = 64


def _width(key: str, lo: float, hi: float) -> None:
    """ValueError naming ``key`` for a range too narrow to compute in: fewer than MIN_RANGE_ULPS floats between
    lo and hi, or a width that is not a normal float."""
    width = hi - lo
    ulp = math.ulp(max(abs(lo), abs(hi)))
    if not width >= MIN_RANGE_ULPS * ulp or width < sys.float_info.min:
        raise ValueError(f"{key}: the range [{lo!r}, {hi!r}] is too narrow to compute in (width {width:.3g}; "
                         f"at least {MIN_RANGE_ULPS} float steps, {MIN_RANGE_ULPS * ulp:.3g}, are needed)")


def _axis_ranges(ranges: dict[str, tuple[float, float]]) -> dict[str, tuple[float, float]]:
    """``ranges`` (axis -> [lo, hi], a grid region or a task box) unchanged, or ValueError naming the axis: each
    range finite with lo < hi, within MAX_MAGNITUDE and wide enough to compute in."""
    for axis, (lo, hi) in ranges.items():
        if not (math.isfinite(lo) and math.isfinite(hi)) or not lo < hi:
            raise ValueError(f"{axis}: need finite lo < hi, got [{lo}, {hi}]")
        _magnitude(axis, lo, hi)
        _width(axis, lo, hi)
    return ranges


class DexterityConfig(_Strict):
    band_edges: list[float] = Field(default_factory=lambda: [0.0, 0.1, 0.3, 1.0])

    @field_validator("band_edges")
    @classmethod
    def _edges_ok(cls, v):
        if len(v) < 2 or len(v) > 17:
            raise ValueError("need between 2 and 17 edges")
        if v[0] != 0.0 or v[-1] != 1.0:
            raise ValueError("must start at 0 and end at 1")
        if any(not b > a for a, b in zip(v, v[1:], strict=False)):
            raise ValueError("must be strictly increasing")
        return v


class TaskConfig(_Strict):
    """A task region (box) that must be covered, and an optional path (polyline of task points) to follow."""

    box: dict[str, tuple[float, float]]  # per task axis name
    resolution: int | None = Field(None, ge=2, le=1024, description="cells per axis; null = grid.resolution")
    path: list[list[float]] | None = None
    path_samples: int = Field(200, ge=2, le=100_000, description="points sampled along the whole path")

    @field_validator("box")
    @classmethod
    def _box_ok(cls, v):
        return _axis_ranges(v)

    @field_validator("path")
    @classmethod
    def _path_ok(cls, v):
        from scalesynth.paths import check_polyline

        return None if v is None else check_polyline(v, dims=(2, 3))


class ObjectiveConfig(_Strict):
    metric: str = Field(..., description="a metric of the catalogue (`scalesynth metrics MECH`)")
    sense: Literal["max", "min"] = "max"
    band: int | None = Field(None, description="band index for band_share / band_volume")


class ConstraintConfig(_Strict):
    metric: str = Field(..., description="a metric of the catalogue (`scalesynth metrics MECH`)")
    min: float | None = None
    max: float | None = None
    band: int | None = None

    @field_validator("min", "max")
    @classmethod
    def _finite(cls, v):
        if v is not None and not math.isfinite(v):
            raise ValueError(f"must be finite, got {v}")
        return v

    @model_validator(mode="after")
    def _one_side(self):
        for side in ("min", "max"):
            value = getattr(self, side)
            if value is not None and not math.isfinite(value):
                raise ValueError(f"{side}: must be finite, got {value}")
        if self.min is None and self.max is None:
            raise ValueError("give min, max or both")
        if self.min is not None and self.max is not None and not self.min <= self.max:
            raise ValueError(f"min {self.min} must not exceed max {self.max}")
        return self


class AlgorithmConfig(_Strict):
    name: Literal["nsga2"] = "nsga2"
    pop_size: int = Field(200, ge=4, le=100_000)
    n_gen: int = Field(200, ge=1, le=100_000)
    eta_crossover: float = Field(20.0, gt=0)
    eta_mutation: float = Field(20.0, gt=0)
    prob_crossover: float = Field(0.9, ge=0, le=1)
    prob_mutation: float | None = Field(None, ge=0, le=1, description="per variable; null = 1/n_var")
    seed: int = Field(1, ge=0, le=2**32 - 1)


class OutputConfig(_Strict):
    dir: str | None = Field(None, description="results directory; null = results/<name>")
    checkpoint_every: int = Field(5, ge=1)


class UnitsConfig(_Strict):
    """``length``: the unit every length of the config and the results is in; it must be the mechanism's own
    (null = the mechanism's, filled in at validation): scalesynth does not convert lengths."""

    length: Literal[LENGTH_UNITS] | None = None  # type: ignore[valid-type]


class RunConfig(_Strict):
    # used as a directory name (results/<name>, batch OUT/<name>): no separators, no leading dot ('.', '..')
    name: str = Field(..., min_length=1, max_length=128, pattern=r"^[A-Za-z0-9_][A-Za-z0-9_.-]*$")
    # a registered mechanism's name, or {description: FILE or MAPPING}: a user's described mechanism (FILE relative
    # to the config file); after validation the name, with the mechanism in _mech (cfg.mech)
    mechanism: str | dict[str, Any]
    units: UnitsConfig = Field(default_factory=UnitsConfig)
    design: dict[str, float] = Field(default_factory=dict, description="design evaluated by `evaluate`")
    options: dict[str, Any] = Field(default_factory=dict)
    bounds: dict[str, tuple[float, float]] = Field(default_factory=dict)
    grid: GridConfig = Field(default_factory=GridConfig)
    dexterity: DexterityConfig = Field(default_factory=DexterityConfig)
    task: TaskConfig | None = None
    cycle: cycle_config.CycleConfig | None = Field(None, description="pick-and-place cycle (scalesynth.cycle)")
    dynamics: dynamics_config.DynamicsConfig | None = Field(None, description="mass model of the links (cycles)")
    motors: dynamics_config.MotorsConfig | None = Field(None, description="motors and gears of the actuators")
    references: dict[str, dict[str, float]] = Field(
        default_factory=dict, description="labelled designs re-evaluated and drawn beside the front (e.g. a paper's)"
    )
    objectives: list[ObjectiveConfig] = Field(
        default_factory=lambda: [ObjectiveConfig(metric="volume"), ObjectiveConfig(metric="gci")]
    )
    constraints: list[ConstraintConfig] = Field(default_factory=list)
    algorithm: AlgorithmConfig = Field(default_factory=AlgorithmConfig)
    output: OutputConfig = Field(default_factory=OutputConfig)
    _mech: Any = PrivateAttr(None)  # cfg.mech, found again after unpickling (mechanisms hold unpicklable lambdas)
    _description: Any = PrivateAttr(None)  # a user's description: dumped inline, so a dump reloads it

    @model_serializer(mode="wrap")
    def _dump_without_unset_sections(self, handler):
        # dynamics and motors appear in a dump only when given (dumps of older configs stay as they were)
        data = handler(self)
        for key in ("dynamics", "motors"):
            if data.get(key, 0) is None:
                data.pop(key)
        return data

    @field_serializer("mechanism")
    def _mechanism_out(self, value):
        if self._description is not None:
            return {"description": self._description.model_dump(mode="json", exclude_defaults=True)}
        return value

    def __getstate__(self):
        state = super().__getstate__()
        state["__pydantic_private__"] = {**(state.get("__pydantic_private__") or {}), "_mech": None}
        return state

    @field_validator("design", "bounds", "references", mode="before")
    @classmethod
    def _no_booleans(cls, v):
        """YAML true/false would pass as 1.0/0.0: refuse them where numbers are expected."""
        def walk(node, where):
            if isinstance(node, bool):
                raise ValueError(f"{where}: expected a number, got {str(node).lower()}")
            if isinstance(node, dict):
                for key, child in node.items():
                    walk(child, f"{where}.{key}" if where else str(key))
            elif isinstance(node, (list, tuple)):
                for child in node:
                    walk(child, where)

        walk(v, "")
        return v

    @field_validator("design")
    @classmethod
    def _design_finite(cls, v):
        for key, value in v.items():
            if not math.isfinite(value):
                raise ValueError(f"{key}: must be finite, got {value}")
        return v

    @field_validator("bounds")
    @classmethod
    def _bounds_ok(cls, v):
        for key, (lo, hi) in v.items():
            if not (math.isfinite(lo) and math.isfinite(hi)):
                raise ValueError(f"{key}: bounds must be finite, got [{lo}, {hi}]")
            if not lo < hi:
                raise ValueError(f"{key}: lower bound {lo} must be below upper bound {hi}")
            _magnitude(key, lo, hi)
            _width(key, lo, hi)
        return v

    @model_validator(mode="after")
    def _against_mechanism(self, info: ValidationInfo):
        base_dir = (info.context or {}).get("base_dir")
        mech = mechanism_of(self.mechanism, base_dir)
        self._mech = mech
        if isinstance(self.mechanism, dict) and not _is_registered(mech):
            self._description = mech.description
        self.mechanism = mech.name
        self.units.length = mech.length_unit(self.units.length)
        mech.resolve_design(self.design)
        mech.resolve_options(self.options)
        for label, ref in self.references.items():
            try:
                mech.resolve_design({**self.design, **ref})
            except ScalesynthError as err:
                raise ValueError(f"references.{label}: {err}") from None
        params = {p.name: p for p in mech.parameters}
        for key, (lo, _) in self.bounds.items():
            if key == GEAR_RATIO and key not in params:  # the motors' shared gear ratio searched (issue 29)
                if self.motors is None:
                    raise ValueError(f"bounds.{key}: needs a motors section (the gear ratio searched is the motors')")
                if lo <= 0:
                    raise ValueError(f"bounds.{key}: lower bound must be > 0 for a gear ratio, got {lo}")
                continue
            if key not in params:
                raise ValueError(f"bounds.{key}: unknown parameter of {mech.name} " + hint(str(key), params))
            if params[key].positive and lo <= 0:
                raise ValueError(f"bounds.{key}: lower bound must be > 0 for a length, got {lo}")
        if self.cycle is not None:  # the cycle analysis reads the mass model and motors from its cycle
            self.cycle._dynamics = self.dynamics
            self.cycle._motors = self.motors
            self.cycle._base_dir = base_dir
        self._check_metrics(mech)
        axes = ", ".join(mech.task_axes)
        for axis in self.grid.region or {}:
            if axis not in mech.task_axes:
                raise ValueError(f"grid.region.{axis}: not a task axis of {mech.name} ({axes})")
        if self.task is not None:
            for axis in self.task.box:
                if axis not in mech.task_axes:
                    raise ValueError(f"task.box.{axis}: not a task axis of {mech.name} ({axes})")
            for axis in mech.task_axes:
                if axis not in self.task.box:
                    raise ValueError(f"task.box.{axis}: missing (the box needs every task axis: {axes})")
            if self.task.path is not None and len(self.task.path[0]) != len(mech.task_axes):
                raise ValueError(f"task.path: points need {len(mech.task_axes)} coordinates for {mech.name}")
        if self.cycle is not None:
            cycle_config.check(self.cycle, mech)
            self._check_dynamics(mech, base_dir)
        elif self.dynamics is not None or self.motors is not None:
            raise ValueError(f"{'dynamics' if self.dynamics is not None else 'motors'}: needs a cycle section "
                             "(the masses and motors act along the cycle)")
        if len(self.objectives) < 1:
            raise ValueError("objectives: need at least one")
        seen: dict[tuple, int] = {}
        for i, obj in enumerate(self.objectives):
            key = (obj.metric, obj.band)
            if key in seen:
                raise ValueError(f"objectives[{i}]: duplicate of objectives[{seen[key]}] ({obj.metric}"
                                 + (f", band {obj.band}" if obj.band is not None else "") + ")")
            seen[key] = i
        return self

    def _check_dynamics(self, mech, base_dir) -> None:
        """Check dynamics.masses' groups and the motors against the mechanism (ValueError naming the field)."""
        from scalesynth.dynamics import motors

        if self.motors is not None:
            try:
                motors.resolve(self.motors, len(mech.joints), base_dir)
            except ScalesynthError as err:
                raise ValueError(str(err)) from None
        if self.dynamics is not None and self.dynamics.masses:
            from scalesynth.dynamics import bodies

            geometry = bodies.reference_geometry(mech, self.design, self.options, self.cycle, self.units.length)
            if geometry is not None:
                try:
                    bodies.check_groups(self.dynamics.masses, geometry, mech.name)
                except ScalesynthError as err:
                    raise ValueError(str(err)) from None

    def _check_metrics(self, mech) -> None:
        """Every objective and constraint names a catalogue metric this config can evaluate."""
        from scalesynth.metrics import resolve

        n_bands = len(self.dexterity.band_edges) - 1
        has_task = self.task is not None
        has_path = has_task and self.task.path is not None
        options = mech.resolve_options(self.options)
        for where, items in (("objectives", self.objectives), ("constraints", self.constraints)):
            for i, item in enumerate(items):
                try:
                    m = resolve(mech, self.units.length, item.metric, item.band, n_bands, has_task, has_path, options,
                                self.cycle, self.grid.adaptive)
                except ValueError as err:
                    raise ValueError(f"{where}[{i}].{err}") from None
                if where == "objectives" and item.sense == "min" and m.worst is None:
                    raise ValueError(
                        f"{where}[{i}].sense: {item.metric} has no finite worst value for the hypervolume reference, "
                        "so it cannot be minimised (maximise it, or bound it with a constraint)"
                    )

    # convenient views
    @property
    def mech(self):
        if self._mech is None:
            self._mech = mechanism_of(self.mechanism) if self._description is None else \
                describe_user_mechanism(self._description)
        return self._mech

    def resolved_design(self) -> dict[str, float]:
        return self.mech.resolve_design(self.design)

    def resolved_options(self) -> dict[str, Any]:
        return self.mech.resolve_options(self.options)

    def output_dir(self) -> Path:
        return Path(self.output.dir) if self.output.dir else Path("results") / self.name


def mechanism_of(value: Any, base_dir: Path | None = None):
    """The mechanism a config's ``mechanism`` names: a registered name, or ``{description: FILE or MAPPING}`` (a
    relative FILE read from ``base_dir``); ConfigError / UnknownMechanism, one line, otherwise."""
    if isinstance(value, dict):
        from scalesynth.user_mechanisms import resolve_source

        return resolve_source(value, base_dir)
    from scalesynth.mechanisms import get

    return get(value)


def describe_user_mechanism(description):
    from scalesynth.user_mechanisms import user_mechanism

    return user_mechanism(description)


def _is_registered(mech) -> bool:
    from scalesynth.mechanisms import find

    return find(mech.name) is mech


def _format_validation_error(err: ValidationError) -> str:
    first = err.errors()[0]
    loc = ".".join(str(p) for p in first["loc"])
    msg = first["msg"]
    msg = msg.removeprefix("Value error, ")
    if first["type"] == "extra_forbidden":
        msg = "unknown key"
    if loc and re.match(r"^[\w.\[\]-]+: ", msg):
        return f"{loc}.{msg}"  # a validator that names the entry inside the field, e.g. design + "l1: ..."
    return f"{loc}: {msg}" if loc else msg


def _parse_scalar(text: str) -> Any:
    try:
        return safe_yaml(text, "--set value")
    except ConfigError as err:
        if "invalid YAML" in str(err):
            return text
        raise


def apply_overrides(data: dict, overrides: list[str] | None, design_keys: set[str] | None = None) -> dict:
    """Apply ``key=value`` overrides. A bare key naming a design parameter sets ``design.<key>``, one naming a
    top-level section sets it (``objectives=[...]``), any other bare key sets ``options.<key>``; a dotted key sets
    that path."""
    for item in overrides or []:
        if "=" not in item:
            raise ConfigError(f"--set {item}: expected key=value")
        key, _, raw = item.partition("=")
        key = key.strip()
        if not key:
            raise ConfigError(f"--set {item}: empty key")
        value = _parse_scalar(raw.strip())
        path = key.split(".")
        if any(not part.strip() for part in path):
            raise ConfigError(f"--set {quoted(key)}: empty field name in the dotted path")
        if len(path) == 1:
            if design_keys is not None and key in design_keys:
                path = ["design", key]
            elif key in RunConfig.model_fields:  # a top-level section: objectives=[...], bounds={...}
                path = [key]
            else:
                path = ["options", key]
        node = data
        for part in path[:-1]:
            nxt = node.setdefault(part, {})
            if not isinstance(nxt, dict):
                raise ConfigError(f"--set {key}: {part} is not a section")
            node = nxt
        node[path[-1]] = value
    return data


def config_from_dict(data: Any, overrides: list[str] | None = None, base_dir: str | Path | None = None) -> RunConfig:
    """Validate a config mapping; ``base_dir`` is where a relative ``mechanism: {description: FILE}`` is read from
    (load_config: the config file's directory; None: the working directory)."""
    if not isinstance(data, dict):
        raise ConfigError("config: top level must be a mapping")
    data = dict(data)
    base = Path(base_dir) if base_dir is not None else None
    if overrides:
        design_keys = None
        try:
            raw = data.get("mechanism")
            design_keys = set(mechanism_of(raw if isinstance(raw, dict) else str(raw), base).parameter_names)
        except ScalesynthError:
            pass
        data = apply_overrides(data, overrides, design_keys)
    try:
        return RunConfig.model_validate(data, context={"base_dir": base})
    except ValidationError as err:
        raise ConfigError(_one_line(_format_validation_error(err))) from None
    except ScalesynthError as err:
        raise ConfigError(_one_line(str(err))) from None


# every character str.splitlines() breaks at: a key or value quoted in a message must not break its line
_LINE_BREAKS = {ord(c): repr(c)[1:-1] for c in "\n\r\x0b\x0c\x1c\x1d\x1e\x85\u2028\u2029"}


MAX_MESSAGE = 400  # characters: an error quoting a huge value stays a short line


def _one_line(message: str) -> str:
    """The message with line breaks (from keys or values it quotes) escaped and its length bounded, so errors stay
    one short line."""
    if len(message) > MAX_MESSAGE:
        message = message[:MAX_MESSAGE] + "..."
    return message.translate(_LINE_BREAKS)


def load_config(path: str | Path, overrides: list[str] | None = None) -> RunConfig:
    """Read a YAML config (safe loader: no object construction), apply overrides and validate."""
    path = Path(path)
    try:
        is_file = path.is_file()
    except OSError as err:  # e.g. a name too long for the file system: bad input, not an I/O failure
        raise ConfigError(f"{path}: {err.strerror or err}") from None
    if not is_file:
        raise ConfigError(f"{path}: no such config file")
    text = read_limited(path, MAX_YAML_BYTES)
    return config_from_dict(safe_yaml(text, str(path)), overrides, path.parent)


def dump_config(cfg: RunConfig) -> str:
    return yaml.safe_dump(cfg.model_dump(mode="json"), sort_keys=False)


def check_grid_arguments(mech, resolution: Any, region: Any, band_edges: Any, length_unit: Any) -> None:
    """The grid arguments of the Python API's ``evaluate``, checked as a config checks ``grid.resolution``,
    ``grid.region``, ``dexterity.band_edges`` and ``units.length``: ConfigError, one line naming the argument."""
    limit = GridConfig.model_fields["resolution"].metadata
    lo_res = next(m.ge for m in limit if hasattr(m, "ge"))
    hi_res = next(m.le for m in limit if hasattr(m, "le"))
    if isinstance(resolution, bool):
        raise ConfigError(f"resolution: expected an integer, got {resolution}")
    if isinstance(resolution, int) and not lo_res <= resolution <= hi_res:
        raise ConfigError(f"resolution: {resolution} cells per axis is outside {lo_res}..{hi_res}, the grids "
                          f"scalesynth evaluates (as grid.resolution of a config)")
    if region is not None and not isinstance(region, dict):
        try:
            region = dict(region)
        except (TypeError, ValueError):
            raise ConfigError(f"region: expected {{task axis: [lo, hi]}}, got {quoted(region)}") from None
    if length_unit is not None and length_unit not in LENGTH_UNITS:
        raise ConfigError(f"length_unit: must be one of {', '.join(LENGTH_UNITS)}, got {quoted(length_unit)}")
    try:
        GridConfig.model_validate({"resolution": resolution, "region": region})
        DexterityConfig.model_validate({"band_edges": band_edges if isinstance(band_edges, list)
                                        else list(band_edges) if isinstance(band_edges, tuple) else band_edges})
    except ValidationError as err:
        raise ConfigError(_one_line(_format_validation_error(err))) from None
    axes = ", ".join(mech.task_axes)
    for axis in region or {}:
        if axis not in mech.task_axes:
            raise ConfigError(f"region.{quoted(axis)[1:-1]}: not a task axis of {mech.name} ({axes})")
