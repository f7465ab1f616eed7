"""Slow NumPy twin of the rotary Delta, written from its textbook kinematics in the Delta's own conventions (z up,
base plane z = 0, leg i at phi_i = 0, 120, 240 deg, theta 0 horizontal outward and positive downward, elbows
out), independently of scalesynth's description machinery: per leg, in its own frame (x' = x cos phi + y sin phi,
y' = -x sin phi + y cos phi, a = R - r), A cos theta + B sin theta = K with A = 2 L (a - x'), B = 2 L z,
K = l^2 - L^2 - (a - x')^2 - y'^2 - z^2; theta = atan2(B, A) +- acos(K / hypot(A, B)), the root with the larger
cos theta; then J = Jx^-1 Jq with rows of Jx the forearm vectors s_i = Q_i - E_i and Jq = diag(s_i . dE_i/dtheta_i),
its singular values by np.linalg.svd."""

import numpy as np

PHIS = np.radians([0.0, 120.0, 240.0])


def delta_thetas(design, x, y, z):
    """Elbows-out arm angles (3, *shape) and the reach mask (*shape) at platform centres (x, y, z)."""
    R, r, L, l = (design[k] for k in ("base_radius", "platform_radius", "upper_arm", "forearm"))
    a = R - r
    x, y, z = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (x, y, z)))
    ok = np.ones(x.shape, dtype=bool)
    thetas = []
    with np.errstate(invalid="ignore", divide="ignore"):
        for phi in PHIS:
            xp = x * np.cos(phi) + y * np.sin(phi)
            yp = -x * np.sin(phi) + y * np.cos(phi)
            A = 2 * L * (a - xp)
            B = 2 * L * z
            K = l**2 - L**2 - (a - xp) ** 2 - yp**2 - z**2
            n = np.hypot(A, B)
            ok &= (n > 0) & (np.abs(K) <= n)
            g = np.arccos(np.clip(K / n, -1, 1))
            t1, t2 = np.arctan2(B, A) + g, np.arctan2(B, A) - g
            thetas.append(np.where(np.cos(t1) >= np.cos(t2), t1, t2))
    return np.array(thetas), ok


def delta_jacobian(design, p, thetas):
    """(Jx, Jq, J) at one pose p with arm angles thetas."""
    R, r, L = design["base_radius"], design["platform_radius"], design["upper_arm"]
    jx, jq = np.zeros((3, 3)), np.zeros((3, 3))
    for i, (phi, th) in enumerate(zip(PHIS, thetas, strict=True)):
        u = np.array([np.cos(phi), np.sin(phi), 0.0])
        e = (R + L * np.cos(th)) * u + np.array([0.0, 0.0, -L * np.sin(th)])
        s = np.asarray(p, dtype=float) + r * u - e
        de = np.array([-L * np.sin(th) * u[0], -L * np.sin(th) * u[1], -L * np.cos(th)])
        jx[i] = s
        jq[i, i] = s @ de
    return jx, jq, np.linalg.solve(jx, jq)


def delta_fields(design, options, x, y, z):
    """(LCI, sigma_min, sigma_max) of J = dx/dq at arrays of points, shape x.shape + (3,); LCI -1 (and 0, 0) where
    a leg does not reach or theta_limits (modulo 2 pi) exclude the elbows-out angle."""
    x, y, z = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (x, y, z)))
    thetas, ok = delta_thetas(design, x, y, z)
    lim = options.get("theta_limits")
    if lim is not None:
        for th in thetas:
            ok &= np.mod(th - lim[0], 2 * np.pi) <= lim[1] - lim[0]
    out = np.zeros(x.shape + (3,))
    out[..., 0] = -1.0
    for idx in zip(*np.nonzero(ok), strict=True):
        _, _, j = delta_jacobian(design, (x[idx], y[idx], z[idx]), thetas[(slice(None), *idx)])
        sv = np.linalg.svd(j, compute_uv=False)
        out[idx] = (sv[-1] / sv[0], sv[-1], sv[0])
    return out


def linear_delta_fields(design, options, x, y, z):
    """The linear Delta's (LCI, sigma_min, sigma_max) of J = dx/dq at arrays of points, shape x.shape + (3,), LCI -1
    (and 0, 0) where unreachable. Independent of the description machinery: leg i's rail is the vertical line through
    a (cos phi_i, sin phi_i) (a = R - r, the platform offset taken off); at platform centre P its carriage is
    h_i = sqrt(l^2 - d_i^2) above P (d_i the horizontal distance from P to that line), at depth s_i = -z - h_i below
    the base plane, which must lie in options['stroke']. The forearm f_i = P - C_i = (P_xy - c_i, -h_i),
    J = Jx^-1 Jq with Jx rows f_i and Jq = diag(f_i . (0, 0, -1)) = diag(h_i); singular values by np.linalg.svd."""
    a, l = design["base_radius"] - design["platform_radius"], design["forearm"]
    lo, hi = options["stroke"]
    x, y, z = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (x, y, z)))
    out = np.zeros(x.shape + (3,))
    out[..., 0] = -1.0
    for idx in np.ndindex(x.shape):
        rows = []
        for phi in PHIS:
            dx, dy = x[idx] - a * np.cos(phi), y[idx] - a * np.sin(phi)
            d2 = dx * dx + dy * dy
            if d2 > l * l:
                break
            h = np.sqrt(l * l - d2)
            if not lo <= -z[idx] - h <= hi:
                break
            rows.append([dx, dy, -h])
        if len(rows) < 3:
            continue
        jx = np.array(rows)
        jq = np.diag(-jx[:, 2])
        sv = np.linalg.svd(np.linalg.solve(jx, jq), compute_uv=False)
        out[idx] = (sv[-1] / sv[0], sv[-1], sv[0])
    return out


def linear_delta_volume(design, options, zlim, n=2000):
    """The linear Delta's workspace volume by its closed form, a double integral: at a point of the plane with
    horizontal distances d_i <= l to the three rails (a = R - r, as linear_delta_fields), z ranges over
    [-s_hi - h_i, -s_lo - h_i] for every i (h_i = sqrt(l^2 - d_i^2), [s_lo, s_hi] the stroke), within zlim = (z_lo,
    z_hi); the height min(-s_lo - max h_i, z_hi) - max(-s_hi - min h_i, z_lo) (at least 0) integrated by the
    midpoint rule on an n x n grid of the box of the three discs' intersection, that of the curved triangle about the
    axis where l < 2 a / sqrt(3) (x in [a - l, rho], |y| <= rho sin 60 deg, rho = sqrt(l^2 - 3 a^2 / 4) - a / 2, its
    corners at rho, 120 and 240 deg): a sliver's own extent (smooth integrand inside, O(1/n) at the rims)."""
    a, ll = design["base_radius"] - design["platform_radius"], design["forearm"]
    s_lo, s_hi = options["stroke"]
    if ll < a:
        return 0.0
    centres = a * np.stack([np.cos(PHIS), np.sin(PHIS)], axis=1)
    lo, hi = (centres - ll).max(axis=0), (centres + ll).min(axis=0)
    if ll < 2.0 * a / np.sqrt(3.0):
        rho = np.sqrt(ll * ll - 0.75 * a * a) - 0.5 * a
        lo, hi = np.maximum(lo, [a - ll, -rho * np.sqrt(0.75)]), np.minimum(hi, [rho, rho * np.sqrt(0.75)])
    x, y = np.meshgrid(lo[0] + (np.arange(n) + 0.5) * (hi[0] - lo[0]) / n,
                       lo[1] + (np.arange(n) + 0.5) * (hi[1] - lo[1]) / n, indexing="ij")
    d2 = np.stack([(x - c[0]) ** 2 + (y - c[1]) ** 2 for c in centres])
    h = np.sqrt(np.clip(ll * ll - d2, 0.0, None))
    top = np.minimum(-s_lo - h.max(axis=0), zlim[1])
    bottom = np.maximum(-s_hi - h.min(axis=0), zlim[0])
    height = np.where((d2 <= ll * ll).all(axis=0), np.clip(top - bottom, 0.0, None), 0.0)
    return float(height.sum() * (hi[0] - lo[0]) * (hi[1] - lo[1]) / n**2)


def ren_thetas(L, l, R, r, x, y, z):
    """Arm angles (3, *shape), elbows out (the root with the larger cos theta), and the reach mask, written from Ren,
    Zheng and Wang 2026, eq. (6)-(10): leg i at alpha_i = 0, 120, 240 deg, [(R - r + L cos t) cos a - x]^2 +
    [(R - r + L cos t) sin a - y]^2 + (L sin t + z)^2 = l^2, with t = tan(theta / 2) the quadratic
    A t^2 + B t + C = 0, A = K - 2 L (a - w), B = 4 L z, C = K + 2 L (a - w), a = R - r, w = x cos a_i + y sin a_i,
    K = a^2 + L^2 + x^2 + y^2 + z^2 - l^2 - 2 a w (re-derived here: the paper's eq. (8) prints C's last term as
    -2 L (R - r)); theta = 2 arctan t."""
    x, y, z = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (x, y, z)))
    a = R - r
    ok = np.ones(x.shape, dtype=bool)
    out = []
    with np.errstate(invalid="ignore", divide="ignore"):
        for alpha in PHIS:
            w = x * np.cos(alpha) + y * np.sin(alpha)
            k = a * a + L * L + x * x + y * y + z * z - l * l - 2 * a * w
            qa, qb, qc = k - 2 * L * (a - w), 4 * L * z, k + 2 * L * (a - w)
            disc = qb * qb - 4 * qa * qc
            ok &= disc >= 0
            s = np.sqrt(np.clip(disc, 0.0, None))
            t1, t2 = 2 * np.arctan((-qb + s) / (2 * qa)), 2 * np.arctan((-qb - s) / (2 * qa))
            out.append(np.where(np.cos(t1) >= np.cos(t2), t1, t2))
    return np.array(out), ok


def ren_volume(L, l, R, r, theta_limits, h, z_max=0.0):
    """Volume of the points at or below z_max whose three elbows-out angles (ren_thetas) lie in theta_limits (rad,
    not wrapped), counted on a cell-centred grid of step h over the box |x|, |y| <= R - r + L + l,
    z in [-(L + l), z_max] (lengths in one unit, volume in its cube)."""
    lo, hi = theta_limits
    reach = R - r + L + l
    xs = np.arange(-reach, reach, h) + 0.5 * h
    x, y = np.meshgrid(xs, xs, indexing="ij")
    count = 0
    for z in np.arange(-(L + l), z_max, h) + 0.5 * h:
        th, ok = ren_thetas(L, l, R, r, x, y, z)
        count += int((ok & np.all((th >= lo) & (th <= hi), axis=0)).sum())
    return count * h ** 3
