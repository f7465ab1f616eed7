"""Pick-and-place cycles (scalesynth.cycle): motion laws against their closed forms, actuator rates against finite
differences of the IK positions, power balance, rate scaling, capsule clearance against brute force and an
optimiser, seed 001's drive curves against the recorded output of the old `drives` command, the `cycle` command
and its bad input."""

import json
import math

import numpy as np
import pytest
import yaml
from scipy.optimize import minimize
from typer.testing import CliRunner

from scalesynth.cli import app
from scalesynth.config import load_config
from scalesynth.cycle import analysis, trajectory
from scalesynth.cycle.clearance import clearance, segment_distance
from scalesynth.cycle.config import METRES_PER_UNIT
from scalesynth.dynamics.config import DynamicsConfig
from scalesynth.mechanisms.base import wrap_angle

from conftest import ROOT

FIVEBAR = load_config(ROOT / "configs" / "fivebar_packing.yaml")
PPRS = load_config(ROOT / "configs" / "pprs_rprs.yaml")
SEED000 = load_config(ROOT / "configs" / "paper_2pauu_ppap.yaml")
TOOL = load_config(ROOT / "configs" / "rps_upu_tool.yaml")
RPS = load_config(ROOT / "configs" / "rps_upu.yaml")  # task axes (z, theta, psi): mm and rad
UPS = load_config(ROOT / "configs" / "ups_sspr.yaml")  # task axes (alpha, beta, Y): rad and mm
CASES = {"planar-fivebar": FIVEBAR, "pprs-rprs": PPRS, "2pauu-ppap": SEED000, "rps-upu-tool": TOOL, "rps-upu": RPS,
         "ups-sspr": UPS}
CYCLE_CONFIGS = sorted(p.name for p in (ROOT / "configs").glob("*.yaml") if "cycle" in yaml.safe_load(p.read_text()))


def run(cfg, massless=False, **changes):
    """The config's cycle with changes (100 time intervals unless given: enough for every check, fast);
    ``massless``: links without mass (dynamics.masses: {}), the payload alone."""
    cyc = cfg.cycle.model_copy(update={"samples": 100, **changes})
    if massless:
        cyc._dynamics = DynamicsConfig(masses={})
    return analysis.analyse(cfg.mech, cfg.resolved_design(), cfg.resolved_options(), cyc, cfg.units.length)


# ----- motion laws ----------------------------------------------------------------------------------------
@pytest.mark.parametrize("law, peak_v, peak_a", [
    ("poly345", 1.875, 10 / math.sqrt(3)),  # s' = 30 t^2 (1-t)^2 at t = 1/2; s'' at t = 1/2 -+ sqrt(3)/6
    ("modified_trapezoid", 2.0, 4.888124),  # the classic modified trapezoid: C_v = 2, C_a = 4.8881
])
def test_motion_law_boundary_values_peaks_and_derivatives(law, peak_v, peak_a):
    tau = np.linspace(0.0, 1.0, 200_001)
    s, sd, sdd = trajectory.law_profile(law, tau)
    assert (s[0], s[-1], sd[0], sd[-1]) == pytest.approx((0.0, 1.0, 0.0, 0.0), abs=1e-12)
    assert sdd[0] == pytest.approx(0.0, abs=1e-12) and sdd[-1] == pytest.approx(0.0, abs=1e-9)
    assert sd.max() == pytest.approx(peak_v, rel=1e-6)
    assert np.abs(sdd).max() == pytest.approx(peak_a, rel=1e-5)
    h = tau[1] - tau[0]
    np.testing.assert_allclose(np.gradient(s, h)[1:-1], sd[1:-1], atol=1e-8)
    np.testing.assert_allclose(np.gradient(sd, h)[1:-1], sdd[1:-1], atol=2e-6)
    np.testing.assert_allclose(s + s[::-1], 1.0, atol=1e-12)  # rest-to-rest laws are point-symmetric


def test_trajectory_vertices_times_and_closure():
    traj = trajectory.build([[0, 0], [4, 0], [4, 1]], "poly345", 3.0, 300)
    # closed back to the start; durations proportional to sqrt(length): 2 : 1 : sqrt(17)
    np.testing.assert_allclose(traj.vertices, [[0, 0], [4, 0], [4, 1], [0, 0]])
    w = np.sqrt([4.0, 1.0, math.sqrt(17.0)])
    np.testing.assert_allclose(traj.vertex_times, np.concatenate([[0], np.cumsum(3.0 * w / w.sum())]))
    for k, tv in enumerate(traj.vertex_times):
        i = int(np.argmin(np.abs(traj.t - tv)))
        assert traj.t[i] == pytest.approx(tv)
        np.testing.assert_allclose(traj.p[i], traj.vertices[k], atol=1e-12)
        np.testing.assert_allclose(traj.pd[i], 0.0, atol=1e-12)  # rest at every vertex
    assert traj.t[-1] == 3.0 and np.all(np.diff(traj.t) > 0)


# ----- actuator rates against finite differences of the IK positions ---------------------------------------
def _ik(cfg, pose, ref):
    """The configured branch's IK at a pose, angles unwrapped towards ref (independent of the velocity map)."""
    mech = cfg.mech
    sols = {s.label: s.values for s in mech.inverse_kinematics(cfg.resolved_design(), cfg.resolved_options(), pose)}
    q = np.array(sols[mech.kernel_branch(cfg.resolved_options())])
    ang = np.array([u == "angle" for u in mech.joint_units])
    q[ang] = ref[ang] + wrap_angle(q[ang] - ref[ang])
    return q


@pytest.mark.parametrize("name", CASES)
@pytest.mark.parametrize("law", ["poly345", "modified_trapezoid"])
def test_rates_match_finite_differences_of_ik_positions(name, law):
    cfg = CASES[name]
    res = run(cfg, law=law, samples=120)
    traj = res.traj
    seg = np.diff(traj.vertices, axis=0)
    durations = np.diff(traj.vertex_times)
    checked = 0
    for s in range(0, len(traj.t) - 1, 7):
        k = traj.segment[s]
        tau = (traj.t[s] - traj.vertex_times[k]) / durations[k]
        if not 0.02 < tau < 0.98:
            continue
        h = 1e-4
        poses = [traj.vertices[k] + trajectory.law_profile(law, tau + j * h)[0] * seg[k] for j in (-1, 0, 1)]
        q_m, q_0, q_p = (_ik(cfg, p, res.q[s]) for p in poses)
        dt = h * durations[k]
        np.testing.assert_allclose(q_0, res.q[s], rtol=0, atol=1e-9)
        scale_v = np.abs(res.qd).max(axis=0)
        scale_a = np.abs(res.qdd).max(axis=0)
        # central differences: truncation O(h^2), rounding of the second difference ~ 1e-16 / h^2 relative
        err_v = np.abs((q_p - q_m) / (2 * dt) - res.qd[s])
        err_a = np.abs((q_p - 2 * q_0 + q_m) / dt**2 - res.qdd[s])
        assert np.all(err_v <= 1e-6 * scale_v), (s, err_v / scale_v)
        assert np.all(err_a <= 2e-4 * scale_a), (s, err_a / scale_a)
        checked += 1
    assert checked >= 10


@pytest.mark.parametrize("name", CASES)
def test_power_balance_at_every_sample(name):
    """sum force_i qd_i (W) = m (a - g) . v of the payload point at every sample; in mixed units (rps-upu, ups-sspr)
    also = F . x_dot with F in N along length axes and N m about angle axes, x_dot in m/s and rad/s."""
    cfg = CASES[name]
    cartesian = all(u == "length" for u in cfg.mech.task_units)
    gravity = [1.0, -3.0, -9.0][-len(cfg.mech.task_axes):] if cartesian else [1.0, -3.0, -9.0]
    res = run(cfg, massless=True, payload=2.5, gravity=gravity)  # links with mass: tests/test_dynamics.py
    m = METRES_PER_UNIT[cfg.units.length]
    joint_si = np.array([m if u == "length" else 1.0 for u in cfg.mech.joint_units])
    task_si = np.array([m if u == "length" else 1.0 for u in cfg.mech.task_units])
    actuator_power = np.sum(res.force * res.qd * joint_si, axis=1)
    payload_power = np.sum(2.5 * (res.payload_accel * m - res.gravity) * res.payload_velocity * m, axis=1)
    task_power = np.sum(res.task_force * res.traj.pd * task_si, axis=1)
    assert np.abs(payload_power).max() > 0.1  # W: the check is not 0 = 0
    np.testing.assert_allclose(actuator_power, payload_power, rtol=0, atol=1e-9 * np.abs(payload_power).max())
    np.testing.assert_allclose(task_power, payload_power, rtol=0, atol=1e-9 * np.abs(payload_power).max())
    if cartesian:  # F = m (a - g) exactly
        np.testing.assert_allclose(res.task_force, 2.5 * (res.traj.pdd * m - res.gravity), rtol=1e-12)
    # the gravity part of the forces: what the actuators exert holding the payload still at the same poses
    still = run(cfg, massless=True, payload=2.5, gravity=gravity,
                cycles_per_minute=1e-6 * cfg.cycle.cycles_per_minute)
    np.testing.assert_allclose(res.force_gravity, still.force, rtol=0, atol=1e-6 * np.abs(res.force).max())


@pytest.mark.parametrize("name", CASES)
def test_doubling_the_rate_doubles_speeds_and_quadruples_accelerations(name):
    cfg = CASES[name]
    slow = run(cfg)
    fast = run(cfg, cycles_per_minute=2 * cfg.cycle.cycles_per_minute)
    np.testing.assert_allclose(fast.traj.t, slow.traj.t / 2, rtol=1e-12)
    np.testing.assert_allclose(fast.q, slow.q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(fast.qd, 2 * slow.qd, rtol=1e-9, atol=1e-9 * np.abs(slow.qd).max())
    np.testing.assert_allclose(fast.qdd, 4 * slow.qdd, rtol=1e-6, atol=1e-6 * np.abs(slow.qdd).max())
    # inertial forces quadruple, gravity's part stays: tau(2x) - tau_g = 4 (tau(1x) - tau_g)
    tau_g = slow.force_gravity
    if all(u == "length" for u in cfg.mech.task_units):
        bare = run(cfg, massless=True)  # the payload's weight alone (the links' own: tests/test_dynamics.py)
        np.testing.assert_allclose(bare.force_gravity, np.einsum("nik,k->ni", bare.force_map,
                                                                 -bare.payload * bare.gravity))
    np.testing.assert_allclose(fast.force - tau_g, 4 * (slow.force - tau_g), rtol=1e-6,
                               atol=1e-6 * np.abs(slow.force).max())


def test_max_cycles_per_minute_from_speed_and_force_limits():
    cfg = FIVEBAR
    design, options = cfg.resolved_design(), cfg.resolved_options()
    base = cfg.cycle.model_copy(update={"speed_limits": 6.0, "samples": 100})
    m = analysis.metrics(cfg.mech, design, options, base, "mm")
    peak = run(cfg).qd
    # speeds scale with the rate: 60 cycles/min * 6 rad/s / peak |qd|
    assert m["max_cycles_per_minute"] == pytest.approx(60 * 6.0 / np.abs(peak).max(), rel=1e-12)
    # at that rate the limit is reached exactly
    k = m["max_cycles_per_minute"] / 60
    assert np.abs(run(cfg, cycles_per_minute=60 * k).qd).max() == pytest.approx(6.0, rel=1e-9)
    # force limits: the rate found leaves the worst actuator force at the limit
    forced = cfg.cycle.model_copy(update={"force_limits": 20.0, "samples": 100})
    m = analysis.metrics(cfg.mech, design, options, forced, "mm")
    at = run(cfg, cycles_per_minute=m["max_cycles_per_minute"])
    assert np.abs(at.force).max() == pytest.approx(20.0, rel=1e-6)
    # gravity alone above the limit: no rate works
    tiny = cfg.cycle.model_copy(update={"force_limits": 1.0, "samples": 100})
    assert analysis.metrics(cfg.mech, design, options, tiny, "mm")["max_cycles_per_minute"] == 0.0


# ----- seed 001: the old drives curves --------------------------------------------------------------------
def test_seed001_drive_curves_unchanged_from_the_recorded_drives_output():
    ref = np.loadtxt(ROOT / "tests" / "data" / "cycle" / "drives_seed001_square.csv", delimiter=",", skiprows=1)
    res = run(PPRS, law="constant", period=1.0, cycles_per_minute=None, samples=len(ref) - 1)
    np.testing.assert_allclose(res.traj.t, ref[:, 0], atol=1e-11)
    np.testing.assert_allclose(res.traj.p, ref[:, 1:4], rtol=1e-11, atol=1e-9)
    np.testing.assert_allclose(res.q, ref[:, 4:], rtol=1e-11, atol=1e-9)  # 12 significant digits in the file


def test_drives_alias_writes_the_recorded_bytes(tmp_path):
    """`drives` is `cycle` on the default square with the constant law: its drives.csv equals, byte for byte, the
    file the old implementation wrote (tests/data/cycle/README.md)."""
    res = CliRunner().invoke(app, ["drives", str(ROOT / "configs" / "pprs_rprs.yaml"), "--out", str(tmp_path)])
    assert res.exit_code == 0, res.output
    recorded = (ROOT / "tests" / "data" / "cycle" / "drives_seed001_square.csv").read_text()
    assert (tmp_path / "drives.csv").read_text() == recorded


# ----- clearance ------------------------------------------------------------------------------------------
def _segment_points(a, b, n):
    t = np.linspace(0.0, 1.0, n)[:, None]
    return a + t * (b - a)


def test_segment_distance_against_brute_force_and_an_optimiser():
    rng = np.random.default_rng(7)
    cases = [rng.normal(size=(4, 3)) for _ in range(30)]
    # degenerate cases: parallel, collinear overlapping, a point, crossing, both points
    cases += [np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.0]]),
              np.array([[0, 0, 0], [2, 0, 0], [1, 0, 0], [3, 0, 0.0]]),
              np.array([[0, 0, 0], [0, 0, 0], [1, -1, 0], [1, 1, 0.0]]),
              np.array([[-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0.0]]),
              np.array([[0, 0, 0], [0, 0, 0], [3, 4, 0], [3, 4, 0.0]])]
    for p1, q1, p2, q2 in cases:
        d = float(segment_distance(p1, q1, p2, q2))
        pa, pb = _segment_points(p1, q1, 801), _segment_points(p2, q2, 801)
        brute = np.min(np.linalg.norm(pa[:, None, :] - pb[None, :, :], axis=2))
        # the grids are 1/800 of each segment apart: brute force overestimates by at most half of that each
        assert d <= brute + 1e-12
        assert brute - d <= (np.linalg.norm(q1 - p1) + np.linalg.norm(q2 - p2)) / 1600 + 1e-12
        def gap(st, p1=p1, q1=q1, p2=p2, q2=q2):
            return np.linalg.norm(p1 + st[0] * (q1 - p1) - p2 - st[1] * (q2 - p2))

        opt = minimize(gap, x0=[0.5, 0.5], bounds=[(0, 1), (0, 1)], method="L-BFGS-B")
        assert d <= opt.fun + 1e-12 and opt.fun - d <= 1e-6


@pytest.mark.parametrize("name", CASES)
def test_mechanism_clearance_against_points_sampled_on_the_capsules(name):
    """Brute force: 400 points along each capsule's axis; a capsule's surface lies at its radius from the axis, so
    the smallest point-set distance of each non-adjacent pair minus the two radii can only exceed the exact
    clearance, by at most half the point spacing of the two segments."""
    cfg = CASES[name]
    res = run(cfg, samples=40)
    design, options = cfg.resolved_design(), cfg.resolved_options()
    for s in (0, 7, 23):
        geo = cfg.mech.link_geometry(design, options, res.traj.p[s], res.q[s])
        clouds = [_segment_points(seg.a, seg.b, 400) for seg in geo.segments]
        gaps = []
        for i, j in geo.checked_pairs():
            d = np.min(np.linalg.norm(clouds[i][:, None, :] - clouds[j][None, :, :], axis=2))
            gaps.append(d - geo.segments[i].radius - geo.segments[j].radius)
        brute = min(gaps)
        exact = clearance(geo).value
        assert exact == pytest.approx(res.clearance[s], abs=1e-12)
        longest = max(np.linalg.norm(seg.b - seg.a) for seg in geo.segments)
        assert exact <= brute + 1e-9
        assert brute - exact <= longest / 399 + 1e-9


def test_fivebar_link_geometry_and_adjacency():
    cfg = FIVEBAR
    design, options = cfg.resolved_design(), cfg.resolved_options()
    pose = (0.0, -725.0)
    q = next(s.values for s in cfg.mech.inverse_kinematics(design, options, pose) if s.label == "+-")
    geo = cfg.mech.link_geometry(design, options, pose, q)
    seg = {s.name: s for s in geo.segments}
    # spec §2.7 point o: alpha1 = -0.305041, alpha2 = -2.836552; elbows at B_i + l1 (cos, sin)
    elbow = [200 + 475 * math.cos(-0.305041), 475 * math.sin(-0.305041), 0]
    np.testing.assert_allclose(seg["arm1"].b, elbow, atol=1e-3)
    np.testing.assert_allclose(seg["forearm2"].b, [0, -725, 0])
    assert np.linalg.norm(seg["forearm1"].b - seg["forearm1"].a) == pytest.approx(875.0)
    names = {(geo.segments[i].body, geo.segments[j].body) for i, j in geo.checked_pairs()}
    assert ("arm1", "arm2") in names and ("base", "forearm1") in names
    assert ("arm1", "forearm1") not in names and ("forearm1", "forearm2") not in names
    with_radius = cfg.mech.link_geometry(design, {**options, "link_radius": {"arm1": 7.0}}, pose, q)
    assert {s.name: s.radius for s in with_radius.segments}["arm1"] == 7.0


def test_interference_is_negative_clearance():
    """Fat links collide: radius 250 mm on every body makes the two arms (400 mm apart at the base) overlap."""
    fat = {**FIVEBAR.resolved_options(), "link_radius": 250.0}
    res = analysis.analyse(FIVEBAR.mech, FIVEBAR.resolved_design(), fat, FIVEBAR.cycle, "mm")
    assert res.clearance.min() == pytest.approx(400.0 - 500.0)  # the pivots B1, B2 are 2 r = 400 mm apart
    m = analysis.result_metrics(res, FIVEBAR.cycle)
    assert m["cycle_feasible"] == 0.0 and m["cycle_min_clearance"] == pytest.approx(-100.0)


# ----- command and bad input ------------------------------------------------------------------------------
def test_cycle_command_writes_csv_json_and_plots(tmp_path):
    res = CliRunner().invoke(app, ["cycle", str(ROOT / "configs" / "fivebar_packing.yaml"), "--out", str(tmp_path),
                                   "--json"])
    assert res.exit_code == 0, res.output
    info = json.loads(res.stdout)
    header = (tmp_path / "cycle.csv").read_text().splitlines()[0].split(",")
    assert header == ["t", "p_x", "pd_x", "pdd_x", "p_y", "pd_y", "pdd_y", "q1", "qd1", "qdd1", "force1",
                      "q2", "qd2", "qdd2", "force2", "lci", "clearance", "deflection"]  # the five-bar has stiffness
    units = json.loads((tmp_path / "cycle.json").read_text())["units"]
    assert units["pdd_x"] == "mm/s^2" and units["qd1"] == "rad/s" and units["force2"] == "N m"
    assert info["metrics"]["cycle_feasible"] == 1.0
    # adept preset: 25 mm up, 305 mm across, 25 mm down and back, from the start point
    np.testing.assert_allclose(info["vertices"], [[-152.5, -800], [-152.5, -775], [152.5, -775], [152.5, -800],
                                                  [152.5, -775], [-152.5, -775], [-152.5, -800]])
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["actuators.png", "cycle.csv", "cycle.json", "path.png", "quality.png"]


def _write(tmp_path, cfg, **cycle):
    data = yaml.safe_load((ROOT / "configs" / cfg).read_text())
    data["cycle"] = {**data.get("cycle", {}), **cycle}
    data["cycle"] = {k: v for k, v in data["cycle"].items() if v is not None}
    path = tmp_path / "c.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.mark.parametrize("cfg, change, message", [
    ("fivebar_packing.yaml", {"preset": None, "start": None, "direction": None, "path": [[0, -700], [0, -2000]]},
     "error: cycle.path[1]: (0, -2000) is outside the workspace"),
    ("fivebar_packing.yaml", {"preset": None, "start": None, "direction": None, "path": [[0, -700]]},
     "error: cycle.path: need at least 2 points, got 1"),
    ("fivebar_packing.yaml", {"cycles_per_minute": None, "period": -1.0},
     "error: cycle.period: must be a finite number > 0"),
    ("fivebar_packing.yaml", {"cycles_per_minute": 0}, "error: cycle.cycles_per_minute: must be a finite number > 0"),
    ("fivebar_packing.yaml", {"payload": 0}, "error: cycle.payload: must be a finite number > 0"),
    ("fivebar_packing.yaml", {"preset": "scara"},
     "error: cycle.preset: unknown preset 'scara' (known: adept, abb-cycle-1)"),
    ("fivebar_packing.yaml", {"start": [0, -300]}, "error: cycle.adept[0]: (0, -300) is outside the workspace"),
    ("fivebar_packing.yaml", {"law": "cubic"}, "error: cycle.law: unknown motion law 'cubic'"),
    ("fivebar_packing.yaml", {"payload": -2.0}, "error: cycle.payload: must be a finite number > 0"),
    ("fivebar_packing.yaml", {"direction": [1.0, 1.0]}, "error: cycle.direction: must be perpendicular to gravity"),
    ("fivebar_packing.yaml", {"preset": None, "start": None, "direction": None, "path": [[0, -700], [1e13, -700]]},
     "error: cycle.path.1: 1e+13 is beyond +-1e+12"),
    ("fivebar_packing.yaml", {"preset": None, "start": None, "direction": None, "path": [[0, -700], [0, -700]]},
     "error: cycle.path: all points coincide"),
    ("fivebar_packing.yaml", {"payload": 2e12}, "error: cycle.payload: 2e+12 is beyond +-1e+12"),
    ("fivebar_packing.yaml", {"gravity": [0.0, -1e13]}, "error: cycle.gravity.1: -1e+13 is beyond +-1e+12"),
    ("rps_upu.yaml", {"path": None, "preset": "adept", "start": [40, 0, 0], "cycles_per_minute": 30},
     "error: cycle.preset: adept needs two Cartesian task axes; rps-upu has z, theta, psi"),
])
def test_bad_cycle_input_one_line_exit_2_nothing_written(tmp_path, cfg, change, message):
    path = _write(tmp_path, cfg, **change)
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["cycle", str(path), "--out", str(out)])
    assert res.exit_code == 2, res.output
    assert res.stderr.startswith(message), res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
    assert not out.exists()


# ----- per-voxel clearance field ---------------------------------------------------------------------------
def test_numba_segment_distance_matches_the_numpy_version():
    from scalesynth.kernels.clearance import segment_distance as jit_distance

    rng = np.random.default_rng(11)
    pts = rng.normal(size=(400, 4, 3))
    pts[::7, 1] = pts[::7, 0]  # some zero-length segments
    pts[::5, 3] = pts[::5, 2] + 2.0 * (pts[::5, 1] - pts[::5, 0])  # some parallel pairs
    for p1, q1, p2, q2 in pts:
        assert jit_distance(*p1, *q1, *p2, *q2) == pytest.approx(float(segment_distance(p1, q1, p2, q2)), abs=1e-12)


@pytest.mark.parametrize("name, radius, extra", [
    ("planar-fivebar", None, {}), ("planar-fivebar", 150.0, {}), ("pprs-rprs", None, {}), ("pprs-rprs", 30.0, {}),
    ("rps-upu", None, {}), ("rps-upu", 25.0, {}), ("rps-upu", 25.0, {"model": "C"}),
    ("rps-upu", 25.0, {"model": "C", "c3_variant": "upu"}), ("rps-upu-tool", None, {}), ("rps-upu-tool", 20.0, {}),
    ("ups-sspr", None, {}), ("ups-sspr", 30.0, {}),
])
def test_clearance_field_matches_numpy_link_geometry(name, radius, extra):
    """The field kernel's clearance at every reachable node of a grid against cycle.clearance of the mechanism's
    link_geometry (NumPy, the cycle's code path), and interference_free = reachable and clearance >= 0."""
    from scalesynth.evaluate import make_grid
    from scalesynth.kernels import grid as kgrid

    cfg = CASES[name]
    mech = cfg.mech
    design = cfg.resolved_design()
    options = mech.resolve_options({**cfg.options, "link_radius": radius, **extra})
    g = make_grid(mech, design, options, 31 if mech.planar else 9)
    slot = mech.field_names.index("clearance")
    fields = kgrid.sample_fields(mech.field_kernel, mech.n_fields, mech.pack(design, options), g.lo, g.step, g.shape)
    reach = fields[..., 0] >= 0
    checked = 0
    branch = mech.kernel_branch(options)
    for i, j, k in zip(*np.nonzero(reach), strict=True):
        pose = tuple(g.axis(a)[n] for a, n in enumerate((i, j, k)))[: len(mech.task_axes)]
        q = next(s.values for s in mech.inverse_kinematics(design, options, pose) if s.label == branch)
        expected = clearance(mech.link_geometry(design, options, pose, q)).value
        assert fields[i, j, k, slot] == pytest.approx(expected, abs=1e-9)
        checked += 1
    assert checked > 20
    free = mech.resolve_options({**options, "interference_free": True})
    only = kgrid.sample_fields(mech.field_kernel, mech.n_fields, mech.pack(design, free), g.lo, g.step, g.shape)
    assert np.array_equal(only[..., 0] >= 0, reach & (fields[..., slot] >= 0))
    if radius is not None:
        assert (reach & (fields[..., slot] < 0)).any()  # fat links: some reachable poses do interfere


def test_five_bar_synthesis_minimising_cycle_speed_with_clearance_constraint(tmp_path):
    """Done-when of issue 13: cycle_max_actuator_speed (min) as an objective, cycle_min_clearance >= 0 as a
    constraint; every front row's cycle metrics equal a fresh analysis of that design."""
    data = yaml.safe_load((ROOT / "configs" / "fivebar_packing.yaml").read_text())
    data.update(name="fivebar_cycle", grid={"resolution": 16}, task=None,
                objectives=[{"metric": "cycle_max_actuator_speed", "sense": "min"}, {"metric": "gci", "sense": "max"}],
                constraints=[{"metric": "cycle_min_clearance", "min": 0.0}],
                algorithm={"pop_size": 6, "n_gen": 2, "seed": 3}, output={"checkpoint_every": 1})
    data["cycle"]["samples"] = 24
    path = tmp_path / "c.yaml"
    path.write_text(yaml.safe_dump(data))
    res = CliRunner().invoke(app, ["optimize", str(path), "--out", str(tmp_path / "run"), "--no-plots"])
    assert res.exit_code == 0, res.output
    import pandas as pd

    front = pd.read_csv(tmp_path / "run" / "pareto.csv")
    assert len(front) >= 1
    cfg = load_config(path)
    for _, row in front.iterrows():
        design = {k: row[k] for k in ("r", "l1", "l2")}
        m = analysis.metrics(cfg.mech, design, cfg.resolved_options(), cfg.cycle, "mm")
        assert row["cycle_max_actuator_speed_rad_per_s"] == pytest.approx(m["cycle_max_actuator_speed"], rel=1e-9)
        assert row["cycle_min_clearance_mm"] >= 0
    res = CliRunner().invoke(app, ["cycle", str(tmp_path / "run"), "--design", "best-cycle_max_actuator_speed",
                                   "--out", str(tmp_path / "cyc"), "--json"])
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["metrics"]["cycle_max_actuator_speed"] == pytest.approx(
        front["cycle_max_actuator_speed_rad_per_s"].min(), rel=1e-9)


def test_bad_link_options_are_one_line_errors(tmp_path):
    cfg = ROOT / "configs" / "fivebar_packing.yaml"
    for change, message in (("interference_free=maybe", "options.interference_free: expected true or false"),
                            ("link_radius=-1", "options.link_radius: expected a length >= 0"),
                            ("link_radius={elbow: 3}", "options.link_radius.elbow: unknown body")):
        res = CliRunner().invoke(app, ["cycle", str(cfg), "--set", change, "--out", str(tmp_path / "out")])
        assert res.exit_code == 2 and message in res.stderr, res.stderr
        assert not (tmp_path / "out").exists()


def _payload_fd(cfg, res, point):
    """Velocity and acceleration of the payload point (callable pose -> 3-D point) by central differences in time
    along the motion law (independent of the analysis' Jacobian), at the samples inside the segments."""
    traj = res.traj
    seg = np.diff(traj.vertices, axis=0)
    durations = np.diff(traj.vertex_times)
    law = traj.law[0]
    out = []
    for s in range(0, len(traj.t) - 1, 5):
        k = traj.segment[s]
        tau = (traj.t[s] - traj.vertex_times[k]) / durations[k]
        if not 0.02 < tau < 0.98:
            continue
        h = 1e-4
        c_m, c_0, c_p = (point(traj.vertices[k] + trajectory.law_profile(law, tau + j * h)[0] * seg[k])
                         for j in (-1, 0, 1))
        dt = h * durations[k]
        out.append((s, (c_p - c_m) / (2 * dt), (c_p - 2 * c_0 + c_m) / dt**2))
    assert len(out) >= 10
    return out


def test_rps_upu_cycle_in_mixed_task_axes(tmp_path):
    """rps-upu's task axes are (z, theta, psi); the payload sits at O' = (0, 0, z) in the P-model, so the generalised
    force is exactly (m (z_ddot - g_z), 0, 0): N along z, no torque about the angles (a point mass on the rotation
    axes). The command writes its cycle with mm and rad columns."""
    res = run(RPS, massless=True, samples=100)  # the payload's force alone
    m = 1e-3
    np.testing.assert_allclose(res.task_force[:, 0], RPS.cycle.payload * (res.traj.pdd[:, 0] * m + 9.80665),
                               rtol=1e-9)
    np.testing.assert_allclose(res.task_force[:, 1:], 0.0, atol=1e-12)
    np.testing.assert_allclose(res.payload_velocity, np.column_stack([0 * res.traj.t, 0 * res.traj.t,
                                                                      res.traj.pd[:, 0]]), atol=1e-9)
    out = tmp_path / "out"
    cli = CliRunner().invoke(app, ["cycle", str(ROOT / "configs" / "rps_upu.yaml"), "--set", "cycle.samples=60",
                                   "--out", str(out), "--json"])
    assert cli.exit_code == 0, cli.output
    units = json.loads((out / "cycle.json").read_text())["units"]
    assert (units["p_z"], units["pd_theta"], units["pdd_psi"], units["force1"]) == ("mm", "rad/s", "rad/s^2", "N")


def test_ups_sspr_payload_motion_against_finite_differences():
    """ups-sspr carries its payload at B1 = (sin(beta) rho, Y, cos(beta) rho), rho = sqrt(c^2 - Y^2) (spec §3.1,
    written out here independently of the mechanism): the analysis' payload velocity and acceleration equal
    central differences in time of that point along the cycle."""
    c = UPS.resolved_design()["c"]

    def b1(x):
        rho = math.sqrt(c * c - x[2] ** 2)
        return np.array([math.sin(x[1]) * rho, x[2], math.cos(x[1]) * rho])

    res = run(UPS, samples=120)
    for s, v, a in _payload_fd(UPS, res, b1):
        np.testing.assert_allclose(res.payload_velocity[s], v, rtol=0, atol=1e-6 * np.abs(res.payload_velocity).max())
        np.testing.assert_allclose(res.payload_accel[s], a, rtol=0, atol=2e-4 * np.abs(res.payload_accel).max())


@pytest.mark.parametrize("config", CYCLE_CONFIGS)
def test_cycle_runs_on_the_configs_with_a_cycle(tmp_path, config):
    """`scalesynth cycle` on each shipped config with a cycle (fewer samples for speed): exit 0, feasible, clearance
    >= 0, and the power balance of its CSV columns (force_i qd_i against m (a - g) . v of the payload)."""
    out = tmp_path / "out"
    cli = CliRunner().invoke(app, ["cycle", str(ROOT / "configs" / config), "--set", "cycle.samples=60",
                                   "--out", str(out), "--json"])
    assert cli.exit_code == 0, cli.output
    cfg = load_config(ROOT / "configs" / config, ["cycle.samples=60"])
    res = run(cfg, samples=60)
    m = analysis.result_metrics(res, cfg.cycle)
    assert m["cycle_feasible"] == 1.0 and m["cycle_min_clearance"] >= 0, m
    assert json.loads(cli.stdout)["metrics"] == pytest.approx(m, rel=1e-12)
    lu = METRES_PER_UNIT[cfg.units.length]
    joint_si = np.array([lu if u == "length" else 1.0 for u in cfg.mech.joint_units])
    bare = run(cfg, massless=True, samples=60)  # the payload alone (with the links: tests/test_dynamics.py)
    payload = cfg.cycle.payload * (bare.payload_accel * lu - bare.gravity) * bare.payload_velocity * lu
    np.testing.assert_allclose(np.sum(bare.force * bare.qd * joint_si, axis=1), payload.sum(axis=1), atol=1e-9)


def test_pprs_rail_input_follows_x_exactly():
    """Seed 001, conv O, zero orientation: w1 = u1 . C1 = x + r, so qd1 = pd_x and qdd1 = pdd_x exactly (spec §1.3);
    on the 20 mm square with 3-4-5 sides of 0.25 s the peak is 1.875 * 20 / 0.25 = 150 mm/s."""
    res = run(PPRS, samples=200)
    np.testing.assert_allclose(res.q[:, 0], res.traj.p[:, 0] + PPRS.resolved_design()["r"], atol=1e-9)
    np.testing.assert_allclose(res.qd[:, 0], res.traj.pd[:, 0], atol=1e-9)
    np.testing.assert_allclose(res.qdd[:, 0], res.traj.pdd[:, 0], atol=1e-6 * np.abs(res.traj.pdd).max())
    assert np.abs(res.qd[:, 0]).max() == pytest.approx(150.0, rel=1e-4)


# ----- deflection along the cycle -----------------------------------------------------------------------------
STIFF = load_config(ROOT / "configs" / "fivebar_stiffness.yaml")


PAPER = load_config(ROOT / "configs" / "paper_2pauu_ppap.yaml")
# seed 000's stiffness fields are opt-in (options.stiffness_metrics), so that its fast path stays in use without them
PAPER_STIFF = load_config(ROOT / "configs" / "paper_2pauu_ppap.yaml", ["options.stiffness_metrics=true"])


@pytest.mark.parametrize("cfg, samples", [(STIFF, (0, 13, 31, 47)), (UPS, (5, 29)), (PPRS, (3, 40)),
                                          (PAPER_STIFF, (7, 33)), (RPS, (11, 52)), (TOOL, (2, 37))])
def test_deflection_along_the_cycle_equals_the_pose_level_stiffness_command(cfg, samples):
    """At sample poses, the cycle's deflection column equals `scalesynth stiffness MECH --pose P --load F` (the
    frame model solved by the NumPy reference, ideal joints) with F = m (g - a) the force the payload exerts on the
    platform at that sample (N; its weight at rest)."""
    res = run(cfg, samples=60)
    assert res.deflection is not None and np.all(res.deflection > 0)
    m = METRES_PER_UNIT[cfg.units.length]
    design = cfg.resolved_design()
    sets = [f"{k}={v}" for k, v in design.items()]
    for s in samples:
        load = cfg.cycle.payload * (res.gravity - res.payload_accel[s] * m)
        cli = CliRunner().invoke(app, ["stiffness", cfg.mech.name, "--pose", ",".join(f"{v:.17g}" for v in
                                 res.traj.p[s]), "--load", ",".join(f"{v:.17g}" for v in load), "--json",
                                 *[a for kv in sets for a in ("--set", kv)],
                                 *[a for k, v in cfg.options.items() for a in ("--set", f"{k}={json.dumps(v)}")]])
        assert cli.exit_code == 0, cli.output
        ref = json.loads(cli.stdout)["deflection_norm"]
        assert res.deflection[s] == pytest.approx(ref, rel=1e-7), s
    assert analysis.result_metrics(res, cfg.cycle)["cycle_max_deflection"] == pytest.approx(res.deflection.max())


def test_seed000_reports_no_cycle_deflection_unless_its_stiffness_fields_are_on():
    """With options.stiffness_metrics off, 2pauu-ppap's kernel writes no deflection: the cycle has no deflection
    column (not a column of zeros) and the catalogue refuses cycle_max_deflection, naming the option."""
    from scalesynth import metrics

    res = run(PAPER)
    assert res.deflection is None and "deflection" not in res.columns()
    assert "cycle_max_deflection" not in analysis.result_metrics(res, PAPER.cycle)
    m = metrics.catalogue(PAPER.mech, PAPER.units.length)["cycle_max_deflection"]
    why = metrics.applicable(m, True, False, PAPER.resolved_options(), PAPER.cycle)
    assert why == "needs options.stiffness_metrics (false)"
    assert metrics.applicable(m, True, False, PAPER_STIFF.resolved_options(), PAPER_STIFF.cycle) is None


def test_seed001_square_stays_in_one_assembly_mode_and_a_larger_square_is_refused():
    """Seed 001's square (the old drive_curves checks, now on the cycle): Newton FK of each sample's actuators from
    the previous sample's pose lands back on the sample (one assembly mode along the whole loop); the 40 mm square
    centred at (-30, -30) leaves the workspace at z = 200 mm, a one-line CycleError naming the sample."""
    from scalesynth.mechanisms.pprs_rprs import Geometry, newton_fk, sigma_vector

    res = run(PPRS, law="constant", period=1.0, cycles_per_minute=None, samples=100)
    design, options = PPRS.resolved_design(), PPRS.resolved_options()
    geo = Geometry.of(design, options)
    poses = np.column_stack([res.traj.p, np.tile(options["orientation"], (len(res.traj.t), 1))])
    fk, conv = newton_fk(geo, sigma_vector(options["sigma"]), res.q[1:], poses[:-1])
    assert conv.all()
    np.testing.assert_allclose(fk, poses[1:], rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.q[-1], res.q[0], atol=1e-12)  # back at E: back to the start values
    big = [[-50, -50, 200], [-10, -50, 200], [-10, -10, 200], [-50, -10, 200]]
    with pytest.raises(analysis.CycleError, match=r"^cycle\.path\[\d\]: .* is outside the workspace"):
        run(PPRS, path=big)


# ----- fast path: vectorised kinematics and kernel clearance against the per-pose reference ---------------------
@pytest.mark.parametrize("name", CASES)
def test_fast_cycle_analysis_equals_the_reference_analysis(name):
    """analyse() (Mechanism.cycle_kinematics, vectorised where a mechanism overrides it; clearance from the field
    kernel where it has one) against analyse(reference=True) (inverse_kinematics, velocity_map and link_geometry
    per pose): every column and metric equal to rounding."""
    cfg = CASES[name]
    fast, ref = run(cfg, samples=80), None
    cyc = cfg.cycle.model_copy(update={"samples": 80})
    ref = analysis.analyse(cfg.mech, cfg.resolved_design(), cfg.resolved_options(), cyc, cfg.units.length,
                           reference=True)
    for key, col in ref.columns().items():
        scale = max(np.abs(col).max(), 1e-300)
        np.testing.assert_allclose(fast.columns()[key], col, rtol=0, atol=1e-9 * scale, err_msg=key)
    assert fast.min_clearance_pair == ref.min_clearance_pair
    assert analysis.result_metrics(fast, cyc) == pytest.approx(analysis.result_metrics(ref, cyc), rel=1e-9)


@pytest.mark.parametrize("name", [n for n in CASES if type(CASES[n].mech).cycle_kinematics
                                  is not analysis.Mechanism.cycle_kinematics])
def test_vectorised_cycle_kinematics_equal_the_per_pose_loop(name):
    """Each override of cycle_kinematics against the base class's loop at the cycle's samples and at a pose far
    beyond the workspace (NaN rows wherever the loop finds no branch, in both)."""
    cfg = CASES[name]
    mech, design, options = cfg.mech, cfg.resolved_design(), cfg.resolved_options()
    res = run(cfg, samples=40)
    lo, hi = mech.bounding_box(design, options)
    k = len(mech.task_axes)
    far = np.array(hi[:k]) + 3.0 * (np.array(hi[:k]) - np.array(lo[:k])) + 1.0
    poses = np.vstack([res.traj.p, far[None, :]])
    label = mech.kernel_branch(options)
    q, a = mech.cycle_kinematics(design, options, poses, label)
    q_ref, a_ref = analysis.Mechanism.cycle_kinematics(mech, design, options, poses, label)
    assert np.array_equal(np.isnan(q), np.isnan(q_ref)) and not np.isnan(q[:-1]).any()
    live = ~np.isnan(q_ref).any(axis=1)
    ang = np.array([u == "angle" for u in mech.joint_units])
    dq = q[live] - q_ref[live]
    dq[:, ang] = wrap_angle(dq[:, ang])
    np.testing.assert_allclose(dq, 0.0, atol=1e-9)
    np.testing.assert_allclose(a[live], a_ref[live], rtol=1e-9, atol=1e-12 * np.abs(a_ref[live]).max())


@pytest.mark.parametrize("name", ["rps-upu", "ups-sspr", "rps-upu-tool"])
def test_vectorised_payload_points_equal_payload_point(name):
    cfg = CASES[name]
    mech, design, options = cfg.mech, cfg.resolved_design(), cfg.resolved_options()
    poses = run(cfg, samples=30).traj.p
    np.testing.assert_allclose(mech.payload_points(design, options, poses),
                               [mech.payload_point(design, options, p) for p in poses], rtol=0, atol=1e-12)


# ----- the population path (the optimiser's cycle metrics) against analysis.metrics per design ---------------
def _population_designs(cfg, n=11):
    """The config's design (a followed cycle), n designs drawn uniformly from the bounds (seed 0; many cycles
    cannot be followed there) and a degenerate one (every bounded dimension 0)."""
    rng = np.random.default_rng(0)
    base = cfg.resolved_design()
    drawn = [{**base, **{k: float(rng.uniform(lo, hi)) for k, (lo, hi) in cfg.bounds.items()}} for _ in range(n)]
    return [base, *drawn, {**base, **dict.fromkeys(cfg.bounds, 0.0)}]


@pytest.mark.parametrize("name, limits", [*((n, {}) for n in CASES),
                                          ("planar-fivebar", {"speed_limits": 3.0, "force_limits": 40.0})])
def test_population_metrics_equal_the_per_design_metrics(name, limits):
    """cycle.population.population_metrics (the design-independent work once, the rest batched over the designs)
    against analysis.metrics design by design: every metric bit-identical (the same element-wise operations in the
    same order), followed and refused cycles alike; with limits also max_cycles_per_minute."""
    from scalesynth.cycle.population import population_metrics

    cfg = CASES[name]
    cyc = cfg.cycle.model_copy(update={"samples": 40, **limits})
    designs = _population_designs(cfg)
    opts = cfg.resolved_options()
    rows = [analysis.metrics(cfg.mech, d, opts, cyc, cfg.units.length) for d in designs]
    got = population_metrics(cfg.mech, designs, opts, cyc, cfg.units.length)
    assert set(got) == set(analysis.METRICS)
    for key in analysis.METRICS:
        np.testing.assert_array_equal(got[key], [r.get(key, 0.0) for r in rows], err_msg=key)
    followed = got["cycle_min_clearance"] > -analysis.CYCLE_PENALTY  # -PENALTY only for a cycle not followed
    assert followed[0] and not followed[-1] and followed.sum() < len(designs) - 1  # both kinds in the draw
    if limits:
        assert np.all(got["max_cycles_per_minute"][followed] > 0.0)


def test_fivebar_population_cycle_kinematics_equal_cycle_kinematics_per_design():
    """planar-fivebar's batched kinematics (designs x poses in one NumPy pass) against cycle_kinematics of each
    design at its own poses: bit-identical, NaN rows out of reach alike."""
    cfg = FIVEBAR
    mech, opts = cfg.mech, cfg.resolved_options()
    designs = [mech.resolve_design(d) for d in _population_designs(cfg)[:-1]]
    rng = np.random.default_rng(1)
    lo, hi = mech.bounding_box(designs[0], opts)
    poses = rng.uniform(lo[:2], hi[:2], size=(len(designs), 30, 2))
    label = mech.kernel_branch(opts)
    q, a = mech.population_cycle_kinematics(designs, opts, poses, label)
    for d, p, qi, ai in zip(designs, poses, q, a, strict=True):
        q_one, a_one = mech.cycle_kinematics(d, opts, p, label)
        np.testing.assert_array_equal(qi, q_one)
        np.testing.assert_array_equal(ai, a_one)
    assert np.isnan(q).any() and not np.isnan(q).all()  # both reachable and unreachable poses
