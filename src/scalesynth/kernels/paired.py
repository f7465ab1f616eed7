"""A field kernel evaluated at one point per packed design: row i of ``params`` at ``pts[i]``.

For per-sample evaluations where the packed parameters change along a sequence of points (the deflection along a
cycle re-packs the load at every sample; the cycle metrics of many designs evaluate each design at its own
samples). Bound per field kernel and disk-cached like the grid kernels (``kernels.bind``).
"""

from __future__ import annotations

import numpy as np

from scalesynth.kernels.bind import bind
from scalesynth.kernels.flags import FASTMATH

FIELD_KERNEL = None  # bound by kernels.bind
N_FIELDS = 0


def _paired_points_fields(params, pts):
    """Template of paired_points_fields."""
    n_fields = N_FIELDS
    n = pts.shape[0]
    out = np.empty((n, n_fields))
    cell = np.empty(n_fields)
    for i in range(n):
        FIELD_KERNEL(params[i], pts[i, 0], pts[i, 1], pts[i, 2], cell)
        out[i, :] = cell
    return out


def paired_points_fields(field_kernel, n_fields: int, params: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Every field of packed design ``params[i]`` at point ``pts[i]``: params (n, k), pts (n, 3) -> (n, n_fields);
    field 0 (LCI) -1 where unreachable."""
    return bind(_paired_points_fields, field_kernel, n_fields, fastmath=FASTMATH)(
        np.ascontiguousarray(params, dtype=float), np.ascontiguousarray(pts, dtype=float))
