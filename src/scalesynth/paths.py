"""Task paths: polylines of task points, their validation (task.path, cycle.path) and sampling by arc length."""

from __future__ import annotations

import math
import sys
from collections.abc import Sequence

import numpy as np


def check_polyline(points: list[list[float]], dims: tuple[int, ...] | None = None, closed: bool = False
                   ) -> list[list[float]]:
    """The one validator of a polyline config value (task.path, cycle.path); raise ValueError with the message a
    pydantic field validator turns into '<field>: <message>'. At least 2 points, all with the same number of
    coordinates (one of ``dims`` if given), finite and within +-MAX_MAGNITUDE (the entry named by its index);
    ``closed`` (a cycle): not all points equal, so the loop has a length."""
    from scalesynth.mechanisms.base import MAX_MAGNITUDE

    if len(points) < 2:
        raise ValueError(f"need at least 2 points, got {len(points)}")
    n = {len(p) for p in points}
    if len(n) != 1 or (dims is not None and next(iter(n)) not in dims):
        allowed = "" if dims is None else " " + " or ".join(str(d) for d in dims)
        raise ValueError(f"every point needs the same{allowed} number of coordinates")
    for i, p in enumerate(points):
        for c in p:
            if not math.isfinite(c):
                raise ValueError(f"{i}: coordinates must be finite, got {c}")
            if abs(c) > MAX_MAGNITUDE:
                raise ValueError(f"{i}: {c:g} is beyond +-{MAX_MAGNITUDE:g}, the largest magnitude scalesynth "
                                 "computes with (products of such values overflow)")
    if closed and all(p == points[0] for p in points):
        raise ValueError("all points coincide: the path has no length")
    _check_segment_lengths(points, closed)
    return points


def _check_segment_lengths(points: list[list[float]], closed: bool) -> None:
    """Every segment between two different points has a length that is a normal float as the code computes it
    (np.linalg.norm of the difference): points a denormal apart give a difference whose square underflows, a
    segment of length 0 that is dropped or divided by (cycle.trajectory, sample_path)."""
    pts = np.asarray(points, dtype=float)
    if closed:
        pts = np.vstack([pts, pts[:1]])
    diff = np.diff(pts, axis=0)
    length = np.linalg.norm(diff, axis=1)
    moving = np.any(diff != 0.0, axis=1)
    short = np.flatnonzero(moving & ~(length >= sys.float_info.min))
    if short.size:
        i = int(short[0])
        j = (i + 1) % (len(pts) - 1) if closed else i + 1
        raise ValueError(f"{j}: point {j} is only {float(np.max(np.abs(diff[i]))):.3g} from point {i}, so close "
                         "that the segment's squared length underflows to 0 (give equal points or points further "
                         "apart)")


def sample_path(points: Sequence[Sequence[float]], samples: int) -> np.ndarray:
    """``samples`` points evenly spaced by arc length along a polyline (ends included), padded to 3 columns."""
    pts = np.asarray(points, dtype=float)
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    if s[-1] == 0.0:
        out = np.repeat(pts[:1], samples, axis=0)
    else:
        t = np.linspace(0.0, s[-1], samples)
        out = np.stack([np.interp(t, s, pts[:, a]) for a in range(pts.shape[1])], axis=1)
    return np.pad(out, ((0, 0), (0, 3 - out.shape[1])))
