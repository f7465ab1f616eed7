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

A mechanism whose task holds degrees of freedom constant (the platform orientation of pprs-rprs and the 6-DOF
described mechanisms; velocity_map has columns past the task axes) needs the endpoints' derivatives along those
too: the generalised force on held axis j is M_j = sum_e (de/dtheta_j) . f_e (virtual work of a virtual turn at
fixed position), from the mechanism's ``held_link_jacobian`` (pprs-rprs, hexa, hexapod: the platform turned by
+-1e-5 rad about frame axis j, the IK re-solved in the branch), and A^T tau = [F; M] (docs/cycles.md).
"""

from __future__ import annotations

import numpy as np

from scalesynth.cycle import config as ccfg
from scalesynth.mechanisms.links import SegmentPoints, segment_ends

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


def endpoints(mech, design, options, poses: np.ndarray, q: np.ndarray) -> SegmentPoints:
    """Segment endpoints (links.SegmentPoints), length unit, at poses (m, k) with joint values q (m, n_joints): the
    mechanism's vectorised ``link_endpoints`` where it has one, else link_geometry per pose (every end its own
    moving point). NaN points where q is not finite."""
    bad = ~np.all(np.isfinite(q), axis=1)
    vectorised = getattr(mech, "link_endpoints", None)
    if vectorised is not None:
        out = vectorised(design, options, poses, q)
        out.points[..., bad] = np.nan
        return out
    ends = segment_ends(mech, design, options, poses, q)  # (m, s, 2, 3)
    if ends is None:
        raise ValueError("no pose of the cycle is reachable")
    s = ends.shape[1]
    points = np.moveaxis(ends, 0, -1).reshape(2 * s, 3, -1)  # every end its own point, coordinate-major
    return SegmentPoints(points, np.arange(2 * s).reshape(s, 2), np.full((s, 2, 3), np.nan))


def link_points(mech, design, options, poses: np.ndarray, label: str) -> np.ndarray:
    """Segment endpoints (m, n_segments, 2, 3), length unit, at poses (m, k): IK (cycle_kinematics) in branch
    ``label``, then ``endpoints``. NaN rows where the branch does not reach."""
    q, _ = mech.cycle_kinematics(design, options, poses, label)
    out = np.moveaxis(endpoints(mech, design, options, poses, q).segments(), -1, 0)
    out[~np.all(np.isfinite(q), axis=1)] = np.nan
    return out


def endpoint_motion(mech, design, options, p, pd, pdd, q, A, a_dot, size: float):
    """The moving points (links.SegmentPoints at the samples), their Jacobians J (P, 3, k, n) = de/dx (length
    unit per task unit) and accelerations (P, 3, n) (length unit per s^2) along the sampled motion p, pd, pdd
    (n, k), from the cycle's joint values q (n, nj), velocity map A (n, nj, nj) and (dA/dt) x_dot a_dot (n, nj);
    coordinate-major (samples last)."""
    n, k = p.shape
    scale = np.array([size if u == "length" else 1.0 for u in mech.task_units])
    h = JACOBIAN_STEP * scale
    reach = np.max(np.abs(pd) / scale, axis=1)
    moving = reach > 0.0
    eps = np.where(moving, SECOND_STEP / np.where(moving, reach, 1.0), 0.0)
    # the 2k + 3 evaluations, evaluation-major (2k + 3, n, .): x +- h e_j with q +- h A e_j, then x + eps x_d,
    # x, x - eps x_d with q +- eps q_d + eps^2/2 a_dot
    dx = np.eye(k)[:, None, :] * h[:, None, None]  # (k, 1, k)
    dq = np.transpose(A[:, :, :k], (2, 0, 1)) * h[:, None, None]  # (k, n, nj)
    step_x = eps[:, None] * pd
    step_q = eps[:, None] * np.einsum("nij,nj->ni", A[:, :, :k], pd)
    bend = 0.5 * (eps * eps)[:, None] * a_dot
    poses = np.concatenate([p + dx, p - dx, (p + step_x)[None], p[None], (p - step_x)[None]])
    qs = np.concatenate([q + dq, q - dq, (q + step_q + bend)[None], q[None], (q - step_q + bend)[None]])
    sp = endpoints(mech, design, options, poses.reshape(-1, k), qs.reshape(-1, q.shape[1]))
    e = sp.points.reshape(*sp.points.shape[:2], 2 * k + 3, n)
    jac = (e[..., :k, :] - e[..., k:2 * k, :]) / (2.0 * h)[:, None]
    acc = jac[..., 0, :] * pdd[:, 0]
    for j in range(1, k):
        acc += jac[..., j, :] * pdd[:, j]
    inv_eps2 = np.where(moving, 1.0 / np.where(moving, eps * eps, 1.0), 0.0)
    acc += (e[..., 2 * k, :] - 2.0 * e[..., 2 * k + 1, :] + e[..., 2 * k + 2, :]) * inv_eps2
    return SegmentPoints(e[..., 2 * k + 1, :], sp.index, sp.fixed), jac, acc


def point_masses(index: np.ndarray, masses: np.ndarray, n_points: int) -> np.ndarray:
    """The rods' constant mass matrix on the moving points (P, P) kg: segment a -> b of mass m adds m/3 on the
    diagonal at a and b and m/6 between them (T = m/6 (|va|^2 + va.vb + |vb|^2)); fixed ends (-1) drop out."""
    out = np.zeros((n_points, n_points))
    for (a, b), m in zip(index, masses, strict=True):
        if m == 0.0:
            continue
        for u, v in ((a, a), (b, b)):
            if u >= 0:
                out[u, v] += m / 3.0
        if a >= 0 and b >= 0:
            out[a, b] += m / 6.0
            out[b, a] += m / 6.0
    return out


def generalised_forces(mech, index: np.ndarray, jac: np.ndarray, acc: np.ndarray, masses: np.ndarray,
                       g3: np.ndarray, length_unit: str) -> tuple[np.ndarray, np.ndarray]:
    """The links' generalised force on the task axes (n, k) and its gravity part (n, k): N along a length axis,
    N m about an angle axis, from the moving points' Jacobians (P, 3, k, n) and accelerations (P, 3, n; length
    unit per s^2), which point each segment end is (``index`` (s, 2), -1 fixed), segment masses (s,) kg and
    gravity g3 (3,) m/s^2 (endpoint_motion's layout). Per point, the forces of the rod ends on it summed:
    f = M a - (weight share), M = point_masses."""
    m_per_unit = ccfg.METRES_PER_UNIT[length_unit]
    n_points = jac.shape[0]
    weight = np.zeros((n_points, 3))  # -m g / 2 per moving end
    for (a, b), m in zip(index, masses, strict=True):
        for u in (a, b):
            if u >= 0:
                weight[u] -= 0.5 * m * g3
    mass = point_masses(index, masses, n_points)
    f = np.tensordot(mass, acc * m_per_unit, axes=(1, 0)) + weight[:, :, None]  # (P, 3, n)
    col = np.array([1.0 if u == "length" else m_per_unit for u in mech.task_units])  # m per m or m per rad
    flat = jac.reshape(-1, *jac.shape[-2:])  # (P 3, k, n)
    F = np.einsum("lkn,ln->nk", flat, f.reshape(-1, f.shape[-1])) * col
    F_g = np.einsum("lkn,l->nk", flat, weight.ravel()) * col
    return F, F_g


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


def segment_accelerations(index: np.ndarray, acc: np.ndarray) -> np.ndarray:
    """Each segment end's acceleration (n, s, 2, 3) from the moving points' (P, 3, n) (endpoint_motion's layout;
    a fixed end, index -1, is at rest)."""
    n = acc.shape[2]
    out = np.zeros((n, *index.shape, 3))
    moving = index >= 0
    out[:, moving] = np.transpose(acc, (2, 0, 1))[:, index[moving]]
    return out


def actuator_forces(mech, A_si: np.ndarray, F: np.ndarray) -> np.ndarray:
    """tau (n, n_joints) with A_si^T tau = [F; 0] (F (n, k') on the task axes and any held axes after them, SI;
    the rest 0)."""
    n, nj = A_si.shape[:2]
    full = np.zeros((n, nj))
    full[:, : F.shape[1]] = F
    return np.linalg.solve(np.transpose(A_si, (0, 2, 1)), full[..., None])[..., 0]


def link_forces(mech, design, options, cyc, traj, size: float, q: np.ndarray, A: np.ndarray, a_dot: np.ndarray,
                A_si: np.ndarray, length_unit: str, label: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The links' share of one design's cycle: actuator forces (n, nj) and their gravity part (n, nj), SI, and the
    generalised force on the task axes (n, k). ``q``, ``A``, ``a_dot``: the cycle's joint values (n, nj), velocity
    map (n, nj, nj) and (dA/dt) x_dot (n, nj) at the samples, joint and task units; ``A_si`` the velocity map in
    SI. The mass model from ``cyc``'s dynamics section (attached by the run config; None: tubes of the options'
    sections), at the cycle's first sample; ``label`` the branch (held_link_jacobian's)."""
    from scalesynth.dynamics import bodies

    dyn = getattr(cyc, "_dynamics", None)
    ref = mech.link_geometry(design, options, traj.p[0], q[0])
    masses = bodies.segment_masses(ref, options, dyn, length_unit, mech.name)
    n, nj = A_si.shape[:2]
    k = traj.p.shape[1]
    if not np.any(masses):
        return np.zeros((n, nj)), np.zeros((n, nj)), np.zeros((n, k))
    sp, jac, acc = endpoint_motion(mech, design, options, traj.p, traj.pd, traj.pdd, q, A, a_dot, size)
    g3 = frame_gravity(cyc, mech)
    F, F_g = generalised_forces(mech, sp.index, jac, acc, masses, g3, length_unit)
    M, M_g = np.zeros((n, 0)), np.zeros((n, 0))
    if nj > k:
        M, M_g = held_forces(mech, design, options, traj.p, segment_accelerations(sp.index, acc), masses, g3, label,
                             length_unit)
    if not (np.all(np.isfinite(F)) and np.all(np.isfinite(M))):
        from scalesynth.errors import InvalidPose

        raise InvalidPose("cycle: a sample lies on the boundary of the workspace (the links' motion is not defined "
                          "around it)")
    return (actuator_forces(mech, A_si, np.hstack([F, M])), actuator_forces(mech, A_si, np.hstack([F_g, M_g])), F)
