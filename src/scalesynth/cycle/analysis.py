"""Cycle analysis of one design: actuator positions, rates and forces, LCI and link clearance along a cycle.

Along the sampled trajectory (``cycle.trajectory``), in the configured working mode (``kernel_branch``):

* every sample must be in the workspace (the point kernel: reachable within every limit); the IK branch is
  followed with continuity (angles unwrapped; each step in q must match, to first order, the step the velocity
  map predicts for the step in x, so a branch jump is caught) and the determinant of the velocity map may not
  change sign between samples (a singularity crossed). A failure raises :class:`CycleError` naming the sample,
  its time and its position;
* q from the closed-form IK; q_dot = A x_dot with the mechanism's velocity map A (inverse Jacobian);
  q_ddot = A x_ddot + A_dot x_dot, where A_dot x_dot is the derivative of A along the motion, taken by a
  central difference of A over a displacement of 1e-6 of the mechanism's size (IK re-solved in the branch);
* actuator forces for the payload, quasi-static plus payload inertia: the payload is a point mass m, the
  links are massless and joint friction is ignored, so A_SI^T tau = [F; 0] with F the generalised force on
  the task axes, tau in N for prismatic and N m for revolute actuators (SI units, whatever the config's
  length unit). With Cartesian task axes the payload sits at the task point and F = m (a - g) (N). With an
  angular task axis (rps-upu, ups-sspr) it sits at the mechanism's ``payload_point`` c(x) (3-D, mechanism
  frame): c_dot = J_c x_dot, c_ddot = J_c x_ddot + (d J_c/dt) x_dot, and F = J_c^T m (c_ddot - g), i.e.
  tau = A_SI^-T [J_c^T m (c_ddot - g); 0]: N along a length axis, N m about an angle axis (J_c and its
  derivative by central differences of c). Either way sum tau_i q_dot_i = F . x_dot = m (c_ddot - g) . c_dot
  (W) at every sample (power balance);
* the LCI from the point kernel and the clearance of the link capsules (``cycle.clearance``).

* the deflection (``CycleResult.deflection``, where the mechanism has a per-voxel ``deflection`` field and a
  ``load`` option, and the options switch the field on: planar-fivebar, pprs-rprs, ups-sspr, and 2pauu-ppap with
  ``stiffness_metrics: true``): at every sample the magnitude of the payload point's deflection
  under the force the payload exerts on the platform, m (g - c_ddot) (N; at rest its weight), from the
  mechanism's stiffness model with ideal joints (its field kernel re-packed with that load; the same model as
  the pose-level ``scalesynth stiffness`` command, tested against it). None for the other mechanisms.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from scalesynth.cycle import config as ccfg
from scalesynth.cycle import trajectory
from scalesynth.cycle.clearance import clearance
from scalesynth.dynamics.inverse import link_forces
from scalesynth.errors import InvalidPose, ScalesynthError
from scalesynth.mechanisms.base import Mechanism, wrap_angle

# relative displacement (of the mechanism's size) for the directional derivative of the velocity map
_DERIV_STEP = 1e-6
# relative displacement for the second difference of the payload point along the motion (rounding ~ 1e-16 / step^2)
_SECOND_STEP = 1e-4


class CycleError(InvalidPose):
    """The cycle cannot be followed (outside the workspace, a branch jump, a singularity); exit code 2."""


@dataclass(frozen=True)
class CycleResult:
    """One design's cycle. Arrays per sample (n rows): q, qd, qdd (n, n_joints) in the length unit or rad
    (per s, per s^2); force (n, n_joints) in N or N m, force_gravity (n, n_joints) its part due to gravity
    alone; task_force (n, k) the generalised force F on the task axes (N along a length axis, N m about an
    angle axis); payload_velocity, payload_accel (n, 3 or k) the payload point's velocity and acceleration
    (length unit per s, per s^2; payload axes, ``cycle.config.payload_axes``); lci (n,); clearance (n,) in the
    length unit (< 0: interference) and min_clearance_pair the two segments at its minimum. ``deflection``: hook for the
    stiffness model, None until a mechanism provides one; see ``deflection_along``."""

    traj: trajectory.Trajectory
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    force: np.ndarray
    task_force: np.ndarray
    lci: np.ndarray
    clearance: np.ndarray
    min_clearance_pair: tuple[str, str] | None  # the two segments at the smallest clearance
    task_axes: tuple[str, ...]
    task_units: tuple[str, ...]
    joints: tuple[str, ...]
    joint_units: tuple[str, ...]
    length_unit: str
    payload: float
    gravity: np.ndarray
    force_map: np.ndarray  # (n, n_joints, k): force = force_map @ F
    force_gravity: np.ndarray
    payload_velocity: np.ndarray
    payload_accel: np.ndarray
    deflection: np.ndarray | None = None
    motor_speed: np.ndarray | None = None  # (n, n_joints) rad/s at the motor shaft, with motors
    motor_torque: np.ndarray | None = None  # (n, n_joints) N m at the motor shaft (rotor inertia included)

    def columns(self) -> dict[str, np.ndarray]:
        """cycle.csv's columns in order: t; p_a, pd_a, pdd_a per task axis; q, qd, qdd, force per actuator
        (1-based); lci, clearance."""
        out = {"t": self.traj.t}
        for a, name in enumerate(self.task_axes):
            out[f"p_{name}"] = self.traj.p[:, a]
            out[f"pd_{name}"] = self.traj.pd[:, a]
            out[f"pdd_{name}"] = self.traj.pdd[:, a]
        for i in range(len(self.joints)):
            out[f"q{i + 1}"] = self.q[:, i]
            out[f"qd{i + 1}"] = self.qd[:, i]
            out[f"qdd{i + 1}"] = self.qdd[:, i]
            out[f"force{i + 1}"] = self.force[:, i]
        out["lci"] = self.lci
        out["clearance"] = self.clearance
        if self.deflection is not None:
            out["deflection"] = self.deflection
        if self.motor_torque is not None:
            for i in range(len(self.joints)):
                out[f"motor_speed{i + 1}"] = self.motor_speed[:, i]
                out[f"motor_torque{i + 1}"] = self.motor_torque[:, i]
        return out

    def units(self) -> dict[str, str]:
        """Unit of each column of ``columns``."""
        lu = self.length_unit
        out = {"t": "s"}
        for name, u in zip(self.task_axes, self.task_units, strict=True):
            base = lu if u == "length" else "rad"
            out.update({f"p_{name}": base, f"pd_{name}": f"{base}/s", f"pdd_{name}": f"{base}/s^2"})
        for i, u in enumerate(self.joint_units, start=1):
            base = lu if u == "length" else "rad"
            out.update({f"q{i}": base, f"qd{i}": f"{base}/s", f"qdd{i}": f"{base}/s^2",
                        f"force{i}": "N" if u == "length" else "N m"})
        out.update({"lci": "1", "clearance": lu})
        if self.deflection is not None:
            out["deflection"] = lu
        if self.motor_torque is not None:
            for i in range(len(self.joints)):
                out.update({f"motor_speed{i + 1}": "rad/s", f"motor_torque{i + 1}": "N m"})
        return out


def _size(mech: Mechanism, design, options) -> float:
    lo, hi = mech.bounding_box(design, options)
    return float(max(np.max(np.asarray(hi) - np.asarray(lo)), 1e-12))


def _where(mech: Mechanism, traj, k: int) -> str:
    pos = ", ".join(f"{v:.6g}" for v in traj.p[k])
    axes = ", ".join(mech.task_axes)
    return f"sample {k} (t = {traj.t[k]:.4g} s, segment {traj.segment[k] + 1}) at ({axes}) = ({pos})"


def check_vertices(mech: Mechanism, design, options, verts: np.ndarray, what: str) -> None:
    """Raise CycleError naming the first vertex outside the workspace (within every limit)."""
    from scalesynth.kernels.grid import points_lci

    lci = points_lci(mech.point_kernel, mech.pack(design, options), np.pad(verts, ((0, 0), (0, 3 - verts.shape[1]))))
    bad = np.nonzero(lci < 0)[0]
    if bad.size:
        k = int(bad[0])
        pos = ", ".join(f"{v:.6g}" for v in verts[k])
        raise CycleError(
            f"{what}[{k}]: ({pos}) is outside the workspace of the design (working mode "
            f"{mech.kernel_branch(options)}, within the limits)"
        )


def _kinematics_source(mech: Mechanism, design, options, label: str, reference: bool):
    """poses (n, k) -> (q (n, nj) with NaN rows out of reach in the branch, A (n, nj, nj)): the mechanism's
    (possibly vectorised) ``cycle_kinematics``, or with ``reference`` the base class's per-pose loop over
    inverse_kinematics and velocity_map (the obviously correct twin the tests compare with)."""
    if reference:
        return lambda poses: Mechanism.cycle_kinematics(mech, design, options, poses, label)
    return lambda poses: mech.cycle_kinematics(design, options, poses, label)


def _unwrap_along(q: np.ndarray, angular: np.ndarray) -> np.ndarray:
    """q (n, nj) with its angle columns moved by whole turns so that each sample lies within pi of the previous
    one (q[s] = q[s - 1] + wrap(q[s] - q[s - 1]))."""
    out = np.array(q, dtype=float)
    if np.any(angular) and len(out) > 1:
        steps = wrap_angle(np.diff(out[:, angular], axis=0))
        out[1:, angular] = out[0, angular] + np.cumsum(steps, axis=0)
    return out


def analyse(
    mech: Mechanism,
    design: Mapping[str, float],
    options: Mapping[str, Any],
    cyc: ccfg.CycleConfig,
    length_unit: str,
    *,
    rate_scale: float = 1.0,
    reference: bool = False,
) -> CycleResult:
    """The cycle of one design (module docstring). ``rate_scale`` multiplies the cycle rate (2 = twice as many
    cycles per minute). Raises CycleError where the cycle cannot be followed.

    The per-sample kinematics come from ``Mechanism.cycle_kinematics`` (vectorised over the samples where the
    mechanism provides it) and the clearance from the field kernel's ``clearance`` slot where the mechanism has
    one; ``reference=True`` takes both from the per-pose NumPy methods instead (inverse_kinematics, velocity_map,
    link_geometry), the slow twin the tests hold the fast path to."""
    from scalesynth.kernels.grid import points_lci

    design = mech.resolve_design(design)
    options = mech.resolve_options(options)
    verts = ccfg.vertices(cyc, mech, length_unit)
    check_vertices(mech, design, options, verts, "cycle.path" if cyc.path is not None else f"cycle.{cyc.preset}")
    traj = trajectory.build(verts, cyc.law, cyc.cycle_time / rate_scale, cyc.samples)
    n, k = traj.p.shape
    nj = len(mech.joints)
    packed = mech.pack(design, options)
    pts = np.pad(traj.p, ((0, 0), (0, 3 - k)))
    lci = points_lci(mech.point_kernel, packed, pts)
    outside = np.nonzero(lci < 0)[0]
    if outside.size:
        raise CycleError(f"cycle: {_where(mech, traj, int(outside[0]))} is outside the workspace")
    label = mech.kernel_branch(options)
    kin = _kinematics_source(mech, design, options, label, reference)
    angular = np.array([u == "angle" for u in mech.joint_units])
    size = _size(mech, design, options)
    joint_scale = np.where(angular, size, 1.0)
    q_raw, A = kin(traj.p)
    reach = np.all(np.isfinite(q_raw), axis=1)
    first_out = int(np.argmin(reach)) if not reach.all() else n
    q = _unwrap_along(np.where(reach[:, None], q_raw, 0.0)[:first_out], angular)
    # branch continuity: the step in q must be the one the velocity map predicts for the step in x (to first
    # order; the trapezoidal rule's error is second order), else the branch jumped
    m = q.shape[0]
    if m > 1:
        dx = np.zeros((m - 1, nj))
        dx[:, :k] = np.diff(traj.p[:m], axis=0)
        with np.errstate(invalid="ignore"):
            predicted = np.einsum("sij,sj->si", 0.5 * (A[1:m] + A[: m - 1]), dx)
            miss = np.linalg.norm((np.diff(q, axis=0) - predicted) * joint_scale, axis=1)
            finite = np.all(np.isfinite(A[1:m]), axis=(1, 2)) & np.all(np.isfinite(A[: m - 1]), axis=(1, 2))
            jumps = np.nonzero(finite & (miss > 0.5 * np.linalg.norm(predicted * joint_scale, axis=1) + 1e-9 * size))[0]
        if jumps.size:
            s = int(jumps[0]) + 1
            raise CycleError(
                f"cycle: branch {label} jumps between sample {s - 1} and {_where(mech, traj, s)} (a singularity "
                "or a branch point on the path; more cycle.samples may resolve it)"
            )
    if first_out < n:
        raise CycleError(f"cycle: {_where(mech, traj, first_out)} is out of reach in working mode {label}")
    det = np.linalg.det(A)
    sign = np.sign(det)
    bad = np.nonzero(~np.isfinite(det) | (sign == 0) | (lci <= 0))[0]
    if bad.size:
        raise CycleError(f"cycle: {_where(mech, traj, int(bad[0]))} is singular (LCI {lci[bad[0]]:.3g})")
    flip = np.nonzero(sign[1:] != sign[:-1])[0]
    if flip.size:
        raise CycleError(f"cycle: a singularity lies between {_where(mech, traj, int(flip[0]))} and the next sample")
    qd, qdd, force, force_gravity, task_force, force_map, vel, acc = _rates_and_forces(
        mech, design, options, cyc, length_unit, traj, kin, q, A, label, size)
    g = ccfg.gravity_vector(cyc, mech)
    m_per_unit = ccfg.METRES_PER_UNIT[length_unit]
    gaps = _clearance_along(mech, design, options, packed, traj.p, q, reference)
    at = int(np.argmin(gaps))
    return CycleResult(
        traj=traj, q=q, qd=qd, qdd=qdd, force=force, task_force=task_force, lci=lci, clearance=gaps,
        min_clearance_pair=clearance(mech.link_geometry(design, options, traj.p[at], q[at])).pair,
        task_axes=mech.task_axes, task_units=mech.task_units, joints=mech.joints,
        joint_units=mech.joint_units, length_unit=length_unit, payload=cyc.payload, gravity=g,
        force_map=force_map, force_gravity=force_gravity, payload_velocity=vel, payload_accel=acc,
        deflection=deflection_along(mech, design, options, traj.p, cyc.payload * (g[None, :] - acc * m_per_unit)),
        **_motor_columns(mech, cyc, qd, qdd, force, force_gravity, length_unit),
    )


def _rates_and_forces(mech: Mechanism, design, options, cyc, length_unit: str, traj, kin, q: np.ndarray,
                      A: np.ndarray, label: str, size: float):
    """Actuator rates and forces along the sampled motion ``traj`` (p, pd, pdd), q (n, nj) the joint values and
    A (n, nj, nj) the velocity map at traj.p: (qd, qdd, force, force_gravity, task_force, force_map, payload
    velocity, payload acceleration), the links' and the payload's inverse dynamics together (the arrays of
    CycleResult)."""
    n, k = traj.p.shape
    nj = len(mech.joints)
    pd_full = np.zeros((n, nj))
    pd_full[:, :k] = traj.pd
    pdd_full = np.zeros((n, nj))
    pdd_full[:, :k] = traj.pdd
    qd = np.einsum("nij,nj->ni", A, pd_full)
    a_dot = _a_dot_xdot(kin, mech, traj, size)
    qdd = np.einsum("nij,nj->ni", A, pdd_full) + a_dot
    g = ccfg.gravity_vector(cyc, mech)
    vel, acc, jc = _payload_motion(mech, design, options, traj, size)
    force, force_gravity, task_force, force_map = _forces(mech, A, jc, acc, cyc.payload, g, length_unit)
    links, links_gravity, links_task = link_forces(mech, design, options, cyc, traj, size, q, A, a_dot,
                                                   si_velocity_map(mech, A, length_unit), length_unit, label)
    return (qd, qdd, force + links, force_gravity + links_gravity, task_force + links_task, force_map, vel, acc)


def sample_dynamics(mech: Mechanism, design, options, cyc: ccfg.CycleConfig, length_unit: str, p: np.ndarray,
                    pd: np.ndarray, pdd: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The inverse dynamics of ``analyse`` at arbitrary task states: poses p (n, k) with velocities pd and
    accelerations pdd (task units per s, s^2) -> qd, qdd (n, nj; joint units per s, s^2), force and its gravity
    part (n, nj; N or N m). Design and options resolved; no workspace or branch checks (the caller's path has
    passed ``analyse``). Raises CycleError where a pose is out of reach."""
    design = mech.resolve_design(design)
    options = mech.resolve_options(options)
    p, pd, pdd = (np.asarray(v, dtype=float) for v in (p, pd, pdd))
    n = len(p)
    traj = trajectory.Trajectory(t=np.arange(n, dtype=float), p=p, pd=pd, pdd=pdd, segment=np.zeros(n, dtype=int),
                                 vertices=p[:1], vertex_times=np.zeros(1), law=("given",))
    label = mech.kernel_branch(options)
    kin = _kinematics_source(mech, design, options, label, False)
    q, A = kin(p)
    if not np.all(np.isfinite(q)):
        raise CycleError(f"cycle: {_where(mech, traj, int(np.argmin(np.all(np.isfinite(q), axis=1))))} is out of "
                         f"reach in working mode {label}")
    qd, qdd, force, force_gravity, *_ = _rates_and_forces(mech, design, options, cyc, length_unit, traj, kin, q,
                                                           A, label, _size(mech, design, options))
    return qd, qdd, force, force_gravity


def _motor_columns(mech, cyc, qd, qdd, force, force_gravity, length_unit) -> dict[str, np.ndarray]:
    """motor_speed and motor_torque (n, nj) with motors (dynamics.motors.motor_side), else {}."""
    from scalesynth.dynamics import motors as dm

    mot = dm.of_cycle(cyc, len(mech.joints))
    if mot is None:
        return {}
    js = dm.joint_si(mech.joint_units, length_unit)
    speed, g, a = dm.motor_side(mot, qd * js, qdd * js, force, force_gravity)
    return {"motor_speed": speed, "motor_torque": g + a}


def _clearance_along(mech: Mechanism, design, options, packed, poses: np.ndarray, q: np.ndarray,
                     reference: bool) -> np.ndarray:
    """Clearance (n,) at each sample: the field kernel's clearance slot (one compiled call for all samples) where
    the mechanism's kernel computes it under these options (Mechanism.kernel_clearance), else (and with
    ``reference``) cycle.clearance of link_geometry per sample."""
    if mech.kernel_clearance(options) and not reference:
        from scalesynth.kernels.grid import population_points_fields

        pts = np.pad(poses, ((0, 0), (0, 3 - poses.shape[1])))
        fields = population_points_fields(mech.field_kernel, mech.n_fields, packed[None, :], pts)[0]
        return fields[:, mech.field_names.index("clearance")]
    return np.array([clearance(mech.link_geometry(design, options, poses[s], q[s])).value
                     for s in range(len(poses))])


def _a_dot_xdot(kin, mech: Mechanism, traj, size) -> np.ndarray:
    """(dA/dt) x_dot per sample by a central difference of A along x_dot (IK re-solved in the branch, all
    moving samples in two calls of the kinematics source)."""
    n, k = traj.p.shape
    nj = len(mech.joints)
    out = np.zeros((n, nj))
    speed = np.linalg.norm(traj.pd, axis=1)
    moving = np.nonzero(speed > 0.0)[0]
    if not moving.size:
        return out
    v = traj.pd[moving]
    eps = _DERIV_STEP * size / speed[moving]  # a time step: the pose moves by _DERIV_STEP * size
    q_plus, a_plus = kin(traj.p[moving] + eps[:, None] * v)
    q_minus, a_minus = kin(traj.p[moving] - eps[:, None] * v)
    lost = ~(np.all(np.isfinite(q_plus), axis=1) & np.all(np.isfinite(q_minus), axis=1))
    if lost.any():
        raise CycleError(f"cycle: {_where(mech, traj, int(moving[np.argmax(lost)]))} lies on the boundary of the "
                         "workspace")
    vfull = np.zeros((len(moving), nj))
    vfull[:, :k] = v
    out[moving] = np.einsum("sij,sj->si", a_plus - a_minus, vfull) / (2.0 * eps[:, None])
    return out


def si_velocity_map(mech: Mechanism, A: np.ndarray, length_unit: str) -> np.ndarray:
    """A in SI units (m/s or rad/s both sides): rows of prismatic actuators and columns of Cartesian task axes
    scaled by metres per length unit. Columns past the task axes (held rotations) are rad/s already."""
    m = ccfg.METRES_PER_UNIT[length_unit]
    nj = A.shape[-1]
    row = np.array([m if u == "length" else 1.0 for u in mech.joint_units])
    col = np.ones(nj)
    col[: len(mech.task_units)] = [1.0 / m if u == "length" else 1.0 for u in mech.task_units]
    return A * row[:, None] * col[None, :]


def has_deflection(mech: Mechanism, options: Mapping[str, Any] | None = None) -> bool:
    """Whether the cycle analysis reports a deflection for ``mech`` (a per-voxel deflection field and a load) and,
    given ``options``, whether they switch the field on (its ``needs_options`` set: e.g. 2pauu-ppap's
    ``stiffness_metrics``; with them off the kernel writes no deflection)."""
    if not ("deflection" in mech.field_names and "load" in mech.option_names):
        return False
    return options is None or deflection_field(mech).enabled(options)


def deflection_field(mech: Mechanism):
    """The mechanism's ``deflection`` Field."""
    return mech.fields[mech.field_names.index("deflection")]


def deflection_along(mech: Mechanism, design, options, poses: np.ndarray, loads: np.ndarray) -> np.ndarray | None:
    """Deflection magnitude (length unit) of the platform at each pose (n, k) under its load (n, 2 or 3; N, the
    mechanism's load axes), from the field kernel's ``deflection`` slot with ``options['load']`` replaced per
    sample; None when the mechanism has no deflection field or the options leave it off."""
    if not has_deflection(mech, options):
        return None
    from scalesynth.kernels.paired import paired_points_fields

    loads = np.asarray(loads, dtype=float)
    params = _packed_with_loads(mech, design, options, loads)
    pts = np.pad(np.asarray(poses, dtype=float), ((0, 0), (0, 3 - poses.shape[1])))
    return paired_points_fields(mech.field_kernel, mech.n_fields, params, pts)[:, mech.field_names.index("deflection")]


def _packed_with_loads(mech: Mechanism, design, options, loads: np.ndarray) -> np.ndarray:
    """One packed vector per load (n, k_packed): the design packed once, the load's entries found by packing the
    unit loads (``load_slots``) and overwritten per row; a mechanism that packs its load otherwise is packed once
    per load."""
    zero, slots = load_slots(mech, design, options, loads.shape[1])
    if slots is None:
        return np.stack([mech.pack(design, {**options, "load": [float(v) for v in load]}) for load in loads])
    out = np.tile(zero, (len(loads), 1))
    out[:, slots] = loads
    return out


def load_slots(mech: Mechanism, design, options, dim: int) -> tuple[np.ndarray, list[int] | None]:
    """(the design packed under a zero load (k_packed,), the entry of each of the ``dim`` load axes): each unit
    load must set exactly one entry to 1, else the slots are None (the mechanism packs its load otherwise)."""
    def pack(load):
        return mech.pack(design, {**options, "load": [float(v) for v in load]})

    zero = pack(np.zeros(dim))
    slots = []
    for a in range(dim):
        unit = pack(np.eye(dim)[a])
        diff = np.nonzero(unit != zero)[0]
        if diff.size != 1 or unit[diff[0]] != 1.0 or zero[diff[0]] != 0.0:
            return zero, None
        slots.append(int(diff[0]))
    return zero, slots


def _payload_motion(mech, design, options, traj, size) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """The payload point's velocity and acceleration (n, 3) in the length unit per s (s^2) and its Jacobian
    J_c = dc/dx (n, 3, k; length unit per task unit) for a mechanism with an angular task axis; with Cartesian
    task axes the payload is the task point: (pd, pdd, None), exactly.

    J_c by central differences of ``payload_point`` along each task axis (step _DERIV_STEP times the size for a
    length axis, _DERIV_STEP rad for an angle); (d J_c/dt) x_dot = c''[x_dot, x_dot] by the second difference
    of c along x_dot with the pose moving by _SECOND_STEP (size or rad)."""
    if ccfg.cartesian_task(mech):
        return traj.pd, traj.pdd, None
    n, k = traj.p.shape
    scale = np.array([size if u == "length" else 1.0 for u in mech.task_units])
    x, v = traj.p, traj.pd
    steps = np.eye(k) * (_DERIV_STEP * scale)  # one row per task axis
    reach = np.max(np.abs(v) / scale, axis=1)
    eps = np.where(reach > 0.0, _SECOND_STEP / np.where(reach > 0.0, reach, 1.0), 0.0)  # the pose moves by
    # _SECOND_STEP of its scale along x_dot in the time step eps
    poses = np.concatenate([x[:, None, :] + steps[None], x[:, None, :] - steps[None],
                            np.stack([x + eps[:, None] * v, x, x - eps[:, None] * v], axis=1)], axis=1)
    c = mech.payload_points(design, options, poses.reshape(-1, k)).reshape(n, 2 * k + 3, 3)
    jc = np.transpose((c[:, :k] - c[:, k : 2 * k]) / (2.0 * _DERIV_STEP * scale)[None, :, None], (0, 2, 1))
    vel = np.einsum("nck,nk->nc", jc, v)
    acc = np.einsum("nck,nk->nc", jc, traj.pdd)
    moving = reach > 0.0
    second = c[:, 2 * k] - 2.0 * c[:, 2 * k + 1] + c[:, 2 * k + 2]
    acc[moving] += second[moving] / (eps[moving] ** 2)[:, None]
    return vel, acc, jc


def _forces(mech, A, jc, acc, mass, g, length_unit) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Actuator forces (n, n_joints), their gravity part (n, n_joints), the generalised payload force F on the
    task axes (n, k) and the map from F to the forces (n, n_joints, k), SI. F = m (a - g) with Cartesian task
    axes (``jc`` None), else J_c^T m (c_ddot - g) with J_c in metres per task unit."""
    m_per_unit = ccfg.METRES_PER_UNIT[length_unit]
    cart = mass * (acc * m_per_unit - g[None, :])  # the force the payload needs, payload axes (N)
    weight = np.broadcast_to(-mass * g, cart.shape)
    if jc is None:
        F, F_g = cart, weight
    else:
        # m per task unit: mm/mm columns are m/m already, mm/rad columns scale to m/rad
        jc_si = jc * np.array([1.0 if u == "length" else m_per_unit for u in mech.task_units])
        F = np.einsum("nck,nc->nk", jc_si, cart)
        F_g = np.einsum("nck,nc->nk", jc_si, weight)
    k = F.shape[1]
    A_si = si_velocity_map(mech, A, length_unit)
    force_map = np.linalg.inv(np.transpose(A_si, (0, 2, 1)))[:, :, :k]
    return (np.einsum("nik,nk->ni", force_map, F), np.einsum("nik,nk->ni", force_map, F_g), np.asarray(F),
            force_map)


# ----- design-level metrics (catalogue: cycle_*) ------------------------------------------------------------
CYCLE_PENALTY = 1e12  # a speed/acceleration/force no actuator reaches: the value of an infeasible cycle
METRICS = ccfg.CYCLE_METRICS


def max_rate_scale(res: CycleResult, speed_limits, force_limits) -> float:
    """Largest factor k on the cycle rate that keeps |k qd_i| <= speed limit and |tau_g + k^2 tau_a| <= force
    limit at every sample, where tau_a is the inertial and tau_g the gravity part of the forces (tau is linear
    in F = m a - m g and a scales with k^2). inf without limits; 0 if gravity alone exceeds a force limit."""
    k2 = np.inf
    if speed_limits is not None:
        peak = np.max(np.abs(res.qd), axis=0)
        with np.errstate(divide="ignore"):
            k2 = min(k2, float(np.min((speed_limits / peak) ** 2)))
    if force_limits is not None:
        tau_g = res.force_gravity
        tau_a = res.force - tau_g
        if np.any(np.abs(tau_g) > force_limits):
            return 0.0
        with np.errstate(divide="ignore", invalid="ignore"):
            bound = np.where(tau_a > 0, (force_limits - tau_g) / tau_a,
                             np.where(tau_a < 0, (force_limits + tau_g) / -tau_a, np.inf))
        k2 = min(k2, float(np.min(bound)))
    return float(np.sqrt(k2))


def metrics(mech: Mechanism, design, options, cyc: ccfg.CycleConfig, length_unit: str) -> dict[str, float]:
    """The cycle catalogue metrics of one design; never raises for a cycle that cannot be followed.

    cycle_feasible: 1 when every sample is reachable without a branch jump or singularity, the clearance is
    >= 0 and (with limits) the actuator speeds and forces stay within them, else 0.
    cycle_max_actuator_speed / _accel / _force: the largest |qd_i|, |qdd_i|, |force_i| over the cycle and the
    actuators (length unit or rad per s, per s^2; N or N m); with revolute and prismatic actuators one of each
    per kind (``_revolute``, ``_prismatic``), never a maximum over both units.
    cycle_min_lci, cycle_min_clearance (length unit; < 0 interference). max_cycles_per_minute: the configured
    rate times max_rate_scale (only with speed or force limits). A cycle that cannot be followed gives feasible 0,
    speed, acceleration and force CYCLE_PENALTY, LCI 0, clearance -CYCLE_PENALTY and 0 cycles per minute."""
    try:
        res = analyse(mech, design, options, cyc, length_unit)
    except ScalesynthError:  # CycleError, or a degenerate design's kinematics refusing a pose
        return failed_metrics(mech, options, cyc)
    return result_metrics(res, cyc)


def actuator_peaks(joint_units, qd: np.ndarray, qdd: np.ndarray, force: np.ndarray) -> dict[str, np.ndarray]:
    """The actuator peak metrics (``cycle.config.peak_names``) of D designs: qd, qdd, force (D, n, n_joints) ->
    name -> (D,), the largest |value| over the samples and the actuators of the metric's kind."""
    units = np.asarray(joint_units)
    values = {"speed": qd, "accel": qdd, "force": force}
    out = {}
    for name, kinds in ccfg.peak_names(joint_units).items():
        mask = np.isin(units, kinds)
        out[name] = np.max(np.abs(values[name.split("_")[3]][..., mask]), axis=(1, 2))
    return out


def failed_metrics(mech: Mechanism, options, cyc: ccfg.CycleConfig) -> dict[str, float]:
    """The catalogue metrics of a cycle that cannot be followed (see ``metrics``)."""
    bad = {"cycle_feasible": 0.0, **dict.fromkeys(ccfg.peak_names(mech.joint_units), CYCLE_PENALTY),
           "cycle_min_lci": 0.0, "cycle_min_clearance": -CYCLE_PENALTY}
    if has_deflection(mech, options):
        bad["cycle_max_deflection"] = CYCLE_PENALTY
    if cyc.speed_limits is not None or cyc.force_limits is not None:
        bad["max_cycles_per_minute"] = 0.0
    if getattr(cyc, "_motors", None) is not None:
        from scalesynth.dynamics.motors import failed_motor_metrics

        bad.update(failed_motor_metrics())
    return bad


def result_metrics(res: CycleResult, cyc: ccfg.CycleConfig) -> dict[str, float]:
    """The catalogue metrics (see ``metrics``) of an analysed, followable cycle."""
    n = len(res.joints)
    speed = ccfg.limit_vector(cyc.speed_limits, n)
    force = ccfg.limit_vector(cyc.force_limits, n)
    scale = max_rate_scale(res, speed, force)
    ok = bool(np.min(res.clearance) >= 0.0 and scale >= 1.0)
    out = {
        "cycle_feasible": float(ok),
        **{k: float(v[0]) for k, v in actuator_peaks(res.joint_units, res.qd[None], res.qdd[None],
                                                      res.force[None]).items()},
        "cycle_min_lci": float(np.min(res.lci)),
        "cycle_min_clearance": float(min(np.min(res.clearance), CYCLE_PENALTY)),
    }
    if res.deflection is not None:
        out["cycle_max_deflection"] = float(min(np.max(res.deflection), CYCLE_PENALTY))
    if speed is not None or force is not None:
        out["max_cycles_per_minute"] = 60.0 / cyc.cycle_time * scale
    out.update(motor_metrics(res, cyc)[0])
    return out


def motor_metrics(res: CycleResult, cyc: ccfg.CycleConfig) -> tuple[dict[str, float], str | None]:
    """The motor metrics of an analysed cycle (``dynamics.motors``) and the limit that binds its rate; ({}, None)
    without motors."""
    from scalesynth.dynamics import motors as dm

    mot = dm.of_cycle(cyc, len(res.joints))
    if mot is None:
        return {}, None
    vals, binding = dm.cycle_motor_metrics(mot, res.traj, cyc, res.joint_units, res.length_unit, res.qd[None],
                                           res.qdd[None], res.force[None], res.force_gravity[None])
    return {k: float(v[0]) for k, v in vals.items()}, str(binding[0])
