"""The reference twin of scalesynth.dynamics.inverse's endpoint motion and link forces: the implementation it
replaced, kept here unchanged in substance. Every displaced pose gets its own IK (cycle_kinematics in the branch)
and link_geometry per pose (a plain loop, no vectorised endpoints): de/dx by central differences of the endpoints
along each task axis (step 1e-5 of the size, or 1e-5 rad), e_dd = (de/dx) x_dd + a second difference of the
endpoints along x_d (the pose moving by 1e-4 of its scale). Slow (tens of link_geometry calls per sample) and
obviously what the virtual-work formula says; tests/test_link_dynamics.py holds the fast path to it."""

from __future__ import annotations

import numpy as np

from scalesynth.cycle import config as ccfg
from scalesynth.dynamics import bodies
from scalesynth.dynamics.inverse import JACOBIAN_STEP, SECOND_STEP, actuator_forces, frame_gravity, held_forces


def link_points_by_ik(mech, design, options, poses: np.ndarray, label: str) -> np.ndarray:
    """Endpoints (m, s, 2, 3) at poses (m, k): IK per pose set, link_geometry per pose; NaN where out of reach.
    Written out here, not links.segment_ends: the twin shares no code with the path it checks."""
    q, _ = mech.cycle_kinematics(design, options, poses, label)
    out = None
    for s, pose in enumerate(poses):
        if not np.all(np.isfinite(q[s])):
            continue
        a, b, _ = mech.link_geometry(design, options, pose, q[s]).as_arrays()
        if out is None:
            out = np.full((len(poses), len(a), 2, 3), np.nan)
        out[s, :, 0], out[s, :, 1] = a, b
    return out


def endpoint_motion_by_ik(mech, design, options, p, pd, pdd, label: str, size: float):
    """e, de/dx, velocities and accelerations of the endpoints as inverse.endpoint_motion, by IK at every
    displaced pose."""
    n, k = p.shape
    scale = np.array([size if u == "length" else 1.0 for u in mech.task_units])
    h = JACOBIAN_STEP * scale
    reach = np.max(np.abs(pd) / scale, axis=1)
    eps = np.where(reach > 0.0, SECOND_STEP / np.where(reach > 0.0, reach, 1.0), 0.0)
    steps = np.eye(k) * h
    poses = np.concatenate([p[:, None, :] + steps[None], p[:, None, :] - steps[None],
                            np.stack([p + eps[:, None] * pd, p, p - eps[:, None] * pd], axis=1)], axis=1)
    e = link_points_by_ik(mech, design, options, poses.reshape(-1, k), label).reshape(n, 2 * k + 3, -1, 2, 3)
    jac = (e[:, :k] - e[:, k:2 * k]) / (2.0 * h)[None, :, None, None, None]
    vel = np.einsum("nksec,nk->nsec", jac, pd)
    acc = np.einsum("nksec,nk->nsec", jac, pdd)
    moving = reach > 0.0
    second = e[:, 2 * k] - 2.0 * e[:, 2 * k + 1] + e[:, 2 * k + 2]
    acc[moving] += second[moving] / (eps[moving] ** 2)[:, None, None, None]
    return e[:, 2 * k + 1], jac, vel, acc


def generalised_forces(mech, jac, acc, masses, g3, length_unit: str):
    """F (n, k) and its gravity part from Jacobians (n, k, s, 2, 3) and accelerations (n, s, 2, 3), as the module
    docstring of scalesynth.dynamics.inverse states (sample-major layout)."""
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


def link_forces_by_ik(mech, design, options, cyc, traj, label: str, size: float, A_si: np.ndarray,
                      length_unit: str):
    """Actuator forces (n, nj), their gravity part (n, nj) and the task-axis force (n, k) of the links, SI."""
    dyn = getattr(cyc, "_dynamics", None)
    q0, _ = mech.cycle_kinematics(design, options, traj.p[:1], label)
    ref = mech.link_geometry(design, options, traj.p[0], q0[0])
    masses = bodies.segment_masses(ref, options, dyn, length_unit, mech.name)
    _, jac, _, acc = endpoint_motion_by_ik(mech, design, options, traj.p, traj.pd, traj.pdd, label, size)
    g3 = frame_gravity(cyc, mech)
    F, F_g = generalised_forces(mech, jac, acc, masses, g3, length_unit)
    # held axes (pprs-rprs: the platform orientation): the moments M = (de/dtheta)^T f from the mechanism's
    # held_link_jacobian with this twin's own endpoint accelerations (held_link_jacobian itself is checked against
    # dV/dq in tests/test_pprs_rprs_held.py and tests/test_sixdof_bodies.py)
    M, M_g = held_forces(mech, design, options, traj.p, acc, masses, g3, label, length_unit)
    F_all, F_g_all = np.hstack([F, M]), np.hstack([F_g, M_g])
    return actuator_forces(mech, A_si, F_all), actuator_forces(mech, A_si, F_g_all), F
