"""The ``dynamics:`` and ``motors:`` config sections (pydantic).

```yaml
dynamics:
  masses: {upper_arm: 0.35, forearm: 0.25, platform: 0.4}  # kg per body of each group; the whole mass model
  density: 2700                                             # kg/m^3, without masses: tube links of this material
motors:                                                     # the same for every actuator, at the motor shaft
  peak_torque: 7.16       # N m
  rated_torque: 2.39      # N m
  max_speed: 628.3        # rad/s
  rotor_inertia: 1.1e-4   # kg m^2
  gear_ratio: 20          # motor turns per actuator turn (prismatic actuators: rad per m of travel)
# or: motors: {catalogue: FILE, model: NAME, gear_ratio: 20}   (FILE: a CSV like the shipped one, or 'builtin')
```
"""

from __future__ import annotations

import math

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

# aluminium; a link without a section is a round tube of DEFAULT_TUBE_MM (the stiffness model's default)
DEFAULT_DENSITY = 2700.0
DEFAULT_TUBE_MM = (40.0, 3.0)
MOTOR_RATINGS = ("peak_torque", "rated_torque", "max_speed", "rotor_inertia")


def _finite_nonnegative(name: str, v: float) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
        raise ValueError(f"{name}: must be a finite number >= 0, got {v!r}")
    return float(v)


class DynamicsConfig(BaseModel):
    model_config = ConfigDict(extra="forbid")

    masses: dict[str, float] | None = Field(
        None, description="kg per body of each named group; given, it is the whole mass model (others massless)")
    density: float = Field(DEFAULT_DENSITY, description="kg/m^3 of the tube links when masses is not given")

    @field_validator("masses", mode="before")
    @classmethod
    def _masses_ok(cls, v):
        if v is None:
            return v
        if not isinstance(v, dict):
            raise ValueError(f"expected a mapping {{group: kg}}, got {v!r}")
        return {str(k): _finite_nonnegative(str(k), m) for k, m in v.items()}

    @field_validator("density")
    @classmethod
    def _density_ok(cls, v):
        if not (math.isfinite(v) and v > 0):
            raise ValueError(f"must be a finite number > 0 (kg/m^3), got {v}")
        return v


# the bounds key of a searched gear ratio (``bounds: {gear_ratio: [lo, hi]}``): one ratio shared by every actuator, a
# design variable of the optimisation that replaces motors.gear_ratio in each design's cycle (issue 29)
GEAR_RATIO = "gear_ratio"


class MotorsConfig(BaseModel):
    model_config = ConfigDict(extra="forbid")

    peak_torque: float | None = Field(None, description="N m at the motor shaft")
    rated_torque: float | None = Field(None, description="continuous torque, N m")
    max_speed: float | None = Field(None, description="rad/s at the motor shaft")
    rotor_inertia: float | None = Field(None, description="kg m^2")
    catalogue: str | None = Field(None, description="CSV file of motors, or 'builtin' (the shipped catalogue)")
    model: str | None = Field(None, description="the catalogue row")
    gear_ratio: float | list[float] = Field(..., description="per actuator (or one number): motor / joint speed")
    _row: dict | None = None  # the resolved ratings (motors.resolve)

    @field_validator("peak_torque", "rated_torque", "max_speed")
    @classmethod
    def _positive(cls, v):
        if v is not None and not (math.isfinite(v) and v > 0):
            raise ValueError(f"must be a finite number > 0, got {v}")
        return v

    @field_validator("rotor_inertia")
    @classmethod
    def _inertia(cls, v):
        return None if v is None else _finite_nonnegative("rotor_inertia", v)

    @field_validator("gear_ratio")
    @classmethod
    def _ratio(cls, v):
        for x in [v] if isinstance(v, (int, float)) else v:
            if not (math.isfinite(x) and x > 0):
                raise ValueError(f"must be finite and > 0, got {x}")
        return v

    @model_validator(mode="after")
    def _one_of(self):
        inline = [getattr(self, k) for k in MOTOR_RATINGS]
        if self.catalogue is not None or self.model is not None:
            if self.catalogue is None or self.model is None:
                raise ValueError("give catalogue and model together")
            given = [k for k, v in zip(MOTOR_RATINGS, inline, strict=True) if v is not None]
            if given:
                raise ValueError(f"{given[0]}: not with a catalogue (the row gives it)")
            return self
        missing = [k for k, v in zip(MOTOR_RATINGS, inline, strict=True) if v is None]
        if missing:
            raise ValueError(f"{missing[0]}: missing (give every rating, or catalogue and model)")
        return self
