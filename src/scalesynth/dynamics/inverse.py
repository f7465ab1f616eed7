"""Inverse dynamics of the links along a cycle by virtual work (the mass model: ``dynamics.bodies``).

Every segment a -> b of the mechanism's ``link_geometry`` is a thin uniform rod of mass m: kinetic energy
T = 1/2 [va; vb]^T M [va; vb] with the constant M = m/6 [[2 I, I], [I, 2 I]], potential V = -m g . (a + b)/2. Its
endpoints are functions e(x) of the pose (IK of the configured branch, then link_geometry), so Lagrange's equations
give the generalised force on the task axes F_j = sum_e (de/dx_j) . f_e with the endpoint forces
f_a = m/6 (2 a_dd + b_dd) - m g/2, f_b = m/6 (a_dd + 2 b_dd) - m g/2, and the actuators' share follows from
A^T tau = F (A the velocity map, the same step as the payload's force). de/dx by central differences of e along
each task axis (step 1e-5 of the mechanism's size, or 1e-5 rad); e_dd = (de/dx) x_dd + e''[x_d, x_d], the second
term by a second difference of e along x_d (the pose moving by 1e-4 of its scale): both from the motion law's
analytic x_d, x_dd, so accurate to about 1e-7 relative on smooth laws.

A mechanism whose task holds degrees of freedom constant (the platform orientation of pprs-rprs and the 6-DOF
described mechanisms; velocity_map has columns past the task axes) needs the endpoints' derivatives along those
too: the generalised force on held axis j is M_j = sum_e (de/dtheta_j) . f_e (virtual work of a virtual turn at
fixed position), from the mechanism's ``held_link_jacobian`` where it has one (the 6-DOF ones), and A^T tau =
[F; M]; without it M is taken as 0 (pprs-rprs, docs/cycles.md).
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


def link_points(mech, design, options, poses: np.ndarray, label: str) -> np.ndarray:
    """Segment endpoints (m, n_segments, 2, 3), length unit, at poses (m, k): the mechanism's vectorised
    ``link_points`` where it has one, else IK (cycle_kinematics) and link_geometry per pose. NaN where the
    branch does not reach."""
    if hasattr(mech, "link_points"):
        return mech.link_points(design, options, poses, label)
    q, _ = mech.cycle_kinematics(design, options, poses, label)
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


def endpoint_motion(mech, design, options, p, pd, pdd, label: str, size: float):
    """Endpoints e (n, s, 2, 3), their Jacobians J (n, k, s, 2, 3) = de/dx (length unit per task unit),
    velocities (n, s, 2, 3) and accelerations (n, s, 2, 3) (length unit per s, s^2) along the sampled motion."""
    n, k = p.shape
    scale = np.array([size if u == "length" else 1.0 for u in mech.task_units])
    h = JACOBIAN_STEP * scale
    reach = np.max(np.abs(pd) / scale, axis=1)
    eps = np.where(reach > 0.0, SECOND_STEP / np.where(reach > 0.0, reach, 1.0), 0.0)
    steps = np.eye(k) * h
    poses = np.concatenate([p[:, None, :] + steps[None], p[:, None, :] - steps[None],
                            np.stack([p + eps[:, None] * pd, p, p - eps[:, None] * pd], axis=1)], axis=1)
    e = link_points(mech, design, options, poses.reshape(-1, k), label).reshape(n, 2 * k + 3, -1, 2, 3)
    jac = (e[:, :k] - e[:, k:2 * k]) / (2.0 * h)[None, :, None, None, None]
    vel = np.einsum("nksec,nk->nsec", jac, pd)
    acc = np.einsum("nksec,nk->nsec", jac, pdd)
    moving = reach > 0.0
    second = e[:, 2 * k] - 2.0 * e[:, 2 * k + 1] + e[:, 2 * k + 2]
    acc[moving] += second[moving] / (eps[moving] ** 2)[:, None, None, None]
    return e[:, 2 * k + 1], jac, vel, acc


def endpoint_forces(a_si: np.ndarray, masses: np.ndarray, g3: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The rods' endpoint forces f (n, s, 2, 3), N, from endpoint accelerations (n, s, 2, 3) m/s^2, masses (s,) kg
    and gravity g3 (3,) m/s^2, and their weight part (1, s, 3) per endpoint."""
    m6 = masses[None, :, None] / 6.0
    weight = -0.5 * masses[None, :, None] * g3[None, None, :]
    f = np.stack([m6 * (2.0 * a_si[:, :, 0] + a_si[:, :, 1]) + weight,
                  m6 * (a_si[:, :, 0] + 2.0 * a_si[:, :, 1]) + weight], axis=2)
    return f, weight


def held_forces(mech, design, options, p: np.ndarray, acc: np.ndarray, masses: np.ndarray, g3: np.ndarray,
                label: str, length_unit: str) -> tuple[np.ndarray, np.ndarray]:
    """The links' generalised moments on the held rotations (n, r) N m and their gravity part (n, r), from the
    mechanism's held_link_jacobian (n, r, s, 2, 3) and the endpoint accelerations (n, s, 2, 3; length unit per
    s^2); (n, 0) arrays for a mechanism without one."""
    n = len(p)
    if not hasattr(mech, "held_link_jacobian"):
        return np.zeros((n, 0)), np.zeros((n, 0))
    m_per_unit = ccfg.METRES_PER_UNIT[length_unit]
    jh = mech.held_link_jacobian(design, options, p, label) * m_per_unit  # m per rad
    f, weight = endpoint_forces(acc * m_per_unit, masses, g3)
    M = np.einsum("nrsec,nsec->nr", jh, f)
    M_g = np.einsum("nrsec,sec->nr", jh, np.broadcast_to(weight[0][:, None, :], f.shape[1:]))
    return M, M_g


def generalised_forces(mech, jac: np.ndarray, acc: np.ndarray, masses: np.ndarray, g3: np.ndarray,
                       length_unit: str) -> tuple[np.ndarray, np.ndarray]:
    """The links' generalised force on the task axes (n, k) and its gravity part (n, k): N along a length axis,
    N m about an angle axis, from the Jacobians (n, k, s, 2, 3), endpoint accelerations (n, s, 2, 3; length unit
    per s^2), segment masses (s,) kg and gravity g3 (3,) m/s^2."""
    m_per_unit = ccfg.METRES_PER_UNIT[length_unit]
    f, weight = endpoint_forces(acc * m_per_unit, masses, g3)
    col = np.array([1.0 if u == "length" else m_per_unit for u in mech.task_units])
    jac_si = jac * col[None, :, None, None, None]  # m per m or m per rad
    F = np.einsum("nksec,nsec->nk", jac_si, f)
    F_g = np.einsum("nksec,sec->nk", jac_si, np.broadcast_to(weight[0][:, None, :], f.shape[1:]))
    return F, F_g


def actuator_forces(mech, A_si: np.ndarray, F: np.ndarray) -> np.ndarray:
    """tau (n, n_joints) with A_si^T tau = [F; 0] (F (n, k') on the task axes and any held axes after them, SI;
    the rest 0)."""
    n, nj = A_si.shape[:2]
    full = np.zeros((n, nj))
    full[:, : F.shape[1]] = F
    return np.linalg.solve(np.transpose(A_si, (0, 2, 1)), full[..., None])[..., 0]


def link_forces(mech, design, options, cyc, traj, label: str, size: float, A_si: np.ndarray,
                length_unit: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The links' share of one design's cycle: actuator forces (n, nj) and their gravity part (n, nj), SI, and the
    generalised force on the task axes (n, k). The mass model from ``cyc``'s dynamics section (attached by the
    run config; None: tubes of the options' sections), at the cycle's first sample."""
    from scalesynth.dynamics import bodies

    dyn = getattr(cyc, "_dynamics", None)
    q0, _ = mech.cycle_kinematics(design, options, traj.p[:1], label)
    ref = mech.link_geometry(design, options, traj.p[0], q0[0])
    masses = bodies.segment_masses(ref, options, dyn, length_unit, mech.name)
    n, nj = A_si.shape[:2]
    k = traj.p.shape[1]
    if not np.any(masses):
        return np.zeros((n, nj)), np.zeros((n, nj)), np.zeros((n, k))
    _, jac, _, acc = endpoint_motion(mech, design, options, traj.p, traj.pd, traj.pdd, label, size)
    g3 = frame_gravity(cyc, mech)
    F, F_g = generalised_forces(mech, jac, acc, masses, g3, length_unit)
    M, M_g = held_forces(mech, design, options, traj.p, acc, masses, g3, label, length_unit) if nj > k else (
        np.zeros((n, 0)), np.zeros((n, 0)))
    if not (np.all(np.isfinite(F)) and np.all(np.isfinite(M))):
        from scalesynth.errors import InvalidPose

        raise InvalidPose("cycle: a sample lies on the boundary of the workspace (the links' motion is not defined "
                          "around it)")
    return (actuator_forces(mech, A_si, np.hstack([F, M])), actuator_forces(mech, A_si, np.hstack([F_g, M_g])), F)
