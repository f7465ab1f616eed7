"""The mass model: one mass per capsule segment of a mechanism's ``link_geometry``, each a thin uniform rod.

A body's mass is spread over its segments in proportion to their lengths (equally when all have length 0, e.g.
the five-bar's platform point), skipping segments with ``carries_mass`` False (a parallelogram's short end
links). ``dynamics.masses: {group: kg}`` gives each body of a group that mass (group = the body name without its
trailing digits: arm1 -> arm); a body of a group it does not name is massless. Without it every segment is a
round tube of the options' section (``sections[group]``, else ``tube``, else 40 x 3 mm) and ``dynamics.density``
(default 2700 kg/m^3, aluminium): density * area * length, the lengths taken at the cycle's first pose (a
telescoping leg keeps that mass as it extends). Fixed bodies (the base) get masses too; they never move, so
they add nothing to the forces.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from typing import Any

import numpy as np

from scalesynth.dynamics.config import DEFAULT_TUBE_MM, DynamicsConfig
from scalesynth.errors import InvalidParameter
from scalesynth.names import hint

METRES_PER_UNIT = {"m": 1.0, "dm": 0.1, "cm": 0.01, "mm": 0.001}


def group_of(body: str) -> str:
    """The mass group of a body: its name without trailing digits (arm1 -> arm, upper_arm2 -> upper_arm)."""
    return re.sub(r"\d+$", "", body) or body


def groups(geometry) -> tuple[str, ...]:
    """The mass groups of a LinkGeometry, in order."""
    return tuple(dict.fromkeys(group_of(s.body) for s in geometry.segments))


def check_groups(masses: Mapping[str, float], geometry, mech_name: str) -> None:
    """InvalidParameter naming the first group of ``masses`` that is not a body group of the geometry."""
    known = groups(geometry)
    for g in masses:
        if g not in known:
            raise InvalidParameter(f"dynamics.masses.{g}: unknown body group of {mech_name} " + hint(str(g), known))


def _tube_area_m2(options: Mapping[str, Any], group: str, length_unit: str) -> float:
    m = METRES_PER_UNIT[length_unit]
    sections = options.get("sections") or {}
    if group in sections:
        d, t = (float(v) * m for v in sections[group])
    elif options.get("tube") is not None:
        d, t = (float(v) * m for v in options["tube"])
    else:
        d, t = (v * 1e-3 for v in DEFAULT_TUBE_MM)
    di = d - 2.0 * t
    return math.pi / 4.0 * (d * d - di * di)


def segment_masses(geometry, options: Mapping[str, Any], dyn: DynamicsConfig | None, length_unit: str,
                   mech_name: str) -> np.ndarray:
    """Mass (kg) of every segment of ``geometry`` (a LinkGeometry at the reference pose), shape (n_segments,)."""
    segs = geometry.segments
    carries = np.array([s.carries_mass for s in segs], dtype=bool)
    length = np.array([float(np.linalg.norm(np.asarray(s.b) - np.asarray(s.a))) for s in segs])
    length = length * METRES_PER_UNIT[length_unit]
    out = np.zeros(len(segs))
    if dyn is None or dyn.masses is None:
        density = dyn.density if dyn is not None else DynamicsConfig().density
        for i, s in enumerate(segs):
            if carries[i]:
                out[i] = density * _tube_area_m2(options, group_of(s.body), length_unit) * length[i]
        return out
    check_groups(dyn.masses, geometry, mech_name)
    for body in geometry.bodies:
        mass = dyn.masses.get(group_of(body), 0.0)
        idx = np.array([i for i, s in enumerate(segs) if s.body == body and carries[i]], dtype=int)
        if mass == 0.0 or not idx.size:
            continue
        total = length[idx].sum()
        out[idx] = mass * (length[idx] / total if total > 0 else np.full(idx.size, 1.0 / idx.size))
    return out


def rod_energies(masses: np.ndarray, a, b, va, vb, g3) -> tuple[np.ndarray, np.ndarray]:
    """Kinetic and potential energy (J) of thin uniform rods: masses (s,), endpoints a, b and their velocities
    (..., s, 3) in m and m/s, gravity g3 (3,) m/s^2 -> (...,) each. T = m/6 (|va|^2 + va.vb + |vb|^2) (exact for a
    thin rod; spin about its own axis neglected), V = -m g . (a + b) / 2."""
    kin = masses / 6.0 * (np.sum(va * va, -1) + np.sum(va * vb, -1) + np.sum(vb * vb, -1))
    pot = -masses * ((np.asarray(a) + np.asarray(b)) @ np.asarray(g3)) / 2.0
    return kin.sum(-1), pot.sum(-1)


def reference_geometry(mech, design, options, cyc, length_unit: str):
    """link_geometry at the cycle's first vertex for a config's design and options, or None where it cannot be
    formed there (the cycle analysis then reports why)."""
    from scalesynth.cycle import config as ccfg
    from scalesynth.errors import ScalesynthError

    try:
        d, o = mech.resolve_design(design), mech.resolve_options(options)
        p0 = ccfg.vertices(cyc, mech, length_unit)[:1]
        q, _ = mech.cycle_kinematics(d, o, p0, mech.kernel_branch(o))
        if not np.all(np.isfinite(q)):
            return None
        return mech.link_geometry(d, o, p0[0], q[0])
    except (ScalesynthError, ValueError):
        return None
