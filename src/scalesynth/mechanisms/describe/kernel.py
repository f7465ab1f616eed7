"""The field-kernel template of described 3T mechanisms (three Pa legs): one Numba kernel for every description.

A description is data, so its kernel reads everything from the packed vector ``p`` (``DescribedMechanism.pack``):
for each of the three legs a fixed block of STRIDE slots (layout below) with its leg type, attachment points in
the mechanism frame, arm/rail directions, link lengths, working-mode branch and limits. The leg type is a branch
on a slot value, taken the same way at every voxel (the branch predictor makes it free), so the kernel is
compiled once, disk-cached like every other module-level ``@njit`` function, and type-stable: float64 in, float64
out. Every Numba function of the template lives in this one file, because Numba's cache follows only the file of
the function it compiles (an edit to a leg in another file would not compile afresh).

Per leg (closed form; docs/mechanisms/delta.md and docs/describing.md):

* R-Pa (rotary arm + parallelogram): elbow E = B + L (cos q u + sin q w), u the arm direction at q = 0, w the
  direction it turns to (u x w is the actuated axis). The closure |Q - E| = l, Q = P + r_p the platform joint,
  is A cos q + B sin q = K with D = Q - B, A = 2 L D.u, B = 2 L D.w, K = |D|^2 + L^2 - l^2; reachable iff
  A^2 + B^2 >= K^2. cos q and sin q of both roots come out algebraically; branch +1 ("out") takes the root with the
  larger cos q (the elbow farther along u), -1 the other. Limits on q modulo 2 pi.
* P-Pa (prismatic carriage + parallelogram): carriage C = B + q e on a rail e; |Q - C| = l gives
  q = D.e +- sqrt(l^2 - |D - (D.e) e|^2); branch +1 ("far") the larger q. Limits on q as given.

Velocity: each leg's closure differentiated gives f_i . P_dot = (f_i . t_i) q_dot_i, f_i = Q_i - (elbow or carriage)
the forearm, t_i the actuated point's velocity per unit q_dot_i. So J_x P_dot = J_q q_dot with rows f_i^T and
J_q = diag(f_i . t_i), and dx/dq = J_x^-1 J_q = adj(J_x) J_q / det(J_x). The kernel takes the singular values of
adj(J_x) J_q (its columns are (f_j x f_k) (f_i . t_i)) and divides by |det J_x|: finite at both singularities, LCI 0
where J_x or J_q loses rank. Each f_i is first divided by its length l_i (rows and J_q alike), which leaves J
unchanged and keeps every product far from overflow.
"""

import math

from numba import njit

from scalesynth.kernels import grid as _grid
from scalesynth.kernels.conditioning import SIGMA_CAP, sv_3x3
from scalesynth.kernels.flags import FASTMATH

# leg type codes (legs.LEG_TYPES' ``code``)
R_PA = 1.0
P_PA = 2.0
N_LEGS = 3  # motion 3T: three actuated legs, a square Jacobian
HEAD = 2  # p[0]: number of legs, p[1]: reserved
# slots of one leg's block, from HEAD + i * STRIDE
TYPE = 0
BASE = 1  # 3: base attachment B (R-Pa: on the actuated axis; P-Pa: the rail's origin)
PLAT = 4  # 3: platform joint Q minus the platform centre P
U = 7  # 3: R-Pa: arm direction at q = 0; P-Pa: rail direction e
W = 10  # 3: R-Pa: direction the arm turns to for q > 0 (unused for P-Pa)
AXIS = 13  # 3: the normal of the leg's plane: the cone limit bounds the forearm's component along it
ARM = 16  # R-Pa: upper-arm length L
FOREARM = 17  # forearm length l
BRANCH = 18  # +1 or -1 (see module docstring)
HAS_LIMITS = 19
LO = 20
HI = 21
HAS_CONE = 22
SIN_CONE = 23  # sin of the cone half-angle: |f . axis| <= l sin(cone)
STRIDE = 24
N_PACKED = HEAD + N_LEGS * STRIDE
TWO_PI = 2.0 * math.pi


@njit(cache=True, fastmath=FASTMATH)
def _leg(p, k, x, y, z):
    """One leg at platform centre P = (x, y, z), block from p[k]: (ok, fx, fy, fz, jq, q) with (fx, fy, fz) the
    forearm direction (unit), jq = f . t / l (per unit forearm length) and q the actuated joint value; ok False when
    the leg does not reach P in its branch or its limits (actuator range, ball-joint cone) exclude it."""
    qx = x + p[k + PLAT]
    qy = y + p[k + PLAT + 1]
    qz = z + p[k + PLAT + 2]
    dx = qx - p[k + BASE]
    dy = qy - p[k + BASE + 1]
    dz = qz - p[k + BASE + 2]
    ux = p[k + U]
    uy = p[k + U + 1]
    uz = p[k + U + 2]
    lf = p[k + FOREARM]
    if p[k + TYPE] == R_PA:
        la = p[k + ARM]
        wx = p[k + W]
        wy = p[k + W + 1]
        wz = p[k + W + 2]
        a = 2.0 * la * (dx * ux + dy * uy + dz * uz)
        b = 2.0 * la * (dx * wx + dy * wy + dz * wz)
        kk = dx * dx + dy * dy + dz * dz + la * la - lf * lf
        n2 = a * a + b * b
        if not n2 > 0.0:
            return False, 0.0, 0.0, 0.0, 0.0, 0.0  # Q on the arm's axis: the arm angle is undetermined
        n = math.sqrt(n2)
        h = (n - kk) * (n + kk)  # A^2 + B^2 - K^2, factored: keeps its accuracy at the reach boundary
        if h < 0.0:
            return False, 0.0, 0.0, 0.0, 0.0, 0.0
        s = math.sqrt(h)
        t = p[k + BRANCH] if b >= 0.0 else -p[k + BRANCH]
        c = (a * kk + t * b * s) / n2
        sn = (b * kk - t * a * s) / n2
        q = math.atan2(sn, c)
        if p[k + HAS_LIMITS] > 0.0:
            d = q - p[k + LO]
            d -= TWO_PI * math.floor(d / TWO_PI)
            if d > p[k + HI] - p[k + LO]:
                return False, 0.0, 0.0, 0.0, 0.0, 0.0
        # forearm f = Q - E and the elbow's velocity per unit q_dot, t = L (-sin q u + cos q w)
        fx = dx - la * (c * ux + sn * wx)
        fy = dy - la * (c * uy + sn * wy)
        fz = dz - la * (c * uz + sn * wz)
        jq = la * (fx * (c * wx - sn * ux) + fy * (c * wy - sn * uy) + fz * (c * wz - sn * uz))
    else:  # P-Pa
        de = dx * ux + dy * uy + dz * uz
        px = dx - de * ux
        py = dy - de * uy
        pz = dz - de * uz
        perp = math.sqrt(px * px + py * py + pz * pz)
        h = (lf - perp) * (lf + perp)
        if h < 0.0:
            return False, 0.0, 0.0, 0.0, 0.0, 0.0
        q = de + p[k + BRANCH] * math.sqrt(h)
        if p[k + HAS_LIMITS] > 0.0 and not (p[k + LO] <= q <= p[k + HI]):
            return False, 0.0, 0.0, 0.0, 0.0, 0.0
        fx = dx - q * ux
        fy = dy - q * uy
        fz = dz - q * uz
        jq = fx * ux + fy * uy + fz * uz
    if p[k + HAS_CONE] > 0.0:
        across = fx * p[k + AXIS] + fy * p[k + AXIS + 1] + fz * p[k + AXIS + 2]
        if abs(across) > lf * p[k + SIN_CONE]:
            return False, 0.0, 0.0, 0.0, 0.0, 0.0
    inv = 1.0 / lf
    return True, fx * inv, fy * inv, fz * inv, jq * inv, q


@njit(cache=True, fastmath=FASTMATH)
def _fields(p, x, y, z, out, conditioning):
    """Slots 0-2 (LCI, sigma_min, sigma_max of dx/dq) at P, or write_unreachable; ``conditioning`` (a constant)
    False stops after reach and limits with slot 0 = 0 where they pass (the reach kernel)."""
    k1 = HEAD
    k2 = HEAD + STRIDE
    k3 = HEAD + 2 * STRIDE
    ok, ax, ay, az, j1, _ = _leg(p, k1, x, y, z)
    if not ok:
        _grid.write_unreachable(out)
        return
    ok, bx, by, bz, j2, _ = _leg(p, k2, x, y, z)
    if not ok:
        _grid.write_unreachable(out)
        return
    ok, cx, cy, cz, j3, _ = _leg(p, k3, x, y, z)
    if not ok:
        _grid.write_unreachable(out)
        return
    if not conditioning:
        out[0] = 0.0
        return
    # columns of adj(J_x): f2 x f3, f3 x f1, f1 x f2 (rows f1, f2, f3 = a, b, c)
    x1 = by * cz - bz * cy
    y1 = bz * cx - bx * cz
    z1 = bx * cy - by * cx
    x2 = cy * az - cz * ay
    y2 = cz * ax - cx * az
    z2 = cx * ay - cy * ax
    x3 = ay * bz - az * by
    y3 = az * bx - ax * bz
    z3 = ax * by - ay * bx
    det = ax * x1 + ay * y1 + az * z1
    # singular values of adj(J_x) J_q = those of its transpose, whose rows are jq_i (column i of adj)
    lci, smin, smax = sv_3x3(j1 * x1, j1 * y1, j1 * z1, j2 * x2, j2 * y2, j2 * z2, j3 * x3, j3 * y3, j3 * z3)
    out[0] = lci
    ad = abs(det)
    if not ad * SIGMA_CAP > smax:  # forward (parallel) singularity: dx/dq unbounded
        out[1] = 0.0
        out[2] = SIGMA_CAP
    else:
        out[1] = smin / ad
        out[2] = smax / ad


@njit(cache=True, fastmath=FASTMATH)
def point_fields(p, x, y, z, out):
    """The field kernel (kernels.grid contract): LCI, sigma_min, sigma_max of dx/dq at P = (x, y, z), -1 and zeros
    where a leg does not reach P in its branch or a limit excludes it."""
    _fields(p, x, y, z, out, True)


@njit(cache=True, fastmath=FASTMATH)
def point_reach(p, x, y, z, out):
    """Slot 0 >= 0 exactly where point_fields' is (same legs, branches and limits), -1 elsewhere; no conditioning
    (the adaptive evaluator's nodes and bisections)."""
    _fields(p, x, y, z, out, False)


@njit(cache=True, fastmath=FASTMATH)
def leg_values(p, x, y, z, out):
    """Per leg i: out[i] = (ok 1/0, fx, fy, fz, jq, q) as _leg gives them (tests compare them with the NumPy legs)."""
    for i in range(N_LEGS):
        ok, fx, fy, fz, jq, q = _leg(p, HEAD + i * STRIDE, x, y, z)
        out[i, 0] = 1.0 if ok else 0.0
        out[i, 1] = fx
        out[i, 2] = fy
        out[i, 3] = fz
        out[i, 4] = jq
        out[i, 5] = q
