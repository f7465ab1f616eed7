"""Slow NumPy twin of a planar (2T) two-leg mechanism, written from textbook planar kinematics, independently of
scalesynth's description machinery: a leg is a plain dict.

* RR: pivot B, crank length L, link length l, crank angle measured counter-clockwise from +x (optionally from a
  turned zero direction ``zero`` rad); at the platform joint Q = P + r_p, q = atan2(Q - B) + sigma acos((rho^2 + L^2
  - l^2) / (2 L rho)), rho = |Q - B| (law of cosines); elbow E = B + L (cos q, sin q).
* PR: rail origin B, unit direction e (angle ``rail`` rad), link length l: carriage C = B + q e with |Q - C| = l, so
  q = (Q - B).e + sigma sqrt(l^2 - ((Q - B) x e)^2).

Then J = Jx^-1 Jq, rows of Jx the links f_i = Q_i - A_i (A_i elbow or carriage), Jq = diag(f_i . dA_i/dq_i), and its
singular values by np.linalg.svd. Limits: RR modulo 2 pi, PR as given.
"""

import numpy as np


def leg_q(leg, p):
    """Joint value of ``leg`` at platform point p, or None where it does not reach (limits not applied)."""
    d = np.asarray(p, dtype=float) + np.asarray(leg.get("platform", (0.0, 0.0))) - np.asarray(leg["base"])
    if leg["type"] == "RR":
        rho = np.hypot(*d)
        L, l = leg["arm"], leg["link"]
        c = (rho**2 + L**2 - l**2) / (2 * L * rho)
        if rho == 0 or abs(c) > 1:
            return None
        return np.arctan2(d[1], d[0]) - leg.get("zero", 0.0) + leg["sigma"] * np.arccos(c)
    e = np.array([np.cos(leg["rail"]), np.sin(leg["rail"])])
    cross = d[0] * e[1] - d[1] * e[0]
    if abs(cross) > leg["link"]:
        return None
    return d @ e + leg["sigma"] * np.sqrt(leg["link"] ** 2 - cross**2)


def actuated(leg, q):
    """(A, dA/dq): the elbow or carriage and its velocity per unit q."""
    b = np.asarray(leg["base"], dtype=float)
    if leg["type"] == "RR":
        a = q + leg.get("zero", 0.0)
        return b + leg["arm"] * np.array([np.cos(a), np.sin(a)]), leg["arm"] * np.array([-np.sin(a), np.cos(a)])
    e = np.array([np.cos(leg["rail"]), np.sin(leg["rail"])])
    return b + q * e, e


def in_limits(leg, q):
    lim = leg.get("limits")
    if lim is None:
        return True
    if leg["type"] == "RR":
        return np.mod(q - lim[0], 2 * np.pi) <= lim[1] - lim[0]
    return lim[0] <= q <= lim[1]


def jacobian(legs, p, qs):
    """(Jx, Jq, J) at platform point p with joint values qs."""
    jx, jq = np.zeros((2, 2)), np.zeros((2, 2))
    for i, (leg, q) in enumerate(zip(legs, qs, strict=True)):
        a, t = actuated(leg, q)
        f = np.asarray(p, dtype=float) + np.asarray(leg.get("platform", (0.0, 0.0))) - a
        jx[i] = f
        jq[i, i] = f @ t
    return jx, jq, np.linalg.solve(jx, jq)


def fields(legs, pts):
    """(LCI, sigma_min, sigma_max) of J at points (n, 2) -> (n, 3); LCI -1 (and 0, 0) where a leg does not reach or
    its limits exclude it."""
    out = np.zeros((len(pts), 3))
    out[:, 0] = -1.0
    for k, p in enumerate(pts):
        qs = [leg_q(leg, p) for leg in legs]
        if any(q is None or not in_limits(leg, q) for leg, q in zip(legs, qs, strict=True)):
            continue
        sv = np.linalg.svd(jacobian(legs, p, qs)[2], compute_uv=False)
        out[k] = (sv[-1] / sv[0], sv[-1], sv[0])
    return out
