"""The mechanism description: pydantic models, loading from YAML or a mapping, and the checks across fields.

A description names its design parameters (units, defaults), its options (actuator ranges, cone limits), its motion
type and its legs, each of a type from the leg library (``legs.LEG_TYPES``) with attachment points and link lengths
given as expressions of the parameters (``expressions``). ``pattern: {count: n}`` repeats a leg n times at equal
angles about z (leg k turned by start_deg + 360 k / n degrees); coordinates are given in the leg's own frame, i.e.
before that turn. Every problem is one ConfigError line naming the leg and the field (docs/describing.md).
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from scalesynth.errors import ConfigError
from scalesynth.mechanisms.describe import expressions
from scalesynth.mechanisms.describe.frame import StiffnessSpec
from scalesynth.mechanisms.describe.legs import LEG_TYPES
from scalesynth.names import hint

# The mobility check builds the mechanism, whose modules import this one: the package (describe/__init__.py)
# installs it here, so that no import circle runs through the schema.
MOBILITY_CHECK = None

Expr = float | str
MOTIONS = ("2T", "3T", "6DOF")  # motion types a kernel template handles (kernel2.py, kernel.py, kernel6.py)
LEG_COUNT = {"2T": 2, "3T": 3, "6DOF": 6}  # actuated legs each motion needs (a square Jacobian)
LENGTH_UNITS = ("m", "mm", "cm", "dm")


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class ParameterSpec(_Strict):
    """A design parameter: default value, unit ('length', 'angle' rad, or '1'), what it is."""

    default: float
    doc: str
    unit: Literal["length", "angle", "1"] = "length"
    positive: bool = True


class OptionSpec(_Strict):
    """A setting that is not a design parameter. kind 'range': null or [lo, hi] (an actuator range: rad for a
    revolute, length for a prismatic joint); 'angle': null or a half-angle in rad in (0, pi/2] (a ball-joint cone)."""

    kind: Literal["range", "angle"]
    doc: str
    default: Any = None


class PatternSpec(_Strict):
    """n legs at equal angles about z: leg k turned by start_deg + 360 k / count degrees."""

    count: int = Field(ge=1, le=12)
    start_deg: float = 0.0


class LegSpec(_Strict):
    """One leg (or, with ``pattern``, n copies of it at equal angles)."""

    type: str
    name: str = "leg"
    joint: str | None = None  # joint name prefix; default from the leg type (theta, s)
    pattern: PatternSpec | None = None
    angle_deg: float = 0.0  # a single leg's turn about z (with pattern: use pattern.start_deg)
    base: tuple[Expr, Expr, Expr]
    platform: tuple[Expr, Expr, Expr]
    links: dict[str, Expr] = {}  # a UPS leg has none
    branch: str | None = None
    limits: str | None = None  # name of a 'range' option
    cone: str | None = None  # name of an 'angle' option
    arm_zero: tuple[float, float, float] | None = None
    arm_positive: tuple[float, float, float] | None = None
    rail: tuple[float, float, float] | None = None
    width: Expr = 0.0  # parallelogram width along its short sides (bodies.py): 0 = one bar on the centre line
    cone_axis: tuple[float, float, float] | None = None  # UPS: the joints' cone axis (base frame; platform frame)


class PlanSpec(_Strict):
    """One calibrated plan of the adaptive column evaluator (evaluation.plans.ColumnPlan): the tolerance it was
    calibrated at (volume relative, GCI absolute) and its resolution; the fields mean what ColumnPlan's do."""

    tolerance: dict[Literal["volume", "gci"], float]
    columns: int = Field(ge=2, le=256)
    cells: int = Field(ge=1, le=256)
    bisections: int = Field(default=5, ge=1, le=30)
    levels: int = Field(ge=0, le=6)
    beta: float = Field(default=1.0, gt=0.0, le=100.0)
    zlevels: int = Field(default=0, ge=0, le=8)
    zconfirm: int = Field(default=1, ge=1, le=8)
    faces: bool = False
    field_levels: int = Field(default=-1, ge=-1, le=6)
    gauss_points: Literal[1, 2] = 2


class SectorSpec(_Strict):
    """One calibrated plan of the sector evaluator (evaluation.sector.SectorPlan; legs rotationally symmetric about
    z): the tolerance it was calibrated at and its Gauss-Legendre nodes over the sector's angle, over the radius and
    on a reachable z-interval as long as the box's z-range (shorter ones proportionally fewer, at least
    min_z_points), the radial scan steps and the bisections of the boundary radius."""

    tolerance: dict[Literal["volume", "gci"], float]
    angles: int = Field(ge=1, le=64)
    radii: int = Field(ge=1, le=64)
    z_points: int = Field(ge=1, le=64)
    min_z_points: int = Field(default=1, ge=1, le=64)
    scan: int = Field(default=8, ge=1, le=256)
    bisections: int = Field(default=12, ge=1, le=60)


class EvaluationSpec(_Strict):
    """How the tolerance form evaluates this mechanism: plans calibrated against finer uniform grids (docs/
    describing.md). A config tolerance no plan was calibrated for runs the per-design calibration ladder. A
    sector plan, where one is calibrated for the tolerance and the legs are rotationally symmetric, runs first;
    a block may hold sector plans alone (a design without the symmetry then climbs the ladder)."""

    # omitted: none (validate_default is off, so the default skips min_length); written: at least one
    plans: list[PlanSpec] = Field(default=[], min_length=1, max_length=8)
    sector: list[SectorSpec] = Field(default=[], max_length=8)


class Description(_Strict):
    """A whole mechanism."""

    name: str = Field(pattern=r"^[a-z][a-z0-9-]{0,39}$")
    title: str
    motion: str
    length_unit: str = "m"
    parameters: dict[str, ParameterSpec]
    options: dict[str, OptionSpec] = {}
    legs: list[LegSpec] = Field(min_length=1)
    stiffness: StiffnessSpec | None = None  # defaults of the stiffness options (frame.py)
    # the registered mechanism this description reproduces (a twin for tests; `design` runs only the original
    # unless the spec names the twin)
    reproduces: str | None = None
    evaluation: EvaluationSpec | None = None  # calibrated evaluation plans (the tolerance form); None: the ladder


def _one_line(text: str, limit: int = 200) -> str:
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _format(err: ValidationError) -> str:
    first = err.errors()[0]
    loc = ""
    for part in first["loc"]:
        loc += f"[{part}]" if isinstance(part, int) else (f".{part}" if loc else str(part))
    msg = "unknown key" if first["type"] == "extra_forbidden" else first["msg"].removeprefix("Value error, ")
    return f"{loc}: {msg}" if loc else msg


def parse_description(data: Any, where: str = "description") -> Description:
    """Validate a mapping into a Description; ConfigError ``where: field: problem`` (one line) if anything is wrong:
    the schema, an unknown leg type, motion or unit, a leg field its type does not have or lacks, an expression
    naming an unknown parameter, a limit naming an option of the wrong kind, or legs that do not make the motion."""
    if not isinstance(data, dict):
        raise ConfigError(f"{where}: expected a mapping (name, title, motion, parameters, options, legs)")
    try:
        desc = Description.model_validate(data)
    except ValidationError as err:
        raise ConfigError(_one_line(f"{where}: {_format(err)}")) from None
    try:
        _check(desc)
    except ConfigError as err:
        raise ConfigError(_one_line(f"{where}: {err}")) from None
    return desc


def load_description(path: str | Path, where: str | None = None) -> Description:
    """Read a description file (YAML, the config's safe loader) and validate it; ``where`` starts error lines
    (default the file's name)."""
    from scalesynth.yamlfile import MAX_YAML_BYTES, read_limited, safe_yaml

    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"{path}: no such description file")
    where = where or path.name
    return parse_description(safe_yaml(read_limited(path, MAX_YAML_BYTES), where), where)


def _check(desc: Description) -> None:
    if desc.motion not in MOTIONS:
        raise ConfigError(f"motion: {desc.motion!r} is not handled yet " + hint(desc.motion, MOTIONS, "handled"))
    if desc.length_unit not in LENGTH_UNITS:
        raise ConfigError(f"length_unit: {desc.length_unit!r} " + hint(desc.length_unit, LENGTH_UNITS))
    names = list(desc.parameters)
    for name in names:
        if not re.fullmatch(r"[A-Za-z_]\w{0,39}", name) or name in expressions.CONSTANTS:
            raise ConfigError(f"parameters.{name[:40]}: a parameter name is a word of letters, digits and _ "
                              "(not 'pi')")
        if not math.isfinite(desc.parameters[name].default):
            raise ConfigError(f"parameters.{name}.default: must be finite")
    clash = set(names) & set(desc.options)
    if clash:
        raise ConfigError(f"options.{sorted(clash)[0]}: also a parameter name")
    from scalesynth.mechanisms.describe.bodies import RESERVED_OPTIONS

    taken = (set(names) | set(desc.options)) & set(RESERVED_OPTIONS)
    if taken:
        raise ConfigError(f"options.{sorted(taken)[0]}: every described mechanism has this option (bodies, "
                          "stiffness): choose another name")
    count = 0
    kinds = set()
    for i, leg in enumerate(desc.legs):
        where = f"legs[{i}] ({leg.name})"
        lt = LEG_TYPES.get(leg.type)
        if lt is None:
            raise ConfigError(f"{where}.type: unknown leg type {leg.type!r} " + hint(leg.type, LEG_TYPES, "library"))
        if lt.motion != desc.motion:
            raise ConfigError(f"{where}.type: a {lt.name} leg makes motion {lt.motion}, not {desc.motion} "
                              + hint(leg.type, [k for k, v in LEG_TYPES.items() if v.motion == desc.motion],
                                     f"{desc.motion} legs"))
        kinds.add(lt.joint_unit)
        for field, values in (("base", leg.base), ("platform", leg.platform)):
            for axis, value in zip("xyz", values, strict=True):
                _expression(f"{where}.{field}.{axis}", value, names)
            if desc.motion == "2T" and values[2] not in (0, 0.0):
                raise ConfigError(f"{where}.{field}.z: motion 2T is planar, in the plane z = 0: give z as 0")
        _expression(f"{where}.width", leg.width, names)
        missing = [k for k in lt.links if k not in leg.links]
        if missing:
            raise ConfigError(f"{where}.links: {lt.name} needs {', '.join(lt.links)} (missing {missing[0]})")
        for key, value in leg.links.items():
            if key not in lt.links:
                raise ConfigError(f"{where}.links.{key}: not a link of {lt.name} " + hint(key, lt.links, "links"))
            _expression(f"{where}.links.{key}", value, names)
        if leg.branch is not None and leg.branch not in lt.branches:
            raise ConfigError(f"{where}.branch: {leg.branch!r} is not a branch of {lt.name} "
                              + hint(leg.branch, lt.branches, "branches"))
        for field in ("arm_zero", "arm_positive", "rail", "cone_axis"):
            value = getattr(leg, field)
            if value is not None and field not in lt.frame:
                raise ConfigError(f"{where}.{field}: {lt.name} has no {field} " + hint(field, lt.frame, "frame"))
        frame = leg_frame(leg)
        for field, vec in frame.items():
            if not 0.5 < math.sqrt(sum(v * v for v in vec)) < 2.0:
                raise ConfigError(f"{where}.{field}: expected a unit vector, got {list(vec)}")
            if desc.motion == "2T" and vec[2] != 0.0:
                raise ConfigError(f"{where}.{field}: motion 2T is planar: the direction must lie in the plane "
                                  f"z = 0, got {list(vec)}")
        if "arm_zero" in frame:
            u, w = frame["arm_zero"], frame["arm_positive"]
            if abs(sum(a * b for a, b in zip(u, w, strict=True))) > 1e-9:
                raise ConfigError(f"{where}.arm_positive: must be perpendicular to arm_zero")
        for field, kind in (("limits", "range"), ("cone", "angle")):
            option = getattr(leg, field)
            if option is None:
                continue
            if option not in desc.options:
                raise ConfigError(f"{where}.{field}: unknown option {option!r} " + hint(option, desc.options))
            if desc.options[option].kind != kind:
                raise ConfigError(f"{where}.{field}: option {option!r} is of kind {desc.options[option].kind}, "
                                  f"{field} needs one of kind {kind}")
        count += leg.pattern.count if leg.pattern else 1
    from scalesynth.mechanisms.describe.frame import check_spec

    check_spec(desc.stiffness, desc.length_unit, LEG_TYPES[desc.legs[0].type].code)
    need = LEG_COUNT[desc.motion]
    if count != need:
        raise ConfigError(f"{_extra_leg(desc, need)}: motion {desc.motion} needs {need} actuated legs (a square "
                          f"Jacobian), these give {count}")
    if len(kinds) > 1:
        raise ConfigError("legs: rotary and prismatic actuators together need a characteristic length (not handled "
                          "yet): use legs of one actuation kind")
    _check_evaluation(desc)
    if MOBILITY_CHECK is not None:
        MOBILITY_CHECK(desc)  # the legs make the motion type (a platform that cannot turn, held by its actuators)


def _extra_leg(desc: Description, need: int) -> str:
    """Where a wrong leg count is: the leg (and its pattern's count) whose actuators go past ``need``, an extra
    actuator; 'legs' when there are too few."""
    count = 0
    for i, leg in enumerate(desc.legs):
        count += leg.pattern.count if leg.pattern else 1
        if count > need:
            return f"legs[{i}] ({leg.name})" + (".pattern.count" if leg.pattern else "")
    return "legs"


def _check_evaluation(desc: Description) -> None:
    """Each calibrated plan names both tolerances, finite and in (0, 1), at most once each pair; 3T only (the
    column evaluator of a 3-D task with closed-form column intervals; other motions run the ladder)."""
    if desc.evaluation is None:
        return
    if desc.motion != "3T":
        raise ConfigError(f"evaluation: calibrated plans are read for motion 3T only, not {desc.motion} (leave the "
                          "block out)")
    if not desc.evaluation.plans and not desc.evaluation.sector:
        raise ConfigError("evaluation: needs plans (column plans) or sector (sector plans), or leave the block out")
    seen = set()
    for i, plan in enumerate(desc.evaluation.sector):
        where = f"evaluation.sector[{i}].tolerance"
        _check_tolerance(where, plan.tolerance)
        pair = (plan.tolerance["volume"], plan.tolerance["gci"])
        if pair in seen:
            raise ConfigError(f"{where}: a second sector plan for volume {pair[0]:g}, GCI {pair[1]:g}")
        seen.add(pair)
    seen = set()
    for i, plan in enumerate(desc.evaluation.plans):
        where = f"evaluation.plans[{i}].tolerance"
        _check_tolerance(where, plan.tolerance)
        pair = (plan.tolerance["volume"], plan.tolerance["gci"])
        if pair in seen:
            raise ConfigError(f"{where}: a second plan for volume {pair[0]:g}, GCI {pair[1]:g}")
        seen.add(pair)
        if plan.field_levels > plan.levels:
            raise ConfigError(f"evaluation.plans[{i}].field_levels: {plan.field_levels} is deeper than levels "
                              f"{plan.levels}")


def _check_tolerance(where: str, tolerance: dict[str, float]) -> None:
    """A plan's tolerance names volume and gci, each finite and in (0, 1)."""
    for key in ("volume", "gci"):
        if key not in tolerance:
            raise ConfigError(f"{where}: needs volume and gci (missing {key})")
        value = tolerance[key]
        if not (math.isfinite(value) and 0.0 < value < 1.0):
            raise ConfigError(f"{where}.{key}: expected a number in (0, 1), got {value!r}")


def _expression(where: str, value: Any, names: list[str]) -> expressions.Expression:
    try:
        return expressions.parse(value, names)
    except expressions.ExpressionError as err:
        raise ConfigError(f"{where}: {err}") from None


def leg_frame(leg: LegSpec) -> dict[str, tuple[float, float, float]]:
    """The leg's frame directions (leg frame, before the pattern's turn): the leg type's defaults overlaid by the
    description's."""
    lt = LEG_TYPES[leg.type]
    return {k: tuple(getattr(leg, k) or v) for k, v in lt.frame.items()}
