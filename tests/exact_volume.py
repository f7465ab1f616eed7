"""Exact reachable volume of the seed-000 mechanism (spec §1.9), by 1-D quadrature of the lens-area formula.

Used by the benchmarks to measure the grid's volume error on any design (the tests use the spec's tabulated values).
"""

from __future__ import annotations

import math

from scipy.integrate import quad


def lens_area(r1: float, r2: float, t: float) -> float:
    """Area of the intersection of two disks with radii r1, r2 and centre distance t."""
    if r1 <= 0 or r2 <= 0:
        return 0.0
    if t >= r1 + r2:
        return 0.0
    if t <= abs(r1 - r2):
        return math.pi * min(r1, r2) ** 2
    a1 = r1 * r1 * math.acos(max(-1.0, min(1.0, (t * t + r1 * r1 - r2 * r2) / (2 * t * r1))))
    a2 = r2 * r2 * math.acos(max(-1.0, min(1.0, (t * t + r2 * r2 - r1 * r1) / (2 * t * r2))))
    a3 = 0.5 * math.sqrt(max(0.0, (-t + r1 + r2) * (t + r1 - r2) * (t - r1 + r2) * (t + r1 + r2)))
    return a1 + a2 - a3


def section_area(y: float, delta: float, l1: float, l2: float) -> float:
    """Area of the y-slice: intersection of the two annuli centred (+-delta, e), radii [|l1 - rho|, l1 + rho]."""
    rho = math.sqrt(max(l2 * l2 - y * y, 0.0))
    ro, ri, t = l1 + rho, abs(l1 - rho), 2 * abs(delta)
    return lens_area(ro, ro, t) - 2 * lens_area(ri, ro, t) + lens_area(ri, ri, t)


def exact_volume(m: float, n: float, l1: float, l2: float, **_) -> float:
    """V = 2 * integral_0^l2 A(y) dy, with y = l2 sin(u) to remove the endpoint singularity."""
    delta = m - n
    breaks = [math.asin(min(1.0, math.sqrt(max(l2 * l2 - l1 * l1, 0.0)) / l2))] if l1 < l2 else []

    def integrand(u):
        return section_area(l2 * math.sin(u), delta, l1, l2) * l2 * math.cos(u)

    val, _ = quad(integrand, 0.0, math.pi / 2, points=breaks or None, limit=400, epsabs=1e-11, epsrel=1e-11)
    return 2.0 * val
