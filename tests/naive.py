"""Slow, obviously-correct NumPy twins of the Numba kernels (the reference the kernels are tested against).

Written straight from the spec's equations with NumPy's SVD; no shortcuts shared with the kernels.
"""

from __future__ import annotations

import numpy as np


def pauu_lci(design, options, x, y, z):
    """Seed 000, spec §1.2/§1.4: LCI = 1/cond_2(J), J = Jx^-1 Jq, at arrays of points; -1 where unreachable."""
    x, y, z = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (x, y, z)))
    m, n, l1, l2, c = (design[k] for k in ("m", "n", "l1", "l2", "c"))
    e = 2 * c if options.get("e") is None else options["e"]
    mode = options.get("mode", "++")
    sigma = (1.0 if mode[0] == "+" else -1.0, 1.0 if mode[1] == "+" else -1.0)
    b = z - e
    ok = np.abs(y) < l2
    thetas = []
    with np.errstate(invalid="ignore", divide="ignore"):
        for s, sg in zip((1.0, -1.0), sigma, strict=True):
            a = s * x + n - m
            t1 = 2 * l1 * b
            t2 = -2 * l1 * a
            t3 = a**2 + b**2 + y**2 + l1**2 - l2**2
            disc = t1**2 + t2**2 - t3**2
            ok &= disc >= 0
            theta = np.arctan2(-b, a) + sg * np.arccos(np.clip(t3 / (2 * l1 * np.hypot(a, b)), -1, 1))
            thetas.append(theta)
    lim = options.get("theta1_limits"), options.get("theta2_limits")
    for theta, lims in zip(thetas, lim, strict=True):
        if lims is not None:
            w = np.arctan2(np.sin(theta), np.cos(theta))
            ok &= ((w >= lims[0]) & (w <= lims[1])) | ((w - 2 * np.pi >= lims[0]) & (w - 2 * np.pi <= lims[1])) | (
                (w + 2 * np.pi >= lims[0]) & (w + 2 * np.pi <= lims[1])
            )
    if options.get("stroke_limits") is not None:
        lo, hi = options["stroke_limits"]
        ok &= (y >= lo) & (y <= hi)
    if options.get("z_min") is not None:
        ok &= z >= options["z_min"]
    out = np.full(x.shape, -1.0)
    idx = np.nonzero(ok)
    if idx[0].size == 0:
        return out
    xs, ys, zs = x[idx], y[idx], z[idx]
    th1, th2 = thetas[0][idx], thetas[1][idx]
    k = xs.size
    jx = np.zeros((k, 3, 3))
    jq = np.zeros((k, 3, 3))
    for row, (s, th) in enumerate(((1.0, th1), (-1.0, th2))):
        cx = s * (m + l1 * np.cos(th))
        cz = e - l1 * np.sin(th)
        jx[:, row, 0] = xs + s * n - cx
        jx[:, row, 1] = ys
        jx[:, row, 2] = zs - cz
        a = s * xs + n - m
        jq[:, row, row] = -l1 * (a * np.sin(th) + (zs - e) * np.cos(th))
    jx[:, 2, 1] = 1.0
    jq[:, 2, 2] = 1.0
    # kappa(J) = kappa(J^-1) and J^-1 = Jq^-1 Jx; compute from J^-1 where Jq is regular
    lci = np.zeros(k)
    good = (np.abs(jq[:, 0, 0]) > 0) & (np.abs(jq[:, 1, 1]) > 0)
    jinv = np.linalg.solve(jq[good], jx[good])
    sv = np.linalg.svd(jinv, compute_uv=False)
    lci[good] = sv[:, -1] / sv[:, 0]
    out[idx] = lci
    return out


def grid_nodes(lo, step, shape):
    """Cell-centred node coordinates as broadcastable arrays."""
    axes = [lo[a] + (np.arange(shape[a]) + 0.5) * step[a] for a in range(3)]
    return np.meshgrid(*axes, indexing="ij")


def grid_metrics(lci, cell_measure, edges):
    """Workspace metrics from an LCI array (-1 = unreachable), as plain NumPy reductions."""
    v = lci[lci >= 0]
    out = {"count": v.size, "measure": v.size * cell_measure}
    if v.size == 0:
        out.update(gci=0.0, fci=0.0, min_lci=0.0, max_lci=0.0, shares=[0.0] * (len(edges) - 1))
        return out
    out.update(gci=float(v.mean()), fci=float(v.std()), min_lci=float(v.min()), max_lci=float(v.max()))
    shares = []
    for b in range(len(edges) - 1):
        if b == 0:
            sel = (v >= edges[0]) & (v <= edges[1])
        else:
            sel = (v > edges[b]) & (v <= edges[b + 1])
        shares.append(sel.sum() / v.size)
    out["shares"] = shares
    return out


def fivebar_arm_angles(design, options, x, y):
    """Seed 004, spec §2.2: arm angles (alpha1, alpha2) of the working mode options['mode'] at arrays of points,
    from alpha(sigma) = atan2(E, D) - sigma arccos(-F / sqrt(D^2 + E^2)); NaN where a chain cannot reach."""
    x, y = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (x, y)))
    r, l1, l2 = (design[k] for k in ("r", "l1", "l2"))
    mode = options.get("mode", "+-")
    out = []
    with np.errstate(invalid="ignore", divide="ignore"):
        for u, ch in ((x - r, mode[0]), (x + r, mode[1])):
            sigma = 1.0 if ch == "+" else -1.0
            d = -2 * l1 * u
            e = -2 * l1 * y
            f = u**2 + y**2 + l1**2 - l2**2
            ok = (d**2 + e**2 - f**2 >= 0) & (np.hypot(d, e) > 0)
            alpha = np.arctan2(e, d) - sigma * np.arccos(np.clip(-f / np.hypot(d, e), -1, 1))
            out.append(np.where(ok, alpha, np.nan))
    return out[0], out[1]


def fivebar_lci(design, options, x, y):
    """Seed 004, spec §2.2/§2.4: LCI = sigma_min/sigma_max of J (NumPy SVD) at arrays of points; -1 where
    unreachable or outside the arm limits (intervals taken modulo 2 pi)."""
    x, y = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (x, y)))
    r, l1 = design["r"], design["l1"]
    a1, a2 = fivebar_arm_angles(design, options, x, y)
    ok = np.isfinite(a1) & np.isfinite(a2)
    for alpha, name in ((a1, "alpha1_limits"), (a2, "alpha2_limits")):
        lims = options.get(name)
        if lims is not None:
            with np.errstate(invalid="ignore"):
                ok &= np.mod(alpha - lims[0], 2 * np.pi) <= lims[1] - lims[0]
    out = np.full(x.shape, -1.0)
    idx = np.nonzero(ok)
    if idx[0].size == 0:
        return out
    xs, ys, a1, a2 = x[idx], y[idx], a1[idx], a2[idx]
    # forearm directions from the elbows Q_i = B_i + l1 (cos alpha_i, sin alpha_i), B_1,2 = (+-r, 0)
    b1 = np.arctan2(ys - l1 * np.sin(a1), xs - r - l1 * np.cos(a1))
    b2 = np.arctan2(ys - l1 * np.sin(a2), xs + r - l1 * np.cos(a2))
    # J in the closed form of spec §2.4
    k = xs.size
    j = np.empty((k, 2, 2))
    j[:, 0, 0] = np.sin(b2) * np.sin(b1 - a1)
    j[:, 0, 1] = -np.sin(b1) * np.sin(b2 - a2)
    j[:, 1, 0] = -np.cos(b2) * np.sin(b1 - a1)
    j[:, 1, 1] = np.cos(b1) * np.sin(b2 - a2)
    # at a forward singularity (sin(beta2 - beta1) = 0) J is unbounded and its LCI tends to 0
    det = np.sin(b2 - b1)
    regular = det != 0
    j = j[regular] * (l1 / det[regular])[:, None, None]
    sv = np.linalg.svd(j, compute_uv=False)
    lci = np.zeros(k)
    with np.errstate(invalid="ignore", divide="ignore"):
        lci[regular] = np.where(sv[:, 0] > 0, sv[:, -1] / sv[:, 0], 0.0)
    out[idx] = lci
    return out
