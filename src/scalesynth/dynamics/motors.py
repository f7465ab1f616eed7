"""Motors and gears of the actuators, the motor-side view of a cycle and the shortest cycle time.

Per actuator i with gear ratio n_i (motor speed / joint speed; a prismatic actuator's n is rad of motor per m of
travel, e.g. 2 pi / lead of a ball screw) and a motor of rotor inertia J_r:
motor speed w = n qd, motor torque tau_m = (tau + J_r n^2 qdd) / n, tau the joint torque (force) of the links,
payload and gravity (cycle.csv's force<i>). With the motion law fixed and its period scaled by 1/s (s > 1
faster), qd scales with s and the inertial part of tau_m with s^2 (the torque = tau_g/n + s^2 tau_a, gravity's
part tau_g unchanged), so the limits |w| <= max_speed, |tau_m| <= peak_torque (every sample) and
RMS(tau_m) <= rated_torque (over the motion and the dwell at pick and place, where the motor holds the payload
still) bound s: the speed and peak limits in closed form, the RMS limit by bisection (vectorised over designs).
The cycle time is T0 / s + 2 dwell_s (T0 the cycle's configured period); picks per minute 60 / cycle time.
A design whose motors cannot hold the payload at rest (gravity alone over the peak torque, or its RMS over the
rated torque) gets picks_per_minute 0 and the binding limit named.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from scalesynth.dynamics.config import MOTOR_RATINGS, MotorsConfig
from scalesynth.errors import ConfigError
from scalesynth.names import hint

BUILTIN = "builtin"
_BISECTION_STEPS = 60
LIMITS = ("max_speed", "peak_torque", "rated_torque")


@dataclass(frozen=True)
class Motors:
    """Resolved motors, one value per actuator (n_joints,): ratings at the motor shaft and gear ratios."""

    peak_torque: np.ndarray
    rated_torque: np.ndarray
    max_speed: np.ndarray
    rotor_inertia: np.ndarray
    gear_ratio: np.ndarray
    model: str | None = None


def builtin_catalogue() -> Path:
    """The shipped catalogue CSV (scalesynth/dynamics/data/motors.csv)."""
    return Path(str(resources.files("scalesynth.dynamics") / "data" / "motors.csv"))


def read_catalogue(path: Path) -> dict[str, dict[str, float]]:
    """model -> ratings of a catalogue CSV (columns model, peak_torque, rated_torque, max_speed, rotor_inertia; any
    others, e.g. source, ignored). ConfigError, one line, for a missing or malformed file or a bad rating."""
    where = f"motors.catalogue: {path}"
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ConfigError(f"{where}: no such file") from None
    except (OSError, UnicodeDecodeError) as err:
        raise ConfigError(f"{where}: cannot read it ({type(err).__name__})") from None
    rows = list(csv.DictReader(text.splitlines()))
    need = ("model", *MOTOR_RATINGS)
    if not rows or any(c not in rows[0] for c in need):
        missing = next((c for c in need if not rows or c not in rows[0]), "model")
        raise ConfigError(f"{where}: malformed (need a header with {', '.join(need)}; {missing!r} is missing)")
    out = {}
    for i, row in enumerate(rows, start=2):
        ratings = {}
        for c in MOTOR_RATINGS:
            try:
                v = float(row[c])
            except (TypeError, ValueError):
                raise ConfigError(f"{where}: line {i}, {c}: not a number ({row[c]!r})") from None
            if not math.isfinite(v) or v < 0 or (v == 0 and c != "rotor_inertia"):
                raise ConfigError(f"{where}: line {i}, {c}: must be finite and > 0"
                                  f"{' (>= 0 for rotor_inertia)' if c == 'rotor_inertia' else ''}, got {row[c]!r}")
            ratings[c] = v
        out[str(row["model"]).strip()] = ratings
    return out


def resolve(cfg: MotorsConfig, n_joints: int, base_dir: Path | None = None) -> Motors:
    """Motors per actuator from the config (inline or a catalogue row); ConfigError naming the field."""
    ratio = cfg.gear_ratio
    if isinstance(ratio, list) and len(ratio) != n_joints:
        raise ConfigError(f"motors.gear_ratio: need one number or {n_joints} (one per actuator)")
    ratios = np.full(n_joints, float(ratio)) if isinstance(ratio, (int, float)) else np.asarray(ratio, dtype=float)
    if cfg.catalogue is not None:
        if cfg.catalogue == BUILTIN:
            path = builtin_catalogue()
        else:
            path = Path(cfg.catalogue).expanduser()
            if not path.is_absolute() and base_dir is not None:
                path = Path(base_dir) / path
        table = read_catalogue(path)
        if cfg.model not in table:
            raise ConfigError(f"motors.model: {cfg.model!r} is not in {path.name} " + hint(str(cfg.model), table))
        row = table[cfg.model]
    else:
        row = {c: getattr(cfg, c) for c in MOTOR_RATINGS}
    return Motors(*(np.full(n_joints, float(row[c])) for c in ("peak_torque", "rated_torque", "max_speed",
                                                               "rotor_inertia")), ratios, cfg.model)


def joint_si(joint_units, length_unit: str) -> np.ndarray:
    """Metres (or 1 for angles) per joint unit, (n_joints,)."""
    from scalesynth.cycle.config import METRES_PER_UNIT

    return np.array([METRES_PER_UNIT[length_unit] if u == "length" else 1.0 for u in joint_units])


def motor_side(motors: Motors, qd_si, qdd_si, force, force_gravity):
    """Motor speed w (..., n, nj) rad/s, the gravity part g and the inertial part a of the motor torque
    (..., n, nj) N m at the configured rate: tau_m = g + a."""
    n = motors.gear_ratio
    speed = qd_si * n
    g = force_gravity / n
    a = (force - force_gravity) / n + motors.rotor_inertia * n * qdd_si
    return speed, g, a


def mean_square_torque(g, a, w, s, dwell_total, g_rest2):
    """Mean square motor torque (..., nj) over one cycle at rate factor s (...,): the motion (period T0 / s; w the
    samples' time weights summing to 1) and the dwell at rest (dwell_total s, mean square holding torque
    g_rest2 (..., nj))."""
    s2 = (s * s)[..., None, None]
    motion = np.einsum("...nj,n->...j", (g + s2 * a) ** 2, w)
    t0 = 1.0 / s[..., None]  # motion time per unit T0
    return (t0 * motion + dwell_total * g_rest2) / (t0 + dwell_total)


def rate_limits(motors: Motors, speed, g, a, w, period: float, dwell_total: float, rest: tuple[int, ...]):
    """Largest rate factor s (D,) within every motor limit and the limit that binds (D,) strings, for D designs:
    speed, g, a (D, n, nj) at the configured rate, w (n,) time weights summing to 1, ``rest`` the sample indices
    of pick and place (the dwell's holding torque). s = 0 where gravity alone breaks a torque limit."""
    D = speed.shape[0]
    s = np.full(D, np.inf)
    binding = np.array(["none"] * D, dtype=object)
    peak_speed = np.max(np.abs(speed), axis=1)  # (D, nj)
    with np.errstate(divide="ignore", invalid="ignore"):
        s_speed = np.min(np.where(peak_speed > 0, motors.max_speed / peak_speed, np.inf), axis=1)
    take = s_speed < s
    s[take], binding[take] = s_speed[take], "max_speed"
    P = motors.peak_torque
    with np.errstate(divide="ignore", invalid="ignore"):
        bound = np.where(a > 0, (P - g) / a, np.where(a < 0, (P + g) / -a, np.inf))
    s_peak = np.sqrt(np.clip(np.min(bound, axis=(1, 2)), 0.0, np.inf))
    take = s_peak < s
    s[take], binding[take] = s_peak[take], "peak_torque"
    holding = np.any(np.abs(g) > P, axis=(1, 2))
    # RMS: the mean square at s -> 0 is that of the holding torque alone along the path
    g_rest2 = np.mean(g[:, list(rest)] ** 2, axis=1)
    R2 = motors.rated_torque**2
    slow = np.einsum("dnj,n->dj", g * g, w)
    holding_rms = np.any(slow > R2, axis=1) | np.any(g_rest2 > R2, axis=1)
    fast = np.isfinite(s) & ~holding & ~holding_rms
    over = np.zeros(D, dtype=bool)
    over[fast] = np.any(mean_square_torque(g[fast], a[fast], w, s[fast], dwell_total / period, g_rest2[fast]) > R2,
                        axis=1)
    if np.any(over):
        lo, hi = np.zeros(int(over.sum())) + 1e-12 * s[over], s[over].copy()
        for _ in range(_BISECTION_STEPS):
            mid = 0.5 * (lo + hi)
            bad = np.any(mean_square_torque(g[over], a[over], w, mid, dwell_total / period, g_rest2[over]) > R2,
                         axis=1)
            hi = np.where(bad, mid, hi)
            lo = np.where(bad, lo, mid)
        s[over], binding[over] = lo, "rated_torque"
    s[holding], binding[holding] = 0.0, "peak_torque (holding the payload)"
    s[holding_rms & ~holding] = 0.0
    binding[holding_rms & ~holding] = "rated_torque (holding the payload)"
    return s, binding


def time_weights(t: np.ndarray) -> np.ndarray:
    """Trapezoid weights (n,) of the samples at times t, summing to 1."""
    dt = np.diff(t)
    w = np.zeros(len(t))
    w[:-1] += dt / 2
    w[1:] += dt / 2
    return w / w.sum()


def place_vertex(vertices, preset: str | None) -> int:
    """Index of the place vertex among the path's vertices (m, k; the start not repeated at the end, or repeated):
    the adept and abb-cycle-1 presets' far bottom vertex (S + across, index 3), else the vertex farthest from the
    start (pick is the start, index 0)."""
    verts = np.asarray(vertices, dtype=float)
    if len(verts) > 2 and np.array_equal(verts[-1], verts[0]):
        verts = verts[:-1]
    if preset in ("adept", "abb-cycle-1") and len(verts) == 6:
        return 3
    return int(np.argmax(np.linalg.norm(verts - verts[0], axis=1)))


def rest_samples(traj, preset: str | None) -> tuple[int, ...]:
    """Sample indices of pick (the start) and place (``place_vertex``)."""
    place = place_vertex(traj.vertices[:-1], preset)
    at = [int(np.argmin(np.abs(traj.t - traj.vertex_times[k]))) for k in (0, place)]
    return tuple(at)


MOTOR_METRICS = ("picks_per_minute", "cycle_time_s", "motor_peak_torque_ratio", "motor_rms_torque_ratio",
                 "motor_speed_ratio")
CYCLE_TIME_PENALTY = 1e12  # s: the cycle time of a design whose motors cannot run the cycle


def cycle_motor_metrics(motors: Motors, traj, cyc, joint_units, length_unit: str, qd, qdd, force, force_gravity):
    """The motor metrics of D designs (arrays (D, n, nj): qd, qdd in joint units per s, s^2; force, force_gravity
    SI) -> (name -> (D,), binding limit (D,)): picks_per_minute and cycle_time_s (the shortest period within every
    limit, plus the dwell), and at the configured rate the peak motor torque / peak_torque, the RMS motor torque
    (motion and dwell) / rated_torque and the peak motor speed / max_speed."""
    js = joint_si(joint_units, length_unit)
    speed, g, a = motor_side(motors, qd * js, qdd * js, force, force_gravity)
    w = time_weights(traj.t)
    rest = rest_samples(traj, cyc.preset)
    period = traj.period
    dwell = 2.0 * cyc.dwell_s
    s, binding = rate_limits(motors, speed, g, a, w, period, dwell, rest)
    with np.errstate(divide="ignore"):
        cycle_time = np.where(s > 0, period / np.where(s > 0, s, 1.0) + dwell, CYCLE_TIME_PENALTY)
    g_rest2 = np.mean(g[:, list(rest)] ** 2, axis=1)
    rms = np.sqrt(mean_square_torque(g, a, w, np.ones(len(s)), dwell / period, g_rest2))
    out = {
        "picks_per_minute": np.where(s > 0, 60.0 / cycle_time, 0.0),
        "cycle_time_s": np.minimum(cycle_time, CYCLE_TIME_PENALTY),
        "motor_peak_torque_ratio": np.max(np.abs(g + a) / motors.peak_torque, axis=(1, 2)),
        "motor_rms_torque_ratio": np.max(rms / motors.rated_torque, axis=1),
        "motor_speed_ratio": np.max(np.abs(speed) / motors.max_speed, axis=(1, 2)),
    }
    return out, binding


def failed_motor_metrics() -> dict[str, float]:
    """Motor metrics of a cycle that cannot be followed."""
    return {"picks_per_minute": 0.0, "cycle_time_s": CYCLE_TIME_PENALTY, "motor_peak_torque_ratio": CYCLE_TIME_PENALTY,
            "motor_rms_torque_ratio": CYCLE_TIME_PENALTY, "motor_speed_ratio": CYCLE_TIME_PENALTY}


def of_cycle(cyc, n_joints: int) -> Motors | None:
    """The resolved motors attached to a cycle config (None without a motors section)."""
    cfg = getattr(cyc, "_motors", None)
    if cfg is None:
        return None
    return resolve(cfg, n_joints, getattr(cyc, "_base_dir", None))
