"""NumPy twin of the sector evaluator (mechanisms/describe/sector.py) for the rotary and the linear Delta: the same
Gauss nodes, boundary scan and bisection, r = R (1 - s^2) substitution and z-rules, written as plain Python loops,
with the fields from the textbook kinematics of tests/naive_delta.py (np.linalg.svd per node). Only the reachable
z-intervals of a column come from the template's closed form (kernel.column_intervals, checked against the
field kernel's reach in tests/test_adaptive.py)."""

import math

import numpy as np

from naive_delta import delta_fields
from scalesynth.mechanisms.describe.kernel import column_intervals


def _intervals(p, x, y, zlo, zhi):
    out = np.empty((8, 2))
    k = column_intervals(p, x, y, zlo, zhi, out)
    assert k >= 0, "a column without closed-form intervals"
    return [(float(a), float(b)) for a, b in out[:k]]


def _boundary(p, c, s, rmax, zlo, zhi, nscan, nbisect):
    def nonempty(r):
        return sum(b - a for a, b in _intervals(p, r * c, r * s, zlo, zhi)) > 0.0

    last = next((i for i in range(nscan, -1, -1) if nonempty(rmax * i / nscan)), None)
    if last is None:
        return 0.0
    a = rmax * last / nscan
    if last == nscan:
        return a
    b = rmax * (last + 1) / nscan
    done = 0
    # a sliver about the axis (only r = 0 nonempty): halve until the bracket is within 2^-nbisect of its inner end
    while done < 64 and (done < nbisect or (last == 0 and b - a > 0.5**nbisect * a)):
        m = 0.5 * (a + b)
        a, b = (m, b) if nonempty(m) else (a, m)
        done += 1
    return 0.5 * (a + b)


def sector_volume_gci(design, options, p, angle, rmax, zlo, zhi, plan, fields=delta_fields):
    """(volume, GCI) of the whole turn from the sector [0, angle]: volume = 2 pi / angle times the Gauss sum of
    the exact column lengths; GCI = the LCI's weighted mean over the z-nodes (0 over nothing). ``fields``: the
    mechanism's NumPy twin (naive_delta.delta_fields, or linear_delta_fields for the linear Delta)."""
    xp, wp = np.polynomial.legendre.leggauss(plan.angles)
    xs, ws = np.polynomial.legendre.leggauss(plan.radii)
    volume = 0.0
    nodes, weights = [], []
    for xi, wi in zip(xp, wp, strict=True):
        phi = 0.5 * angle * (xi + 1.0)
        c, s = math.cos(phi), math.sin(phi)
        big_r = _boundary(p, c, s, rmax, zlo, zhi, plan.scan, plan.bisections)
        for xj, wj in zip(xs, ws, strict=True):
            t = 0.5 * (xj + 1.0)
            r = big_r * (1.0 - t * t)
            wcol = wi * 0.5 * angle * wj * big_r * t * r  # dphi/dxi * ds/dxj * dr/ds * r
            for a, b in _intervals(p, r * c, r * s, zlo, zhi):
                volume += wcol * (b - a)
                nq = min(plan.z_points, max(min(plan.min_z_points, plan.z_points),
                                            math.ceil(plan.z_points * (b - a) / (zhi - zlo))))
                xz, wz = np.polynomial.legendre.leggauss(nq)
                for xq, wq in zip(xz, wz, strict=True):
                    nodes.append((r * c, r * s, a + 0.5 * (b - a) * (xq + 1.0)))
                    weights.append(wcol * 0.5 * (b - a) * wq)
    if not nodes:
        return 0.0, 0.0
    x, y, z = np.array(nodes).T
    lci = fields(design, options, x, y, z)[:, 0]
    w = np.array(weights)
    keep = lci >= 0.0
    return volume * 2.0 * math.pi / angle, float(np.sum(w[keep] * lci[keep]) / np.sum(w[keep]))
