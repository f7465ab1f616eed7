"""Numba settings used by every kernel, in one place.

fastmath is limited to flags that keep NaN/inf semantics (no ``nnan``/``ninf``): unreachable voxels are
signalled by sentinel values and must stay detectable, and limits may be +-inf.
"""

FASTMATH = {"nsz", "arcp", "contract", "afn"}
