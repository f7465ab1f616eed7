"""Link geometry of a mechanism at one pose: named capsules (segment + radius) and which bodies share a joint.

Every mechanism's :meth:`~scalesynth.mechanisms.base.Mechanism.link_geometry` returns a :class:`LinkGeometry`
in the mechanism frame (3-D points in the design's length unit; planar mechanisms have z = 0). A body (base,
each moving link, platform) is one or more :class:`Segment` s with the same ``body`` name; two bodies are
*adjacent* when a joint connects them. Clearance (``scalesynth.cycle.clearance``) is measured between the
capsules of non-adjacent bodies only: adjacent capsules always overlap at their common joint. The same
geometry is what a drawing of the robot uses.

Radii come from the mechanism option ``link_radius``: a number (every body) or a mapping body -> radius,
bodies it does not name keeping the mechanism's default (each mechanism states its defaults).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from scalesynth.errors import InvalidParameter
from scalesynth.mechanisms.base import Field
from scalesynth.names import hint

# the per-voxel field of the mechanisms whose field kernels compute their capsules' clearance
CLEARANCE_FIELD = Field(
    "clearance", "{length}", "smallest distance between the capsules of links that share no joint, minus their "
    "radii (< 0: the links interfere); radii from options.link_radius", "max", (-math.inf, math.inf),
)


@dataclass(frozen=True)
class Segment:
    """One capsule: the segment a -> b (3 floats each, length unit) swept by a ball of ``radius``.

    ``name`` identifies the segment (e.g. 'arm1'), ``body`` the rigid body it belongs to (several segments of
    one body, e.g. the sides of a platform triangle, share a body name), ``group`` the body's kind (the body name
    without its number). A zero-length segment is a ball. ``carries_mass``: whether the dynamics spreads its
    body's mass over this segment (False for a parallelogram's short end links: its mass sits on the two long
    bars; ``scalesynth.dynamics.bodies``).
    """

    name: str
    body: str
    a: np.ndarray
    b: np.ndarray
    radius: float
    carries_mass: bool = True

    @property
    def group(self) -> str:
        """The body's group: its name without a trailing number ('forearm2' -> 'forearm', 'arm1' -> 'arm'), the
        key a per-group property (mass, section) is given under."""
        return self.body.rstrip("0123456789")


@dataclass(frozen=True)
class LinkGeometry:
    """The capsules of a mechanism at one pose and the pairs of adjacent bodies (sharing a joint)."""

    segments: tuple[Segment, ...]
    adjacent: frozenset[frozenset[str]]

    @property
    def bodies(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(s.body for s in self.segments))

    def checked_pairs(self) -> list[tuple[int, int]]:
        """Index pairs (i < j) of segments whose clearance counts: different, non-adjacent bodies."""
        out = []
        segs = self.segments
        for i in range(len(segs)):
            for j in range(i + 1, len(segs)):
                bi, bj = segs[i].body, segs[j].body
                if bi != bj and frozenset((bi, bj)) not in self.adjacent:
                    out.append((i, j))
        return out

    def as_arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(a, b, radius) stacked: shapes (n, 3), (n, 3), (n,)."""
        return (
            np.array([s.a for s in self.segments], dtype=float).reshape(-1, 3),
            np.array([s.b for s in self.segments], dtype=float).reshape(-1, 3),
            np.array([s.radius for s in self.segments], dtype=float),
        )


def adjacency(pairs: Iterable[tuple[str, str]]) -> frozenset[frozenset[str]]:
    """The adjacency set of body-name pairs."""
    return frozenset(frozenset(p) for p in pairs)


def kernel_pairs(segment_bodies: Sequence[str], adjacent: frozenset[frozenset[str]]) -> np.ndarray:
    """Index pairs (n, 2) int64, i < j, of the segments whose clearance counts (different bodies that share no
    joint: the rule of LinkGeometry.checked_pairs), for a field kernel's fixed list of capsules whose bodies are
    ``segment_bodies`` (in link_geometry's order)."""
    b = list(segment_bodies)
    return np.array([(i, j) for i in range(len(b)) for j in range(i + 1, len(b))
                     if b[i] != b[j] and frozenset((b[i], b[j])) not in adjacent], dtype=np.int64).reshape(-1, 2)


@dataclass(frozen=True)
class SegmentPoints:
    """Segment endpoints at m poses, as a mechanism's vectorised ``link_endpoints`` gives them: the distinct moving
    points once each, coordinate-major, and which point each segment end is.

    ``points`` (P, 3, m): the moving points (length unit); ``index`` (s, 2) int: the point of each segment's a and
    b, -1 for a fixed end; ``fixed`` (s, 2, 3): the fixed ends' coordinates (NaN at moving ends). A joint shared
    by several segments is one point (its derivatives are taken once); a fixed end moves with no pose.
    """

    points: np.ndarray
    index: np.ndarray
    fixed: np.ndarray

    def segments(self) -> np.ndarray:
        """Every segment's endpoints (s, 2, 3, m): LinkGeometry.as_arrays' a and b at each pose."""
        m = self.points.shape[-1]
        out = np.empty((*self.index.shape, 3, m))
        moving = self.index >= 0
        out[moving] = self.points[self.index[moving]]
        out[~moving] = self.fixed[~moving][:, :, None]
        return out


def segment_points(ends: Sequence[tuple[Any, Any]], m: int) -> SegmentPoints:
    """SegmentPoints at m poses from a list of (a, b) per segment in link_geometry's order. A point is an array
    (3,) or 3 numbers (fixed), an array (m, 3), or 3 coordinates each a number or an array (m,) (moving); the
    same Python object given for several ends is one point."""
    index = np.full((len(ends), 2), -1, dtype=np.int64)
    fixed = np.full((len(ends), 2, 3), np.nan)
    seen: dict[int, int] = {}
    moving: list[Any] = []
    for i, pair in enumerate(ends):
        for j, pt in enumerate(pair):
            if isinstance(pt, np.ndarray) and pt.ndim == 1 or all(np.ndim(c) == 0 for c in pt):
                fixed[i, j] = [float(c) for c in pt]
                continue
            if id(pt) not in seen:
                seen[id(pt)] = len(moving)
                moving.append(pt)
            index[i, j] = seen[id(pt)]
    points = np.empty((len(moving), 3, m))
    for k, pt in enumerate(moving):
        if isinstance(pt, np.ndarray):
            points[k] = pt.T
        else:
            for c in range(3):
                points[k, c] = pt[c]
    return SegmentPoints(points, index, fixed)


def segment_ends(mech, design, options, poses: np.ndarray, q: np.ndarray) -> np.ndarray | None:
    """link_geometry's segment endpoints (m, s, 2, 3), length unit, at poses (m, k) with joint values q
    (m, n_joints), one ``mech.link_geometry`` per pose: the plain path beside a mechanism's vectorised
    ``link_endpoints``. NaN rows where q is not finite; None where no row is (the segment count is then unknown)."""
    out = None
    for s, pose in enumerate(poses):
        if not np.all(np.isfinite(q[s])):
            continue
        a, b, _ = mech.link_geometry(design, options, pose, q[s]).as_arrays()
        if out is None:
            out = np.full((len(poses), len(a), 2, 3), np.nan)
        out[s, :, 0], out[s, :, 1] = a, b
    return out


def point(*coords: float) -> np.ndarray:
    """A 3-D point from 2 or 3 coordinates (planar points get z = 0)."""
    c = [float(v) for v in coords]
    return np.array(c + [0.0] * (3 - len(c)))


def check_radius_option(options: dict[str, Any], bodies: Iterable[str]) -> None:
    """Validate ``options['link_radius']`` in place: null, a number >= 0, or a mapping of known bodies to numbers
    >= 0; raise InvalidParameter naming the entry."""
    value = options.get("link_radius")
    if value is None:
        return
    known = tuple(bodies)
    items = value.items() if isinstance(value, Mapping) else [(None, value)]
    for body, r in items:
        where = "options.link_radius" + ("" if body is None else f".{body}")
        if body is not None and body not in known:
            raise InvalidParameter(f"{where}: unknown body " + hint(str(body), known))
        if isinstance(r, bool) or not isinstance(r, (int, float)) or not math.isfinite(r) or r < 0:
            raise InvalidParameter(f"{where}: expected a length >= 0, got {r!r}")


def radii(options: Mapping[str, Any], defaults: Mapping[str, float]) -> dict[str, float]:
    """Radius per body: ``defaults`` overlaid by the ``link_radius`` option (a number or a mapping)."""
    value = options.get("link_radius")
    out = dict(defaults)
    if value is None:
        return out
    if isinstance(value, Mapping):
        out.update({k: float(v) for k, v in value.items()})
        return out
    return {k: float(value) for k in out}


def mirrored_radii(options: Mapping[str, Any], defaults: Mapping[str, float], pairs: Iterable[tuple[str, str]]) -> bool:
    """Whether every pair of bodies that a mirror symmetry swaps has the same capsule radius (``radii``)."""
    rad = radii(options, defaults)
    return all(rad[a] == rad[b] for a, b in pairs)


def check_flag_option(options: dict[str, Any], name: str) -> None:
    """A boolean option (true/false); raise InvalidParameter naming it otherwise."""
    if not isinstance(options.get(name), bool):
        raise InvalidParameter(f"options.{name}: expected true or false, got {options.get(name)!r}")
