"""Task paths: polylines of task points sampled evenly by arc length (plain NumPy)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


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
