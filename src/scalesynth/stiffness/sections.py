"""Material, link sections, actuator stiffness and load: the stiffness options every modelled mechanism shares.

Defaults: aluminium, E = 70 GPa, Poisson's ratio 0.33 (G = E / (2 (1 + nu)) = 26.3 GPa); every link a round tube of
40 mm outer diameter and 3 mm wall, written in the mechanism's length unit (``[40, 3]`` for mm, ``[0.04, 0.003]``
for m); ``sections`` overrides the tube per link group (``{arm: [60, 4]}``). Forces in N. A mechanism adds its own
actuator stiffness default and load direction (its gravity direction) through :func:`stiffness_options`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from scalesynth.declarations import Option
from scalesynth.errors import InvalidParameter
from scalesynth.names import hint

# Every positive stiffness input (Young's modulus, tube diameter and wall, actuator stiffness) lies in
# [SMALLEST, MAX_MAGNITUDE]: the kernels divide by the rigidities (L / EA, L^3 / 3 EI, 1 / k) and multiply the
# compliances together and by lengths up to MAX_MAGNITUDE, so a tiny positive value (5e-324, a 1e-300 tube whose
# d^4 underflows to 0) would divide by zero or overflow there. 1e-12 is far below any physical value in any unit.
SMALLEST = 1e-12
# a tube wall below this share of its diameter: d^4 - (d - 2 t)^4 loses all its digits (0 for t < ulp(d))
MIN_WALL_SHARE = 1e-9
GPA_TO_N_PER_LENGTH2 = {"mm": 1e3, "cm": 1e5, "dm": 1e7, "m": 1e9}  # 1 GPa = 1e3 N/mm^2 = 1e9 N/m^2
MM_IN = {"mm": 1.0, "cm": 0.1, "dm": 0.01, "m": 1e-3}


@dataclass(frozen=True)
class Section:
    """Axial, bending and torsional rigidity of a link: EA (N), EI (N * length^2, both bending axes: a round tube),
    GJ (N * length^2)."""

    EA: float
    EI: float
    GJ: float


def stiffness_options(length_unit: str, actuator_stiffness: float, actuator_doc: str, load: list[float],
                      load_doc: str) -> tuple[Option, ...]:
    """The shared stiffness options of a mechanism whose lengths are in ``length_unit`` ('mm', 'cm', 'dm' or 'm')."""
    mm = MM_IN[length_unit]
    return (
        Option("youngs_modulus", 70.0, "stiffness: Young's modulus of every link, GPa (aluminium)"),
        Option("poisson_ratio", 0.33, "stiffness: Poisson's ratio (G = E / (2 (1 + nu)))"),
        Option("tube", [40.0 * mm, 3.0 * mm],
               f"stiffness: [outer diameter, wall] of the round-tube links, {length_unit} (40 x 3 mm)"),
        Option("sections", {}, "stiffness: per link group {group: [outer diameter, wall]} overriding tube"),
        Option("actuator_stiffness", actuator_stiffness, "stiffness: " + actuator_doc),
        Option("load", list(load), "stiffness: force on the platform, N, " + load_doc),
    )


def _number(name: str, value: Any) -> float:
    """A float from a number or a numeric string (YAML 1.1 reads 5e8 as a string)."""
    if isinstance(value, str):
        try:
            return float(value)
        except ValueError:
            pass
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InvalidParameter(f"options.{name}: expected a number, got {value!r}")
    return float(value)


def _positive(name: str, value: Any) -> float:
    """A stiffness input in [SMALLEST, MAX_MAGNITUDE] (see SMALLEST: the arithmetic it enters)."""
    from scalesynth.declarations import MAX_MAGNITUDE

    v = _number(name, value)
    if not (v > 0 and math.isfinite(v)):
        raise InvalidParameter(f"options.{name}: must be a finite number > 0, got {value!r}")
    if not SMALLEST <= v <= MAX_MAGNITUDE:
        raise InvalidParameter(f"options.{name}: {v:g} is outside [{SMALLEST:g}, {MAX_MAGNITUDE:g}], the range the "
                               "stiffness kernels compute with (their divisions and products stay finite there)")
    return v


def _tube(name: str, value: Any) -> list[float]:
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise InvalidParameter(f"options.{name}: expected [outer diameter, wall], got {value!r}")
    d = _positive(f"{name}[0]", value[0])
    t = _positive(f"{name}[1]", value[1])
    if t > d / 2:
        raise InvalidParameter(f"options.{name}: wall {t:g} is more than half the outer diameter {d:g}")
    if t < MIN_WALL_SHARE * d:
        raise InvalidParameter(f"options.{name}: wall {t:g} is below {MIN_WALL_SHARE:g} of the outer diameter {d:g} "
                               "(the section's area and inertia would round to 0)")
    return [d, t]


def check_stiffness_options(options: dict[str, Any], dim: int, groups: tuple[str, ...]) -> None:
    """Validate (and normalise in place) the shared stiffness options; raise InvalidParameter naming the field."""
    options["youngs_modulus"] = _positive("youngs_modulus", options["youngs_modulus"])
    nu = _number("poisson_ratio", options["poisson_ratio"])
    if not -1.0 < nu < 0.5:
        raise InvalidParameter(
            f"options.poisson_ratio: must be a number in (-1, 0.5), got {options['poisson_ratio']!r}")
    options["poisson_ratio"] = nu
    options["tube"] = _tube("tube", options["tube"])
    sections = options["sections"] or {}
    if not isinstance(sections, Mapping):
        raise InvalidParameter(f"options.sections: expected a mapping {{group: [diameter, wall]}}, got {sections!r}")
    for key in sections:
        if key not in groups:
            raise InvalidParameter(f"options.sections.{key}: unknown link group " + hint(str(key), groups))
    options["sections"] = {k: _tube(f"sections.{k}", v) for k, v in sections.items()}
    options["actuator_stiffness"] = _positive("actuator_stiffness", options["actuator_stiffness"])
    load = options["load"]
    if not isinstance(load, (list, tuple)) or len(load) != dim:
        raise InvalidParameter(f"options.load: expected {dim} force components (N), got {load!r}")
    out = [_number(f"load[{i}]", v) for i, v in enumerate(load)]
    for i, v in enumerate(out):
        if not math.isfinite(v):
            raise InvalidParameter(f"options.load[{i}]: expected a finite number (N), got {load[i]!r}")
    options["load"] = out


def tube_section(options: Mapping[str, Any], group: str, length_unit: str) -> Section:
    """EA, EI, GJ of link group ``group`` (a round tube of the options' material), in N and N * length^2."""
    d, t = options["sections"].get(group, options["tube"])
    e = options["youngs_modulus"] * GPA_TO_N_PER_LENGTH2[length_unit]
    g = e / (2.0 * (1.0 + options["poisson_ratio"]))
    di = d - 2.0 * t
    area = math.pi / 4.0 * (d * d - di * di)
    inertia = math.pi / 64.0 * (d**4 - di**4)
    return Section(EA=e * area, EI=e * inertia, GJ=g * 2.0 * inertia)


def check_positive_option(options: dict[str, Any], name: str) -> None:
    """Validate (and normalise in place) a mechanism's own stiffness option that must be a finite number > 0
    (e.g. a second actuator stiffness); raise InvalidParameter naming it."""
    options[name] = _positive(name, options[name])
