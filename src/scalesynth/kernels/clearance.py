"""Numba segment-segment distance for the per-voxel ``clearance`` field of the field kernels.

Scalar twin of :func:`scalesynth.cycle.clearance.segment_distance` (the NumPy version the cycle analysis uses; the
tests compare the two): closest points of two segments with clamped parameters (C. Ericson, *Real-Time
Collision Detection*, §5.1.9). Zero-length segments are points.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from scalesynth.kernels.flags import FASTMATH

_EPS = 1e-300


@njit(cache=True, fastmath=FASTMATH)
def _clamp01(v):
    return 0.0 if v < 0.0 else (1.0 if v > 1.0 else v)


@njit(cache=True, fastmath=FASTMATH)
def segment_distance(px, py, pz, qx, qy, qz, ux, uy, uz, vx, vy, vz):
    """Distance between segments P-Q and U-V (3-D points given by coordinates)."""
    d1x, d1y, d1z = qx - px, qy - py, qz - pz
    d2x, d2y, d2z = vx - ux, vy - uy, vz - uz
    rx, ry, rz = px - ux, py - uy, pz - uz
    a = d1x * d1x + d1y * d1y + d1z * d1z
    e = d2x * d2x + d2y * d2y + d2z * d2z
    f = d2x * rx + d2y * ry + d2z * rz
    if a <= _EPS and e <= _EPS:
        s = 0.0
        t = 0.0
    elif a <= _EPS:
        s = 0.0
        t = _clamp01(f / e)
    else:
        c = d1x * rx + d1y * ry + d1z * rz
        if e <= _EPS:
            t = 0.0
            s = _clamp01(-c / a)
        else:
            b = d1x * d2x + d1y * d2y + d1z * d2z
            denom = a * e - b * b
            s = _clamp01((b * f - c * e) / denom) if denom > 1e-14 * a * e else 0.0
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = _clamp01(-c / a)
            elif t > 1.0:
                t = 1.0
                s = _clamp01((b - c) / a)
    dx = px + s * d1x - (ux + t * d2x)
    dy = py + s * d1y - (uy + t * d2y)
    dz = pz + s * d1z - (uz + t * d2z)
    return math.sqrt(dx * dx + dy * dy + dz * dz)


@njit(cache=True, fastmath=FASTMATH)
def planar_capsule_gap(ax, ay, bx, by, ra, cx, cy, dx, dy, rc):
    """Distance between the planar capsules A-B (radius ra) and C-D (radius rc): segment distance minus radii."""
    return segment_distance(ax, ay, 0.0, bx, by, 0.0, cx, cy, 0.0, dx, dy, 0.0) - ra - rc


@njit(cache=True, fastmath=FASTMATH)
def put_segment(seg, k, ax, ay, az, bx, by, bz):
    """Row k of a (n, 6) capsule array: the segment (ax, ay, az) -> (bx, by, bz)."""
    seg[k, 0] = ax
    seg[k, 1] = ay
    seg[k, 2] = az
    seg[k, 3] = bx
    seg[k, 4] = by
    seg[k, 5] = bz


@njit(cache=True, fastmath=FASTMATH)
def min_capsule_gap(seg, pairs, radius):
    """Smallest segment distance minus the two radii over the index pairs (m, 2) of the capsules seg (n, 6) with
    per-segment radii ``radius`` (n,); +inf without pairs."""
    gap = math.inf
    for k in range(pairs.shape[0]):
        i = pairs[k, 0]
        j = pairs[k, 1]
        d = segment_distance(seg[i, 0], seg[i, 1], seg[i, 2], seg[i, 3], seg[i, 4], seg[i, 5],
                             seg[j, 0], seg[j, 1], seg[j, 2], seg[j, 3], seg[j, 4], seg[j, 5])
        gap = min(gap, d - radius[i] - radius[j])
    return gap


# ----- capsules packed as data (the described mechanisms' clearance field; mechanisms/describe/bodies.py) ----------
# A block of the packed vector from ``off``: [n_seg, n_pairs, n_seg records of SEG_STRIDE, n_pairs index pairs]. A
# record is two end points and a radius; an end point is (anchor, cx, cy, cz): the constant c plus the moving point
# the anchor names: ANCHOR_FIXED none, ANCHOR_PLATFORM the platform centre P, i >= 0 leg i's elbow or carriage E_i
# (the row i of the kernel's ``elbows`` array). Every capsule of a described 3T or 6-DOF mechanism is of that form.
ANCHOR_FIXED = -1.0
ANCHOR_PLATFORM = -2.0
END_STRIDE = 4
SEG_STRIDE = 2 * END_STRIDE + 1  # two end points, then the radius


@njit(cache=True, fastmath=FASTMATH, inline="always")
def _end(p, k, elbows, x, y, z):
    """The end point whose record starts at p[k] (the comment above)."""
    a = p[k]
    if a == ANCHOR_FIXED:
        return p[k + 1], p[k + 2], p[k + 3]
    if a == ANCHOR_PLATFORM:
        return p[k + 1] + x, p[k + 2] + y, p[k + 3] + z
    i = int(a)
    return p[k + 1] + elbows[i, 0], p[k + 2] + elbows[i, 1], p[k + 3] + elbows[i, 2]


@njit(cache=True, fastmath=FASTMATH)
def packed_capsule_gap(p, off, elbows, x, y, z):
    """Smallest segment distance minus the two radii over the packed pairs of the packed capsules (block at p[off],
    the comment above) with the platform centre at P = (x, y, z) and the legs' moving points ``elbows`` (n_legs, 3);
    +inf without pairs. Each capsule's end points are placed once, then min_capsule_gap's loop."""
    n_seg = int(p[off])
    n_pairs = int(p[off + 1])
    seg0 = off + 2
    pair0 = seg0 + n_seg * SEG_STRIDE
    seg = np.empty((n_seg, 7))
    for s in range(n_seg):
        k = seg0 + s * SEG_STRIDE
        seg[s, 0], seg[s, 1], seg[s, 2] = _end(p, k, elbows, x, y, z)
        seg[s, 3], seg[s, 4], seg[s, 5] = _end(p, k + END_STRIDE, elbows, x, y, z)
        seg[s, 6] = p[k + 2 * END_STRIDE]
    gap = math.inf
    for k in range(n_pairs):
        i = int(p[pair0 + 2 * k])
        j = int(p[pair0 + 2 * k + 1])
        d = segment_distance(seg[i, 0], seg[i, 1], seg[i, 2], seg[i, 3], seg[i, 4], seg[i, 5],
                             seg[j, 0], seg[j, 1], seg[j, 2], seg[j, 3], seg[j, 4], seg[j, 5])
        gap = min(gap, d - seg[i, 6] - seg[j, 6])
    return gap
