"""Shared check of a mechanism's closed-form column intervals (Mechanism.interval_kernel) against the reach kernel
they replace, point by point (tests/test_*_intervals.py)."""

from collections import Counter

import numpy as np
from numba import njit

K = 8  # rows of the kernels' out array in the checks; no mechanism needs more than 4


@njit
def reach_column(kernel, p, x, y, zs):
    """kernel(p, x, y, z) slot 0 at each z of zs (kernels whose column axis is their last argument)."""
    out = np.empty(1)
    r = np.empty(zs.shape[0])
    for i in range(zs.shape[0]):
        kernel(p, x, y, zs[i], out)
        r[i] = out[0]
    return r


def check_sorted(out, k, zlo, zhi):
    """out[:k] sorted and disjoint (strictly: a gap between neighbours), each a <= b, inside [zlo, zhi]."""
    iv = out[:k]
    assert np.all(iv[:, 0] <= iv[:, 1])
    assert np.all(iv[1:, 0] > iv[:-1, 1])
    if k:
        assert zlo <= iv[0, 0] and iv[-1, 1] <= zhi


def check_column(interval, reach_at, p, x, y, zlo, zhi, zs, tol, counts: Counter, kmax: int = 4) -> np.ndarray:
    """One column (x, y) over [zlo, zhi] of ``interval(p, x, y, zlo, zhi, out) -> k`` against ``reach_at(z array)``
    (the reach kernel's slot 0 along the column):

    - 0 <= k <= kmax and the intervals sorted, disjoint and inside the window (check_sorted);
    - at the sample heights ``zs`` a point lies in an interval exactly where the reach kernel is >= 0, except
      within ``tol`` of an interval end (rounding of the roots against the kernel's own arithmetic);
    - every end inside (zlo, zhi) is a crossing to 2 tol: reachable 2 tol inside, unreachable 2 tol outside (random
      points alone would miss an end off by less than about the window / len(zs));
    - with k >= 2, an out array of k - 1 rows gives -1.

    Adds to ``counts``: points, reachable, excused (mismatches within tol of an end), ends, empty (k = 0), whole
    (the window itself), split (k >= 2). Returns the intervals, (k, 2)."""
    out = np.empty((K, 2))
    k = interval(p, x, y, zlo, zhi, out)
    assert 0 <= k <= kmax, (x, y, k)
    check_sorted(out, k, zlo, zhi)
    iv = out[:k].copy()
    inside = np.any((iv[:, :1] <= zs) & (zs <= iv[:, 1:]), axis=0)
    reachable = reach_at(zs) >= 0.0
    near = np.min(np.abs(zs[:, None] - iv.ravel()), axis=1) < tol if k else np.zeros(len(zs), bool)
    bad = (inside != reachable) & ~near
    assert not bad.any(), (x, y, iv, zs[bad][:5])
    gaps = np.concatenate([[np.inf], iv[1:, 0] - iv[:-1, 1], [np.inf]])
    for m, (a, b) in enumerate(iv):
        if b - a > 4 * tol:
            assert (reach_at(np.array([a + 2 * tol, b - 2 * tol])) >= 0.0).all(), (x, y, iv)
        for end, outside, gap in ((a, a - 2 * tol, gaps[m]), (b, b + 2 * tol, gaps[m + 1])):
            if zlo < end < zhi and gap > 4 * tol:
                assert reach_at(np.array([outside]))[0] < 0.0, (x, y, iv, end)
                counts["ends"] += 1
    counts["points"] += len(zs)
    counts["reachable"] += int(reachable.sum())
    counts["excused"] += int(((inside != reachable) & near).sum())
    counts["empty"] += k == 0
    counts["whole"] += k == 1 and iv[0, 0] == zlo and iv[0, 1] == zhi
    if k >= 2:
        counts["split"] += 1
        assert interval(p, x, y, zlo, zhi, np.empty((k - 1, 2))) == -1
    return iv
