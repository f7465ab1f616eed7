"""Human labels with units for result columns and task axes, e.g. ``volume_m3`` -> ``V [m³]``, ``theta`` -> ``θ [rad]``.

Interim home: once the metric catalogue (issue 10) exists, ``metric_label`` reads its name and unit; the axis
labels stay here (they come from the mechanism's task axes and units).
"""

from __future__ import annotations

import re

_GREEK = {"alpha": "α", "beta": "β", "gamma": "γ", "theta": "θ", "psi": "ψ", "phi": "φ"}
_SUPER = str.maketrans("0123456789", "⁰¹²³⁴⁵⁶⁷⁸⁹")

_NAMES = {
    "gci": "GCI",
    "fci": "FCI",
    "min_lci": "min LCI",
    "max_lci": "max LCI",
    "lci": "LCI",
    "voxels": "voxels",
    "task_coverage": "task coverage",
    "task_gci": "task GCI",
    "task_fci": "task FCI",
    "task_min_lci": "task min LCI",
    "path_min_lci": "path min LCI",
    "path_mean_lci": "path mean LCI",
    "path_reachable": "path reachable share",
    "m_minus_n": "m − n",
    "link_length_sum": "Σ link lengths",
}
_MEASURE = re.compile(r"^(?:(band\d+)_)?(volume|area)_([a-z0-9_]+)$")


def unit_text(suffix: str) -> str:
    """'m3' -> 'm³', 'mm_rad2' -> 'mm·rad²'."""
    parts = []
    for part in suffix.split("_"):
        m = re.fullmatch(r"([a-z]+)(\d*)", part)
        parts.append(m.group(1) + m.group(2).translate(_SUPER) if m else part)
    return "·".join(parts)


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
    return _NAMES.get(column, column)


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
