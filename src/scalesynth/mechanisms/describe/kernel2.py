"""The field-kernel template of described 2T (planar) mechanisms: two planar legs, RR or PR, one Numba kernel.

The plane is z = 0 and the task axes are x, y (z unused). As for kernel.py, everything comes from the packed vector
``p`` (``planar.PlanarMechanism.pack``): per leg a block of STRIDE slots (layout below). Every Numba function of the
template lives in this one file (Numba's disk cache follows the file).

Per leg (closed form; docs/describing.md, "Planar legs"), with B the base point, Q = P + r_p the platform joint,
D = Q - B, (a, b) = (D.u, D.w) its coordinates in the leg's frame (u the arm at q = 0, w the direction it turns to):

* RR (rotary crank of length L, then a link of length l to Q): rho^2 = a^2 + b^2, K = rho^2 + L^2 - l^2 (law of
  cosines), S^2 = 4 L^2 rho^2 - K^2 = ((L + l)^2 - rho^2)(rho^2 - (L - l)^2), in that factored form so that it keeps
  its accuracy at the reach boundary; q = atan2(b, a) + sigma acos(K / (2 L rho)) with sigma = +1 ("+": the crank
  turned towards w from the line B -> Q) or -1 ("-"), whose cosine and sine come out algebraically:
  cos q = (a K - sigma b S) / (2 L rho^2), sin q = (b K + sigma a S) / (2 L rho^2). No trigonometric call, limits
  included (cross products against the limits' directions, modulo 2 pi).
* PR (carriage on a rail e = u, then a link of length l): q = D.e + sigma sqrt(l^2 - (D.n)^2), n the rail's normal;
  sigma = +1 "far", -1 "near". Limits on q as given.

Velocity: |Q - A_i(q_i)| = l_i differentiated gives f_i . P_dot = (f_i . t_i) q_dot_i, f_i = Q_i - A_i the link
(A_i the elbow or carriage), t_i = dA_i/dq_i. So dx/dq = J_x^-1 J_q = adj(J_x) J_q / det(J_x), J_x rows f_i,
J_q = diag(f_i . t_i); singular values of adj(J_x) J_q divided by |det J_x|: finite at both singularities, LCI 0 where
J_x or J_q loses rank. Each f_i is divided by l_i first (rows and J_q alike), which leaves dx/dq unchanged.

Stiffness (slots 3-4, only where the packed flag, options.stiffness_metrics, is set; else 0): stiffness_min and
deflection of frame2.py's frame with ideal joints, condensed per leg in closed form (the section comment below).

Clearance (slot 5, only where the packed flag, options.clearance_metrics or interference_free, is set; else 0): the
smallest capsule gap of bodies.capsules2's capsules (kernels.clearance.packed_capsule_gap); with interference_free a
pose whose capsules overlap is unreachable in every kernel of the template.
"""

import math

import numpy as np
from numba import njit

from scalesynth.kernels import grid as _grid
from scalesynth.kernels.clearance import SEG_STRIDE, packed_capsule_gap
from scalesynth.kernels.conditioning import SIGMA_CAP, sv_2x2
from scalesynth.kernels.flags import FASTMATH
from scalesynth.stiffness import legs as _sl

# leg type codes (legs.LEG_TYPES' ``code``; distinct from kernel.py's and kernel6.py's)
RR = 5.0
PR = 6.0
N_LEGS = 2  # motion 2T: two actuated legs, a square Jacobian
HEAD = 2  # p[0]: number of legs, p[1]: reserved
# slots of one leg's block, from HEAD + i * STRIDE
TYPE = 0
BASE = 1  # 2: base point B (RR: the crank's pivot; PR: the rail's origin)
PLAT = 3  # 2: platform joint Q minus the platform point P
U = 5  # 2: RR: crank direction at q = 0; PR: rail direction e
W = 7  # 2: RR: direction the crank turns to for q > 0; PR: the rail's normal n
ARM = 9  # RR: crank length L
LINK = 10  # link length l
BRANCH = 11  # sigma, +1 or -1 (module docstring)
HAS_LIMITS = 12
LO = 13  # PR: stroke [lo, hi]
HI = 14
COS_LO = 15  # RR: cos, sin of lo and hi, and 1 when hi - lo > pi (the arc test of _arc_ok)
SIN_LO = 16
COS_HI = 17
SIN_HI = 18
WIDE = 19
STRIDE = 20
N_KINEMATIC = HEAD + N_LEGS * STRIDE  # the slots above; the stiffness block (per-voxel stiffness fields) follows
# stiffness block, from N_KINEMATIC: a flag (1: options.stiffness_metrics, the fields are computed), the load (N, in
# the plane), then per leg SSTRIDE slots: EA and EI of the crank (RR; unused for PR), EA of the link and the
# actuator's spring (N length/rad rotary, N/length linear)
STIFF = N_KINEMATIC
LOAD = N_KINEMATIC + 1
SLEGS = N_KINEMATIC + 3
EA_ARM = 0
EI_ARM = 1
EA_BAR = 2
K_ACT = 3
SSTRIDE = 4
N_STIFFNESS = SLEGS + N_LEGS * SSTRIDE
# clearance block, from N_STIFFNESS: a flag (1: the clearance field is computed), the interference_free flag, 1 where
# the legs' capsules are alike (bodies.uniform_legs), then the capsule block of kernels.clearance (at most
# MAX_CAPSULES: per leg a crank and a link, or a rail, a carriage ball and a link; the base; the platform)
CLEAR = N_STIFFNESS
FREE = N_STIFFNESS + 1
UNIFORM = N_STIFFNESS + 2
CAPS = N_STIFFNESS + 3
MAX_CAPSULES = N_LEGS * 3 + 2
N_PACKED = CAPS + 2 + MAX_CAPSULES * SEG_STRIDE + MAX_CAPSULES * (MAX_CAPSULES - 1)
F_STIFFNESS_MIN = 3  # field slots of the stiffness fields
F_DEFLECTION = 4
F_CLEARANCE = 5  # field slot of the clearance


@njit(cache=True, fastmath=FASTMATH)
def _arc_ok(p, k, c, s):
    """True if the angle with cosine c and sine s lies in the leg's limits [lo, hi] modulo 2 pi: sin(q - lo) >= 0 and
    sin(hi - q) >= 0 (two cross products) when hi - lo <= pi; a wider arc is the complement of one narrower than pi,
    so either test suffices."""
    after_lo = p[k + COS_LO] * s - p[k + SIN_LO] * c >= 0.0
    before_hi = c * p[k + SIN_HI] - s * p[k + COS_HI] >= 0.0
    if p[k + WIDE] > 0.0:
        return after_lo or before_hi
    return after_lo and before_hi


@njit(cache=True, fastmath=FASTMATH)
def _leg(p, k, x, y):
    """One leg at platform point P = (x, y), block from p[k]: (ok, fx, fy, jq, a, b) with (fx, fy) the link's
    direction (unit), jq = f . t / l, and (a, b) = (cos q, sin q) for RR, (q, 0) for PR; ok False when the leg does
    not reach P or its limits exclude it."""
    dx = x + p[k + PLAT] - p[k + BASE]
    dy = y + p[k + PLAT + 1] - p[k + BASE + 1]
    ux = p[k + U]
    uy = p[k + U + 1]
    wx = p[k + W]
    wy = p[k + W + 1]
    lf = p[k + LINK]
    sigma = p[k + BRANCH]
    if p[k + TYPE] == RR:
        la = p[k + ARM]
        a = dx * ux + dy * uy
        b = dx * wx + dy * wy
        rho2 = a * a + b * b
        if not rho2 > 0.0:
            return False, 0.0, 0.0, 0.0, 0.0, 0.0  # Q on the pivot: the crank angle is undetermined
        h = ((la + lf) * (la + lf) - rho2) * (rho2 - (la - lf) * (la - lf))
        if h < 0.0:
            return False, 0.0, 0.0, 0.0, 0.0, 0.0
        s = math.sqrt(h)
        kk = rho2 + la * la - lf * lf
        inv = 1.0 / (2.0 * la * rho2)
        c = (a * kk - sigma * b * s) * inv
        sn = (b * kk + sigma * a * s) * inv
        if p[k + HAS_LIMITS] > 0.0 and not _arc_ok(p, k, c, sn):
            return False, 0.0, 0.0, 0.0, 0.0, 0.0
        # elbow offset L (c u + sn w), its velocity per unit q_dot t = L (-sn u + c w)
        ex = c * ux + sn * wx
        ey = c * uy + sn * wy
        fx = dx - la * ex
        fy = dy - la * ey
        jq = la * (fx * (c * wx - sn * ux) + fy * (c * wy - sn * uy))
        inv_l = 1.0 / lf
        return True, fx * inv_l, fy * inv_l, jq * inv_l, c, sn
    # PR
    de = dx * ux + dy * uy
    perp = abs(dx * wx + dy * wy)
    h = (lf - perp) * (lf + perp)
    if h < 0.0:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0
    q = de + sigma * math.sqrt(h)
    if p[k + HAS_LIMITS] > 0.0 and not (p[k + LO] <= q <= p[k + HI]):
        return False, 0.0, 0.0, 0.0, 0.0, 0.0
    fx = dx - q * ux
    fy = dy - q * uy
    jq = fx * ux + fy * uy
    inv_l = 1.0 / lf
    return True, fx * inv_l, fy * inv_l, jq * inv_l, q, 0.0


@njit(cache=True, fastmath=FASTMATH)
def _gap(p, x, y, ax, ay, bx, by):
    """Clearance (length unit) of the packed capsules at P = (x, y) whose legs reach it with unit links a, b: each
    elbow or carriage E_i = Q_i - l_i f_i (z = 0)."""
    elbows = np.zeros((N_LEGS, 3))
    k = HEAD
    lf = p[k + LINK]
    elbows[0, 0] = x + p[k + PLAT] - lf * ax
    elbows[0, 1] = y + p[k + PLAT + 1] - lf * ay
    k = HEAD + STRIDE
    lf = p[k + LINK]
    elbows[1, 0] = x + p[k + PLAT] - lf * bx
    elbows[1, 1] = y + p[k + PLAT + 1] - lf * by
    return packed_capsule_gap(p, CAPS, elbows, x, y, 0.0)


@njit(cache=True, fastmath=FASTMATH)
def _fields(p, x, y, out, conditioning, stiffness=None):
    """Slots 0-2 (LCI, sigma_min, sigma_max of dx/dq) at P, or write_unreachable; ``conditioning`` (a constant)
    False stops after reach, limits and interference_free with slot 0 = 0 where they pass (the reach kernel);
    ``stiffness`` True also writes slots 3-5 (stiffness_min, deflection, clearance; each 0 unless its packed flag is
    set), None (default) leaves them: a None test, so that Numba drops those stages from the variants that do not
    need them (kernel.py's _fields says why). With the packed interference_free flag, overlapping capsules make the
    pose unreachable in every variant."""
    k1 = np.int64(HEAD)  # not the literal HEAD: Numba would compile _leg for it and again for HEAD + STRIDE's int64
    ok, ax, ay, j1, c1, s1 = _leg(p, k1, x, y)
    if not ok:
        _grid.write_unreachable(out)
        return
    ok, bx, by, j2, c2, s2 = _leg(p, k1 + STRIDE, x, y)
    if not ok:
        _grid.write_unreachable(out)
        return
    gap = 0.0
    if p[FREE] > 0.0 or (stiffness is not None and p[CLEAR] > 0.0):
        gap = _gap(p, x, y, ax, ay, bx, by)
        if p[FREE] > 0.0 and gap < 0.0:
            _grid.write_unreachable(out)
            return
    if not conditioning:
        out[0] = 0.0
        return
    # adj(J_x) J_q with rows f1 = a, f2 = b: [[by j1, -ay j2], [-bx j1, ax j2]]
    lci, smin, smax = sv_2x2(by * j1, -ay * j2, -bx * j1, ax * j2)
    out[0] = lci
    ad = abs(ax * by - ay * bx)
    if not ad * SIGMA_CAP > smax:  # forward singularity (links collinear): dx/dq unbounded
        out[1] = 0.0
        out[2] = SIGMA_CAP
    else:
        out[1] = smin / ad
        out[2] = smax / ad
    if stiffness is not None:
        if p[STIFF] > 0.0:
            out[F_STIFFNESS_MIN], out[F_DEFLECTION] = _stiffness(p, ax, ay, c1, s1, bx, by, c2, s2)
        else:
            out[F_STIFFNESS_MIN] = 0.0
            out[F_DEFLECTION] = 0.0
        out[F_CLEARANCE] = gap


@njit(cache=True, fastmath=FASTMATH)
def point_fields(p, x, y, z, out):
    """The field kernel (kernels.grid contract): LCI, sigma_min, sigma_max of dx/dq at P = (x, y), stiffness_min
    (N/length) and deflection (length unit) under the packed load where the packed flag asks for them (else 0;
    _stiffness) and the clearance of the link capsules (length unit) where its flag asks for it (else 0; _gap); -1
    and zeros where a leg does not reach P in its branch, a limit excludes it or (interference_free) two capsules
    overlap; z unused."""
    _fields(p, x, y, out, True, True)


@njit(cache=True, fastmath=FASTMATH)
def point_lci(p, x, y, z, out):
    """Slots 0-2 of point_fields, bit for bit, without the stiffness and clearance stages (Mechanism.lci_kernel);
    interference_free still applies; slots 3-5 not written."""
    _fields(p, x, y, out, True)


@njit(cache=True, fastmath=FASTMATH)
def point_reach(p, x, y, z, out):
    """Slot 0 >= 0 exactly where point_fields' is (same legs, branches, limits and interference_free), -1
    elsewhere; no conditioning."""
    _fields(p, x, y, out, False)


@njit(cache=True, fastmath=FASTMATH)
def leg_values(p, x, y, out):
    """Per leg i: out[i] = (ok 1/0, fx, fy, jq, q) as _leg gives them, q the joint value (RR: atan2 of its cosine
    and sine); tests compare them with the NumPy legs."""
    for i in range(N_LEGS):
        k = HEAD + i * STRIDE
        ok, fx, fy, jq, a, b = _leg(p, k, x, y)
        out[i, 0] = 1.0 if ok else 0.0
        out[i, 1] = fx
        out[i, 2] = fy
        out[i, 3] = jq
        out[i, 4] = math.atan2(b, a) if p[k + TYPE] == RR else a


# ----- per-voxel stiffness (docs/describing.md): frame2.py's frame with ideal joints, condensed per leg -----------
# Each link is pinned at both ends (to its crank or carriage, and to the platform pin) and carries no load between
# them, so it passes only its axial force, along its unit direction f: the leg is a spring along f of compliance
#   c = l / EA_link + what its crank or carriage adds along f:
# * RR: the crank B -> E (unit a = cos q u + sin q w, length L), a cantilever on the actuator's torsional spring k:
#   (f . a)^2 L / EA_arm + (f x a)^2 (L^3 / (3 EI_arm) + L^2 / k) (its stretch, its bending and the spring's turn);
# * PR: the carriage rides the rigid rail on its linear spring k: (f . u)^2 / k.
# The pin's stiffness K = sum_i f_i f_i^T / c_i (2 x 2: the pin only translates), then stiffness.legs.response_2x2
# under the packed load. tests/test_planar_fields.py holds it equal to frame2's frame solved per pose
# (stiffness.solve) and to the hand-written five-bar's field.


@njit(cache=True, fastmath=FASTMATH, inline="always")
def _compliance(p, k, s, fx, fy, c, sn):
    """Leg k's compliance (length/N) along its unit link f (stiffness slots from s; the comment above); (c, sn) the
    crank's cos q and sin q (RR) or (q, 0) (PR), as _leg gives them."""
    ux = p[k + U]
    uy = p[k + U + 1]
    out = p[k + LINK] / p[s + EA_BAR]
    if p[k + TYPE] == RR:
        ax = c * ux + sn * p[k + W]
        ay = c * uy + sn * p[k + W + 1]
        la = p[k + ARM]
        along = fx * ax + fy * ay
        across = fx * ay - fy * ax
        bend = la * la * la / (3.0 * p[s + EI_ARM]) + la * la / p[s + K_ACT]
        return out + along * along * la / p[s + EA_ARM] + across * across * bend
    along = fx * ux + fy * uy
    return out + along * along / p[s + K_ACT]


@njit(cache=True, fastmath=FASTMATH)
def _stiffness(p, ax, ay, c1, s1, bx, by, c2, s2):
    """(stiffness_min N/length, deflection length) of the platform pin whose legs reach it with unit links a, b and
    crank cosines and sines (c_i, s_i) (PR: (q_i, 0)) (the comment above; ideal joints). A singular pose: (0,
    DEFLECTION_CAP), or 0 deflection under no load (stiffness.legs.response_2x2); never NaN."""
    k = np.int64(HEAD)  # int64 block offsets, as in _fields
    s = np.int64(SLEGS)
    g1 = 1.0 / _compliance(p, k, s, ax, ay, c1, s1)
    g2 = 1.0 / _compliance(p, k + STRIDE, s + SSTRIDE, bx, by, c2, s2)
    return _sl.response_2x2(ax * ax * g1 + bx * bx * g2, ax * ay * g1 + bx * by * g2, ay * ay * g1 + by * by * g2,
                            p[LOAD], p[LOAD + 1])
