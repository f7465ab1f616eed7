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


# ----- per-voxel stiffness and clearance (the described 2T template's fields), from textbook statics ---------------
def stiffness(legs, sections, p, qs, load):
    """(stiffness_min, |deflection|) of the pin where both links meet, ideal joints: each link is a two-force member
    (pinned at both ends), so leg i is a spring along its unit link f_i of compliance l / EA_link + f_i^T C_A f_i,
    C_A the 2 x 2 compliance of the actuated point: RR, the crank as a cantilever (axial L / EA, transverse
    L^3 / 3 EI) plus the actuator spring's turn (L^2 / k across the crank); PR, the carriage's spring along the rail
    (1 / k) and the rigid rail across. K = sum f f^T / c; eigvalsh and solve. ``sections``: per leg a dict of
    EA_arm, EI_arm, EA_link, k."""
    K = np.zeros((2, 2))
    for leg, q, s in zip(legs, qs, sections, strict=True):
        a, _ = actuated(leg, q)
        f = np.asarray(p, dtype=float) + np.asarray(leg.get("platform", (0.0, 0.0))) - a
        f = f / np.linalg.norm(f)
        if leg["type"] == "RR":
            t = (a - np.asarray(leg["base"], dtype=float)) / leg["arm"]
            n = np.array([-t[1], t[0]])
            L = leg["arm"]
            ca = L / s["EA_arm"] * np.outer(t, t) + (L**3 / (3 * s["EI_arm"]) + L**2 / s["k"]) * np.outer(n, n)
        else:
            e = np.array([np.cos(leg["rail"]), np.sin(leg["rail"])])
            ca = np.outer(e, e) / s["k"]
        c = leg["link"] / s["EA_link"] + f @ ca @ f
        K += np.outer(f, f) / c
    w = np.linalg.eigvalsh(K)
    return w[0], float(np.linalg.norm(np.linalg.solve(K, load)))


def _point_segment(p, a, b):
    d = b - a
    t = 0.0 if d @ d == 0 else float(np.clip((p - a) @ d / (d @ d), 0.0, 1.0))
    return float(np.linalg.norm(p - (a + t * d)))


def _cross(u, v):
    return u[0] * v[1] - u[1] * v[0]


def segment_distance(a, b, c, d):
    """Distance of the plane segments a-b and c-d: 0 where they cross, else the least of the four end-to-segment
    distances."""
    a, b, c, d = (np.asarray(v, dtype=float) for v in (a, b, c, d))
    d1, d2 = _cross(b - a, c - a) * _cross(b - a, d - a), _cross(d - c, a - c) * _cross(d - c, b - c)
    if d1 < 0 and d2 < 0:
        return 0.0
    return min(_point_segment(a, c, d), _point_segment(b, c, d), _point_segment(c, a, b), _point_segment(d, a, b))


def clearance(legs, radii, p, qs):
    """Smallest gap between the capsules of bodies that share no joint: base B2-B1, per leg arm B-A (RR) or rail
    over the stroke and a carriage ball at A (PR), the link A-Q, the platform Q1-Q2; joints: base-arm, arm-link,
    base-rail, rail-carriage, carriage-link, rail-link, link-platform and link-link where Q1 = Q2. ``radii`` by body
    name (base, arm1, forearm2, ...)."""
    p = np.asarray(p, dtype=float)
    caps = {"base": (legs[1]["base"], legs[0]["base"])}
    joined = set()
    qpts = []
    for i, (leg, q) in enumerate(zip(legs, qs, strict=True), 1):
        a, _ = actuated(leg, q)
        qp = p + np.asarray(leg.get("platform", (0.0, 0.0)))
        qpts.append(qp)
        if leg["type"] == "RR":
            caps[f"arm{i}"] = (leg["base"], a)
            joined |= {("base", f"arm{i}"), (f"arm{i}", f"forearm{i}")}
        else:
            e = np.array([np.cos(leg["rail"]), np.sin(leg["rail"])])
            b = np.asarray(leg["base"], dtype=float)
            caps[f"rail{i}"] = (b + leg["limits"][0] * e, b + leg["limits"][1] * e)
            caps[f"carriage{i}"] = (a, a)
            joined |= {("base", f"rail{i}"), (f"rail{i}", f"carriage{i}"), (f"carriage{i}", f"forearm{i}"),
                       (f"rail{i}", f"forearm{i}")}
        caps[f"forearm{i}"] = (a, qp)
        joined.add((f"forearm{i}", "platform"))
    caps["platform"] = tuple(qpts)
    if np.allclose(qpts[0], qpts[1], rtol=0, atol=0):
        joined.add(("forearm1", "forearm2"))
    names = list(caps)
    gaps = [segment_distance(*caps[u], *caps[v]) - radii[u] - radii[v] for i, u in enumerate(names)
            for v in names[i + 1:] if (u, v) not in joined and (v, u) not in joined]
    return min(gaps)
