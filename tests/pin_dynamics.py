"""Independent rigid-body dynamics for the tests: Pinocchio models of closed chains, and NumPy virtual-work twins.

Nothing here imports scalesynth: it is the checker of scalesynth's dynamics (issue 29), written from the textbook
and from Pinocchio's public API only.

Closed chains in Pinocchio (``closed_chain_*``): the mechanism is cut into a kinematic tree (``pin.Model``) and
each cut is a point loop closure, a pair of frames (f1, f2) whose origins must coincide. With the closure
Jacobian J_c (rows: linear Jacobians of f1 minus f2, world-aligned) and its drift gamma (the relative classical
acceleration of the two points at zero joint acceleration):

* the tree's unknown joint rates follow from J_c v = 0 and J_c a = -gamma, given the known ones;
* inverse dynamics: the tree's generalised forces tau_tree = rnea(q, v, a) must be produced by the actuators and
  the closure forces, tau_tree = S^T tau_act + J_c^T lambda, solved by least squares for (tau_act, lambda)
  (lambda need not be unique where closures are redundant; tau_act is, away from singularities). The residual
  of that solve is returned so a test can see that the chain's equations were consistent.

NumPy twins (``rod_end_forces`` and the ``*_virtual_work`` functions): a uniform thin rod of mass m between ends
A and B (accelerations a_A, a_B) moves rigidly, so a point at fraction s has acceleration (1 - s) a_A + s a_B and
virtual displacement (1 - s) dA + s dB; integrating m (a - g) . dx over the rod gives generalised forces at its
ends F_A = m (a_A/3 + a_B/6 - g/2), F_B = m (a_A/6 + a_B/3 - g/2), and the actuator forces are
tau = sum over ends of (d end / d q)^T F (virtual work; tau . q_dot is the power the actuators deliver). Units SI.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

G0 = 9.80665  # m/s^2, standard gravity (scalesynth's default)
PHIS = np.radians([0.0, 120.0, 240.0])  # Delta legs


# ----------------------------------------------------------------------------------------------------------------
# generic Pinocchio pieces
# ----------------------------------------------------------------------------------------------------------------
def rod_inertia(mass: float, start: np.ndarray, end: np.ndarray) -> pin.Inertia:
    """Uniform thin rod from ``start`` to ``end`` (body frame, m): centre at the middle, m l^2/12 about any axis
    through the centre perpendicular to the rod, nothing about the rod's own axis."""
    start, end = np.asarray(start, float), np.asarray(end, float)
    d = end - start
    length = float(np.linalg.norm(d))
    u = d / length
    return pin.Inertia(float(mass), 0.5 * (start + end), mass * length**2 / 12.0 * (np.eye(3) - np.outer(u, u)))


def point_inertia(mass: float, at=(0.0, 0.0, 0.0)) -> pin.Inertia:
    """Point mass (kg) at ``at`` (body frame, m)."""
    return pin.Inertia(float(mass), np.asarray(at, float), np.zeros((3, 3)))


def add_point_frame(model: pin.Model, name: str, joint: int, at) -> int:
    """An operational frame on ``joint``'s body at ``at`` (body frame, m); returns its id."""
    return model.addFrame(pin.Frame(name, joint, 0, pin.SE3(np.eye(3), np.asarray(at, float)), pin.FrameType.OP_FRAME))


@dataclass
class ClosedChain:
    """A Pinocchio tree plus point loop closures. ``closures``: (frame1, frame2) pairs; ``actuated``: velocity
    indices of the actuated joints, in actuator order."""

    model: pin.Model
    closures: list[tuple[int, int]]
    actuated: list[int]
    data: pin.Data = field(init=False)

    def __post_init__(self):
        self.data = self.model.createData()

    def gap(self, q: np.ndarray) -> np.ndarray:
        """Closure errors (3 per closure, m) at configuration q."""
        pin.framesForwardKinematics(self.model, self.data, q)
        return np.concatenate([self.data.oMf[a].translation - self.data.oMf[b].translation for a, b in self.closures])

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """Closure Jacobian J_c (3 per closure, nv): relative velocity of the closure points = J_c v."""
        pin.computeJointJacobians(self.model, self.data, q)
        pin.updateFramePlacements(self.model, self.data)
        rows = []
        for a, b in self.closures:
            ja = pin.getFrameJacobian(self.model, self.data, a, pin.LOCAL_WORLD_ALIGNED)[:3]
            jb = pin.getFrameJacobian(self.model, self.data, b, pin.LOCAL_WORLD_ALIGNED)[:3]
            rows.append(ja - jb)
        return np.vstack(rows)

    def drift(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """gamma: relative classical acceleration of the closure points at zero joint acceleration (m/s^2)."""
        pin.forwardKinematics(self.model, self.data, q, v, np.zeros(self.model.nv))
        pin.updateFramePlacements(self.model, self.data)
        out = []
        for a, b in self.closures:
            aa = pin.getFrameClassicalAcceleration(self.model, self.data, a, pin.LOCAL_WORLD_ALIGNED).linear
            ab = pin.getFrameClassicalAcceleration(self.model, self.data, b, pin.LOCAL_WORLD_ALIGNED).linear
            out.append(aa - ab)
        return np.concatenate(out)

    def complete_rates(self, q, known: list[int], v_known, a_known) -> tuple[np.ndarray, np.ndarray, float]:
        """Full (v, a) from the known velocity indices' rates: J_c v = 0 and J_c a = -gamma solved (least squares,
        minimum norm: idle spins of rods between ball joints come out zero) for the other indices. Returns
        (v, a, worst residual of the two solves relative to their right-hand sides)."""
        nv = self.model.nv
        unknown = [i for i in range(nv) if i not in known]
        jc = self.jacobian(q)
        v = np.zeros(nv)
        v[known] = v_known
        rhs = -jc[:, known] @ np.asarray(v_known, float)
        v[unknown] = np.linalg.lstsq(jc[:, unknown], rhs, rcond=1e-12)[0]
        res_v = np.linalg.norm(jc @ v) / max(np.linalg.norm(rhs), 1e-300)
        gamma = self.drift(q, v)
        a = np.zeros(nv)
        a[known] = a_known
        rhs_a = -jc[:, known] @ np.asarray(a_known, float) - gamma
        a[unknown] = np.linalg.lstsq(jc[:, unknown], rhs_a, rcond=1e-12)[0]
        res_a = np.linalg.norm(jc @ a + gamma) / max(np.linalg.norm(rhs_a), 1e-300)
        return v, a, float(max(res_v, res_a))

    def inverse_dynamics(self, q, v, a) -> tuple[np.ndarray, float]:
        """Actuator forces (N or N m, in ``actuated`` order) realising (q, v, a) and the relative residual of
        rnea(q, v, a) = S^T tau + J_c^T lambda."""
        tau_tree = pin.rnea(self.model, self.data, q, v, a)
        jc = self.jacobian(q)
        sel = np.zeros((self.model.nv, len(self.actuated)))
        for k, i in enumerate(self.actuated):
            sel[i, k] = 1.0
        mat = np.hstack([sel, jc.T])
        x = np.linalg.lstsq(mat, tau_tree, rcond=1e-12)[0]
        res = np.linalg.norm(mat @ x - tau_tree) / max(np.linalg.norm(tau_tree), 1e-300)
        return x[: len(self.actuated)], float(res)


def set_gravity(model: pin.Model, g_vec) -> None:
    model.gravity = pin.Motion(np.asarray(g_vec, float), np.zeros(3))


# ----------------------------------------------------------------------------------------------------------------
# textbook cases
# ----------------------------------------------------------------------------------------------------------------
def pendulum_model(mass: float, length: float, g: float = G0) -> pin.Model:
    """Uniform thin rod hanging from a revolute joint about +y at the origin (gravity -z); theta 0 hanging straight
    down, so tau = m g (l/2) sin(theta) + (m l^2/3) theta_dd."""
    model = pin.Model()
    set_gravity(model, (0.0, 0.0, -g))
    j = model.addJoint(0, pin.JointModelRY(), pin.SE3.Identity(), "pivot")
    model.appendBodyToJoint(j, rod_inertia(mass, [0, 0, 0], [0, 0, -length]), pin.SE3.Identity())
    return model


@dataclass(frozen=True)
class SliderCrank:
    """Slider-crank in the vertical x-z plane, gravity -z. Crank O -> A of length ``crank`` (m), A = crank (cos phi,
    0, sin phi), phi the actuated angle; connecting rod A -> B of length ``rod``; slider B = (s, 0, 0) on the x axis,
    s = crank cos phi + sqrt(rod^2 - crank^2 sin^2 phi). Crank and rod are uniform thin rods, the slider a point."""

    crank: float
    rod: float
    m_crank: float
    m_rod: float
    m_slider: float
    g: float = G0

    def slider_position(self, phi):
        """s(phi), ds/dphi, d2s/dphi2 (exact)."""
        a, b = self.crank, self.rod
        w = np.sqrt(b**2 - (a * np.sin(phi)) ** 2)
        k = a**2 * np.sin(phi) * np.cos(phi)
        dw = -k / w
        ddw = -(a**2) * np.cos(2 * phi) / w - k**2 / w**3
        return a * np.cos(phi) + w, -a * np.sin(phi) + dw, -a * np.cos(phi) + ddw

    def torque_virtual_work(self, phi, phid, phidd) -> float:
        """Crank torque (N m, about the axis that turns phi positive) by virtual work on the crank angle."""
        a = self.crank
        g = np.array([0.0, 0.0, -self.g])
        da = a * np.array([-np.sin(phi), 0.0, np.cos(phi)])  # dA/dphi
        dda = -a * np.array([np.cos(phi), 0.0, np.sin(phi)])
        acc_a = dda * phid**2 + da * phidd
        _, ds, dds = self.slider_position(phi)
        db = np.array([ds, 0.0, 0.0])
        acc_b = np.array([dds * phid**2 + ds * phidd, 0.0, 0.0])
        f_crank_a = self.m_crank * (acc_a / 3 - g / 2)  # the crank's O end is fixed
        f_rod_a, f_rod_b = rod_end_forces(self.m_rod, acc_a, acc_b, g)
        f_slider = self.m_slider * (acc_b - g)
        return float(da @ (f_crank_a + f_rod_a) + db @ (f_rod_b + f_slider))

    def chain(self) -> tuple[ClosedChain, int, int, int]:
        """Pinocchio tree crank (revolute about -y at O) -> rod (revolute about -y at A), slider (prismatic x on
        the world), closed by rod end B = slider origin. Returns (chain, v index of crank, of rod, of slider)."""
        model = pin.Model()
        set_gravity(model, (0.0, 0.0, -self.g))
        axis = np.array([0.0, -1.0, 0.0])  # turning x towards +z
        jc = model.addJoint(0, pin.JointModelRevoluteUnaligned(axis), pin.SE3.Identity(), "crank")
        model.appendBodyToJoint(jc, rod_inertia(self.m_crank, [0, 0, 0], [self.crank, 0, 0]), pin.SE3.Identity())
        jr = model.addJoint(jc, pin.JointModelRevoluteUnaligned(axis),
                            pin.SE3(np.eye(3), np.array([self.crank, 0.0, 0.0])), "rod")
        model.appendBodyToJoint(jr, rod_inertia(self.m_rod, [0, 0, 0], [self.rod, 0, 0]), pin.SE3.Identity())
        js = model.addJoint(0, pin.JointModelPX(), pin.SE3.Identity(), "slider")
        model.appendBodyToJoint(js, point_inertia(self.m_slider), pin.SE3.Identity())
        fb = add_point_frame(model, "rod_end", jr, [self.rod, 0, 0])
        fs = add_point_frame(model, "slider", js, [0, 0, 0])
        chain = ClosedChain(model, [(fb, fs)], [model.joints[jc].idx_v])
        return chain, model.joints[jc].idx_v, model.joints[jr].idx_v, model.joints[js].idx_v

    def configuration(self, phi: float) -> np.ndarray:
        """Tree configuration (crank, rod relative angle, slider) that closes the loop at crank angle phi."""
        s = self.slider_position(phi)[0]
        a_pt = self.crank * np.array([np.cos(phi), np.sin(phi)])  # (x, z)
        psi = np.arctan2(0.0 - a_pt[1], s - a_pt[0])  # absolute rod angle from x towards z
        return np.array([phi, psi - phi, s])

    def torque_pinocchio(self, phi, phid, phidd) -> tuple[float, float, float]:
        """(crank torque, closure-gap, residual) from Pinocchio: crank rates given, the others from closure."""
        chain, ic, _, _ = self.chain()
        q = self.configuration(phi)
        gap = float(np.max(np.abs(chain.gap(q))))
        v, a, res_k = chain.complete_rates(q, [ic], [phid], [phidd])
        tau, res = chain.inverse_dynamics(q, v, a)
        return float(tau[0]), gap, max(res, res_k)


def rod_end_forces(mass: float, acc_a, acc_b, g) -> tuple[np.ndarray, np.ndarray]:
    """Generalised forces (N) at the ends of a uniform thin rod (module docstring): F_A, F_B."""
    acc_a, acc_b, g = (np.asarray(x, float) for x in (acc_a, acc_b, g))
    return mass * (acc_a / 3 + acc_b / 6 - g / 2), mass * (acc_a / 6 + acc_b / 3 - g / 2)


def quintic(p0, p1, duration: float, t):
    """Rest-to-rest 3-4-5 polynomial from p0 to p1 over ``duration`` s at times t: (p, pd, pdd), each (n, 3)."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    tau = np.clip(np.asarray(t, float) / duration, 0.0, 1.0)[:, None]
    s = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
    sd = (30 * tau**2 - 60 * tau**3 + 30 * tau**4) / duration
    sdd = (60 * tau - 180 * tau**2 + 120 * tau**3) / duration**2
    d = p1 - p0
    return p0 + s * d, sd * d, sdd * d


# ----------------------------------------------------------------------------------------------------------------
# rotary Delta (conventions of docs/mechanisms/delta.md: z up, base plane z = 0, leg i at phi_i = 0/120/240 deg,
# arm axis tangent to the base circle, theta 0 horizontal outward and positive downward, elbows out)
# ----------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class DeltaMasses:
    """Mass model (kg): each upper arm a uniform thin rod from its axis to its elbow; each forearm (one
    parallelogram) ``forearm`` kg shared equally by its two long bars, uniform thin rods, short end links
    massless; the platform and the payload point masses at the platform centre (the tool point)."""

    upper_arm: float
    forearm: float
    platform: float
    payload: float


def delta_ik(design, p) -> np.ndarray:
    """Elbows-out arm angles (3,) at platform centre p (m), or raise ValueError out of reach (textbook closed form:
    A cos theta + B sin theta = K in each leg's frame, the root with the larger cos theta)."""
    R, r, L, l = (design[k] for k in ("base_radius", "platform_radius", "upper_arm", "forearm"))
    x, y, z = (float(c) for c in p)
    out = np.zeros(3)
    for i, phi in enumerate(PHIS):
        xp, yp = x * np.cos(phi) + y * np.sin(phi), -x * np.sin(phi) + y * np.cos(phi)
        A, B = 2 * L * (R - r - xp), 2 * L * z
        K = l**2 - L**2 - (R - r - xp) ** 2 - yp**2 - z**2
        n = np.hypot(A, B)
        if not n > abs(K):
            raise ValueError(f"leg {i + 1} does not reach {p}")
        g = np.arccos(K / n)
        t1, t2 = np.arctan2(B, A) + g, np.arctan2(B, A) - g
        out[i] = t1 if np.cos(t1) >= np.cos(t2) else t2
    return out


def _leg_frame(phi):
    """(u, t): the leg's outward radial unit vector and its arm axis (tangent; theta turns u towards -z)."""
    return np.array([np.cos(phi), np.sin(phi), 0.0]), np.array([-np.sin(phi), np.cos(phi), 0.0])


def delta_leg_kinematics(design, p, pd, pdd):
    """Per leg i: elbow E_i and its d/dtheta, d2/dtheta2, forearm vector s_i = Q_i - E_i; arm rates from the
    differentiated closure |Q_i - E_i|^2 = l^2 (exact): theta_d = s.pd / s.E', theta_dd = (|s_d|^2 + s.pdd -
    theta_d^2 s.E'') / s.E' with s_d = pd - E' theta_d. Returns dict of arrays (3, ...)."""
    R, r, L = design["base_radius"], design["platform_radius"], design["upper_arm"]
    p, pd, pdd = (np.asarray(x, float) for x in (p, pd, pdd))
    th = delta_ik(design, p)
    out = {k: [] for k in ("theta", "theta_d", "theta_dd", "E", "dE", "ddE", "s")}
    for i, phi in enumerate(PHIS):
        u, _ = _leg_frame(phi)
        z = np.array([0.0, 0.0, 1.0])
        e = R * u + L * (np.cos(th[i]) * u - np.sin(th[i]) * z)
        de = L * (-np.sin(th[i]) * u - np.cos(th[i]) * z)
        dde = L * (-np.cos(th[i]) * u + np.sin(th[i]) * z)
        s = p + r * u - e
        thd = (s @ pd) / (s @ de)
        sd = pd - de * thd
        thdd = (sd @ sd + s @ pdd - thd**2 * (s @ dde)) / (s @ de)
        for k, val in zip(out, (th[i], thd, thdd, e, de, dde, s), strict=True):
            out[k].append(val)
    return {k: np.array(v) for k, v in out.items()}


def delta_jacobian(kin) -> np.ndarray:
    """dP/dtheta (3, 3) from the closure: s_i . dP = s_i . E'_i dtheta_i."""
    jx = kin["s"]
    jq = np.diag(np.einsum("ij,ij->i", kin["s"], kin["dE"]))
    return np.linalg.solve(jx, jq)


def delta_torques_virtual_work(design, masses: DeltaMasses, p, pd, pdd, g: float = G0) -> np.ndarray:
    """Arm torques (3,) in N m (about each arm axis, positive turning theta positive) by virtual work: upper arm
    rods B_i -> E_i, each parallelogram as ONE rod E_i -> Q_i of the parallelogram's whole mass (its two bars are
    translated copies of that rod: same velocities at every point, so the same kinetic energy and the same virtual
    work), the platform and payload at P."""
    kin = delta_leg_kinematics(design, p, pd, pdd)
    gv = np.array([0.0, 0.0, -g])
    jac = delta_jacobian(kin)
    acc_e = kin["ddE"] * kin["theta_d"][:, None] ** 2 + kin["dE"] * kin["theta_dd"][:, None]
    f_p = (masses.platform + masses.payload) * (np.asarray(pdd, float) - gv)
    tau = np.zeros(3)
    for i in range(3):
        f_arm = masses.upper_arm * (acc_e[i] / 3 - gv / 2)  # rod from the fixed axis point to the elbow
        f_fe, f_fq = rod_end_forces(masses.forearm, acc_e[i], pdd, gv)  # Q_i moves with P (pure translation)
        tau[i] += kin["dE"][i] @ (f_arm + f_fe)
        f_p = f_p + f_fq
    return tau + jac.T @ f_p


def delta_torques_lumped(design, masses: DeltaMasses, p, pd, pdd, g: float = G0, elbow_share: float = 2.0 / 3.0):
    """Codourey's lumped Delta model (as the literature restates it): each upper arm keeps its own inertia about
    its axis (m L^2/3) and gravity at its middle; each forearm's mass is split into point masses, ``elbow_share`` at
    the elbow and the rest at the platform, its rotational inertia neglected. Arm torques (3,) in N m."""
    kin = delta_leg_kinematics(design, p, pd, pdd)
    gv = np.array([0.0, 0.0, -g])
    jac = delta_jacobian(kin)
    acc_e = kin["ddE"] * kin["theta_d"][:, None] ** 2 + kin["dE"] * kin["theta_dd"][:, None]
    m_p = masses.platform + masses.payload + 3 * (1 - elbow_share) * masses.forearm
    tau = jac.T @ (m_p * (np.asarray(pdd, float) - gv))
    for i in range(3):
        L = design["upper_arm"]
        arm = masses.upper_arm * L**2 / 3 * kin["theta_dd"][i] + kin["dE"][i] @ (-masses.upper_arm * gv / 2)
        tau[i] += arm + kin["dE"][i] @ (elbow_share * masses.forearm * (acc_e[i] - gv))
    return tau


def delta_chain(design, masses: DeltaMasses, width: float = 0.1, g: float = G0):
    """Pinocchio tree of the Delta: the platform a free-flyer (its rotation left free: the parallelograms must hold
    it), three revolute arms about their tangent axes at B_i, and per leg two forearm bars, each a uniform thin rod
    of half the forearm's mass hanging from a ball joint on the arm at E_i +- width/2 t_i; each bar's far end is
    closed onto the platform at Q_i +- width/2 t_i (six point closures). Returns (chain, indices) with indices
    {"platform_v": v indices of the free-flyer (linear 0:3, angular 3:6), "arms_v": (3,), "bars_q": q start
    of each bar's quaternion, "arm_q": q index of each arm}."""
    R, r, L, l = (design[k] for k in ("base_radius", "platform_radius", "upper_arm", "forearm"))
    model = pin.Model()
    set_gravity(model, (0.0, 0.0, -g))
    jp = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "platform")
    model.appendBodyToJoint(jp, point_inertia(masses.platform + masses.payload), pin.SE3.Identity())
    closures, arms_v, arm_q, bars_q = [], [], [], []
    down = np.array([0.0, 0.0, -1.0])  # a bar's axis in its own frame
    for i, phi in enumerate(PHIS):
        u, t = _leg_frame(phi)
        ja = model.addJoint(0, pin.JointModelRevoluteUnaligned(t), pin.SE3(np.eye(3), R * u), f"arm{i + 1}")
        model.appendBodyToJoint(ja, rod_inertia(masses.upper_arm, [0, 0, 0], L * u), pin.SE3.Identity())
        arms_v.append(model.joints[ja].idx_v)
        arm_q.append(model.joints[ja].idx_q)
        for side in (-1.0, 1.0):
            jb = model.addJoint(ja, pin.JointModelSpherical(), pin.SE3(np.eye(3), L * u + side * width / 2 * t),
                                f"bar{i + 1}{'ab'[side > 0]}")
            model.appendBodyToJoint(jb, rod_inertia(masses.forearm / 2, [0, 0, 0], l * down), pin.SE3.Identity())
            bars_q.append(model.joints[jb].idx_q)
            fb = add_point_frame(model, f"bar{i + 1}{'ab'[side > 0]}_end", jb, l * down)
            fp = add_point_frame(model, f"plat{i + 1}{'ab'[side > 0]}", jp, r * u + side * width / 2 * t)
            closures.append((fb, fp))
    chain = ClosedChain(model, closures, arms_v)
    return chain, {"platform_v": list(range(model.joints[jp].idx_v, model.joints[jp].idx_v + 6)),
                   "arms_v": arms_v, "arm_q": arm_q, "bars_q": bars_q}


def delta_configuration(chain: ClosedChain, idx, design, p) -> np.ndarray:
    """Tree configuration closing every loop with the platform at p (no rotation) and elbows-out arm angles: each
    bar turned (shortest rotation) from hanging straight down to the direction of s_i = Q_i - E_i."""
    R, L = design["base_radius"], design["upper_arm"]
    q = pin.neutral(chain.model)
    q[0:3] = p  # free-flyer: translation, then quaternion (x, y, z, w) = identity
    th = delta_ik(design, p)
    for i, phi in enumerate(PHIS):
        u, t = _leg_frame(phi)
        q[idx["arm_q"][i]] = th[i]
        e = R * u + L * (np.cos(th[i]) * u - np.sin(th[i]) * np.array([0.0, 0.0, 1.0]))
        s = np.asarray(p, float) + design["platform_radius"] * u - e
        rot_arm = pin.AngleAxis(th[i], t).matrix()
        s_arm = rot_arm.T @ (s / np.linalg.norm(s))  # direction in the arm's frame
        quat = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, -1.0]), s_arm)
        for k in (2 * i, 2 * i + 1):
            q[idx["bars_q"][k]: idx["bars_q"][k] + 4] = quat.coeffs()
    return q


def delta_torques_pinocchio(design, masses: DeltaMasses, p, pd, pdd, width: float = 0.1, g: float = G0):
    """Arm torques (3,) N m from the Pinocchio closed chain with the platform centre's motion (p, pd, pdd) given:
    the other rates from the closures, then rnea + closure forces. Returns (tau, info) with info the closure gap
    (m), the solves' relative residuals, the platform's angular velocity and acceleration (should be 0) and the arm
    rates Pinocchio found."""
    chain, idx = delta_chain(design, masses, width, g)
    q = delta_configuration(chain, idx, design, p)
    lin = idx["platform_v"][:3]
    v, a, res_k = chain.complete_rates(q, lin, pd, pdd)  # free-flyer velocity is in the platform frame = world here
    tau, res = chain.inverse_dynamics(q, v, a)
    ang = idx["platform_v"][3:]
    info = {"gap": float(np.max(np.abs(chain.gap(q)))), "residual": max(res, res_k),
            "platform_spin": float(max(np.max(np.abs(v[ang])), np.max(np.abs(a[ang])))),
            "theta_d": v[idx["arms_v"]], "theta_dd": a[idx["arms_v"]]}
    return tau, info


# ----------------------------------------------------------------------------------------------------------------
# planar five-bar (seed 004; conventions of scalesynth.mechanisms.planar_fivebar's docstring: pivots B1 = (r, 0),
# B2 = (-r, 0), arm angles alpha_i from +x counter-clockwise, elbows Q_i = B_i + l1 (cos, sin) alpha_i, forearms
# Q_i -> P of length l2, all in the vertical x-y plane)
# ----------------------------------------------------------------------------------------------------------------
def fivebar_torques_pinocchio(r, l1, l2, m_arm, m_forearm, m_platform, alpha, p, pd, pdd, g_vec):
    """Arm torques (2,) N m about +z of the planar five-bar (lengths in m): arms and forearms uniform thin rods of
    m_arm, m_forearm kg each (a parallelogram forearm's two bars are translated copies of one rod: the same),
    m_platform (platform + payload) a point at P. ``alpha`` (2,) the arm angles (they fix the assembly mode); the
    platform's motion (p, pd, pdd) in the plane (m, m/s, m/s^2); g_vec (2,) gravity in the plane. Returns (tau,
    info) with the closure gap, the solves' residuals and the arm rates Pinocchio found."""
    model = pin.Model()
    set_gravity(model, (g_vec[0], g_vec[1], 0.0))
    jp = model.addJoint(0, pin.JointModelTranslation(), pin.SE3.Identity(), "platform")
    model.appendBodyToJoint(jp, point_inertia(m_platform), pin.SE3.Identity())
    fp = add_point_frame(model, "P", jp, [0, 0, 0])
    closures, arms_v, q = [], [], []
    p3 = np.array([p[0], p[1], 0.0])
    for i, (bx, al) in enumerate(zip((r, -r), alpha, strict=True)):
        ja = model.addJoint(0, pin.JointModelRZ(), pin.SE3(np.eye(3), np.array([bx, 0.0, 0.0])), f"arm{i + 1}")
        model.appendBodyToJoint(ja, rod_inertia(m_arm, [0, 0, 0], [l1, 0, 0]), pin.SE3.Identity())
        jf = model.addJoint(ja, pin.JointModelRZ(), pin.SE3(np.eye(3), np.array([l1, 0.0, 0.0])), f"fore{i + 1}")
        model.appendBodyToJoint(jf, rod_inertia(m_forearm, [0, 0, 0], [l2, 0, 0]), pin.SE3.Identity())
        closures.append((add_point_frame(model, f"fore{i + 1}_end", jf, [l2, 0, 0]), fp))
        arms_v.append(model.joints[ja].idx_v)
        elbow = np.array([bx + l1 * np.cos(al), l1 * np.sin(al), 0.0])
        beta = np.arctan2(p3[1] - elbow[1], p3[0] - elbow[0])
        q += [al, beta - al]
    chain = ClosedChain(model, closures, arms_v)
    qv = np.concatenate([p3, q])  # the translation joint comes first (added first)
    v, a, res_k = chain.complete_rates(qv, [0, 1, 2], [pd[0], pd[1], 0.0], [pdd[0], pdd[1], 0.0])
    tau, res = chain.inverse_dynamics(qv, v, a)
    return tau, {"gap": float(np.max(np.abs(chain.gap(qv)))), "residual": max(res, res_k),
                 "alpha_d": v[arms_v], "alpha_dd": a[arms_v]}
