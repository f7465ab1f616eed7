"""Helpers of the closed-form column-interval kernels (Mechanism.interval_kernel): sorting the few candidate
heights where a column's reachability can change, and collecting the reachable pieces between them."""

from numba import njit

from scalesynth.kernels.flags import FASTMATH


@njit(cache=True, fastmath=FASTMATH)
def sort_span(a, start, stop):
    """Insertion sort of a[start:stop] in place (a handful of candidate heights)."""
    for i in range(start + 1, stop):
        v = a[i]
        j = i - 1
        while j >= start and a[j] > v:
            a[j + 1] = a[j]
            j -= 1
        a[j + 1] = v


@njit(cache=True, fastmath=FASTMATH)
def add_piece(out, k, a, b):
    """Add the reachable piece [a, b] to the k sorted intervals in out[:k] (float64, (K, 2)), pieces coming in
    order: it extends the last interval when that ends at a (a candidate height between two reachable pieces),
    else it starts a new one. Returns the new k, or -1 when out has no row left."""
    if k > 0 and out[k - 1, 1] == a:
        out[k - 1, 1] = b
        return k
    if k == out.shape[0]:
        return -1
    out[k, 0] = a
    out[k, 1] = b
    return k + 1
