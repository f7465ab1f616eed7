"""The cycle metrics of a whole population at once (the optimiser's path): ``analysis.metrics`` of every design,
with the design-independent work done once and the per-design work batched.

Shared by the population: the options resolved, the trajectory built and the vertex and sample points padded
once. Per design (a short Python loop): resolve, pack, one LCI call at the vertices and samples together, the
size. Batched over the designs that stay in the workspace: the kinematics (``population_cycle_kinematics``, one
NumPy pass over designs x samples for the five-bar, a loop over ``cycle_kinematics`` elsewhere), the branch,
singularity and boundary checks, rates, forces, one clearance kernel call and one deflection kernel call.

Each step is the one ``analysis.analyse`` takes, element for element; a design fails here exactly when analyse
raises for it (every failure gives the same ``failed_metrics``). tests/test_cycle.py holds the result to
``analysis.metrics`` per design for every mechanism. Not re-done here: the segment pair at the minimum
clearance (``CycleResult.min_clearance_pair``; no metric uses it).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from types import SimpleNamespace
from typing import Any

import numpy as np

from scalesynth.cycle import analysis, trajectory
from scalesynth.cycle import config as ccfg
from scalesynth.dynamics import motors
from scalesynth.dynamics.inverse import link_forces
from scalesynth.errors import ScalesynthError
from scalesynth.mechanisms.base import Mechanism, wrap_angle


def population_metrics(mech: Mechanism, designs: Sequence[Mapping[str, float]], options: Mapping[str, Any],
                       cyc: ccfg.CycleConfig, length_unit: str) -> dict[str, np.ndarray]:
    """Every cycle catalogue metric (``analysis.METRICS``) of every design: name -> (n_designs,), 0.0 where a
    metric does not apply (as ``metrics`` leaves it out)."""
    try:
        opts = mech.resolve_options(options)
    except ScalesynthError:  # every design fails alike; metrics() says how
        return _stack([analysis.metrics(mech, d, options, cyc, length_unit) for d in designs])
    rows: list[dict[str, float] | None] = [None] * len(designs)
    failed = analysis.failed_metrics(mech, opts, cyc)
    for i, row in _followed(mech, designs, opts, cyc, length_unit).items():
        rows[i] = row
    return _stack([failed if row is None else row for row in rows])


def _stack(rows: list[dict[str, float]]) -> dict[str, np.ndarray]:
    return {k: np.array([r.get(k, 0.0) for r in rows], dtype=float) for k in analysis.METRICS}


def _kinematics(mech: Mechanism, designs, options, poses: np.ndarray, label: str):
    """population_cycle_kinematics at poses (D, n, k) -> (q, A, refused (D,) bool): a design whose kinematics
    raise (a degenerate design) is refused alone (NaN rows), as analyse would raise for it."""
    try:
        q, a = mech.population_cycle_kinematics(designs, options, poses, label)
        return q, a, np.zeros(len(designs), dtype=bool)
    except ScalesynthError:
        nj = len(mech.joints)
        q = np.full((len(designs), poses.shape[1], nj), np.nan)
        a = np.full((len(designs), poses.shape[1], nj, nj), np.nan)
        refused = np.zeros(len(designs), dtype=bool)
        for i, (d, p) in enumerate(zip(designs, poses, strict=True)):
            try:
                q[i], a[i] = mech.cycle_kinematics(d, options, p, label)
            except ScalesynthError:
                refused[i] = True
        return q, a, refused


def _followed(mech: Mechanism, designs, options, cyc: ccfg.CycleConfig, length_unit: str) -> dict[int, dict]:
    """{design index: metrics} for the designs whose cycle can be followed (the others are left out)."""
    from scalesynth.kernels.grid import points_lci

    verts = ccfg.vertices(cyc, mech, length_unit)
    traj = trajectory.build(verts, cyc.law, cyc.cycle_time, cyc.samples)
    n, k = traj.p.shape
    nj = len(mech.joints)
    nv = len(verts)
    pts = np.zeros((nv + n, 3))  # the vertices, then the samples (analyse pads both to 3 columns)
    pts[:nv, :k] = verts
    pts[nv:, :k] = traj.p
    # per design: resolve, pack, LCI at the vertices and samples; outside the workspace (a vertex, or a sample
    # not strictly inside: analyse refuses LCI <= 0 as singular) the design fails here
    live, resolved, packed, lcis, sizes = [], [], [], [], []
    for i, d in enumerate(designs):
        try:
            rd = mech.resolve_design(d)
            p = mech.pack(rd, options)
            lci = points_lci(mech.point_kernel, p, pts)
            size = analysis._size(mech, rd, options)
        except ScalesynthError:
            continue
        if np.any(lci[:nv] < 0) or np.any(lci[nv:] <= 0):
            continue
        live.append(i)
        resolved.append(rd)
        packed.append(p)
        lcis.append(lci[nv:])
        sizes.append(size)
    if not live:
        return {}
    live = np.array(live)
    packed, lci, size = np.array(packed), np.array(lcis), np.array(sizes)
    label = mech.kernel_branch(options)
    angular = np.array([u == "angle" for u in mech.joint_units])

    # the kinematics at the samples; reach, branch continuity and singularities (analyse's checks, batched)
    q_raw, A, refused = _kinematics(mech, resolved, options, np.broadcast_to(traj.p, (len(live), n, k)), label)
    ok = ~refused & np.all(np.isfinite(q_raw), axis=(1, 2))
    q = np.where(np.isfinite(q_raw), q_raw, 0.0)
    if np.any(angular) and n > 1:
        steps = wrap_angle(np.diff(q[:, :, angular], axis=1))
        q[:, 1:, angular] = q[:, :1, angular] + np.cumsum(steps, axis=1)
    joint_scale = np.where(angular[None, :], size[:, None], 1.0)[:, None, :]  # (D, 1, nj)
    with np.errstate(invalid="ignore", over="ignore"):
        if n > 1:
            dx = np.zeros((n - 1, nj))
            dx[:, :k] = np.diff(traj.p, axis=0)
            predicted = np.einsum("dsij,sj->dsi", 0.5 * (A[:, 1:] + A[:, :-1]), dx)
            miss = np.linalg.norm((np.diff(q, axis=1) - predicted) * joint_scale, axis=2)
            finite = np.all(np.isfinite(A[:, 1:]), axis=(2, 3)) & np.all(np.isfinite(A[:, :-1]), axis=(2, 3))
            jumps = finite & (miss > 0.5 * np.linalg.norm(predicted * joint_scale, axis=2) + 1e-9 * size[:, None])
            ok &= ~np.any(jumps, axis=1)
        det = np.where(ok[:, None], np.linalg.det(np.where(ok[:, None, None, None], A, 0.0)), np.nan)
    sign = np.sign(det)
    ok &= np.all(np.isfinite(det) & (sign != 0), axis=1) & np.all(sign[:, 1:] == sign[:, :-1], axis=1)
    keep = np.nonzero(ok)[0]
    live, packed, lci, size, q, A = live[keep], packed[keep], lci[keep], size[keep], q[keep], A[keep]
    resolved = [resolved[j] for j in keep]

    # rates: qd = A x_dot, qdd = A x_ddot + (dA/dt) x_dot (central difference of A along x_dot, as _a_dot_xdot)
    pd_full = np.zeros((n, nj))
    pd_full[:, :k] = traj.pd
    pdd_full = np.zeros((n, nj))
    pdd_full[:, :k] = traj.pdd
    qd = np.einsum("dnij,nj->dni", A, pd_full)
    a_dot = np.zeros((len(live), n, nj))
    speed = np.linalg.norm(traj.pd, axis=1)
    moving = np.nonzero(speed > 0.0)[0]
    if moving.size and len(live):
        v = traj.pd[moving]
        eps = analysis._DERIV_STEP * size[:, None] / speed[moving]  # (D, m) time steps
        q_plus, a_plus, r_plus = _kinematics(mech, resolved, options, traj.p[moving] + eps[..., None] * v, label)
        q_minus, a_minus, r_minus = _kinematics(mech, resolved, options, traj.p[moving] - eps[..., None] * v, label)
        lost = ~(np.all(np.isfinite(q_plus), axis=2) & np.all(np.isfinite(q_minus), axis=2))
        ok = ~(r_plus | r_minus | np.any(lost, axis=1))  # a sample on the boundary of the workspace
        vfull = np.zeros((len(moving), nj))
        vfull[:, :k] = v
        with np.errstate(invalid="ignore"):
            a_dot[:, moving] = np.einsum("dsij,sj->dsi", a_plus - a_minus, vfull) / (2.0 * eps[..., None])
    else:
        ok = np.ones(len(live), dtype=bool)
    qdd = np.einsum("dnij,nj->dni", A, pdd_full) + a_dot

    # payload motion, forces, clearance and deflection
    g = ccfg.gravity_vector(cyc, mech)
    if ccfg.cartesian_task(mech):
        acc = np.broadcast_to(traj.pdd, (len(live), n, k))
        jc = None
    else:
        acc = np.zeros((len(live), n, 3))
        jc = [None] * len(live)
        for j, d in enumerate(resolved):
            try:
                _, acc[j], jc[j] = analysis._payload_motion(mech, d, options, traj, size[j])
            except ScalesynthError:
                ok[j] = False
    keep = np.nonzero(ok)[0]
    live, packed, lci, q, A, a_dot, qd, qdd, acc, size = (live[keep], packed[keep], lci[keep], q[keep], A[keep],
                                                          a_dot[keep], qd[keep], qdd[keep], acc[keep], size[keep])
    jc = None if jc is None else [jc[j] for j in keep]
    resolved = [resolved[j] for j in keep]
    if not len(live):
        return {}
    nd = len(live)
    if jc is None:  # Cartesian task axes: one call over designs x samples
        force, force_gravity, _, _ = analysis._forces(mech, A.reshape(nd * n, nj, nj), None,
                                                      acc.reshape(nd * n, k), cyc.payload, g, length_unit)
        force, force_gravity = force.reshape(nd, n, nj), force_gravity.reshape(nd, n, nj)
    else:  # per design: J_c's memory layout as analyse has it, so that einsum sums in the same order
        per = [analysis._forces(mech, A[j], jc[j], acc[j], cyc.payload, g, length_unit) for j in range(nd)]
        force, force_gravity = np.array([f[0] for f in per]), np.array([f[1] for f in per])
    # the links' inertia and weight (dynamics.inverse, per design), added as analyse adds them
    ok = np.ones(nd, dtype=bool)
    for j in range(nd):
        try:
            links, links_g, _ = link_forces(mech, resolved[j], options, cyc, traj, size[j], q[j], A[j], a_dot[j],
                                            analysis.si_velocity_map(mech, A[j], length_unit), length_unit, label)
        except ScalesynthError:
            ok[j] = False
            continue
        force[j] += links
        force_gravity[j] += links_g
    if not ok.all():
        keep = np.nonzero(ok)[0]
        live, packed, lci, q, A, qd, qdd, acc, force, force_gravity = (
            live[keep], packed[keep], lci[keep], q[keep], A[keep], qd[keep], qdd[keep], acc[keep], force[keep],
            force_gravity[keep])
        resolved = [resolved[j] for j in keep]
        nd = len(live)
        if not nd:
            return {}
    gaps = _clearance(mech, resolved, options, packed, traj.p, q)
    deflection = _deflection(mech, resolved, options, packed, traj.p,
                             cyc.payload * (g[None, None, :] - acc * ccfg.METRES_PER_UNIT[length_unit]))

    # the metrics (analysis.result_metrics per design; max and min are exact, so batched reductions agree)
    speed_lim = ccfg.limit_vector(cyc.speed_limits, nj)
    force_lim = ccfg.limit_vector(cyc.force_limits, nj)
    limited = speed_lim is not None or force_lim is not None
    scale = np.full(nd, np.inf)  # max_rate_scale without limits
    if limited:
        scale = np.array([analysis.max_rate_scale(SimpleNamespace(qd=qd[j], force=force[j],
                                                                  force_gravity=force_gravity[j]), speed_lim, force_lim)
                          for j in range(nd)])
    min_gap = np.min(gaps, axis=1)
    cols = {
        "cycle_feasible": ((min_gap >= 0.0) & (scale >= 1.0)).astype(float),
        **analysis.actuator_peaks(mech.joint_units, qd, qdd, force),
        "cycle_min_lci": np.min(lci, axis=1),
        "cycle_min_clearance": np.minimum(min_gap, analysis.CYCLE_PENALTY),
    }
    if deflection is not None:
        cols["cycle_max_deflection"] = np.minimum(np.max(deflection, axis=1), analysis.CYCLE_PENALTY)
    if limited:
        cols["max_cycles_per_minute"] = 60.0 / cyc.cycle_time * scale
    mot = motors.of_cycle(cyc, nj)
    ratios = getattr(cyc, "_gear_ratios", None)
    if mot is not None and ratios is not None:  # each design's own (shared) gear ratio, (D, 1, nj)
        mot = replace(mot, gear_ratio=np.broadcast_to(np.asarray(ratios, dtype=float)[live][:, None, None],
                                                      (nd, 1, nj)))
    if mot is not None:
        cols.update(motors.cycle_motor_metrics(mot, traj, cyc, mech.joint_units, length_unit, qd, qdd, force,
                                               force_gravity)[0])
    return {int(i): {name: float(col[j]) for name, col in cols.items()} for j, i in enumerate(live)}


def _clearance(mech: Mechanism, designs, options, packed: np.ndarray, poses: np.ndarray, q: np.ndarray):
    """Clearance (D, n) of every design at every sample: one field-kernel call for all designs where the
    mechanism's kernel computes the clearance under these options (Mechanism.kernel_clearance), else
    analysis._clearance_along per design."""
    if not mech.kernel_clearance(options):
        return np.array([analysis._clearance_along(mech, d, options, p, poses, qd, False)
                         for d, p, qd in zip(designs, packed, q, strict=True)])
    from scalesynth.kernels.grid import population_points_fields

    pts = np.zeros((len(poses), 3))
    pts[:, : poses.shape[1]] = poses
    fields = population_points_fields(mech.field_kernel, mech.n_fields, packed, pts)
    return fields[:, :, mech.field_names.index("clearance")]


def _deflection(mech: Mechanism, designs, options, packed: np.ndarray, poses: np.ndarray, loads: np.ndarray):
    """analysis.deflection_along of every design (D, n) under its loads (D, n, dim) in one kernel call, or None
    where the mechanism has no deflection. The load slots are found once (on the first design) where the design's
    packed vector with its load slots zeroed is its zero-load packing; else each design re-packs its loads."""
    if not analysis.has_deflection(mech, options):
        return None
    from scalesynth.kernels.paired import paired_points_fields

    nd, n, dim = loads.shape
    zero, slots = analysis.load_slots(mech, designs[0], options, dim)
    if slots is not None:
        check = packed[0].copy()
        check[slots] = 0.0
        slots = slots if np.array_equal(check, zero) else None
    if slots is None:
        params = np.concatenate([analysis._packed_with_loads(mech, d, options, f)
                                 for d, f in zip(designs, loads, strict=True)])
    else:
        params = np.repeat(packed, n, axis=0)
        params[:, slots] = loads.reshape(nd * n, dim)
    pts = np.zeros((nd * n, 3))
    pts[:, : poses.shape[1]] = np.tile(poses, (nd, 1))
    fields = paired_points_fields(mech.field_kernel, mech.n_fields, params, pts)
    return fields[:, mech.field_names.index("deflection")].reshape(nd, n)
