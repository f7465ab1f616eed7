"""The time-optimal motion along a cycle's path under the motors' peak torque and speed (toppra).

The cycle's path is a closed polyline in task axes; at each vertex the direction jumps, so any motion with finite
acceleration stops there: the time-optimal cycle is the sum of time-optimal rest-to-rest moves along each straight
segment x(s) = v_k + s (v_k+1 - v_k), s in [0, 1]. Along a segment x' = v_k+1 - v_k and x'' = 0, so with the path
velocity s_d and acceleration s_dd the task velocity is x' s_d and the acceleration x' s_dd: the inverse dynamics
(links, payload, gravity; ``cycle.analysis.sample_dynamics``) and the motor torque tau_m = (tau + J_r n^2 qdd) / n
are linear in (s_dd, s_d^2, 1),

    tau_m(s) = a(s) s_dd + b(s) s_d^2 + c(s),        motor speed w(s) = w'(s) s_d,

and the coefficient arrays come from three evaluations per grid point: (s_d, s_dd) = (0, 0) gives c, (0, 1) gives
a + c and (1, 0) gives b + c (the motor speed w'). toppra (Pham and Pham's TOPP-RA: reachability analysis on a
grid, the seidel solver) then finds the fastest s_d(s) with |tau_m| <= peak_torque and |w| <= max_speed at every
grid point (collocation). The rated (RMS) torque is not a constraint here (an integral over the cycle, outside
TOPP-RA's form): the RMS of the optimal motion is reported beside it. The cycle time is the sum of the segments'
times plus 2 dwell_s. A design whose motors cannot hold the payload somewhere on the path (|c| > peak_torque), or a
path toppra cannot parameterise, is data: picks 0 and the binding limit named.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from scalesynth.dynamics import motors as dm

EVAL_INTERVALS = 48  # per segment: where the inverse dynamics is evaluated (the coefficients are smooth in s)
GRID_INTERVALS = 240  # per segment: toppra's collocation grid, the coefficients splined onto it


@dataclass(frozen=True)
class PathCoefficients:
    """Motor torque and speed along one straight segment (grid of N + 1 points s in [0, 1]):
    tau_m = a s_dd + b s_d^2 + c (N m, (N + 1, nj) each), motor speed = w s_d (rad/s per unit s_d, (N + 1, nj))."""

    s: np.ndarray
    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    w: np.ndarray


@dataclass(frozen=True)
class OptimalCycle:
    """The time-optimal cycle: cycle_time_s (motion + dwell; CYCLE_TIME_PENALTY when infeasible),
    picks_per_minute (0 when infeasible), segment_times_s, binding (the limits active somewhere on the optimal
    motion, or why it is infeasible), rms_torque_ratio (RMS motor torque over the motion and the dwell / rated
    torque, largest actuator; None when infeasible), and per segment the grid s, path velocity sd and the
    interval accelerations sdd."""

    cycle_time_s: float
    picks_per_minute: float
    segment_times_s: list[float]
    binding: str
    rms_torque_ratio: float | None
    profiles: list[tuple[np.ndarray, np.ndarray, np.ndarray]]

    def summary(self) -> dict:
        return {"time_optimal_cycle_time_s": self.cycle_time_s,
                "time_optimal_picks_per_minute": self.picks_per_minute,
                "time_optimal_binding_limit": self.binding,
                "time_optimal_rms_torque_ratio": self.rms_torque_ratio,
                "time_optimal_segment_times_s": self.segment_times_s}


def sampled_coefficients(mech, design, options, cyc, length_unit: str, motors: dm.Motors, vertices: np.ndarray,
                         intervals: int = EVAL_INTERVALS) -> list[PathCoefficients]:
    """PathCoefficients of every segment of the closed polyline through ``vertices`` (m, k; the first repeated at
    the end or not) at ``intervals + 1`` evenly spaced s, from the cycle's inverse dynamics: (s_d, s_dd) = (0, 1)
    gives a + c with c its gravity part (the torque at rest), (1, 0) gives b + c and the motor speed w (all segments
    and both evaluations in one call)."""
    from scalesynth.cycle.analysis import sample_dynamics
    from scalesynth.cycle.trajectory import close

    verts = close(vertices)
    steps = np.diff(verts, axis=0)
    keep = np.linalg.norm(steps, axis=1) > 0  # zero-length segments dropped, as in cycle.trajectory.build
    starts, steps = verts[:-1][keep], steps[keep]
    s = np.linspace(0.0, 1.0, intervals + 1)
    m, k = steps.shape
    p = (starts[:, None, :] + s[None, :, None] * steps[:, None, :]).reshape(-1, k)
    d = np.repeat(steps, len(s), axis=0)
    zero = np.zeros_like(p)
    qd, qdd, force, force_gravity = sample_dynamics(mech, design, options, cyc, length_unit, np.tile(p, (2, 1)),
                                                    np.concatenate([zero, d]), np.concatenate([d, zero]))
    js = dm.joint_si(mech.joint_units, length_unit)
    speed, g, a = dm.motor_side(motors, qd * js, qdd * js, force, force_gravity)
    tau = (g + a).reshape(2, m, len(s), -1)
    c = g.reshape(2, m, len(s), -1)[0]
    speed = speed.reshape(2, m, len(s), -1)
    return [PathCoefficients(s=s, a=tau[0, i] - c[i], b=tau[1, i] - c[i], c=c[i], w=speed[1, i]) for i in range(m)]


def refine(coef: PathCoefficients, intervals: int) -> PathCoefficients:
    """The coefficients on a finer even grid of ``intervals + 1`` points, each a cubic spline through the samples
    (they are smooth functions of s along a segment inside the workspace)."""
    from scipy.interpolate import CubicSpline

    s = np.linspace(0.0, 1.0, intervals + 1)
    return PathCoefficients(s, *(CubicSpline(coef.s, v, axis=0)(s) for v in (coef.a, coef.b, coef.c, coef.w)))


def combine(at0: list[PathCoefficients], at1: list[PathCoefficients], payload: float) -> list[PathCoefficients]:
    """Coefficients for any payload from those at payload 0 and 1 kg: the payload is a point mass, so the
    torques are affine in its mass (the motor speed does not depend on it)."""
    return [PathCoefficients(c0.s, *(v0 + payload * (v1 - v0) for v0, v1 in ((c0.a, c1.a), (c0.b, c1.b),
                                                                                (c0.c, c1.c))), c0.w)
            for c0, c1 in zip(at0, at1, strict=True)]


def speed_bound(coef: PathCoefficients, motors: dm.Motors) -> np.ndarray:
    """Largest s_d^2 (N + 1,) the motor speed limit allows at each grid point (inf where no motor moves)."""
    with np.errstate(divide="ignore"):
        return np.min(np.where(np.abs(coef.w) > 0, (motors.max_speed / np.abs(coef.w)) ** 2, np.inf), axis=1)


def _toppra_segment(coef: PathCoefficients, motors: dm.Motors):
    """toppra on one segment: (sd (N + 1,), sdd (N,)) or None when it finds no parameterisation."""
    import toppra
    from toppra.constraint import DiscretizationType, LinearConstraint
    from toppra.interpolator import AbstractGeometricPath

    nj = coef.a.shape[1]
    x_max = np.minimum(speed_bound(coef, motors), 1e30)

    class Segment(AbstractGeometricPath):  # the path itself is never evaluated: the constraint holds the numbers
        def __call__(self, path_positions, order=0):
            raise NotImplementedError

        @property
        def dof(self):
            return nj

        @property
        def path_interval(self):
            return np.array([0.0, 1.0])

    class MotorLimits(LinearConstraint):
        def __init__(self):
            super().__init__()
            self.identical = True
            self.dof = nj
            self.set_discretization_type(DiscretizationType.Collocation)
            self._format_string = "    motor peak torque and speed\n"

        def compute_constraint_params(self, path, gridpoints, *args, **kwargs):
            F = np.vstack([np.eye(nj), -np.eye(nj)])
            g = np.concatenate([motors.peak_torque, motors.peak_torque])
            xbound = np.column_stack([np.zeros(len(gridpoints)), x_max])
            return coef.a, coef.b, coef.c, F, g, None, xbound

    log = logging.getLogger("toppra")
    level = log.level
    log.setLevel(logging.CRITICAL)  # toppra logs a failed parameterisation as a warning: here it is data
    try:
        algo = toppra.algorithm.TOPPRA([MotorLimits()], Segment(), gridpoints=coef.s, solver_wrapper="seidel")
        sdd, sd, _ = algo.compute_parameterization(0.0, 0.0)
    finally:
        log.setLevel(level)
    if sd is None or not np.all(np.isfinite(sd)):
        return None
    return np.asarray(sd, dtype=float), np.asarray(sdd, dtype=float)


def segment_time(s: np.ndarray, sd: np.ndarray) -> float:
    """Time (s) to run the grid s at path velocities sd, constant path acceleration per interval:
    sum 2 ds / (sd_i + sd_i+1); inf where a whole interval is at rest."""
    den = sd[:-1] + sd[1:]
    if np.any(den <= 0):
        return math.inf
    return float(np.sum(2.0 * np.diff(s) / den))


def _active(coef: PathCoefficients, motors: dm.Motors, sd, sdd) -> set[str]:
    """The limits within 1 % of binding somewhere on the motion."""
    x = sd * sd
    u = np.append(sdd, sdd[-1])
    tau = coef.a * u[:, None] + coef.b * x[:, None] + coef.c
    out = set()
    if np.any(np.abs(tau) >= 0.99 * motors.peak_torque):
        out.add("peak_torque")
    if np.any(np.abs(coef.w) * sd[:, None] >= 0.99 * motors.max_speed):
        out.add("max_speed")
    return out


def time_optimal(coefs: list[PathCoefficients], motors: dm.Motors, dwell_s: float, place: int) -> OptimalCycle:
    """The time-optimal cycle from the segments' coefficients (``path_coefficients``); ``place`` the vertex index
    of the place position (the dwell's holding torque there and at the start)."""
    times, profiles, active = [], [], set()
    for coef in coefs:
        if np.any(np.abs(coef.c) > motors.peak_torque):
            return _infeasible("peak_torque (holding the payload)")
        found = _toppra_segment(coef, motors)
        if found is None:
            return _infeasible("toppra: no parameterisation within peak_torque and max_speed")
        sd, sdd = found
        t = segment_time(coef.s, sd)
        if not math.isfinite(t):
            return _infeasible("toppra: the path cannot be left at rest within peak_torque")
        times.append(t)
        profiles.append((coef.s, sd, sdd))
        active |= _active(coef, motors, sd, sdd)
    motion = float(sum(times))
    total = motion + 2.0 * dwell_s
    rms = _rms_ratio(coefs, profiles, motors, dwell_s, place)
    binding = " and ".join(sorted(active)) or "none"
    return OptimalCycle(total, 60.0 / total, times, binding, rms, profiles)


def _rms_ratio(coefs, profiles, motors: dm.Motors, dwell_s: float, place: int) -> float:
    """RMS motor torque over the optimal motion and the dwell at pick and place / rated torque (largest actuator):
    per interval the torque at its start (collocation) held for the interval's time."""
    num = np.zeros(len(motors.rated_torque))
    total = 0.0
    for coef, (s, sd, sdd) in zip(coefs, profiles, strict=True):
        dt = 2.0 * np.diff(s) / (sd[:-1] + sd[1:])
        tau = coef.a[:-1] * sdd[:, None] + coef.b[:-1] * (sd[:-1] ** 2)[:, None] + coef.c[:-1]
        num += np.einsum("ij,i->j", tau * tau, dt)
        total += float(dt.sum())
    for vertex in (0, place):
        hold = coefs[vertex % len(coefs)].c[0]
        num += hold * hold * dwell_s
        total += dwell_s
    return float(np.max(np.sqrt(num / total) / motors.rated_torque))


def _infeasible(why: str) -> OptimalCycle:
    return OptimalCycle(dm.CYCLE_TIME_PENALTY, 0.0, [], why, None, [])


def of_design(mech, design, options, cyc, length_unit: str, payloads=None) -> list[OptimalCycle] | None:
    """The time-optimal cycle of one design at each payload (kg; default the cycle's own), None without motors.
    The path must have passed ``analyse``. One inverse-dynamics evaluation for the cycle's payload alone, two
    (payloads 0 and 1 kg, combined) for several."""
    from scalesynth.cycle import config as ccfg

    motors = dm.of_cycle(cyc, len(mech.joints))
    if motors is None:
        return None
    verts = ccfg.vertices(cyc, mech, length_unit)
    place = dm.place_vertex(verts, cyc.preset)

    def coefficients(payload: float) -> list[PathCoefficients]:
        sampled = sampled_coefficients(mech, design, options, cyc.model_copy(update={"payload": payload}),
                                       length_unit, motors, verts)
        return [refine(c, GRID_INTERVALS) for c in sampled]

    payloads = [cyc.payload] if payloads is None else list(payloads)
    if len(payloads) == 1:
        return [time_optimal(coefficients(payloads[0]), motors, cyc.dwell_s, place)]
    at0, at1 = coefficients(0.0), coefficients(1.0)
    return [time_optimal(combine(at0, at1, m), motors, cyc.dwell_s, place) for m in payloads]
