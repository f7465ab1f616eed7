"""The field-kernel template of described 6-DOF mechanisms (six RUS or UPS legs): one Numba kernel for every
description, over the constant-orientation workspace (the platform's orientation fixed by the options).

Everything is read from the packed vector ``p`` (``sixdof.SixDofMechanism.pack``): p[0] the number of legs (6),
p[1] = 1 / L (L the characteristic length that homogenises rotation), then per leg a block of STRIDE slots (layout
below). The orientation R is constant over a workspace, so ``pack`` stores each platform joint's offset already
turned, rho = R r (mechanism frame), and the kernel never sees R. Every Numba function of this template lives in
this one file (Numba's disk cache follows only the file of the function it compiles); float64 in, float64 out.

Per leg (closed form; docs/describing.md):

* RUS / R-SS (rotary arm, a rod with a spherical or universal joint at each end): elbow E = B + a (cos q u +
  sin q w); |Q - E| = l with Q = P + rho is A cos q + B sin q = K (D = Q - B, A = 2 a D.u, B = 2 a D.w,
  K = |D|^2 + a^2 - l^2), the R-Pa leg's equation for one rod; branch +1 ("out") the root with the larger cos q.
  Limits on q modulo 2 pi; the cone bounds the rod's component along the arm's axis: |f . axis| <= l sin(cone).
* UPS / SPS (prismatic leg between two joints): q = |Q - B|, limits lo <= q <= hi; the cone bounds the leg's angle
  to the base joint's axis and to the platform joint's (turned with the platform): n . axis >= cos(cone).

Velocity: with the platform twist (v, omega) of the platform centre P, each leg's closure differentiated gives
f_i . (v + omega x rho_i) = (f_i . t_i) q_dot_i (f_i the rod Q_i - E_i or the leg Q_i - B_i, t_i the actuated
point's velocity per unit q_dot_i; UPS: f_i unit and f_i . t_i = 1). So q_dot = M (v, L omega) with the rows of M
m_i = (f_i, (rho_i x f_i) / L) / (f_i . t_i): M is the homogenised inverse Jacobian and dx/dq = M^-1. The kernel
takes M's singular values by one-sided (Hestenes) Jacobi, which keeps the small ones to relative accuracy, and
reports those of dx/dq: LCI = s_min(M) / s_max(M), sigma_min = 1 / s_max(M), sigma_max = 1 / s_min(M) (capped).
Where some |f_i . t_i| <= SQUARE_TOL * a_i (a rod square to its arm: an inverse singularity, M unbounded) the
pose is written as singular (LCI 0, sigma_min 0, sigma_max the cap).

Stiffness (slots 3-4, only where the packed flag, options.stiffness_metrics, is set; else 0): stiffness_min and
deflection of frame6.py's idealisation, one bar wrench per leg (the section comment below).

Clearance (slot 5, only where the packed flag, options.clearance_metrics or interference_free, is set; else 0): the
smallest capsule gap of bodies.py's link capsules (kernels.clearance.packed_capsule_gap); with interference_free a
pose whose capsules overlap is unreachable in every kernel of the template.
"""

import math

import numpy as np
from numba import njit

from scalesynth.kernels import grid as _grid
from scalesynth.kernels.clearance import SEG_STRIDE, packed_capsule_gap
from scalesynth.kernels.conditioning import inverse_singular_values
from scalesynth.kernels.flags import FASTMATH
from scalesynth.stiffness import legs as _sl

# leg type codes (legs.LEG_TYPES' ``code``), distinct from the 3T template's
RUS = 3.0
UPS = 4.0
N_LEGS = 6  # motion 6DOF: six actuated legs, a square Jacobian
HEAD = 2  # p[0]: number of legs, p[1]: 1 / characteristic length
INV_L = 1
# slots of one leg's block, from HEAD + i * STRIDE
TYPE = 0
BASE = 1  # 3: base attachment B (RUS: on the arm's axis; UPS: the base joint's centre)
RHO = 4  # 3: platform joint Q minus the platform centre P, turned by the orientation (mechanism frame)
U = 7  # 3: RUS: arm direction at q = 0
W = 10  # 3: RUS: direction the arm turns to for q > 0
AXIS = 13  # 3: RUS: the arm's axis u x w; UPS: the base joint's cone axis
AXIS_P = 16  # 3: UPS: the platform joint's cone axis, turned by the orientation
ARM = 19  # RUS: arm length a
ROD = 20  # RUS: rod length l
BRANCH = 21  # RUS: +1 or -1
HAS_LIMITS = 22
LO = 23
HI = 24
HAS_CONE = 25
CONE = 26  # RUS: sin of the cone half-angle; UPS: its cosine
STRIDE = 27
N_KINEMATIC = HEAD + N_LEGS * STRIDE  # the slots above; the stiffness block (per-voxel stiffness fields) follows
# stiffness block, from N_KINEMATIC: a flag (1: options.stiffness_metrics, the fields are computed) and the load (N),
# then per leg SSTRIDE slots: the arm's section (EA, EI, GJ; RUS), the rod's or leg's EA and the actuator's spring
# (N length/rad rotary, N/length linear)
STIFF = N_KINEMATIC
LOAD = N_KINEMATIC + 1
SLEGS = N_KINEMATIC + 4
EA_ARM = 0
EI_ARM = 1
GJ_ARM = 2
EA_LINK = 3
K_ACT = 4
SSTRIDE = 5
N_STIFFNESS = SLEGS + N_LEGS * SSTRIDE
# clearance block, from N_STIFFNESS (kernel.py's layout): the field's flag, interference_free, 1 where the legs'
# capsules are alike, then the capsule block (at most: per leg an arm and a rod, the base and platform hexagons)
CLEAR = N_STIFFNESS
FREE = N_STIFFNESS + 1
UNIFORM = N_STIFFNESS + 2
CAPS = N_STIFFNESS + 3
MAX_CAPSULES = N_LEGS * 2 + 2 * N_LEGS
N_PACKED = CAPS + 2 + MAX_CAPSULES * SEG_STRIDE + MAX_CAPSULES * (MAX_CAPSULES - 1)
F_STIFFNESS_MIN = 3  # field slots of the stiffness fields
F_DEFLECTION = 4
F_CLEARANCE = 5  # field slot of the clearance
TWO_PI = 2.0 * math.pi
SQUARE_TOL = 1e-12  # |f . t| / (l a) at or below which a RUS leg counts as an exact inverse singularity
JACOBI_TOL = 1e-15  # columns count as orthogonal when |c_i . c_j| <= JACOBI_TOL |c_i| |c_j|
JACOBI_SWEEPS = 60


@njit(cache=True, fastmath=FASTMATH)
def _leg(p, k, x, y, z):
    """One leg at platform centre P = (x, y, z), block from p[k]: (ok, fx, fy, fz, jq, q, square): f the unit rod or
    leg direction, jq = f . t per unit rod length (UPS: 1), q the actuated joint value and square True where the
    rod is square to its arm (an inverse singularity); ok False where the leg does not reach P in its branch or a
    limit (actuator range, joint cone) excludes it."""
    qx = x + p[k + RHO]
    qy = y + p[k + RHO + 1]
    qz = z + p[k + RHO + 2]
    dx = qx - p[k + BASE]
    dy = qy - p[k + BASE + 1]
    dz = qz - p[k + BASE + 2]
    if p[k + TYPE] == RUS:
        ux = p[k + U]
        uy = p[k + U + 1]
        uz = p[k + U + 2]
        wx = p[k + W]
        wy = p[k + W + 1]
        wz = p[k + W + 2]
        la = p[k + ARM]
        lr = p[k + ROD]
        a = 2.0 * la * (dx * ux + dy * uy + dz * uz)
        b = 2.0 * la * (dx * wx + dy * wy + dz * wz)
        kk = dx * dx + dy * dy + dz * dz + la * la - lr * lr
        n2 = a * a + b * b
        if not n2 > 0.0:
            return False, 0.0, 0.0, 0.0, 0.0, 0.0, False  # Q on the arm's axis: the arm angle is undetermined
        n = math.sqrt(n2)
        h = (n - kk) * (n + kk)  # A^2 + B^2 - K^2, factored: keeps its accuracy at the reach boundary
        if h < 0.0:
            return False, 0.0, 0.0, 0.0, 0.0, 0.0, False
        s = math.sqrt(h)
        t = p[k + BRANCH] if b >= 0.0 else -p[k + BRANCH]
        c = (a * kk + t * b * s) / n2
        sn = (b * kk - t * a * s) / n2
        q = math.atan2(sn, c)
        if p[k + HAS_LIMITS] > 0.0:
            d = q - p[k + LO]
            d -= TWO_PI * math.floor(d / TWO_PI)
            if d > p[k + HI] - p[k + LO]:
                return False, 0.0, 0.0, 0.0, 0.0, 0.0, False
        fx = dx - la * (c * ux + sn * wx)
        fy = dy - la * (c * uy + sn * wy)
        fz = dz - la * (c * uz + sn * wz)
        if p[k + HAS_CONE] > 0.0:
            across = fx * p[k + AXIS] + fy * p[k + AXIS + 1] + fz * p[k + AXIS + 2]
            if abs(across) > lr * p[k + CONE]:
                return False, 0.0, 0.0, 0.0, 0.0, 0.0, False
        jq = la * (fx * (c * wx - sn * ux) + fy * (c * wy - sn * uy) + fz * (c * wz - sn * uz))
        inv = 1.0 / lr
        jq *= inv
        return True, fx * inv, fy * inv, fz * inv, jq, q, not abs(jq) > SQUARE_TOL * la
    # UPS
    q = math.sqrt(dx * dx + dy * dy + dz * dz)
    if not q > 0.0:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, False  # both joints at one point: the leg's direction is undetermined
    if p[k + HAS_LIMITS] > 0.0 and not (p[k + LO] <= q <= p[k + HI]):
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, False
    inv = 1.0 / q
    fx = dx * inv
    fy = dy * inv
    fz = dz * inv
    if p[k + HAS_CONE] > 0.0:
        cb = fx * p[k + AXIS] + fy * p[k + AXIS + 1] + fz * p[k + AXIS + 2]
        cp = fx * p[k + AXIS_P] + fy * p[k + AXIS_P + 1] + fz * p[k + AXIS_P + 2]
        if cb < p[k + CONE] or cp < p[k + CONE]:
            return False, 0.0, 0.0, 0.0, 0.0, 0.0, False
    return True, fx, fy, fz, 1.0, q, False


@njit(cache=True, fastmath=FASTMATH)
def _jacobi_extremes(g):
    """(s_min, s_max) of the 6 x 6 matrix g by one-sided Jacobi: rotate pairs of columns until every pair is
    orthogonal; the singular values are then the columns' norms. g is overwritten."""
    for _ in range(JACOBI_SWEEPS):
        turned = False
        for i in range(5):
            for j in range(i + 1, 6):
                alpha = 0.0
                beta = 0.0
                gamma = 0.0
                for r in range(6):
                    alpha += g[r, i] * g[r, i]
                    beta += g[r, j] * g[r, j]
                    gamma += g[r, i] * g[r, j]
                if not abs(gamma) > JACOBI_TOL * math.sqrt(alpha) * math.sqrt(beta):
                    continue
                turned = True
                zeta = (beta - alpha) / (2.0 * gamma)
                t = 1.0 / (abs(zeta) + math.hypot(1.0, zeta))
                if zeta < 0.0:
                    t = -t
                c = 1.0 / math.hypot(1.0, t)
                s = c * t
                for r in range(6):
                    gi = g[r, i]
                    gj = g[r, j]
                    g[r, i] = c * gi - s * gj
                    g[r, j] = s * gi + c * gj
        if not turned:
            break
    smin = math.inf
    smax = 0.0
    for j in range(6):
        nn = 0.0
        for r in range(6):
            nn += g[r, j] * g[r, j]
        nn = math.sqrt(nn)
        smin = min(smin, nn)
        smax = max(smax, nn)
    return smin, smax


@njit(cache=True, fastmath=FASTMATH)
def _gap(p, x, y, z):
    """Clearance (length unit) of the packed capsules at P = (x, y, z), every leg reaching it: a RUS leg's elbow
    E_i = Q_i - l_i f_i (a UPS leg has none: its row is unused)."""
    elbows = np.zeros((N_LEGS, 3))
    for i in range(N_LEGS):
        k = HEAD + i * STRIDE
        if p[k + TYPE] == RUS:
            _, fx, fy, fz, _, _, _ = _leg(p, k, x, y, z)
            lr = p[k + ROD]
            elbows[i, 0] = x + p[k + RHO] - lr * fx
            elbows[i, 1] = y + p[k + RHO + 1] - lr * fy
            elbows[i, 2] = z + p[k + RHO + 2] - lr * fz
    return packed_capsule_gap(p, CAPS, elbows, x, y, z)


@njit(cache=True, fastmath=FASTMATH)
def _fields(p, x, y, z, out, conditioning, stiffness=None):
    """Slots 0-2 (LCI, sigma_min, sigma_max of the homogenised dx/dq) at P, or write_unreachable; ``conditioning``
    (a constant) False stops after reach and limits with slot 0 = 0 where they pass (the reach kernel);
    ``stiffness`` True also writes slots 3-5 (stiffness_min, deflection, clearance; each 0 unless its packed flag is
    set), None (default) leaves them (a None test: Numba compiles both branches of a literal bool's; kernel.py's
    _fields). With the packed interference_free flag, overlapping capsules make the pose unreachable in every
    variant."""
    inv_l = p[INV_L]
    g = np.empty((6, 6))
    square = False
    for i in range(N_LEGS):
        k = HEAD + i * STRIDE
        ok, fx, fy, fz, jq, _, sq = _leg(p, k, x, y, z)
        if not ok:
            _grid.write_unreachable(out)
            return
        if not conditioning:
            continue
        square |= sq
        if square:
            continue
        rx = p[k + RHO]
        ry = p[k + RHO + 1]
        rz = p[k + RHO + 2]
        s = 1.0 / jq
        # column i of M^T: row m_i = (f, (rho x f) / L) / jq
        g[0, i] = fx * s
        g[1, i] = fy * s
        g[2, i] = fz * s
        g[3, i] = (ry * fz - rz * fy) * inv_l * s
        g[4, i] = (rz * fx - rx * fz) * inv_l * s
        g[5, i] = (rx * fy - ry * fx) * inv_l * s
    gap = 0.0
    if p[FREE] > 0.0 or (stiffness is not None and p[CLEAR] > 0.0):
        gap = _gap(p, x, y, z)
        if p[FREE] > 0.0 and gap < 0.0:
            _grid.write_unreachable(out)
            return
    if not conditioning:
        out[0] = 0.0
        return
    if square:
        _grid.write_singular(out)
    else:
        smin, smax = _jacobi_extremes(g)
        if not smax > 0.0:
            _grid.write_singular(out)
        else:
            out[0] = min(1.0, smin / smax)
            out[1], out[2] = inverse_singular_values(smin, smax)
    if stiffness is not None:
        if p[STIFF] > 0.0:
            # an inverse singularity is not one of the frame: the arm's bending and its spring still hold the rod
            out[F_STIFFNESS_MIN], out[F_DEFLECTION] = _stiffness(p, x, y, z)
        else:
            out[F_STIFFNESS_MIN] = 0.0
            out[F_DEFLECTION] = 0.0
        out[F_CLEARANCE] = gap


# ----- per-voxel stiffness (docs/describing.md): frame6.py's idealisation condensed per leg -----------------------
# Each leg passes one wrench to the rigid platform: the force along its rod or leg through the platform joint Q,
# w = (f, rho x f) at P (f the unit rod Q - E or leg Q - B, rho = Q - P): a RUS rod is a bar (a universal joint at the
# elbow, a spherical one at Q), a UPS leg too (universal at B, spherical at Q). Its flexibility phi = w^T C w over the
# chain: RUS, the arm as a cantilever B -> E loaded at its tip E by the force f alone (the rod's line passes through
# E; stiffness.legs.tip_bilinear), the actuator's torsional spring ((n . ((E - B) x f))^2 / k) and the rod's axial
# l / EA; UPS, 1 / k + q / EA (the leg of length q; its cylinder and piston halves in series). The platform
# K = sum w w^T / phi (the wrench form; stiffness.legs.outer_add) -> response_upper under the packed load, with the
# reference solver's characteristic length: its longest link (RUS the arm or rod, UPS a half leg, q / 2).


@njit(cache=True, fastmath=FASTMATH)
def _stiffness(p, x, y, z):
    """(stiffness_min N/length, deflection length) of the rigid platform at P = (x, y, z), every leg reaching it
    (the comment above; ideal joints); (0, DEFLECTION_CAP) where K is singular (0 deflection under no load)."""
    kk = (0.0,) * 21
    longest = 0.0
    for i in range(N_LEGS):
        k = HEAD + i * STRIDE
        s = SLEGS + i * SSTRIDE
        _, fx, fy, fz, _, q, _ = _leg(p, k, x, y, z)
        rx = p[k + RHO]
        ry = p[k + RHO + 1]
        rz = p[k + RHO + 2]
        if p[k + TYPE] == RUS:
            la = p[k + ARM]
            lr = p[k + ROD]
            c = math.cos(q)
            sn = math.sin(q)
            # arm B -> E, E - B = la (c u + sn w)
            ax = la * (c * p[k + U] + sn * p[k + W])
            ay = la * (c * p[k + U + 1] + sn * p[k + W + 1])
            az = la * (c * p[k + U + 2] + sn * p[k + W + 2])
            phi = _sl.tip_bilinear(la, p[s + EA_ARM], p[s + EI_ARM], p[s + GJ_ARM], ax / la, ay / la, az / la,
                                   fx, fy, fz, 0.0, 0.0, 0.0, fx, fy, fz, 0.0, 0.0, 0.0)
            m = p[k + AXIS] * (ay * fz - az * fy) + p[k + AXIS + 1] * (az * fx - ax * fz) + \
                p[k + AXIS + 2] * (ax * fy - ay * fx)
            phi += m * m / p[s + K_ACT] + lr / p[s + EA_LINK]
            longest = max(longest, la, lr)
        else:
            phi = 1.0 / p[s + K_ACT] + q / p[s + EA_LINK]
            longest = max(longest, 0.5 * q)
        w = 1.0 / math.sqrt(phi)
        kk = _sl.outer_add(kk, fx * w, fy * w, fz * w, (ry * fz - rz * fy) * w, (rz * fx - rx * fz) * w,
                           (rx * fy - ry * fx) * w)
    return _sl.response_upper(kk, p[LOAD], p[LOAD + 1], p[LOAD + 2], longest)


@njit(cache=True, fastmath=FASTMATH)
def point_fields(p, x, y, z, out):
    """The field kernel (kernels.grid contract): LCI, sigma_min, sigma_max of the homogenised dx/dq at platform
    centre P = (x, y, z) (orientation from the packed legs), and stiffness_min (N/length) and deflection (length
    unit) of the platform under the packed load where the packed flag asks for them (else 0; _stiffness), and the
    clearance of the link capsules (length unit) where its flag asks for it (else 0; _gap); -1 and zeros where a
    leg does not reach P in its branch, a limit excludes it or (interference_free) two capsules overlap."""
    _fields(p, x, y, z, out, True, True)


@njit(cache=True, fastmath=FASTMATH)
def point_lci(p, x, y, z, out):
    """Slots 0-2 of point_fields, bit for bit, without the stiffness and clearance stages (Mechanism.lci_kernel;
    interference_free still applies); slots 3-5 not written."""
    _fields(p, x, y, z, out, True)


@njit(cache=True, fastmath=FASTMATH)
def point_reach(p, x, y, z, out):
    """Slot 0 >= 0 exactly where point_fields' is (interference_free included), -1 elsewhere; no conditioning (the
    adaptive evaluator)."""
    _fields(p, x, y, z, out, False)


@njit(cache=True, fastmath=FASTMATH)
def leg_values(p, x, y, z, out):
    """Per leg i: out[i] = (ok 1/0, fx, fy, fz, jq, q, square 1/0) as _leg gives them (tests compare them with the
    NumPy legs)."""
    for i in range(N_LEGS):
        ok, fx, fy, fz, jq, q, sq = _leg(p, HEAD + i * STRIDE, x, y, z)
        out[i, 0] = 1.0 if ok else 0.0
        out[i, 1] = fx
        out[i, 2] = fy
        out[i, 3] = fz
        out[i, 4] = jq
        out[i, 5] = q
        out[i, 6] = 1.0 if sq else 0.0
