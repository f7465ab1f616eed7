"""Human labels with units for result columns, fields and task axes: ``volume_m3`` -> ``V [m³]``,
``mean_sigma_min_mm_per_rad`` -> ``mean σ_min [mm/rad]``, ``theta`` -> ``θ [rad]``.

Names and units come from the metric catalogue (``scalesynth.metrics``) and the mechanism's fields and task axes;
this module only turns them into text for axes, colour bars and hover labels.
"""

from __future__ import annotations

import re

_GREEK = {"alpha": "α", "beta": "β", "gamma": "γ", "theta": "θ", "psi": "ψ", "phi": "φ", "sigma": "σ"}
_SUPER = str.maketrans("0123456789", "⁰¹²³⁴⁵⁶⁷⁸⁹")

# the literature's short names of the LCI statistics; other names come from the catalogue, made readable
_NAMES = {
    "gci": "GCI",
    "fci": "FCI",
    "min_lci": "min LCI",
    "max_lci": "max LCI",
    "lci": "LCI",
    "m_minus_n": "m − n",
    "link_length_sum": "Σ link lengths",
}
_DIMENSIONLESS_NAMES = ("gci", "fci", "min_lci", "max_lci", "lci")  # LCI statistics outside a catalogue
_PREFIXES = ("task_", "path_", "cycle_")  # families whose names are a prefix and a workspace-style name
_MEASURE = re.compile(r"^(?:(band\d+)_)?(volume|area)_([a-z0-9_]+)$")


def unit_text(suffix: str) -> str:
    """'m3' -> 'm³', 'mm_rad2' -> 'mm·rad²', 'mm/rad' -> 'mm/rad', 'mm_per_rad' -> 'mm/rad'."""
    suffix = suffix.replace("_per_", "/")
    parts = []
    for part in suffix.split("_"):
        m = re.fullmatch(r"([A-Za-z]+)(\d*)", part)
        parts.append(m.group(1) + m.group(2).translate(_SUPER) if m else part)
    return "·".join(parts)


def _pretty_name(name: str) -> str:
    """'mean_sigma_min' -> 'mean σ_min' (catalogue names of field statistics)."""
    for word, sym in (("sigma_min", "σ_min"), ("sigma_max", "σ_max")):
        name = name.replace(word, sym)
    return name.replace("_", " ").replace("σ min", "σ_min").replace("σ max", "σ_max")


DIMENSIONLESS = "[-]"  # what an explicit label (report.html) writes for a quantity without a unit


def parameter_unit(unit: str, length_unit: str) -> str:
    """A design parameter's (or derived column's) unit text: 'length' -> the config's length unit, 'angle' ->
    'rad', '1' -> '' (dimensionless), otherwise the text with {length} filled in."""
    if unit == "length":
        return length_unit
    if unit == "angle":
        return "rad"
    return "" if unit in ("1", "") else unit.replace("{length}", length_unit)


def labeller(cfg, explicit: bool = False):
    """A function column -> label for a run config, the one place that names result columns with their units:
    the metric catalogue's units for every metric column, the mechanism's for its design parameters and derived
    columns. ``explicit``: a dimensionless quantity says so ('GCI [-]'), so that every axis carries a unit
    (report.html)."""
    from scalesynth.metrics import catalogue

    n_bands = len(cfg.dexterity.band_edges) - 1
    length = cfg.units.length
    units: dict[str, tuple[str, str]] = {}
    for m in catalogue(cfg.mech, length).values():
        for col in m.columns(n_bands):
            units[col] = (m.name, "" if m.unit in ("1", "") else unit_text(m.unit))
    for p in cfg.mech.parameters:
        units.setdefault(p.name, (p.name, unit_text(parameter_unit(p.unit, length))))
    for col, unit in cfg.mech.derived_units:
        units.setdefault(col, (col, unit_text(parameter_unit(unit, length))))

    def label(column: str) -> str:
        share = re.fullmatch(r"band\d+_share", column) is not None
        if column in units and not (share or _MEASURE.match(column)):  # measures: 'V of band 2 [m³]'
            name, unit = units[column]
            if unit:
                return f"{_name(name)} [{unit}]"
            return f"{_name(name)} {DIMENSIONLESS}" if explicit else _name(name)
        text = metric_label(column)
        known = column in units or column in _DIMENSIONLESS_NAMES or share
        return f"{text} {DIMENSIONLESS}" if explicit and known and not text.endswith("]") else text

    return label


def field_label(mech, name: str, length_unit: str, explicit: bool = False) -> str:
    """Colour-bar label of a per-voxel field: 'LCI' (``explicit``: 'LCI [-]'), 'σ_min [mm/rad]'."""
    for f in getattr(mech, "fields", ()):
        if f.name == name:
            unit = f.unit.replace("{length}", length_unit)
            base = _name(name)
            if unit in ("1", ""):
                return f"{base} {DIMENSIONLESS}" if explicit else base
            return f"{base} [{unit_text(unit)}]"
    return _name(name)


def metric_label(column: str) -> str:
    """Axis label of a result column: name and unit (dimensionless metrics have no unit)."""
    m = _MEASURE.match(column)
    if m:
        band, kind, unit = m.groups()
        sym = "V" if kind == "volume" else "A"
        if band:
            sym = f"{sym} of band {band[4:]}"
        return f"{sym} [{unit_text(unit)}]"
    m = re.fullmatch(r"band(\d+)_share", column)
    if m:
        return f"share of band {m.group(1)}"
    return _name(column)


def _name(name: str) -> str:
    """'task_gci' -> 'task GCI', 'path_min_lci' -> 'path min LCI', 'mean_sigma_min' -> 'mean σ_min'."""
    if name in _NAMES:
        return _NAMES[name]
    for prefix in _PREFIXES:
        if name.startswith(prefix) and len(name) > len(prefix):
            return f"{prefix[:-1]} {_name(name[len(prefix):])}"
    return _pretty_name(name)


def axis_name(name: str) -> str:
    return _GREEK.get(name, name)


def axis_unit(mech, axis: int, length_unit: str) -> str:
    return length_unit if mech.task_units[axis] == "length" else "rad"


def axis_label(mech, axis: int, length_unit: str) -> str:
    """'x [m]', 'θ [rad]' for task axis ``axis`` of ``mech``."""
    return f"{axis_name(mech.task_axes[axis])} [{axis_unit(mech, axis, length_unit)}]"


def same_units(mech, axes) -> bool:
    """True when the task axes all share one unit (then a plot may draw them to equal scale)."""
    return len({mech.task_units[a] for a in axes}) == 1
