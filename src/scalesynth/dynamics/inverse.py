"""Inverse dynamics of the links along a cycle by virtual work (the mass model: ``dynamics.bodies``).

Every segment a -> b of the mechanism's ``link_geometry`` is a thin uniform rod of mass m: kinetic energy
T = 1/2 [va; vb]^T M [va; vb] with the constant M = m/6 [[2 I, I], [I, 2 I]], potential V = -m g . (a + b)/2. Its
endpoints e(x) = g(x, q(x)) follow from the pose x and the joint values q (IK of the configured branch), so
Lagrange's equations give the generalised force on the task axes F_j = sum_e (de/dx_j) . f_e with the endpoint
forces f_a = m/6 (2 a_dd + b_dd) - m g/2, f_b = m/6 (a_dd + 2 b_dd) - m g/2, and the actuators' share follows from
A^T tau = F (A the velocity map, the same step as the payload's force).

No IK beyond the cycle's own: the cycle already has q, A (dq/dx) and a_dot = (dA/dt) x_dot at every sample, so
the endpoints' derivatives come from g alone (the mechanism's vectorised ``link_endpoints``, else link_geometry
per pose). de/dx_j by central differences of g along (e_j, A e_j) (step 1e-5 of the mechanism's size, or 1e-5
rad): g_x e_j + g_q A e_j, the derivative along the branch. e_dd = (de/dx) x_dd + e''[x_d, x_d], the second term
by a second difference of g along (x_d, q_d) with q bent by a_dot (the pose moving by 1e-4 of its scale): the
branch's second-order path, so the difference is e'' to O(step^2) (the branch's third-order term is odd and
cancels). Accurate to about 1e-8 relative on smooth laws; tests/link_dynamics_twin.py is the reference that
re-solves the IK at every displaced pose (as this module did before), and tests/test_link_dynamics.py holds the two
together on every mechanism.

A mechanism whose task holds degrees of freedom constant (pprs-rprs: the platform orientation; velocity_map has
columns past the task axes) would need the endpoints' derivatives along those too; the links' generalised force
on them is taken as 0 (docs/cycles.md).
"""

from __future__ import annotations

import numpy as np

from scalesynth.cycle import config as ccfg

JACOBIAN_STEP = 1e-5
SECOND_STEP = 1e-4


def frame_gravity(cyc, mech) -> np.ndarray:
    """Gravity (3,) m/s^2 in the mechanism frame: the cycle's gravity vector, its task axes x, y, z placed on the
    frame axes of those names (planar mechanisms: the x-y plane, gravity default -y)."""
    g = ccfg.gravity_vector(cyc, mech)
    if not ccfg.cartesian_task(mech):
        return np.asarray(g, dtype=float)
    out = np.zeros(3)
    for a, name in enumerate(mech.task_axes):
        out["xyz".index(name)] = g[a]
    return out


def endpoints(mech, design, options, poses: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Segment endpoints (m, n_segments, 2, 3), length unit, at poses (m, k) with joint values q (m, n_joints): the
    mechanism's vectorised ``link_endpoints`` where it has one, else link_geometry per pose. NaN rows where q is not
    finite."""
    if hasattr(mech, "link_endpoints"):
        out = mech.link_endpoints(design, options, poses, q)
        out[~np.all(np.isfinite(q), axis=1)] = np.nan
        return out
    out = None
    for s, pose in enumerate(poses):
        if not np.all(np.isfinite(q[s])):
            continue
        a, b, _ = mech.link_geometry(design, options, pose, q[s]).as_arrays()
        if out is None:
            out = np.full((len(poses), len(a), 2, 3), np.nan)
        out[s, :, 0], out[s, :, 1] = a, b
    if out is None:
        raise ValueError("no pose of the cycle is reachable")
    return out


def link_points(mech, design, options, poses: np.ndarray, label: str) -> np.ndarray:
    """Segment endpoints (m, n_segments, 2, 3), length unit, at poses (m, k): IK (cycle_kinematics) in branch
    ``label``, then ``endpoints``. NaN where the branch does not reach."""
    q, _ = mech.cycle_kinematics(design, options, poses, label)
    return endpoints(mech, design, options, poses, q)


def endpoint_motion(mech, design, options, p, pd, pdd, q, A, a_dot, size: float, segments=None):
    """Endpoints e (n, s, 2, 3), their Jacobians J (n, k, s, 2, 3) = de/dx (length unit per task unit),
    velocities (n, s, 2, 3) and accelerations (n, s, 2, 3) (length unit per s, s^2) along the sampled motion
    p, pd, pdd (n, k), from the cycle's joint values q (n, nj), velocity map A (n, nj, nj) and (dA/dt) x_dot
    a_dot (n, nj). ``segments``: an index of the segments to keep (default all)."""
    n, k = p.shape
    nj = q.shape[1]
    scale = np.array([size if u == "length" else 1.0 for u in mech.task_units])
    h = JACOBIAN_STEP * scale
    reach = np.max(np.abs(pd) / scale, axis=1)
    eps = np.where(reach > 0.0, SECOND_STEP / np.where(reach > 0.0, reach, 1.0), 0.0)
    steps = np.eye(k) * h
    dq = np.transpose(A[:, :, :k], (0, 2, 1)) * h[None, :, None]  # (n, k, nj): q moves along A e_j
    qd = np.einsum("nij,nj->ni", A[:, :, :k], pd)
    bend = 0.5 * (eps * eps)[:, None] * a_dot
    poses = np.concatenate([p[:, None, :] + steps[None], p[:, None, :] - steps[None],
                            np.stack([p + eps[:, None] * pd, p, p - eps[:, None] * pd], axis=1)], axis=1)
    qs = np.concatenate([q[:, None, :] + dq, q[:, None, :] - dq,
                         np.stack([q + eps[:, None] * qd + bend, q, q - eps[:, None] * qd + bend], axis=1)], axis=1)
    e = endpoints(mech, design, options, poses.reshape(-1, k), qs.reshape(-1, nj)).reshape(n, 2 * k + 3, -1, 2, 3)
    if segments is not None:
        e = e[:, :, segments]
    jac = (e[:, :k] - e[:, k:2 * k]) / (2.0 * h)[None, :, None, None, None]
    vel = np.einsum("nksec,nk->nsec", jac, pd)
    acc = np.einsum("nksec,nk->nsec", jac, pdd)
    moving = reach > 0.0
    second = e[:, 2 * k] - 2.0 * e[:, 2 * k + 1] + e[:, 2 * k + 2]
    acc[moving] += second[moving] / (eps[moving] ** 2)[:, None, None, None]
    return e[:, 2 * k + 1], jac, vel, acc


def generalised_forces(mech, jac: np.ndarray, acc: np.ndarray, masses: np.ndarray, g3: np.ndarray,
                       length_unit: str) -> tuple[np.ndarray, np.ndarray]:
    """The links' generalised force on the task axes (n, k) and its gravity part (n, k): N along a length axis,
    N m about an angle axis, from the Jacobians (n, k, s, 2, 3), endpoint accelerations (n, s, 2, 3; length unit
    per s^2), segment masses (s,) kg and gravity g3 (3,) m/s^2."""
    m_per_unit = ccfg.METRES_PER_UNIT[length_unit]
    a_si = acc * m_per_unit
    m6 = masses[None, :, None] / 6.0
    weight = -0.5 * masses[None, :, None] * g3[None, None, :]  # (1, s, 3) per endpoint
    f = np.stack([m6 * (2.0 * a_si[:, :, 0] + a_si[:, :, 1]) + weight,
                  m6 * (a_si[:, :, 0] + 2.0 * a_si[:, :, 1]) + weight], axis=2)  # (n, s, 2, 3)
    col = np.array([1.0 if u == "length" else m_per_unit for u in mech.task_units])
    jac_si = jac * col[None, :, None, None, None]  # m per m or m per rad
    F = np.einsum("nksec,nsec->nk", jac_si, f)
    F_g = np.einsum("nksec,sec->nk", jac_si, np.broadcast_to(weight[0][:, None, :], f.shape[1:]))
    return F, F_g


def actuator_forces(mech, A_si: np.ndarray, F: np.ndarray) -> np.ndarray:
    """tau (n, n_joints) with A_si^T tau = [F; 0] (F (n, k) on the task axes, SI)."""
    n, nj = A_si.shape[:2]
    full = np.zeros((n, nj))
    full[:, : F.shape[1]] = F
    return np.linalg.solve(np.transpose(A_si, (0, 2, 1)), full[..., None])[..., 0]


def link_forces(mech, design, options, cyc, traj, size: float, q: np.ndarray, A: np.ndarray, a_dot: np.ndarray,
                A_si: np.ndarray, length_unit: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The links' share of one design's cycle: actuator forces (n, nj) and their gravity part (n, nj), SI, and the
    generalised force on the task axes (n, k). ``q``, ``A``, ``a_dot``: the cycle's joint values (n, nj), velocity
    map (n, nj, nj) and (dA/dt) x_dot (n, nj) at the samples, joint and task units; ``A_si`` the velocity map in
    SI. The mass model from ``cyc``'s dynamics section (attached by the run config; None: tubes of the options'
    sections), at the cycle's first sample."""
    from scalesynth.dynamics import bodies

    dyn = getattr(cyc, "_dynamics", None)
    ref = mech.link_geometry(design, options, traj.p[0], q[0])
    masses = bodies.segment_masses(ref, options, dyn, length_unit, mech.name)
    n, nj = A_si.shape[:2]
    k = traj.p.shape[1]
    if not np.any(masses):
        return np.zeros((n, nj)), np.zeros((n, nj)), np.zeros((n, k))
    heavy = np.nonzero(masses)[0]  # massless segments add nothing
    _, jac, _, acc = endpoint_motion(mech, design, options, traj.p, traj.pd, traj.pdd, q, A, a_dot, size, heavy)
    F, F_g = generalised_forces(mech, jac, acc, masses[heavy], frame_gravity(cyc, mech), length_unit)
    if not np.all(np.isfinite(F)):
        from scalesynth.errors import InvalidPose

        raise InvalidPose("cycle: a sample lies on the boundary of the workspace (the links' motion is not defined "
                          "around it)")
    return actuator_forces(mech, A_si, F), actuator_forces(mech, A_si, F_g), F
