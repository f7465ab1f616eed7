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

Stiffness (slots 3-4, only where the packed flag, options.stiffness_metrics, is set; else 0): stiffness_min and
deflection of frame.py's idealisation, condensed per leg in closed form (the section comment below).

Clearance (slot 5, only where the packed flag, options.clearance_metrics or interference_free, is set; else 0): the
smallest capsule gap of bodies.py's link capsules (the packed capsule block, kernels.clearance.packed_capsule_gap);
with interference_free a pose whose capsules overlap is unreachable in every kernel of the template.
"""

import math

import numpy as np
from numba import njit

from scalesynth.kernels import grid as _grid
from scalesynth.kernels.clearance import SEG_STRIDE, packed_capsule_gap
from scalesynth.kernels.conditioning import SIGMA_CAP, sv_3x3
from scalesynth.kernels.flags import FASTMATH
from scalesynth.stiffness import legs as _sl

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
N_KINEMATIC = HEAD + N_LEGS * STRIDE  # the slots above; the stiffness block (per-voxel stiffness fields) follows
# stiffness block, from N_KINEMATIC: a flag (1: options.stiffness_metrics, the fields are computed), the load
# (N), the characteristic length of the singularity test (the longest link, as the reference solver's), then per
# leg SSTRIDE slots: sections (EA, EI, GJ) of the upper arm (R-Pa) and of each forearm bar, the actuator's spring
# (N length/rad rotary, N/length linear) and half the parallelogram's width
STIFF = N_KINEMATIC
LOAD = N_KINEMATIC + 1
CHAR_LEN = N_KINEMATIC + 4
SLEGS = N_KINEMATIC + 5
EA_ARM = 0
EI_ARM = 1
GJ_ARM = 2
EA_BAR = 3
EI_BAR = 4
GJ_BAR = 5
K_ACT = 6
HALF_WIDTH = 7
SSTRIDE = 8
N_STIFFNESS = SLEGS + N_LEGS * SSTRIDE
# clearance block, from N_STIFFNESS: a flag (1: the clearance field is computed), the interference_free flag, 1 where
# the legs' capsules are alike (bodies.uniform_legs: the field keeps the legs' symmetry), then the capsule block of
# kernels.clearance (at most MAX_CAPSULES capsules: per leg an arm or rail, its elbow or carriage side and two bars;
# the base triangle; the platform polygon of six corners)
CLEAR = N_STIFFNESS
FREE = N_STIFFNESS + 1
UNIFORM = N_STIFFNESS + 2
CAPS = N_STIFFNESS + 3
MAX_CAPSULES = N_LEGS * 4 + N_LEGS + 2 * N_LEGS
N_PACKED = CAPS + 2 + MAX_CAPSULES * SEG_STRIDE + MAX_CAPSULES * (MAX_CAPSULES - 1)
F_STIFFNESS_MIN = 3  # field slots of the stiffness fields
F_DEFLECTION = 4
F_CLEARANCE = 5  # field slot of the clearance
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
def _gap(p, x, y, z, ax, ay, az, bx, by, bz, cx, cy, cz):
    """Clearance (length unit) of the packed capsules at P = (x, y, z) whose legs reach it with unit forearms a, b,
    c: each elbow or carriage E_i = Q_i - l_i f_i."""
    elbows = np.empty((N_LEGS, 3))
    f = np.array([ax, ay, az, bx, by, bz, cx, cy, cz])
    for i in range(N_LEGS):
        k = HEAD + i * STRIDE
        lf = p[k + FOREARM]
        elbows[i, 0] = x + p[k + PLAT] - lf * f[3 * i]
        elbows[i, 1] = y + p[k + PLAT + 1] - lf * f[3 * i + 1]
        elbows[i, 2] = z + p[k + PLAT + 2] - lf * f[3 * i + 2]
    return packed_capsule_gap(p, CAPS, elbows, x, y, z)


@njit(cache=True, fastmath=FASTMATH)
def _fields(p, x, y, z, out, conditioning, stiffness=None):
    """Slots 0-2 (LCI, sigma_min, sigma_max of dx/dq) at P, or write_unreachable; ``conditioning`` (a constant)
    False stops after reach and limits with slot 0 = 0 where they pass (the reach kernel); ``stiffness`` True also
    writes slots 3-5 (stiffness_min, deflection, clearance; each 0 unless its packed flag is set), None (default)
    leaves them: a None test, because Numba drops the branch of a None argument by its type but compiles both
    branches of a literal bool's (the stiffness and clearance stages are most of the template's compile time).
    With the packed interference_free flag, overlapping capsules make the pose unreachable in every variant."""
    # np.int64, not the literal HEAD: Numba would compile _leg a second time for the literal 2 (the column
    # kernel's loop calls it with an int64)
    k1 = np.int64(HEAD)
    k2 = k1 + STRIDE
    k3 = k1 + 2 * STRIDE
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
    gap = 0.0
    if p[FREE] > 0.0 or (stiffness is not None and p[CLEAR] > 0.0):
        gap = _gap(p, x, y, z, ax, ay, az, bx, by, bz, cx, cy, cz)
        if p[FREE] > 0.0 and gap < 0.0:
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
    if stiffness is not None:
        if p[STIFF] > 0.0:
            out[F_STIFFNESS_MIN], out[F_DEFLECTION] = _stiffness(p, x, y, z, ax, ay, az, bx, by, bz, cx, cy, cz)
        else:
            out[F_STIFFNESS_MIN] = 0.0
            out[F_DEFLECTION] = 0.0
        out[F_CLEARANCE] = gap


@njit(cache=True, fastmath=FASTMATH)
def point_fields(p, x, y, z, out):
    """The field kernel (kernels.grid contract): LCI, sigma_min, sigma_max of dx/dq at P = (x, y, z), and
    stiffness_min (N/length) and deflection (length unit) of the platform under the packed load where the packed
    flag asks for them (else 0; _stiffness), and the clearance of the link capsules (length unit) where its flag
    asks for it (else 0; _gap); -1 and zeros where a leg does not reach P in its branch, a limit excludes it or
    (interference_free) two capsules overlap."""
    _fields(p, x, y, z, out, True, True)


@njit(cache=True, fastmath=FASTMATH)
def point_lci(p, x, y, z, out):
    """Slots 0-2 of point_fields, bit for bit, without the stiffness and clearance stages (Mechanism.lci_kernel: a
    search whose workspace metrics are the LCI's alone; interference_free still applies); slots 3-5 not written."""
    _fields(p, x, y, z, out, True)


@njit(cache=True, fastmath=FASTMATH)
def point_reach(p, x, y, z, out):
    """Slot 0 >= 0 exactly where point_fields' is (same legs, branches, limits and interference_free), -1
    elsewhere; no conditioning (the adaptive evaluator's nodes and bisections)."""
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


# ----- per-voxel stiffness (docs/describing.md): the idealisation of frame.py, condensed per leg ------------------
# Leg i: the platform joint Q = P + r (r the packed platform offset), the elbow or carriage E = Q - l f (f the unit
# forearm), n the leg's normal (R-Pa: the actuated axis), h half the parallelogram's width.
# * E to platform: each bar E +- h n -> Q +- h n sits on universal joints (t, n) at both ends, t = unit(n x f), so it
#   passes only the wrenches reciprocal to those four rotations: its axial force, w_+- = (f, (r +- h n) x f) at P,
#   and a couple along m = unit(n x t) = (n (n . f) - f) / s, s = |n x f|, w_m = (0, m). On the bar, a cantilever of
#   length l loaded at its tip, the two do not couple (the force lies on its axis): flexibilities l / EA and
#   l (s^2 / GJ + (1 - s^2) / EI) (m . f = -s). The two bars share w_m: the parallelogram passes the wrenches
#   W = [w_+, w_-, w_m] with flexibility diag(l / EA, l / EA, half the couple's).
# * base to E, in series (the same wrench passes): R-Pa, the upper arm B -> E as a cantilever clamped on the
#   actuator (stiffness.legs.tip_bilinear of the wrenches moved to E) and the actuator's torsional spring about n
#   through B ((n . M_B)(n . M_B') / k); P-Pa, the carriage's spring along the rail ((u . F)(u . F') / k).
# * the leg: K_leg = W Phi^-1 W^T with Phi the sum of the two (3 x 3), the wrench form of stiffness.legs
#   (N (N^T C N)^-1 N^T over the leg's chain); the platform K = sum of the legs' (6 x 6 at P, as 21 scalars) ->
#   stiffness.legs.response_upper under the packed load. tests/test_delta_stiffness_fields.py holds it equal to the
#   frame assembled and solved per pose (stiffness.solve).


@njit(cache=True, fastmath=FASTMATH, inline="always")
def _base_flex(p, k, s, rot, lax, lay, laz, ex, ey, ez, f1x, f1y, f1z, m1x, m1y, m1z, f2x, f2y, f2z, m2x, m2y, m2z):
    """w1^T C_e w2 for wrenches (F, M) at P and the compliance C_e of leg k's base-to-E chain (the comment above):
    ``rot`` True for R-Pa, whose arm runs B -> E = B + la (la: E - B; E = (ex, ey, ez) minus P)."""
    if not rot:
        a1 = f1x * p[k + U] + f1y * p[k + U + 1] + f1z * p[k + U + 2]
        a2 = f2x * p[k + U] + f2y * p[k + U + 1] + f2z * p[k + U + 2]
        return a1 * a2 / p[s + K_ACT]
    # moments about E (P - E = -e) and about B (P - B = -e + la)
    n1x = m1x - (ey * f1z - ez * f1y)
    n1y = m1y - (ez * f1x - ex * f1z)
    n1z = m1z - (ex * f1y - ey * f1x)
    n2x = m2x - (ey * f2z - ez * f2y)
    n2y = m2y - (ez * f2x - ex * f2z)
    n2z = m2z - (ex * f2y - ey * f2x)
    length = math.sqrt(lax * lax + lay * lay + laz * laz)
    inv = 1.0 / length
    beam = _sl.tip_bilinear(length, p[s + EA_ARM], p[s + EI_ARM], p[s + GJ_ARM], lax * inv, lay * inv, laz * inv,
                            f1x, f1y, f1z, n1x, n1y, n1z, f2x, f2y, f2z, n2x, n2y, n2z)
    nx = p[k + AXIS]
    ny = p[k + AXIS + 1]
    nz = p[k + AXIS + 2]
    b1 = nx * (n1x + lay * f1z - laz * f1y) + ny * (n1y + laz * f1x - lax * f1z) + nz * (n1z + lax * f1y - lay * f1x)
    b2 = nx * (n2x + lay * f2z - laz * f2y) + ny * (n2y + laz * f2x - lax * f2z) + nz * (n2z + lax * f2y - lay * f2x)
    return beam + b1 * b2 / p[s + K_ACT]


@njit(cache=True, fastmath=FASTMATH)
def _add_leg(kk, p, k, s, x, y, z, fx, fy, fz):
    """(ok, kk + K_leg's 21 upper entries) for leg block k (stiffness slots from s) with unit forearm f, at
    P = (x, y, z) (the comment above); ok False where the leg's wrench space is degenerate (kk unchanged)."""
    lf = p[k + FOREARM]
    rx = p[k + PLAT]
    ry = p[k + PLAT + 1]
    rz = p[k + PLAT + 2]
    nx = p[k + AXIS]
    ny = p[k + AXIS + 1]
    nz = p[k + AXIS + 2]
    h = p[s + HALF_WIDTH]
    nf = nx * fx + ny * fy + nz * fz
    sn2 = 1.0 - nf * nf
    if not sn2 > 0.0:
        return False, kk  # a forearm along the leg's normal: its universal joints' axes coincide
    sn = math.sqrt(sn2)
    mx = (nx * nf - fx) / sn
    my = (ny * nf - fy) / sn
    mz = (nz * nf - fz) / sn
    # axial wrenches' moments at P: (r +- h n) x f = c0 +- h c1
    c0x = ry * fz - rz * fy
    c0y = rz * fx - rx * fz
    c0z = rx * fy - ry * fx
    c1x = h * (ny * fz - nz * fy)
    c1y = h * (nz * fx - nx * fz)
    c1z = h * (nx * fy - ny * fx)
    ax = c0x + c1x
    ay = c0y + c1y
    az = c0z + c1z
    bx = c0x - c1x
    by = c0y - c1y
    bz = c0z - c1z
    # E - P and, for R-Pa, the arm E - B
    ex = rx - lf * fx
    ey = ry - lf * fy
    ez = rz - lf * fz
    rot = p[k + TYPE] == R_PA
    lax = ex + x - p[k + BASE]
    lay = ey + y - p[k + BASE + 1]
    laz = ez + z - p[k + BASE + 2]
    axial = lf / p[s + EA_BAR]
    couple = 0.5 * lf * (sn2 / p[s + GJ_BAR] + (1.0 - sn2) / p[s + EI_BAR])
    # Phi = the bars' diagonal + W^T C_e W
    q00 = axial + _base_flex(p, k, s, rot, lax, lay, laz, ex, ey, ez, fx, fy, fz, ax, ay, az, fx, fy, fz, ax, ay, az)
    q01 = _base_flex(p, k, s, rot, lax, lay, laz, ex, ey, ez, fx, fy, fz, ax, ay, az, fx, fy, fz, bx, by, bz)
    q02 = _base_flex(p, k, s, rot, lax, lay, laz, ex, ey, ez, fx, fy, fz, ax, ay, az, 0.0, 0.0, 0.0, mx, my, mz)
    q11 = axial + _base_flex(p, k, s, rot, lax, lay, laz, ex, ey, ez, fx, fy, fz, bx, by, bz, fx, fy, fz, bx, by, bz)
    q12 = _base_flex(p, k, s, rot, lax, lay, laz, ex, ey, ez, fx, fy, fz, bx, by, bz, 0.0, 0.0, 0.0, mx, my, mz)
    q22 = couple + _base_flex(p, k, s, rot, lax, lay, laz, ex, ey, ez, 0.0, 0.0, 0.0, mx, my, mz, 0.0, 0.0, 0.0, mx,
                              my, mz)
    ok, i00, i01, i02, i11, i12, i22 = _sl.sym3_inverse(q00, q01, q02, q11, q12, q22)
    if not ok:
        return False, kk
    # Phi^-1 = L L^T (Cholesky); K_leg = sum over the columns c of L of (W L_c)(W L_c)^T
    l00 = math.sqrt(i00)
    l10 = i01 / l00
    l20 = i02 / l00
    d11 = i11 - l10 * l10
    if not d11 > 0.0:
        return False, kk
    l11 = math.sqrt(d11)
    l21 = (i12 - l20 * l10) / l11
    d22 = i22 - l20 * l20 - l21 * l21
    if not d22 > 0.0:
        return False, kk
    l22 = math.sqrt(d22)
    # column 0: w_+ l00 + w_- l10 + w_m l20; column 1: w_- l11 + w_m l21; column 2: w_m l22
    g = l00 + l10
    kk = _sl.outer_add(kk, fx * g, fy * g, fz * g, ax * l00 + bx * l10 + mx * l20, ay * l00 + by * l10 + my * l20,
                       az * l00 + bz * l10 + mz * l20)
    kk = _sl.outer_add(kk, fx * l11, fy * l11, fz * l11, bx * l11 + mx * l21, by * l11 + my * l21,
                       bz * l11 + mz * l21)
    kk = _sl.outer_add(kk, 0.0, 0.0, 0.0, mx * l22, my * l22, mz * l22)
    return True, kk


@njit(cache=True, fastmath=FASTMATH)
def _stiffness(p, x, y, z, ax, ay, az, bx, by, bz, cx, cy, cz):
    """(stiffness_min N/length, deflection length) of the platform at P = (x, y, z) whose legs reach it with unit
    forearms a, b, c (the comment above; ideal joints). A singular leg or
    platform: (0, DEFLECTION_CAP), or 0 deflection under no load (stiffness.legs' caps); never NaN."""
    fx = p[LOAD]
    fy = p[LOAD + 1]
    fz = p[LOAD + 2]
    kk = (0.0,) * 21
    k = np.int64(HEAD)  # int64 block offsets: the literals would compile _add_leg twice (_fields' comment)
    s = np.int64(SLEGS)
    ok1, kk = _add_leg(kk, p, k, s, x, y, z, ax, ay, az)
    ok2, kk = _add_leg(kk, p, k + STRIDE, s + SSTRIDE, x, y, z, bx, by, bz)
    ok3, kk = _add_leg(kk, p, k + 2 * STRIDE, s + 2 * SSTRIDE, x, y, z, cx, cy, cz)
    if not (ok1 and ok2 and ok3):
        return 0.0, (0.0 if (fx == 0.0 and fy == 0.0 and fz == 0.0) else _sl.DEFLECTION_CAP)
    return _sl.response_upper(kk, fx, fy, fz, p[CHAR_LEN])


# ----- column intervals (Mechanism.interval_kernel): the reachable set of a z-column in closed form ---------------
# Along a column (x, y fixed, z varying) each leg's reach and limits can change only where a closed-form condition
# holds with equality, each a root of a polynomial of degree <= 2 in z:
# * R-Pa whose actuated axis a = u x w is horizontal (a_z = 0; every Delta): the leg reaches Q iff the distance
#   rho of D = Q - B from the axis, in the arm's plane, lies in [|L - h|, L + h], h = sqrt(l^2 - gamma^2) with
#   gamma = D . a constant along the column; rho^2 is quadratic in z. The limits change where q = lo or q = hi
#   (|D - L (cos q u + sin q w)| = l, quadratic), the branch's root flips where b = 2 L D . w changes sign (linear).
#   The cone bounds f . a = gamma: constant along the column. A tilted axis (a_z != 0): -1 (nodes and bisection).
# * P-Pa: the perpendicular distance from the rail (quadratic), q = lo or hi (quadratic), and the cone's
#   D . axis = +-l sin(cone) (linear; f . axis = D . axis since the rail is perpendicular to the axis).
# Between consecutive breakpoints every leg's predicate is constant, so one reach test at each segment's midpoint
# (the reach kernel's own legs, branches and limits) decides the segment. Extra breakpoints only split segments.
MAX_BREAKS = 2 + N_LEGS * 9
AXIS_TILT = 1e-12  # |a_z| above this: the axis is not horizontal, the column is not handled in closed form


@njit(cache=True, fastmath=FASTMATH, inline="always")
def _roots(a, b, c, zlo, zhi, br, nb):
    """Append the real roots of a z^2 + b z + c = 0 inside (zlo, zhi) to br[nb:]; the new count. a may be 0 (linear);
    a near-degenerate quadratic may add spurious roots, which only split segments."""
    if a != 0.0:
        disc = b * b - 4.0 * a * c
        if disc < 0.0:
            return nb
        s = math.sqrt(disc)
        # the stable pair: q = -(b + sign(b) s) / 2, roots q / a and c / q
        qq = -0.5 * (b + s) if b >= 0.0 else -0.5 * (b - s)
        r1 = qq / a
        if zlo < r1 < zhi:
            br[nb] = r1
            nb += 1
        if qq != 0.0:
            r2 = c / qq
            if zlo < r2 < zhi:
                br[nb] = r2
                nb += 1
        return nb
    if b != 0.0:
        r = -c / b
        if zlo < r < zhi:
            br[nb] = r
            nb += 1
    return nb


@njit(cache=True, fastmath=FASTMATH, inline="always")
def _offset_roots(d0x, d0y, d0z, ox, oy, oz, lf, zlo, zhi, br, nb):
    """Roots in z of |D0 + z e_z - o| = l (the leg's sphere of radius l about offset o): z^2 + 2 (d0z - oz) z +
    |D0 - o|^2 - l^2 = 0."""
    ex = d0x - ox
    ey = d0y - oy
    ez = d0z - oz
    return _roots(1.0, 2.0 * ez, ex * ex + ey * ey + ez * ez - lf * lf, zlo, zhi, br, nb)


@njit(cache=True, fastmath=FASTMATH, inline="always")
def _leg_breaks(p, k, x, y, zlo, zhi, br, nb):
    """Append leg k's breakpoints along the column at (x, y) (comment above); -1 when the leg is not handled."""
    d0x = x + p[k + PLAT] - p[k + BASE]
    d0y = y + p[k + PLAT + 1] - p[k + BASE + 1]
    d0z = p[k + PLAT + 2] - p[k + BASE + 2]  # D at z = 0
    ux = p[k + U]
    uy = p[k + U + 1]
    uz = p[k + U + 2]
    lf = p[k + FOREARM]
    if p[k + TYPE] == R_PA:
        ax = p[k + AXIS]
        ay = p[k + AXIS + 1]
        az = p[k + AXIS + 2]
        if abs(az) > AXIS_TILT:
            return -1
        la = p[k + ARM]
        wx = p[k + W]
        wy = p[k + W + 1]
        wz = p[k + W + 2]
        gamma = d0x * ax + d0y * ay + d0z * az
        h2 = lf * lf - gamma * gamma
        if h2 > 0.0:
            h = math.sqrt(h2)
            al0 = d0x * ux + d0y * uy + d0z * uz
            be0 = d0x * wx + d0y * wy + d0z * wz
            a2 = uz * uz + wz * wz
            a1 = 2.0 * (al0 * uz + be0 * wz)
            a0 = al0 * al0 + be0 * be0
            nb = _roots(a2, a1, a0 - (la + h) * (la + h), zlo, zhi, br, nb)
            nb = _roots(a2, a1, a0 - (la - h) * (la - h), zlo, zhi, br, nb)
            nb = _roots(0.0, wz, be0, zlo, zhi, br, nb)  # b = 0: the branch's root flips
            if p[k + HAS_LIMITS] > 0.0:
                for q in (p[k + LO], p[k + HI]):
                    c = la * math.cos(q)
                    s = la * math.sin(q)
                    nb = _offset_roots(d0x, d0y, d0z, c * ux + s * wx, c * uy + s * wy, c * uz + s * wz, lf, zlo,
                                       zhi, br, nb)
        # h2 <= 0: the leg reaches no point of the column (a single point at most); no breakpoint needed
    else:  # P-Pa
        de0 = d0x * ux + d0y * uy + d0z * uz
        nb = _roots(1.0 - uz * uz, 2.0 * (d0z - de0 * uz), d0x * d0x + d0y * d0y + d0z * d0z - de0 * de0 - lf * lf,
                    zlo, zhi, br, nb)
        if p[k + HAS_LIMITS] > 0.0:
            for q in (p[k + LO], p[k + HI]):
                nb = _offset_roots(d0x, d0y, d0z, q * ux, q * uy, q * uz, lf, zlo, zhi, br, nb)
        if p[k + HAS_CONE] > 0.0:
            nx = p[k + AXIS]
            ny = p[k + AXIS + 1]
            nz = p[k + AXIS + 2]
            if abs(nx * ux + ny * uy + nz * uz) > AXIS_TILT:
                return -1
            dn0 = d0x * nx + d0y * ny + d0z * nz
            bound = lf * p[k + SIN_CONE]
            nb = _roots(0.0, nz, dn0 - bound, zlo, zhi, br, nb)
            nb = _roots(0.0, nz, dn0 + bound, zlo, zhi, br, nb)
    return nb


@njit(cache=True, fastmath=FASTMATH, inline="always")
def _reaches(p, x, y, z):
    """Whether every leg reaches P = (x, y, z) in its branch and limits (point_reach's slot 0 >= 0)."""
    for i in range(N_LEGS):
        ok, _, _, _, _, _ = _leg(p, HEAD + i * STRIDE, x, y, z)
        if not ok:
            return False
    return True


@njit(cache=True, fastmath=FASTMATH)
def column_intervals(p, x, y, zlo, zhi, out):
    """The interval kernel (Mechanism.interval_kernel): the reachable set of the column at (x, y) over [zlo, zhi] as
    k sorted, disjoint intervals in out[:k] (out: (K, 2)); -1 when a leg is not handled in closed form (a tilted
    R-Pa axis), with interference_free (the capsules' overlap has no closed form here) or more than K intervals are
    needed."""
    if p[FREE] > 0.0:
        return -1
    br = np.empty(MAX_BREAKS)
    br[0] = zlo
    nb = 1
    for i in range(N_LEGS):
        nb = _leg_breaks(p, HEAD + i * STRIDE, x, y, zlo, zhi, br, nb)
        if nb < 0:
            return -1
    br[nb] = zhi
    nb += 1
    # insertion sort (a few dozen values)
    for i in range(2, nb - 1):
        v = br[i]
        j = i - 1
        while j >= 1 and br[j] > v:
            br[j + 1] = br[j]
            j -= 1
        br[j + 1] = v
    k = 0
    open_ = False
    for i in range(nb - 1):
        a = br[i]
        b = br[i + 1]
        if not b > a:
            continue
        if _reaches(p, x, y, 0.5 * (a + b)):
            if open_:
                out[k - 1, 1] = b
            else:
                if k >= out.shape[0]:
                    return -1
                out[k, 0] = a
                out[k, 1] = b
                k += 1
                open_ = True
        else:
            open_ = False
    return k
