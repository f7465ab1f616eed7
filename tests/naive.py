"""Slow, obviously-correct NumPy twins of the Numba kernels (the reference the kernels are tested against).

Written straight from the spec's equations with NumPy's SVD; no shortcuts shared with the kernels.
"""

from __future__ import annotations

import numpy as np

SIGMA_CAP = 1e12  # the kernels' stand-in for an unbounded singular value (kernels/conditioning.py)


def jacobian_fields(j, regular):
    """(LCI, sigma_min, sigma_max) of a stack of Jacobians dx/dq (k, n, n) by NumPy's SVD where ``regular``;
    elsewhere (exact singular poses) the kernels' convention LCI 0, sigma_min 0, sigma_max SIGMA_CAP."""
    k = j.shape[0]
    out = np.zeros((k, 3))
    out[:, 2] = SIGMA_CAP
    if regular.any():
        sv = np.linalg.svd(j[regular], compute_uv=False)
        with np.errstate(invalid="ignore", divide="ignore"):
            out[regular, 0] = np.where(sv[:, 0] > 0, sv[:, -1] / sv[:, 0], 0.0)
        out[regular, 1] = np.minimum(sv[:, -1], SIGMA_CAP)
        out[regular, 2] = np.minimum(sv[:, 0], SIGMA_CAP)
    return out


def inverse_jacobian_fields(a):
    """(LCI, sigma_min, sigma_max) of J = A^-1 for a stack of inverse Jacobians dq/dx (k, n, n): J by
    np.linalg.inv where A is regular, then jacobian_fields."""
    regular = np.abs(np.linalg.det(a)) > 0
    j = np.zeros_like(a)
    if regular.any():
        j[regular] = np.linalg.inv(a[regular])
    return jacobian_fields(j, regular)


def pauu_lci(design, options, x, y, z):
    """Seed 000: the LCI of pauu_fields (-1 where unreachable)."""
    return pauu_fields(design, options, x, y, z)[..., 0]


def pauu_fields(design, options, x, y, z):
    """Seed 000, spec §1.2/§1.4: (LCI = 1/cond_2(J), sigma_min(J), sigma_max(J)), J = Jx^-1 Jq = dx/dq, at arrays of
    points, shape x.shape + (3,); LCI -1 (and 0, 0) where unreachable."""
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
    out = np.zeros(x.shape + (3,))
    out[..., 0] = -1.0
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
    # J = Jx^-1 Jq where both are regular (an exact singularity is the kernels' convention)
    good = (np.abs(jq[:, 0, 0]) > 0) & (np.abs(jq[:, 1, 1]) > 0) & (np.abs(np.linalg.det(jx)) > 0)
    j = np.zeros((k, 3, 3))
    j[good] = np.linalg.solve(jx[good], jq[good])
    out[idx] = jacobian_fields(j, good)
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


def assert_report_equals_grid_metrics(rep, ref, gci_rel=1e-9, fci=False, bands=0):
    """The evaluator's report ``rep`` against ``ref = grid_metrics(twin, ...)`` on the same grid: the same voxel
    count, measure to 1e-12 and GCI to ``gci_rel`` relative, min and max LCI to 1e-7 (a wrong min/max sentinel or
    reduction passes every other check); with ``fci`` the FCI to 1e-7, and the first ``bands`` band shares to 1e-12."""
    import pytest

    assert rep.metrics["voxels"] == ref["count"]
    assert rep.measure == pytest.approx(ref["measure"], rel=1e-12)
    assert rep.gci == pytest.approx(ref["gci"], rel=gci_rel)
    if fci:
        assert rep.metrics["fci"] == pytest.approx(ref["fci"], rel=1e-7)
    for b in range(bands):
        assert rep.metrics[f"band{b}_share"] == pytest.approx(ref["shares"][b], abs=1e-12)
    assert rep.metrics["min_lci"] == pytest.approx(ref["min_lci"], rel=1e-7, abs=1e-10)
    assert rep.metrics["max_lci"] == pytest.approx(ref["max_lci"], rel=1e-7, abs=1e-10)


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
    """Seed 004: the LCI of fivebar_fields (-1 where unreachable)."""
    return fivebar_fields(design, options, x, y)[..., 0]


def fivebar_fields(design, options, x, y):
    """Seed 004, spec §2.2/§2.4: (LCI = sigma_min/sigma_max, sigma_min, sigma_max) of J = dx/dq (mm/rad, NumPy SVD)
    at arrays of points, shape x.shape + (3,); LCI -1 where unreachable or outside the arm limits (intervals taken
    modulo 2 pi)."""
    x, y = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (x, y)))
    r, l1 = design["r"], design["l1"]
    a1, a2 = fivebar_arm_angles(design, options, x, y)
    ok = np.isfinite(a1) & np.isfinite(a2)
    for alpha, name in ((a1, "alpha1_limits"), (a2, "alpha2_limits")):
        lims = options.get(name)
        if lims is not None:
            with np.errstate(invalid="ignore"):
                ok &= np.mod(alpha - lims[0], 2 * np.pi) <= lims[1] - lims[0]
    out = np.zeros(x.shape + (3,))
    out[..., 0] = -1.0
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
    j[regular] *= (l1 / det[regular])[:, None, None]
    out[idx] = jacobian_fields(j, regular)
    return out


def pprs_lci(design, options, x, y, z):
    """Seed 001: the LCI of pprs_fields (-1 where unreachable)."""
    return pprs_fields(design, options, x, y, z)[..., 0]


def pprs_fields(design, options, x, y, z):
    """Seed 001, spec §1.3/§1.5/§1.8: LCI = sigma_min/sigma_max (NumPy SVD) of J_t with the beta row times
    beta_length (default R) and the angular columns over angle_length (default r), at arrays of positions of
    O1 with the options' orientation; -1 where the IK is not real or an actuator leaves its limits."""
    x, y, z = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (x, y, z)))
    r, big_r = design["r"], design["R"]
    links = [design["L1"], design["L2"], design["L3"]]
    phi, theta, psi = options.get("orientation", (0.0, 0.0, 0.0))
    sigma = [1.0 if ch == "+" else -1.0 for ch in options.get("sigma", "+++")]
    conv_r = options.get("w_convention", "O") == "R"
    beta_len = big_r if options.get("beta_length") is None else options["beta_length"]
    ang_len = r if options.get("angle_length") is None else options["angle_length"]
    rz = np.array([[np.cos(phi), -np.sin(phi), 0], [np.sin(phi), np.cos(phi), 0], [0, 0, 1]])
    ry = np.array([[np.cos(theta), 0, np.sin(theta)], [0, 1, 0], [-np.sin(theta), 0, np.cos(theta)]])
    rx = np.array([[1, 0, 0], [0, np.cos(psi), -np.sin(psi)], [0, np.sin(psi), np.cos(psi)]])
    rot = rz @ ry @ rx
    az = np.radians([0.0, 120.0, options.get("chain3_azimuth_deg", 210.0)])
    u = np.stack([np.cos(az), np.sin(az), np.zeros(3)], axis=1)
    e = np.cross([0.0, 0.0, 1.0], u)
    body = np.array([[r, 0, 0], [-r / 2, np.sqrt(3) * r / 2, 0], [-r / 2, -np.sqrt(3) * r / 2, 0]])
    rk = body @ rot.T  # r_k = R c_k'
    pts = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)
    out = np.zeros((pts.shape[0], 3))
    out[:, 0] = -1.0
    zhat = np.array([0.0, 0.0, 1.0])
    for n, p in enumerate(pts):
        c = p + rk
        lam = np.array([e[k] @ c[k] for k in range(3)])
        if np.any(np.abs(lam) > links):
            continue
        kap = np.sqrt(np.array(links) ** 2 - lam**2)
        w = [big_r - u[k] @ c[k] if conv_r else u[k] @ c[k] for k in range(2)]
        rho3 = big_r - u[2] @ c[2]
        h3 = c[2, 2]
        mu3 = np.hypot(rho3, h3)
        beta = np.arctan2(h3, rho3)
        s = [c[0, 2] - sigma[0] * kap[0], c[1, 2] - sigma[1] * kap[1], mu3 - sigma[2] * kap[2]]
        ok = all(options["w_limits"][0] <= v <= options["w_limits"][1] for v in w)
        ok &= all(options["s_limits"][0] <= v <= options["s_limits"][1] for v in s)
        ok &= options["beta_limits"][0] <= beta <= options["beta_limits"][1]
        if not ok:
            continue
        if np.any(kap == 0):
            out[n] = (0.0, 0.0, SIGMA_CAP)
            continue
        d3 = -np.cos(beta) * u[2] + np.sin(beta) * zhat
        g = [
            -u[0] if conv_r else u[0],
            -u[1] if conv_r else u[1],
            (rho3 * zhat + h3 * u[2]) / mu3**2,
            zhat + sigma[0] * lam[0] / kap[0] * e[0],
            zhat + sigma[1] * lam[1] / kap[1] * e[1],
            d3 + sigma[2] * lam[2] / kap[2] * e[2],
        ]
        chain = [0, 1, 2, 0, 1, 2]
        jt = np.array([np.concatenate([g[j], np.cross(rk[chain[j]], g[j])]) for j in range(6)])
        js = np.diag([1, 1, beta_len, 1, 1, 1]) @ jt @ np.diag([1, 1, 1, 1 / ang_len, 1 / ang_len, 1 / ang_len])
        out[n] = inverse_jacobian_fields(js[None])[0]  # J_t maps the twist to the input rates: dq/dx
    return out.reshape(x.shape + (3,))


def ups_sspr_lci(design, options, alpha, beta, y):
    """Seed 003: the LCI of ups_sspr_fields (-1 where unreachable)."""
    return ups_sspr_fields(design, options, alpha, beta, y)[..., 0]


def ups_sspr_fields(design, options, alpha, beta, y):
    """Seed 003, spec §3.1/§3.3/§3.5: LCI = 1/cond_2(J diag(1/L, 1/L, 1)), J = dl/d(alpha, beta, Y), at arrays of
    task points; -1 outside the workspace box, outside |Y| < c or outside an actuator's limits.

    Built from explicit rotation matrices R = Ry(beta) Rx(alpha), their derivative matrices and l1 = |(2/3)P - M|.
    """
    alpha, beta, y = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (alpha, beta, y)))
    a, b, c = design["a"], design["b"], design["c"]
    big_l = c if options.get("characteristic_length") is None else options["characteristic_length"]
    base = {2: np.array([-np.sqrt(3) * a / 2, -a / 2, 0.0]), 3: np.array([np.sqrt(3) * a / 2, -a / 2, 0.0])}
    plat = {2: np.array([-b / np.sqrt(2), b / np.sqrt(2), 0.0]), 3: np.array([b / np.sqrt(2), b / np.sqrt(2), 0.0])}
    m_point = np.array([0.0, -a / 2, 0.0])
    y_range = options.get("Y_range") or (-0.999 * c, 0.999 * c)
    ok = (alpha >= options["alpha_range"][0]) & (alpha <= options["alpha_range"][1])
    ok &= (beta >= options["beta_range"][0]) & (beta <= options["beta_range"][1])
    ok &= (y >= y_range[0]) & (y <= y_range[1]) & (np.abs(y) < c)
    out = np.zeros(alpha.shape + (3,))
    out[..., 0] = -1.0
    idx = np.nonzero(ok)
    al, be, yy = alpha[idx], beta[idx], y[idx]
    n = al.size
    if n == 0:
        return out
    zero, one = np.zeros(n), np.ones(n)
    sa, ca, sb, cb = np.sin(al), np.cos(al), np.sin(be), np.cos(be)

    def mat(*rows):  # (n, 3, 3) stack of matrices from 3 rows of 3 arrays each
        return np.stack([np.stack(r, -1) for r in rows], -2)

    rx = mat((one, zero, zero), (zero, ca, -sa), (zero, sa, ca))
    drx = mat((zero, zero, zero), (zero, -sa, -ca), (zero, ca, -sa))  # d Rx / d alpha
    ry = mat((cb, zero, sb), (zero, one, zero), (-sb, zero, cb))
    dry = mat((-sb, zero, cb), (zero, zero, zero), (-cb, zero, -sb))  # d Ry / d beta
    rho = np.sqrt(c * c - yy * yy)
    p = np.stack([sb * rho, yy, cb * rho], -1)
    dp_db = np.stack([cb * rho, zero, -sb * rho], -1)
    dp_dy = np.stack([-sb * yy / rho, one, -cb * yy / rho], -1)
    lengths = {1: np.linalg.norm(2.0 / 3.0 * p - m_point, axis=-1)}
    jac = np.zeros((n, 3, 3))
    jac[:, 0, 2] = (2.0 / 3.0) * (a / 2) / lengths[1]
    for i in (2, 3):
        leg = p + (ry @ rx @ plat[i]) - base[i]
        lengths[i] = np.linalg.norm(leg, axis=-1)
        cols = (ry @ drx @ plat[i], dp_db + dry @ rx @ plat[i], dp_dy)
        for k, col in enumerate(cols):
            jac[:, i - 1, k] = np.einsum("nj,nj->n", leg, col) / lengths[i]
    keep = np.ones(n, dtype=bool)
    for i in (1, 2, 3):
        lim = options.get(f"l{i}_limits")
        if lim is not None:
            keep &= (lengths[i] >= lim[0]) & (lengths[i] <= lim[1])
    jac[:, :, :2] /= big_l
    fields = inverse_jacobian_fields(jac)  # jac = dl/dx homogenised: J = its inverse
    fields[~keep] = (-1.0, 0.0, 0.0)
    out[idx] = fields
    return out


def rps_upu_lci(design, options, z, theta, psi):
    """Seed 002: the LCI of rps_upu_fields (-1 where unreachable)."""
    return rps_upu_fields(design, options, z, theta, psi)[..., 0]


def rps_upu_fields(design, options, z, theta, psi):
    """Seed 002, spec §2.3/§2.5: LCI = 1/cond_2 of dq/d(z, L theta, L psi) (NumPy SVD) at arrays of points; -1 where
    a leg leaves the stroke limits or the C-model parametrisation is degenerate.

    q: P-model from the closed-form q_i^2 of §2.3; C-model as |p + R b_i' - a_i| with R = Rz(phi) Ry(theta) Rx(psi)
    multiplied out as matrices, cos/sin phi = (cos psi, sin theta sin psi)/norm. dq/dx by complex-step
    differentiation, Im q(x + i s e_k)/s (exact to round-off; no derivative formula shared with the kernel).
    """
    z, theta, psi = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (z, theta, psi)))
    g, h, c, e = (float(design[k]) for k in ("g", "h", "c", "e"))
    model, variant = options.get("model", "P"), options.get("c3_variant", "plane")
    big_l = h if options.get("characteristic_length") is None else float(options["characteristic_length"])
    x = np.stack([z.ravel(), theta.ravel(), psi.ravel()], axis=-1)
    n = x.shape[0]

    def legs(xc):
        zz, th, ps = xc[:, 0], xc[:, 1], xc[:, 2]
        st, ct, sp, cp = np.sin(th), np.cos(th), np.sin(ps), np.cos(ps)
        if model == "P":
            q1s = g**2 + h**2 + zz**2 - 2 * g * h * cp - 2 * h * zz * ct * sp
            q2s = g**2 + h**2 + zz**2 - 2 * g * h * cp + 2 * h * zz * ct * sp
            q3s = c**2 + e**2 + zz**2 - 2 * c * e * ct - 2 * c * zz * st
            return np.sqrt(np.stack([q1s, q2s, q3s], axis=-1)), np.ones(xc.shape[0], dtype=bool)
        nrm = np.sqrt((st * sp) ** 2 + cp**2)
        ok = np.abs(nrm) ** 2 >= 1e-24
        nrm = np.where(ok, nrm, 1.0)
        cf, sf = cp / nrm, st * sp / nrm
        zero, one = np.zeros_like(th), np.ones_like(th)
        rz = np.array([[cf, -sf, zero], [sf, cf, zero], [zero, zero, one]])
        ry = np.array([[ct, zero, st], [zero, one, zero], [-st, zero, ct]])
        rx = np.array([[one, zero, zero], [zero, cp, -sp], [zero, sp, cp]])
        rot = np.einsum("ijn,jkn,kln->nil", rz, ry, rx)
        if variant == "plane":
            y0 = -c * rot[:, 1, 0]  # B3 in the plane y = 0
        else:
            ok &= np.abs(rot[:, 2, 2]) >= 1e-12
            r22 = np.where(ok, rot[:, 2, 2], 1.0)
            y0 = rot[:, 1, 2] * (zz + c * rot[:, 2, 0]) / r22 - c * rot[:, 1, 0]
        p = np.stack([zero, y0, zz], axis=-1)
        a = np.array([[0.0, -g, 0.0], [0.0, g, 0.0], [e, 0.0, 0.0]])
        b = np.array([[0.0, -h, 0.0], [0.0, h, 0.0], [c, 0.0, 0.0]])
        d = p[:, None, :] + np.einsum("nij,kj->nki", rot, b) - a[None]
        return np.sqrt(np.sum(d * d, axis=-1)), ok

    q, ok = legs(x.astype(complex))
    q = q.real
    stroke = options.get("stroke_limits")
    if stroke is not None:
        ok &= np.all((q >= stroke[0]) & (q <= stroke[1]), axis=1)
    step = 1e-20
    jac = np.zeros((n, 3, 3))
    for k in range(3):
        xc = x.astype(complex)
        xc[:, k] += 1j * step
        jac[:, :, k] = legs(xc)[0].imag / step
    jac[:, :, 1:] /= big_l
    out = np.zeros((n, 3))
    out[:, 0] = -1.0
    good = ok & np.all(q > 0, axis=1)
    out[good] = inverse_jacobian_fields(jac[good])  # jac = dq/dx homogenised: J = its inverse
    out[ok & ~np.all(q > 0, axis=1)] = (0.0, 0.0, SIGMA_CAP)
    return out.reshape(z.shape + (3,))


def rps_upu_tool_lci(design, options, x, y, z):
    """Seed 002 tool point: the LCI of rps_upu_tool_fields (-1 where unreachable)."""
    return rps_upu_tool_fields(design, options, x, y, z)[..., 0]


def rps_upu_tool_fields(design, options, x, y, z):
    """Seed 002, spec §2.8: LCI = 1/cond_2 of dq/dT (NumPy SVD) of the tool point T = (x, y, z) = O' + R (0, 0, -d),
    P-model, principal branch; -1 where T is out of reach, the pose leaves the z/theta/psi ranges or a leg leaves
    the stroke limits.

    The pose comes from the spec's inverse (psi = asin(T_y/d), theta = asin(-T_x/(d cos psi)),
    z0 = T_z + d cos theta cos psi), q from the closed-form q_i^2 of §2.3, and dq/dT by complex-step
    differentiation of that composition.
    """
    x, y, z = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (x, y, z)))
    g, h, c, e = (float(design[k]) for k in ("g", "h", "c", "e"))
    d = float(options["tool_offset"])
    pts = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=-1)

    def pose(t):
        ps = np.arcsin(t[:, 1] / d)
        th = np.arcsin(-t[:, 0] / (d * np.cos(ps)))
        return t[:, 2] + d * np.cos(th) * np.cos(ps), th, ps

    def legs(t):
        z0, th, ps = pose(t)
        q1s = g**2 + h**2 + z0**2 - 2 * g * h * np.cos(ps) - 2 * h * z0 * np.cos(th) * np.sin(ps)
        q2s = g**2 + h**2 + z0**2 - 2 * g * h * np.cos(ps) + 2 * h * z0 * np.cos(th) * np.sin(ps)
        q3s = c**2 + e**2 + z0**2 - 2 * c * e * np.cos(th) - 2 * c * z0 * np.sin(th)
        return np.sqrt(np.stack([q1s, q2s, q3s], axis=-1))

    ok = (np.abs(pts[:, 1]) <= d) & (np.abs(pts[:, 0]) <= d * np.sqrt(np.clip(1 - (pts[:, 1] / d) ** 2, 0, 1)))
    ok &= np.abs(pts[:, 1]) < d  # psi = +-pi/2 leaves theta undetermined
    out = np.zeros((pts.shape[0], 3))
    out[:, 0] = -1.0
    t = pts[ok]
    z0, th, ps = pose(t)
    keep = np.ones(t.shape[0], dtype=bool)
    for name, v in (("z_range", z0), ("theta_range", th), ("psi_range", ps)):
        keep &= (v >= options[name][0]) & (v <= options[name][1])
    q = legs(t)
    if options.get("stroke_limits") is not None:
        lo, hi = options["stroke_limits"]
        keep &= np.all((q >= lo) & (q <= hi), axis=1)
    step = 1e-20
    jac = np.zeros((t.shape[0], 3, 3))
    for k in range(3):
        tc = t.astype(complex)
        tc[:, k] += 1j * step
        jac[:, :, k] = legs(tc).imag / step
    fields = inverse_jacobian_fields(jac)  # jac = dq/dT: J = its inverse
    fields[~keep] = (-1.0, 0.0, 0.0)
    out[np.nonzero(ok)[0]] = fields
    return out.reshape(x.shape + (3,))


def column_stats(fields, n_fields, lo, hi, ndim, n, m, nbis, maxlev, tol_v, tol_g, edges, beta=1.0, zlevels=0,
                 zconfirm=1, faces=False, ny=None, mirror=(False, False), intervals=None, field_levels=-1,
                 gauss_points=2):
    """NumPy twin of kernels.adaptive.column_stats for one design, vectorised over the active columns of a level:
    ``fields(points (k, 3)) -> (k, n_fields)`` (field 0 LCI, -1 unreachable); lo, hi: the design's box (3,); n, ny:
    coarse columns along cross axes 0, 1 (ny default n; planar: unused); mirror: the lo face of cross axis 0, 1 is
    a mirror plane (clamped neighbour, no face column there even with ``faces``); intervals (3-D only, as the
    kernel's interval_kernel): ``intervals(x, y, zlo, zhi)`` -> the column's reachable intervals [(a, b), ...]
    (sorted, disjoint) or None (then that column takes the nodes and bisections), one evaluation per call;
    field_levels >= 0: a new column at a deeper level takes its measure alone and its parent's Gauss points
    with their weights times (its measure / the parent's / nk), unless the parent has no measure or its mean-LCI
    indicator fired (kernels.adaptive step 3b); gauss_points 1: the midpoint rule per piece. Returns (stats row
    in the layout of kernels.grid with counts in coarse-cell units, error_volume, error_gci, level,
    evaluations)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    ca = ndim - 1
    zlo = lo[ca]
    hz0 = (hi[ca] - zlo) / m
    nudge = 2.0**-20  # kernels.adaptive.END_NUDGE: the end nodes are evaluated just inside the box
    ny = (n if ny is None else ny) if ndim == 3 else 1
    hx = (hi[0] - lo[0]) / n
    hy = (hi[1] - lo[1]) / ny if ndim == 3 else 1.0
    gx = 1.0 / np.sqrt(3.0)
    evals = 0
    nb = len(edges) - 1
    if not (hz0 > 0 and hx > 0 and hy > 0):  # an empty box: nothing reachable
        row = np.zeros(1 + 4 * n_fields + nb)
        row[3:1 + 4 * n_fields:4], row[4:1 + 4 * n_fields:4] = np.inf, -np.inf
        return row, 0.0, 0.0, 0, 0

    def pts(xx, yy, zz):
        return np.c_[xx, yy, zz] if ndim == 3 else np.c_[xx, zz, np.full(zz.shape, lo[2])]

    def gauss(X, Y, nc, pc, za, zb, area):
        """2-point Gauss rule on the pieces [za, zb] of columns pc (of nc): column measure L, LCI sum S (in units
        of hz0), and the Gauss points' owner column, fields and weights x area; ``gauss_points`` 1: the midpoint
        rule (the fields at each piece's midpoint with its whole length)."""
        nonlocal evals
        half, mid = 0.5 * (zb - za), 0.5 * (za + zb)
        if gauss_points == 1:
            q = fields(pts(X[pc], Y[pc], mid))
            evals += mid.size
            ok = q[:, 0] >= 0
            w = np.where(ok, 2 * half / hz0, 0.0)
            L = np.bincount(pc, weights=w, minlength=nc).astype(float)
            S = np.bincount(pc, weights=w * np.where(ok, q[:, 0], 0.0), minlength=nc).astype(float)
            return L, S, pc, q, w * area
        zq = np.c_[mid - half * gx, mid + half * gx].ravel()
        q = fields(pts(np.repeat(X[pc], 2), np.repeat(Y[pc], 2), zq)).reshape(-1, 2, n_fields)
        evals += zq.size
        ok = q[:, :, 0] >= 0
        w = np.where(ok, np.where(ok.sum(axis=1) == 2, half, 2 * half)[:, None] / hz0, 0.0)
        # float64 also without pieces (np.bincount of nothing is int64, which would truncate what is stored in it)
        L = np.bincount(pc, weights=w.sum(axis=1), minlength=nc).astype(float)
        S = np.bincount(pc, weights=(w * np.where(ok, q[:, :, 0], 0.0)).sum(axis=1), minlength=nc).astype(float)
        return L, S, np.repeat(pc, 2), q.reshape(-1, n_fields), w.ravel() * area

    def measure(X, Y, nc, pc, za, zb, area, fields_on):
        """gauss(), or without ``fields_on`` the pieces' lengths alone (L; S zero, no Gauss points)."""
        if fields_on:
            return gauss(X, Y, nc, pc, za, zb, area)
        L = np.bincount(pc, weights=(zb - za) / hz0, minlength=nc).astype(float)
        return L, np.zeros(nc), pc[:0], np.zeros((0, n_fields)), np.zeros(0)

    def columns(X, Y, area, mz, fields_on=True):
        """Column measure L, LCI sum S (z in units of hz0) and the Gauss points (fields, weights x area) of each,
        with mz z-cells: the closed-form intervals where ``intervals`` gives them, else nodes and bisection."""
        nonlocal evals
        if X.size == 0:
            return np.zeros(0), np.zeros(0), np.zeros(0, dtype=np.int64), np.zeros((0, n_fields)), np.zeros(0)
        if intervals is None or ndim != 3:
            return node_columns(X, Y, area, mz, fields_on)
        nc = X.size
        hz = (hi[ca] - zlo) / mz
        ivs = [intervals(x, y, zlo, zlo + mz * hz) for x, y in zip(X, Y, strict=True)]
        evals += nc
        pc, za, zb = [], [], []
        for c, iv in enumerate(ivs):
            for k in range(mz if iv is not None else 0):  # each z-cell's intersection with each interval
                for a, b in iv:
                    pa, pb = max(zlo + k * hz, a), min(zlo + (k + 1) * hz, b)
                    if pb > pa:
                        pc.append(c)
                        za.append(pa)
                        zb.append(pb)
        L, S, owner, qv, qw = measure(X, Y, nc, np.array(pc, dtype=np.int64), np.array(za), np.array(zb), area,
                                      fields_on)
        back = np.flatnonzero([iv is None for iv in ivs])
        if back.size:
            Lb, Sb, ob, qb, wb = node_columns(X[back], Y[back], area, mz, fields_on)
            L[back], S[back] = Lb, Sb
            owner, qv, qw = np.r_[owner, back[ob]], np.r_[qv, qb], np.r_[qw, wb]
        return L, S, owner, qv, qw

    def node_columns(X, Y, area, mz, fields_on=True):
        """columns() by nodes and bisection."""
        nonlocal evals
        nc = X.size
        hz = (hi[ca] - zlo) / mz
        zn = zlo + np.arange(mz + 1) * hz
        z_eval = zlo + np.r_[nudge, np.arange(1, mz), mz - nudge] * hz
        m = mz
        lci = fields(pts(np.repeat(X, m + 1), np.repeat(Y, m + 1), np.tile(z_eval, nc)))[:, 0].reshape(nc, m + 1)
        evals += nc * (m + 1)
        r = lci >= 0
        ci, ck = np.nonzero(r[:, :-1] != r[:, 1:])
        a, b, ra = zn[ck], zn[ck + 1], r[ci, ck]
        for _ in range(nbis):
            mid = 0.5 * (a + b)
            same = (fields(pts(X[ci], Y[ci], mid))[:, 0] >= 0) == ra
            evals += mid.size
            a, b = np.where(same, mid, a), np.where(same, b, mid)
        cross = 0.5 * (a + b)
        full = r[:, :-1] & r[:, 1:]
        za = np.where(full, zn[None, :-1], np.nan)
        zb = np.where(full, zn[None, 1:], np.nan)
        za[ci, ck] = np.where(ra, zn[ck], cross)
        zb[ci, ck] = np.where(ra, cross, zn[ck + 1])
        pc, pk = np.nonzero(~np.isnan(za))
        return measure(X, Y, nc, pc, za[pc, pk], zb[pc, pk], area, fields_on)

    ci, cj = (v.ravel() for v in np.meshgrid(np.arange(n), np.arange(ny), indexing="ij"))
    lg, sg = np.zeros((n, ny)), np.zeros((n, ny))
    # face columns [side, L or S, index]: x = lo, hi per j; y = lo, hi per i
    fxg, fyg = np.zeros((2, 2, ny)), np.zeros((2, 2, n))
    kept_v, kept_w = [], []
    src = None  # per active column: the previous level's column it repeats (centre children), else -1
    par = own = None  # per active column: its parent (previous level's index); whether it evaluates its fields
    p_owner = p_qv = p_qw = None  # the previous level's Gauss points: owner column, fields, weights
    nk = 9 if ndim == 3 else 3
    prev = None
    err_v = err_g = zerr_v = zerr_g = 0.0
    level = 0
    mz, zl, zok = m, 0, 0

    def change(vol, gci):
        return (abs(vol - prev[0]) / vol if vol > 0 else (0.0 if prev[0] == 0 else 1.0)), abs(gci - prev[1])

    while True:
        scale = 3.0 ** level
        area = 1.0 / scale ** (ndim - 1)
        X = lo[0] + (ci + 0.5) * hx / scale
        Y = lo[1] + (cj + 0.5) * hy / scale
        inherit = 0 <= field_levels < level
        if src is None:
            L, S, owner, qv, qw = columns(X, Y, area, mz)
            lg[ci, cj], sg[ci, cj] = L, S
        else:  # the centre children repeat their parents' columns (values, 1/nk of the weights), the others are new
            lpar, spar = lg[ci, cj], sg[ci, cj]  # the parent's L, S (repeated over its children)
            inh = (src < 0) & inherit & (lpar > 0) & ~own
            new = (src < 0) & ~inh
            L, S, o_new, v_new, w_new = columns(X[new], Y[new], area, mz)
            lg[ci[new], cj[new]], sg[ci[new], cj[new]] = L, S  # the centre ones' L, S: the parent's (repeated)
            # inheriting children: their measure alone, their parent's Gauss points with the weights scaled
            Li, *_ = columns(X[inh], Y[inh], area, mz, fields_on=False)
            ia = np.flatnonzero(inh)
            lg[ci[ia], cj[ia]], sg[ci[ia], cj[ia]] = Li, Li * (spar[ia] / lpar[ia])
            ratio = np.zeros(ci.size)
            ratio[~new] = 1.0 / nk
            ratio[ia] = Li / (lpar[ia] * nk)
            parent = np.where(src >= 0, src, par)
            pos = np.flatnonzero(new)
            rep = np.flatnonzero(~new)
            take = [np.flatnonzero(p_owner == parent[a]) for a in rep]
            owner = np.concatenate([pos[o_new]] + [np.full(len(t), a) for a, t in zip(rep, take, strict=True)])
            qv = np.concatenate([v_new] + [p_qv[t] for t in take])
            qw = np.concatenate([w_new] + [p_qw[t] * ratio[a] for a, t in zip(rep, take, strict=True)])
        vol, ssum = lg.sum() * area, sg.sum() * area
        gci = ssum / vol if vol > 0 else 0.0
        if level == 0 and zl > 0:
            zerr_v, zerr_g = change(vol, gci)
            zok = zok + 1 if zerr_v <= tol_v and zerr_g <= tol_g else 0
        if level == 0 and zl < zlevels and zok < zconfirm:
            prev = (vol, gci)  # z-levels: again with twice the z-cells
            mz, zl = 2 * mz, zl + 1
            continue
        if level > 0:
            err_v, err_g = change(vol, gci)
        prev = (vol, gci)
        stop = level >= maxlev or (level >= 1 and err_v <= tol_v and err_g <= tol_g)
        flag = np.zeros(ci.size, dtype=bool)
        if not stop:  # second differences along each cross axis, neighbours clamped at the box
            if faces:  # the face column next to each active edge column (in column order, x faces first)
                for axis in range(ndim - 1):
                    idx, other = (ci, cj) if axis == 0 else (cj, ci)
                    fg = fxg if axis == 0 else fyg
                    for side in (0, 1):
                        if side == 0 and mirror[axis]:
                            continue  # a mirror plane: the edge column is its own neighbour (clamped)
                        e = idx == (0 if side == 0 else lg.shape[axis] - 1)
                        if not e.any():
                            continue
                        face = lo[axis] + (nudge if side == 0 else (n, ny)[axis] - nudge) * (hx if axis == 0 else hy)
                        FX = np.full(e.sum(), face) if axis == 0 else X[e]
                        FY = np.full(e.sum(), face) if axis == 1 else Y[e]
                        # with inherited fields: the face column's measure times the edge column's mean LCI
                        le, se = lg[ci[e], cj[e]], sg[ci[e], cj[e]]
                        fon = ~(inherit & (le > 0))
                        fl, fs = np.zeros(e.sum()), np.zeros(e.sum())
                        fl[fon], fs[fon], *_ = columns(FX[fon], FY[fon], area, mz)
                        lm, *_ = columns(FX[~fon], FY[~fon], area, mz, fields_on=False)
                        fl[~fon], fs[~fon] = lm, lm * (se[~fon] / np.where(fon, 1.0, le)[~fon])
                        fg[side, 0, other[e]], fg[side, 1, other[e]] = fl, fs
            for axis in range(ndim - 1):
                sh = lg.shape[axis]
                lo_i = (np.maximum(ci - 1, 0), cj) if axis == 0 else (ci, np.maximum(cj - 1, 0))
                hi_i = (np.minimum(ci + 1, sh - 1), cj) if axis == 0 else (ci, np.minimum(cj + 1, sh - 1))
                idx, other = (ci, cj) if axis == 0 else (cj, ci)
                fg = fxg if axis == 0 else fyg
                for t, (g, tol) in enumerate(((lg, tol_v), (sg, tol_g))):
                    c, below, above = g[ci, cj], g[lo_i], g[hi_i]
                    if faces:  # ghost neighbour 2 F - c beyond the box face (F: the face column)
                        if not mirror[axis]:
                            below = np.where(idx == 0, 2.0 * fg[0, t, other] - c, below)
                        above = np.where(idx == sh - 1, 2.0 * fg[1, t, other] - c, above)
                    d2 = np.abs(above + below - 2.0 * c)
                    flag |= d2 * area / 24.0 > tol * vol * beta / (n * ny)
            if 0 <= field_levels <= level:  # step 3b: the mean LCI's second differences (no measure: itself)
                ff = ~(lg[ci, cj] > 0)
                mean = np.where(lg > 0, sg / np.where(lg > 0, lg, 1.0), np.nan)
                mc = mean[ci, cj]
                for axis in range(ndim - 1):
                    sh = lg.shape[axis]
                    lo_i = (np.maximum(ci - 1, 0), cj) if axis == 0 else (ci, np.maximum(cj - 1, 0))
                    hi_i = (np.minimum(ci + 1, sh - 1), cj) if axis == 0 else (ci, np.minimum(cj + 1, sh - 1))
                    below = np.where(lg[lo_i] > 0, mean[lo_i], mc)
                    above = np.where(lg[hi_i] > 0, mean[hi_i], mc)
                    ff |= np.abs(above + below - 2.0 * mc) * lg[ci, cj] * area / 24.0 > tol_g * vol * beta / (n * ny)
            else:
                ff = np.ones(ci.size, dtype=bool)
        keep = ~flag[owner]
        kept_v.append(qv[keep])
        kept_w.append(qw[keep])
        if stop or not flag.any():
            break
        da, db = (v.ravel() for v in np.meshgrid(np.arange(3), np.arange(3 if ndim == 3 else 1), indexing="ij"))
        p_owner, p_qv, p_qw = owner, qv, qw
        centre = (da == 1) & ((db == 1) | (ndim == 2))
        src = np.where(centre[None, :], np.flatnonzero(flag)[:, None], -1).ravel()
        par = np.repeat(np.flatnonzero(flag), centre.size)
        own = np.repeat(ff[flag], centre.size)
        ci = (3 * ci[flag][:, None] + da[None, :]).ravel()
        cj = (3 * cj[flag][:, None] + db[None, :]).ravel() if ndim == 3 else np.zeros(ci.size, dtype=np.int64)
        lg = np.repeat(np.repeat(lg, 3, axis=0), 3 if ndim == 3 else 1, axis=1)
        sg = np.repeat(np.repeat(sg, 3, axis=0), 3 if ndim == 3 else 1, axis=1)
        fxg, fyg = np.repeat(fxg, 3 if ndim == 3 else 1, axis=2), np.repeat(fyg, 3, axis=2)
        level += 1
    v, wt = np.concatenate(kept_v), np.concatenate(kept_w)
    keep = wt > 0
    v, wt = v[keep], wt[keep]
    row = np.zeros(1 + 4 * n_fields + nb)
    row[0] = wt.sum()
    for f in range(n_fields):
        row[1 + 4 * f: 5 + 4 * f] = [(wt * v[:, f]).sum(), (wt * v[:, f] ** 2).sum(),
                                     v[:, f].min() if len(v) else np.inf, v[:, f].max() if len(v) else -np.inf]
    band = np.searchsorted(np.asarray(edges)[1:-1], v[:, 0], side="left")
    row[1 + 4 * n_fields:] = np.bincount(band, weights=wt, minlength=nb)
    return row, max(err_v, zerr_v), max(err_g, zerr_g), level, evals
