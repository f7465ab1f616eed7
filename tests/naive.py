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
