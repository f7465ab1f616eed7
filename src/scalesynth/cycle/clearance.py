"""Clearance between link capsules: segment-segment distance minus the two radii.

``segment_distance`` is the closed-form closest-point computation for two segments (clamped parameters, as in
C. Ericson, *Real-Time Collision Detection*, §5.1.9), vectorised over pairs. The clearance of a
:class:`~scalesynth.mechanisms.links.LinkGeometry` is the smallest capsule distance over its checked pairs
(different, non-adjacent bodies); negative means the capsules overlap (interference).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scalesynth.mechanisms.links import LinkGeometry

_EPS = 1e-300


def segment_distance(p1: np.ndarray, q1: np.ndarray, p2: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """Distance between segments p1-q1 and p2-q2; arrays (..., 3) -> (...). Degenerate (zero-length) segments
    are points."""
    p1, q1, p2, q2 = (np.asarray(v, dtype=float) for v in (p1, q1, p2, q2))
    d1 = q1 - p1
    d2 = q2 - p2
    r = p1 - p2
    a = np.einsum("...i,...i->...", d1, d1)
    e = np.einsum("...i,...i->...", d2, d2)
    f = np.einsum("...i,...i->...", d2, r)
    c = np.einsum("...i,...i->...", d1, r)
    b = np.einsum("...i,...i->...", d1, d2)
    denom = a * e - b * b
    with np.errstate(divide="ignore", invalid="ignore"):
        # s on segment 1 minimising the distance to the infinite line 2 (any s when parallel: take 0)
        s = np.where(denom > 1e-14 * np.maximum(a * e, _EPS), np.clip((b * f - c * e) / denom, 0.0, 1.0), 0.0)
        # segment 2 a point: s is the projection of p2 on segment 1
        s = np.where(e > _EPS, s, np.clip(-c / np.where(a > _EPS, a, 1.0), 0.0, 1.0))
        s = np.where(a > _EPS, s, 0.0)
        t = np.where(e > _EPS, (b * s + f) / np.where(e > _EPS, e, 1.0), 0.0)
        # t outside [0, 1]: clamp it and recompute s for the clamped t
        t_c = np.clip(t, 0.0, 1.0)
        s_c = np.where(a > _EPS, np.clip((t_c * b - c) / np.where(a > _EPS, a, 1.0), 0.0, 1.0), 0.0)
        s = np.where(t != t_c, s_c, s)
        t = t_c
    c1 = p1 + s[..., None] * d1
    c2 = p2 + t[..., None] * d2
    return np.linalg.norm(c1 - c2, axis=-1)


@dataclass(frozen=True)
class Clearance:
    """Smallest capsule distance of a geometry (length unit; < 0: interference) and the two segments at it."""

    value: float
    pair: tuple[str, str] | None  # segment names; None when no pair is checked


def clearance(geo: LinkGeometry) -> Clearance:
    """Smallest distance between non-adjacent capsules minus their radii (+inf when nothing is checked)."""
    pairs = geo.checked_pairs()
    if not pairs:
        return Clearance(float("inf"), None)
    a, b, rad = geo.as_arrays()
    i = np.array([p[0] for p in pairs])
    j = np.array([p[1] for p in pairs])
    gaps = segment_distance(a[i], b[i], a[j], b[j]) - rad[i] - rad[j]
    k = int(np.argmin(gaps))
    return Clearance(float(gaps[k]), (geo.segments[i[k]].name, geo.segments[j[k]].name))
