"""The time-optimal cycle (dynamics.optimal, toppra), the abb-cycle-1 preset, the datasheet and the market sanity
check (issue 29; docs/cycles.md).

* the path coefficients: the motor torque is affine in (s_dd, s_d^2) (the inverse dynamics evaluated at other
  (s_d, s_dd) pairs), and they give back the fixed-law motion's motor torque of ``analyse``;
* toppra's time is never longer than the fixed-law time, agrees with a brute-force forward/backward pass on a
  10x finer grid (written here), and its motion, re-evaluated with the inverse dynamics, keeps the limits;
* a design whose motors cannot hold the payload is data; abb-cycle-1's vertices and dwell; the datasheet;
* a 1130 mm-reach Delta (tests/data/delta_market_sanity.json) gives vendors' rates, falling with payload.
"""

import copy
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.interpolate import CubicSpline

from scalesynth.config import config_from_dict
from scalesynth.cycle import analysis
from scalesynth.cycle import config as ccfg
from scalesynth.cycle.datasheet import payloads_of
from scalesynth.dynamics import motors as dm
from scalesynth.dynamics import optimal

from refdata import DATA

ROOT = Path(__file__).resolve().parents[1]
MARKET = json.loads((DATA / "delta_market_sanity.json").read_text())


def delta_config(**changes) -> dict:
    """The market sanity Delta (tests/data/delta_market_sanity.json) as a run config dict."""
    cyc = {k: v for k, v in MARKET["cycle"].items() if k != "start_note"}
    cfg = {
        "name": "market", "mechanism": "delta", "units": {"length": "m"}, "design": MARKET["design"],
        "options": {"theta_limits": [-1.0, 1.5707963267948966]},
        "bounds": {"base_radius": [0.2, 0.5], "upper_arm": [0.3, 1.0], "forearm": [0.6, 1.4]},
        "grid": {"region": {"z": [-2.5, -0.3]}},
        "dynamics": {"masses": MARKET["masses_kg"]},
        "motors": {"catalogue": "builtin", "model": MARKET["motor"], "gear_ratio": MARKET["gear_ratio"]},
        "cycle": {**cyc, "cycles_per_minute": 60, "payload": 1.0},
        "objectives": [{"metric": "volume", "sense": "max"}, {"metric": "gci", "sense": "max"}],
    }
    for key, value in changes.items():
        cfg[key] = {**cfg[key], **value} if isinstance(value, dict) else value
    return cfg


FIVEBAR = {
    "name": "fb", "mechanism": "planar-fivebar", "units": {"length": "mm"}, "design": {"r": 200, "l1": 475, "l2": 875},
    "options": {"mode": "+-", "alpha1_limits": [-1.3962634015954636, 0.6108652381980153],
                "alpha2_limits": [2.530727415391778, 4.537856055185257]},
    "bounds": {"r": [50, 400], "l1": [250, 800], "l2": [500, 1400]},
    "motors": {"catalogue": "builtin", "model": "SGM7J-08A", "gear_ratio": 30},
    "cycle": {"preset": "adept", "start": [-152.5, -800.0], "direction": [1.0, 0.0], "law": "modified_trapezoid",
              "cycles_per_minute": 60, "payload": 2.0, "gravity": [0.0, -9.80665], "dwell_s": 0.05},
    "objectives": [{"metric": "volume", "sense": "max"}, {"metric": "gci", "sense": "max"}],
}


def _load(data):
    cfg = config_from_dict(copy.deepcopy(data), base_dir=ROOT)
    return cfg, cfg.resolved_options()


@pytest.fixture(scope="module")
def market():
    cfg, options = _load(delta_config())
    res = analysis.analyse(cfg.mech, cfg.design, options, cfg.cycle, cfg.units.length)
    return cfg, options, res


def _motors(cfg):
    return dm.of_cycle(cfg.cycle, len(cfg.mech.joints))


def _motor_torque(cfg, options, p, pd, pdd):
    """Motor torque and speed (n, nj) from the inverse dynamics at task states (n, k)."""
    qd, qdd, force, force_gravity = analysis.sample_dynamics(cfg.mech, cfg.design, options, cfg.cycle,
                                                             cfg.units.length, p, pd, pdd)
    js = dm.joint_si(cfg.mech.joint_units, cfg.units.length)
    speed, g, a = dm.motor_side(_motors(cfg), qd * js, qdd * js, force, force_gravity)
    return g + a, speed


# ---------------------------------------------------------------------------------------------------------------
# the coefficients of tau_m = a s_dd + b s_d^2 + c
# ---------------------------------------------------------------------------------------------------------------
def test_motor_torque_is_affine_in_path_acceleration_and_squared_velocity(market):
    """Along a straight segment x(s) = v + s d the inverse dynamics at (s_d, s_dd) = (1, 1), (2, 0), (0, 3),
    (0.5, -2) equals a s_dd + b s_d^2 + c from the coefficients' own pairs (0, 1) and (1, 0), to 1e-6 of the peak
    torque (the finite-difference steps of the inverse dynamics are relative to the motion: ~1e-7), and the motor
    speed is w s_d."""
    cfg, options, _ = market
    verts = ccfg.vertices(cfg.cycle, cfg.mech, cfg.units.length)
    coefs = optimal.sampled_coefficients(cfg.mech, cfg.design, options, cfg.cycle, cfg.units.length, _motors(cfg),
                                         verts, intervals=6)
    seg = 2  # the 305 mm across move
    d = verts[3] - verts[2]
    p = verts[2] + coefs[seg].s[:, None] * d
    scale = float(np.max(_motors(cfg).peak_torque))
    for sd, sdd in ((1.0, 1.0), (2.0, 0.0), (0.0, 3.0), (0.5, -2.0)):
        tau, speed = _motor_torque(cfg, options, p, sd * np.tile(d, (len(p), 1)), sdd * np.tile(d, (len(p), 1)))
        expect = coefs[seg].a * sdd + coefs[seg].b * sd * sd + coefs[seg].c
        assert np.max(np.abs(tau - expect)) < 1e-6 * scale, (sd, sdd)
        assert np.max(np.abs(speed - coefs[seg].w * sd)) < 1e-9 * np.max(np.abs(coefs[seg].w)) * max(sd, 1.0)
    assert np.max(np.abs(coefs[seg].a)) > 0 and np.max(np.abs(coefs[seg].b)) > 0


def test_coefficients_give_back_the_fixed_law_motor_torque(market):
    """The poly345 law along each segment: s(t), s_d, s_dd from the sampled trajectory's task motion; the
    coefficients (splined from 48 intervals) give analyse's motor_torque at every sample to 1e-4 of its peak (the
    spline's error; cycle.csv's motor_torque columns come from the sampled motion, not from the coefficients)."""
    cfg, options, res = market
    coefs = optimal.sampled_coefficients(cfg.mech, cfg.design, options, cfg.cycle, cfg.units.length, _motors(cfg),
                                         res.traj.vertices)
    traj = res.traj
    peak = np.max(np.abs(res.motor_torque))
    for k, coef in enumerate(coefs):
        rows = np.nonzero(traj.segment[:-1] == k)[0]
        d = traj.vertices[k + 1] - traj.vertices[k]
        axis = int(np.argmax(np.abs(d)))
        s = (traj.p[rows, axis] - traj.vertices[k, axis]) / d[axis]
        sd = traj.pd[rows, axis] / d[axis]
        sdd = traj.pdd[rows, axis] / d[axis]
        a, b, c = (CubicSpline(coef.s, v, axis=0)(s) for v in (coef.a, coef.b, coef.c))
        tau = a * sdd[:, None] + b * (sd * sd)[:, None] + c
        assert np.max(np.abs(tau - res.motor_torque[rows])) < 1e-4 * peak, k


# ---------------------------------------------------------------------------------------------------------------
# toppra against the fixed law and a brute-force time scaling
# ---------------------------------------------------------------------------------------------------------------
def brute_force_time(coef: optimal.PathCoefficients, peak: np.ndarray, max_speed: np.ndarray) -> float:
    """Rest-to-rest minimum time on the grid of ``coef`` by the classic forward/backward pass (written here, not
    toppra): x = s_d^2; at each grid point the admissible s_dd for a given x is the intersection over the motors
    of a u + b x + c in [-peak, peak]; the maximum velocity curve (largest x with a non-empty interval, within the
    speed limit) by bisection; forward from rest accelerating at the largest s_dd, capped by the curve; backward
    from rest decelerating at the smallest; the profile is their minimum; time sum 2 ds / (s_d,i + s_d,i+1)."""
    s, a, b, c = coef.s, coef.a, coef.b, coef.c

    def interval(i, x):
        """(lowest, highest) admissible s_dd at grid points i (array) for x (array); lo > hi: none."""
        up = peak - b[i] * x[..., None] - c[i]
        dn = -peak - b[i] * x[..., None] - c[i]
        ai = a[i]
        with np.errstate(divide="ignore", invalid="ignore"):
            lo = np.where(ai > 0, dn / ai, np.where(ai < 0, up / ai, np.where((dn <= 0) & (up >= 0), -np.inf, np.inf)))
            hi = np.where(ai > 0, up / ai, np.where(ai < 0, dn / ai, np.where((dn <= 0) & (up >= 0), np.inf, -np.inf)))
        return lo.max(axis=-1), hi.min(axis=-1)

    n = len(s)
    idx = np.arange(n)
    with np.errstate(divide="ignore"):
        x_speed = np.min(np.where(np.abs(coef.w) > 0, (max_speed / np.abs(coef.w)) ** 2, np.inf), axis=1)
    lo_x, hi_x = np.zeros(n), np.minimum(x_speed, 1e12)
    top_ok = np.less_equal(*interval(idx, hi_x))
    for _ in range(80):
        mid = 0.5 * (lo_x + hi_x)
        ok = np.less_equal(*interval(idx, mid))
        lo_x, hi_x = np.where(ok, mid, lo_x), np.where(ok, hi_x, mid)
    mvc = np.where(top_ok, np.minimum(x_speed, 1e12), lo_x)
    ds = np.diff(s)
    fwd = np.zeros(n)
    for i in range(n - 1):
        fwd[i + 1] = min(mvc[i + 1], max(fwd[i] + 2 * ds[i] * float(interval(i, np.float64(fwd[i]))[1]), 0.0))
    bwd = np.zeros(n)
    for i in range(n - 1, 0, -1):
        bwd[i - 1] = min(mvc[i - 1], max(bwd[i] - 2 * ds[i - 1] * float(interval(i, np.float64(bwd[i]))[0]), 0.0))
    sd = np.sqrt(np.minimum(fwd, bwd))
    return float(np.sum(2 * ds / (sd[:-1] + sd[1:])))


CASES = {
    "delta-market": delta_config(),
    "delta-bag-weak-gear": delta_config(design={"base_radius": 0.25, "platform_radius": 0.2, "upper_arm": 0.75,
                                                "forearm": 0.95},
                                        motors={"model": "SGM7A-30A", "gear_ratio": 30}),
    "fivebar": FIVEBAR,
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_toppra_is_never_slower_than_the_fixed_law_and_matches_a_brute_force_scaling(case):
    """Three designs (the market Delta, the Briot-Arakelian-Glazunov Delta on a bigger motor and a lower gear, the
    five-bar with its own motors, a 2 kg payload and modified-trapezoid law): toppra's cycle time <= the fixed-law
    cycle time (the fixed law is one admissible motion under the same peak and speed limits, and the fixed law
    also keeps the RMS limit); per segment toppra's time within 1 % of the brute-force pass on a 10x finer grid
    (2400 intervals of the same splined coefficients; both converge to the continuous optimum, toppra's
    collocation from below by O(1/N))."""
    cfg, options = _load(CASES[case])
    res = analysis.analyse(cfg.mech, cfg.design, options, cfg.cycle, cfg.units.length)
    fixed, _ = analysis.motor_metrics(res, cfg.cycle)
    best = optimal.of_design(cfg.mech, cfg.design, options, cfg.cycle, cfg.units.length)[0]
    assert best.picks_per_minute > 0
    assert best.cycle_time_s <= fixed["cycle_time_s"]
    assert best.cycle_time_s == pytest.approx(sum(best.segment_times_s) + 2 * cfg.cycle.dwell_s, rel=1e-12)
    mot = _motors(cfg)
    sampled = optimal.sampled_coefficients(cfg.mech, cfg.design, options, cfg.cycle, cfg.units.length, mot,
                                           ccfg.vertices(cfg.cycle, cfg.mech, cfg.units.length))
    for k, coef in enumerate(sampled):
        brute = brute_force_time(optimal.refine(coef, 10 * optimal.GRID_INTERVALS), mot.peak_torque, mot.max_speed)
        assert best.segment_times_s[k] == pytest.approx(brute, rel=0.01), k


def test_the_time_optimal_motion_keeps_the_limits_under_the_inverse_dynamics(market):
    """toppra's profile (s_d at the grid points, s_dd per interval) re-evaluated with the inverse dynamics itself
    (not the coefficients) at every grid point of the across move: |motor torque| <= peak torque and |motor speed|
    <= max speed, to 1 % (the coefficients are splined; toppra's collocation holds the limits at the grid points
    with the interval's s_dd), and some motor is within 2 % of a limit (the motion is not merely feasible)."""
    cfg, options, _ = market
    best = optimal.of_design(cfg.mech, cfg.design, options, cfg.cycle, cfg.units.length)[0]
    verts = ccfg.vertices(cfg.cycle, cfg.mech, cfg.units.length)
    s, sd, sdd = best.profiles[2]
    d = verts[3] - verts[2]
    p = verts[2] + s[:-1, None] * d
    tau, speed = _motor_torque(cfg, options, p, sd[:-1, None] * d, sdd[:, None] * d)
    mot = _motors(cfg)
    torque_use = np.max(np.abs(tau) / mot.peak_torque)
    speed_use = np.max(np.abs(speed) / mot.max_speed)
    assert torque_use <= 1.01 and speed_use <= 1.01
    assert max(torque_use, speed_use) >= 0.98


def test_motors_too_weak_to_hold_the_payload_are_data(tmp_path):
    """The market Delta on the smallest catalogue servo without a gear (gear 1: the arms' weight alone needs
    tens of N m at the joint, the servo gives 4.46 N m): cycle exits 0, picks_per_minute 0 for both the fixed
    law and toppra, each naming the binding limit."""
    cfg = delta_config(motors={"model": "SGM7J-04A", "gear_ratio": 1})
    path = tmp_path / "weak.json"
    path.write_text(json.dumps(cfg))
    info = _cli(["cycle", str(path), "--out", str(tmp_path / "out"), "--json"])
    assert info["picks_per_minute"] == 0 and info["binding_limit"] == "peak_torque (holding the payload)"
    assert info["time_optimal_picks_per_minute"] == 0
    assert info["time_optimal_binding_limit"] == "peak_torque (holding the payload)"
    for row in info["datasheet"]["rows"]:
        assert row["picks_per_minute"] == 0 and row["time_optimal_picks_per_minute"] == 0
        assert row["peak_tool_speed_m_s"] is None


def _cli(args, code=0):
    proc = subprocess.run([sys.executable, "-m", "scalesynth", *args], capture_output=True, text=True, timeout=900,
                          cwd=ROOT)
    assert proc.returncode == code, proc.stderr
    return json.loads(proc.stdout) if "--json" in args else proc


# ---------------------------------------------------------------------------------------------------------------
# abb-cycle-1
# ---------------------------------------------------------------------------------------------------------------
def test_abb_cycle_1_is_the_adept_path_with_35_ms_of_vacuum():
    """abb-cycle-1 on a Delta (no rotation axis): the adept preset's six vertices (25 mm up, 305 mm across, in m
    here), dwell_s 0.035 unless the config sets one (0 kept)."""
    cfg, _ = _load(delta_config())
    adept, _ = _load(delta_config(cycle={"preset": "adept", "dwell_s": 0.0}))
    v = ccfg.vertices(cfg.cycle, cfg.mech, "m")
    np.testing.assert_array_equal(v, ccfg.vertices(adept.cycle, adept.mech, "m"))
    np.testing.assert_allclose(v[3] - v[0], [0.305, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(v[1] - v[0], [0.0, 0.0, 0.025], atol=1e-15)
    data = delta_config()
    data["cycle"].pop("dwell_s")
    assert _load(data)[0].cycle.dwell_s == 0.035
    assert _load(delta_config(cycle={"dwell_s": 0.0}))[0].cycle.dwell_s == 0.0


def test_abb_cycle_1_turns_a_rotation_task_axis_by_90_degrees_over_the_across_move():
    """A mechanism whose task axes are x, y, z and a tool angle phi: phi + pi/2 at the far vertices (2 to 4),
    the start's phi elsewhere; the Cartesian part is the adept path."""
    class Stub:
        task_axes = ("x", "y", "z", "phi")
        task_units = ("length", "length", "length", "angle")

    cyc = ccfg.CycleConfig(preset="abb-cycle-1", start=[0.0, 0.0, -1.0, 0.3], direction=[1, 0, 0, 0],
                           gravity=[0.0, 0.0, -9.80665, 0.0], cycles_per_minute=60)
    v = ccfg.vertices(cyc, Stub(), "m")
    np.testing.assert_allclose(v[:, 3], [0.3, 0.3, 0.3 + np.pi / 2, 0.3 + np.pi / 2, 0.3 + np.pi / 2, 0.3])
    np.testing.assert_allclose(v[3, :3] - v[0, :3], [0.305, 0.0, 0.0], atol=1e-15)


def test_abb_cycle_1_needs_cartesian_task_axes(tmp_path):
    """On rps-upu (z, theta, psi) the preset is refused with one line naming the field, exit 2."""
    path = tmp_path / "c.yaml"
    path.write_text("name: c\nmechanism: rps-upu\nunits: {length: mm}\ndesign: {g: 80, h: 50, c: 50, e: 0}\n"
                    "bounds: {g: [60, 100]}\ncycle: {preset: abb-cycle-1, start: [40, 0, 0], cycles_per_minute: 60}\n"
                    "objectives: [{metric: volume, sense: max}]\n")
    proc = _cli(["cycle", str(path), "--out", str(tmp_path / "o")], code=2)
    line = proc.stderr.strip()
    assert "\n" not in line and "cycle.preset: abb-cycle-1 needs two Cartesian task axes" in line
    assert not (tmp_path / "o").exists()


# ---------------------------------------------------------------------------------------------------------------
# the datasheet and the market
# ---------------------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def market_sheet(tmp_path_factory):
    out = tmp_path_factory.mktemp("sheet")
    path = out / "market.json"
    path.write_text(json.dumps(delta_config()))
    proc = _cli(["cycle", str(path), "--out", str(out / "cycle"), "--datasheet"])
    return proc.stdout, json.loads((out / "cycle" / "cycle.json").read_text())


def test_datasheet_in_cycle_json_and_printed(market, market_sheet):
    """cycle.json's datasheet has a row per payload (0.1, 1, 3 kg and the cycle's own); the row at the cycle's
    payload repeats the top-level picks_per_minute (1e-9: the affine payload combination) and the toppra rate;
    --datasheet prints the table with every payload; the RMS-limited fixed law runs its motors at RMS ratio 1."""
    text, info = market_sheet
    sheet = info["datasheet"]
    assert [r["payload_kg"] for r in sheet["rows"]] == [0.1, 1.0, 3.0]
    row = sheet["rows"][1]
    assert row["picks_per_minute"] == pytest.approx(info["picks_per_minute"], rel=1e-9)
    assert row["time_optimal_picks_per_minute"] == info["time_optimal_picks_per_minute"]
    assert info["time_optimal_picks_per_minute"] >= info["picks_per_minute"]
    for r in sheet["rows"]:
        assert r["peak_tool_speed_m_s"] > 0 and r["peak_tool_accel_m_s2"] > 0
        assert max(r["motor_peak_torque_ratio"], r["motor_rms_torque_ratio"], r["motor_speed_ratio"]) \
            == pytest.approx(1.0, rel=1e-6)
    assert "datasheet: motor SGM7A-15A" in text and "picks/min" in text
    assert payloads_of(ccfg.CycleConfig(preset="adept", start=[0, 0], cycles_per_minute=1, payload=2.0)) \
        == [0.1, 1.0, 2.0, 3.0]


def test_datasheet_without_motors_is_refused(tmp_path):
    """--datasheet on a config without motors: one line naming the flag, exit 2, nothing written."""
    data = delta_config()
    data.pop("motors")
    path = tmp_path / "c.json"
    path.write_text(json.dumps(data))
    proc = _cli(["cycle", str(path), "--out", str(tmp_path / "o"), "--datasheet"], code=2)
    assert proc.stderr.strip().startswith("error: --datasheet: the config has no motors section")
    assert not (tmp_path / "o").exists()


def test_a_1130_mm_packaging_delta_runs_at_vendors_rates_and_slows_with_payload(market_sheet):
    """tests/data/delta_market_sanity.json: the Autonox RL5-1450 geometry with assumed masses, a 1.5 kW servo
    through its published 1:55 gear, on abb-cycle-1: the fixed-law rate at 1 kg lies in the vendors' band
    (100-200 picks/min; ABB's IRB 360-3/1130: 150), and both rates fall strictly from 0.1 to 1 to 3 kg."""
    _, info = market_sheet
    rows = {r["payload_kg"]: r for r in info["datasheet"]["rows"]}
    lo, hi = MARKET["expected_band_picks_per_minute_at_1kg"]
    assert lo <= rows[1.0]["picks_per_minute"] <= hi
    for key in ("picks_per_minute", "time_optimal_picks_per_minute"):
        assert rows[0.1][key] > rows[1.0][key] > rows[3.0][key] > 0, key


def test_delta_picks_config_optimises_picks_per_minute(tmp_path):
    """configs/delta_picks.yaml at a small budget (8 designs, 2 generations, seed 1): exit 0, population.csv has a
    picks_per_minute column with a design above 0 (a Delta of these sizes on a 1.5 kW servo runs the cycle), the
    front is not empty (a design reaches both rims of the cylinder within the motor limits) and report.md and
    report.html carry the knee design's datasheet."""
    import csv

    out = tmp_path / "run"
    _cli(["optimize", "configs/delta_picks.yaml", "--set", f"output.dir={out}", "--set", "algorithm.pop_size=8",
          "--set", "algorithm.n_gen=2"])
    rows = list(csv.DictReader((out / "population.csv").open()))
    assert rows and "picks_per_minute" in rows[0]
    assert max(float(r["picks_per_minute"]) for r in rows) > 0
    front = list(csv.DictReader((out / "pareto.csv").open()))
    assert front and all(float(r["path_reachable"]) == 1.0 for r in front)
    report = (out / "report.md").read_text()
    assert "## Datasheet of the" in report and "| kg | picks/min |" in report
    assert "<h2>Datasheet of the" in (out / "report.html").read_text()
