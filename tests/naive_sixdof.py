"""Slow NumPy twins of the hexapod (6 x UPS) and the Hexa (6 x RUS), written from their textbook kinematics in the
conventions of their doc pages, independently of scalesynth's description machinery (no legs, no packing, no
expressions): the joint points come straight from the design parameters, the platform's orientation is
R = Rz(yaw) Ry(pitch) Rx(roll) of options['orientation'], and the homogenised Jacobian is H = diag(I, L I) Jx^-1 Jq
with rows of Jx [f_i, (R r_i) x f_i], its singular values by np.linalg.svd.

* Hexapod: base joint i at base_radius (cos, sin)(phi_i + s_i base_half_angle), platform joint at platform_radius
  (cos, sin)(phi_i + s_i platform_half_angle), legs ordered a1 a2 a3 b1 b2 b3 (s = +1 for a, -1 for b,
  phi = 0, 120, 240 deg). q_i = |P + R r_i - B_i| in options['leg_length']; Jq = I and f_i the unit leg.
* Hexa: arm i's axis along the tangent at phi_i through c_i = base_radius e_phi + s_i arm_spacing t_phi; the elbow
  E_i = c_i + arm (cos theta e_phi - sin theta z) (theta 0 outward, positive downward); |P + R r_i - E_i| = rod;
  of the two roots the one with the larger cos theta (elbows out); theta_limits modulo 2 pi; Jq = diag(f_i . dE_i).
"""

import numpy as np

PHIS = np.radians([0.0, 120.0, 240.0])
SIGNS = (1.0, 1.0, 1.0, -1.0, -1.0, -1.0)


def rotation(rpy):
    a, b, c = rpy
    rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    rz = np.array([[np.cos(c), -np.sin(c), 0], [np.sin(c), np.cos(c), 0], [0, 0, 1]])
    return rz @ ry @ rx


def _phis():
    return [PHIS[i % 3] for i in range(6)]


def hexapod_points(design):
    """(B (6, 3), r (6, 3)): base joints and platform joint offsets (platform frame)."""
    R, r, ab, ap = (design[k] for k in ("base_radius", "platform_radius", "base_half_angle", "platform_half_angle"))
    b = np.array([[R * np.cos(p + s * ab), R * np.sin(p + s * ab), 0.0] for p, s in zip(_phis(), SIGNS, strict=True)])
    q = np.array([[r * np.cos(p + s * ap), r * np.sin(p + s * ap), 0.0] for p, s in zip(_phis(), SIGNS, strict=True)])
    return b, q


def hexa_points(design):
    """(c (6, 3) the arm axes' points, e (6, 3) the outward directions, r (6, 3) platform joint offsets)."""
    R, s_, r, ap = (design[k] for k in ("base_radius", "arm_spacing", "platform_radius", "platform_half_angle"))
    c, e, q = [], [], []
    for p, s in zip(_phis(), SIGNS, strict=True):
        ep = np.array([np.cos(p), np.sin(p), 0.0])
        tp = np.array([-np.sin(p), np.cos(p), 0.0])
        c.append(R * ep + s * s_ * tp)
        e.append(ep)
        q.append([r * np.cos(p + s * ap), r * np.sin(p + s * ap), 0.0])
    return np.array(c), np.array(e), np.array(q)


def characteristic_length(options, r):
    return options.get("characteristic_length") or np.linalg.norm(r, axis=1).max()


def _sv(jx, jq, length):
    """(LCI, sigma_min, sigma_max) of H; (0, 0, inf) where Jx is exactly singular (dx/dq unbounded)."""
    try:
        j = np.linalg.solve(jx, jq)
    except np.linalg.LinAlgError:
        return 0.0, 0.0, np.inf
    h = np.vstack([j[:3], length * j[3:]])
    sv = np.linalg.svd(h, compute_uv=False)
    return sv[-1] / sv[0], sv[-1], sv[0]


def hexapod_fields(design, options, x, y, z):
    """(LCI, sigma_min, sigma_max) of H at arrays of platform centres, shape x.shape + (3,); LCI -1 (0, 0) where a
    leg length leaves options['leg_length']."""
    b, r = hexapod_points(design)
    rot = rotation(options.get("orientation") or (0.0, 0.0, 0.0))
    rho = r @ rot.T
    length = characteristic_length(options, r)
    lo, hi = options["leg_length"]
    x, y, z = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (x, y, z)))
    out = np.zeros(x.shape + (3,))
    out[..., 0] = -1.0
    for idx in np.ndindex(x.shape):
        f = np.array([x[idx], y[idx], z[idx]]) + rho - b
        q = np.linalg.norm(f, axis=1)
        if not np.all((q >= lo) & (q <= hi)):
            continue
        n = f / q[:, None]
        jx = np.hstack([n, np.cross(rho, n)])
        out[idx] = _sv(jx, np.eye(6), length)
    return out


def hexa_thetas(design, options, p):
    """Elbows-out arm angles (6,) at platform centre p, or None where a rod does not reach."""
    c, e, r = hexa_points(design)
    rot = rotation(options.get("orientation") or (0.0, 0.0, 0.0))
    L, l = design["arm"], design["rod"]
    out = []
    for ci, ei, ri in zip(c, e, r, strict=True):
        d = np.asarray(p, dtype=float) + rot @ ri - ci
        # |d - L (cos t e - sin t z)|^2 = l^2: A cos t + B sin t = K
        A, B, K = 2 * L * (d @ ei), -2 * L * d[2], d @ d + L * L - l * l
        n = np.hypot(A, B)
        if n == 0 or abs(K) > n:
            return None
        g = np.arccos(K / n)
        t1, t2 = np.arctan2(B, A) + g, np.arctan2(B, A) - g
        out.append(t1 if np.cos(t1) >= np.cos(t2) else t2)
    return np.arctan2(np.sin(out), np.cos(out))


def hexa_fields(design, options, x, y, z):
    """(LCI, sigma_min, sigma_max) of H at arrays of platform centres, shape x.shape + (3,); LCI -1 (0, 0) where a
    rod does not reach or theta_limits exclude an elbows-out angle."""
    c, e, r = hexa_points(design)
    rot = rotation(options.get("orientation") or (0.0, 0.0, 0.0))
    rho = r @ rot.T
    length = characteristic_length(options, r)
    L = design["arm"]
    lim = options.get("theta_limits")
    zz = np.array([0.0, 0.0, 1.0])
    x, y, z = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (x, y, z)))
    out = np.zeros(x.shape + (3,))
    out[..., 0] = -1.0
    for idx in np.ndindex(x.shape):
        p = np.array([x[idx], y[idx], z[idx]])
        th = hexa_thetas(design, options, p)
        if th is None or (lim is not None and np.any(np.mod(th - lim[0], 2 * np.pi) > lim[1] - lim[0])):
            continue
        jx, jq = np.zeros((6, 6)), np.zeros((6, 6))
        for i in range(6):
            elbow = c[i] + L * (np.cos(th[i]) * e[i] - np.sin(th[i]) * zz)
            f = p + rho[i] - elbow
            jx[i] = np.concatenate([f, np.cross(rho[i], f)])
            jq[i, i] = f @ (L * (-np.sin(th[i]) * e[i] - np.cos(th[i]) * zz))
        out[idx] = _sv(jx, jq, length)
    return out


def masory_wang_level_volume(rp, rb, alpha_p, alpha_b, lo, hi, theta_max, n=200):
    """Workspace volume of a Stewart platform held level (no rotation), written from Masory and Wang 1995: the joints
    of their eq. (1), b_i = rb (cos, sin)(a_bi), p_i = rp (cos, sin)(a_pi) with a_b = (ab, 120 - ab, 120 + ab,
    240 - ab, 240 + ab, 360 - ab) deg (a_p alike), leg i from B_i to P + p_i; leg lengths in [lo, hi] (their
    eq. (4)) and the joint angles of eq. (5a), (5b) with perpendicular mounting (n_b = n_p = z), i.e. every leg
    within theta_max of the vertical. Along a vertical line at horizontal distance rho from c_i = b_i - p_i leg i
    holds z in [max(rho cot theta_max, sqrt(lo^2 - rho^2)), sqrt(hi^2 - rho^2)]; the six intervals' intersection
    is integrated over (x, y) by the midpoint rule, n cells along the longer side of the box where every leg's
    horizontal reach hi sin theta_max covers (lengths in the paper's units, volume in their cube). Angles in
    rad."""
    deg = np.radians([0.0, 120.0, 120.0, 240.0, 240.0, 360.0])
    sign = np.array([1.0, -1.0, 1.0, -1.0, 1.0, -1.0])
    ab, ap = deg + sign * alpha_b, deg + sign * alpha_p
    c = np.stack([rb * np.cos(ab) - rp * np.cos(ap), rb * np.sin(ab) - rp * np.sin(ap)], axis=1)
    reach = hi * np.sin(theta_max)
    (x0, y0), (x1, y1) = (c - reach).max(axis=0), (c + reach).min(axis=0)
    if x1 <= x0 or y1 <= y0:
        return 0.0
    h = max(x1 - x0, y1 - y0) / n
    x, y = np.meshgrid(x0 + (np.arange(int(np.ceil((x1 - x0) / h))) + 0.5) * h,
                       y0 + (np.arange(int(np.ceil((y1 - y0) / h))) + 0.5) * h, indexing="ij")
    z_lo, z_hi = np.zeros(x.shape), np.full(x.shape, np.inf)
    for cx, cy in c:
        rho2 = (x - cx) ** 2 + (y - cy) ** 2
        top = np.where(rho2 <= hi * hi, np.sqrt(np.clip(hi * hi - rho2, 0.0, None)), -np.inf)
        bottom = np.maximum(np.sqrt(rho2) / np.tan(theta_max), np.sqrt(np.clip(lo * lo - rho2, 0.0, None)))
        z_lo, z_hi = np.maximum(z_lo, bottom), np.minimum(z_hi, top)
    return float(np.clip(z_hi - z_lo, 0.0, None).sum() * h * h)
