"""Link dynamics along the cycle (scalesynth.dynamics): the power balance sum tau . qd = d/dt (kinetic + potential
energy of every body and the payload) at every sample of every mechanism's cycle, the energies from the bodies'
own positions (link_geometry at the motion law's exact poses, finite differences in time; never the torques);
the dynamics.masses contract; motors and the shortest cycle time against a brute-force time scaling."""

import numpy as np
import pytest

from scalesynth.config import config_from_dict, load_config
from scalesynth.cycle import analysis, trajectory
from scalesynth.cycle import config as ccfg
from scalesynth.dynamics import bodies, inverse, motors
from scalesynth.dynamics.config import DynamicsConfig
from scalesynth.errors import ScalesynthError

from conftest import ROOT

CONFIGS = {"planar-fivebar": "fivebar_packing", "pprs-rprs": "pprs_rprs", "2pauu-ppap": "paper_2pauu_ppap",
           "rps-upu-tool": "rps_upu_tool", "rps-upu": "rps_upu", "ups-sspr": "ups_sspr", "hexa": "hexa",
           "hexapod": "hexapod"}


def _cfg(name):
    return load_config(ROOT / "configs" / f"{CONFIGS[name]}.yaml")


def _run(cfg, dyn=None, samples=60, **changes):
    cyc = cfg.cycle.model_copy(update={"samples": samples, **changes})
    cyc._dynamics = dyn
    return cyc, analysis.analyse(cfg.mech, cfg.resolved_design(), cfg.resolved_options(), cyc, cfg.units.length)


def _pose_at(traj, t):
    """The motion law's exact pose at time t (not a sampled one)."""
    k = min(int(np.searchsorted(traj.vertex_times, t, side="right") - 1), len(traj.vertex_times) - 2)
    dur = traj.vertex_times[k + 1] - traj.vertex_times[k]
    s, _, _ = trajectory.law_profile(traj.law[k], (t - traj.vertex_times[k]) / dur)
    return traj.vertices[k] + s * (traj.vertices[k + 1] - traj.vertices[k])


def _energy(cfg, cyc, masses, traj, t, dt):
    """Kinetic + potential energy (J) of every rod and the payload at time t, velocities by central differences
    of the positions over +-dt."""
    mech, d, o = cfg.mech, cfg.resolved_design(), cfg.resolved_options()
    m = ccfg.METRES_PER_UNIT[cfg.units.length]
    poses = np.array([_pose_at(traj, t - dt), _pose_at(traj, t), _pose_at(traj, t + dt)])
    e = inverse.link_points(mech, d, o, poses, mech.kernel_branch(o)) * m
    v = (e[2] - e[0]) / (2 * dt)
    g3 = inverse.frame_gravity(cyc, mech)
    kin, pot = bodies.rod_energies(masses, e[1][:, 0], e[1][:, 1], v[:, 0], v[:, 1], g3)
    if ccfg.cartesian_task(mech):
        c = np.zeros((3, 3))
        for a, axis in enumerate(mech.task_axes):
            c[:, "xyz".index(axis)] = poses[:, a] * m
    else:
        c = mech.payload_points(d, o, poses) * m
    cv = (c[2] - c[0]) / (2 * dt)
    return kin + pot + cyc.payload * (0.5 * cv @ cv - g3 @ c[1])


@pytest.mark.parametrize("name", CONFIGS)
def test_power_balance_with_link_masses_at_every_sample(name):
    cfg = _cfg(name)
    cyc, res = _run(cfg)
    mech = cfg.mech
    o = cfg.resolved_options()
    q0, _ = mech.cycle_kinematics(cfg.resolved_design(), o, res.traj.p[:1], mech.kernel_branch(o))
    geometry = mech.link_geometry(cfg.resolved_design(), o, res.traj.p[0], q0[0])
    masses = bodies.segment_masses(geometry, o, None, cfg.units.length, mech.name)
    assert masses.sum() > 0.1  # kg of moving links: the check is not the payload's alone
    power = np.sum(res.force * res.qd * motors.joint_si(mech.joint_units, cfg.units.length), axis=1)
    T = res.traj.period
    # d/dt by the fourth-order central stencil over h (truncation ~ (h omega)^4, omega ~ 2 pi / the shortest
    # segment's time); the velocities inside by central differences over 1e-6 T (truncation ~ 1e-9 relative)
    h, small = 1e-4 * T, 1e-6 * T

    def energy(t):
        return _energy(cfg, cyc, masses, res.traj, t, small)

    d_energy = np.array([(8 * (energy(t + h) - energy(t - h)) - (energy(t + 2 * h) - energy(t - 2 * h))) / (12 * h)
                         for t in res.traj.t[1:-1]])
    scale = np.abs(power).max()
    assert scale > 0.1  # W
    np.testing.assert_allclose(power[1:-1], d_energy, rtol=0, atol=1e-6 * scale)


def _fivebar_dict(**sections):
    cfg = load_config(ROOT / "configs" / "fivebar_pnp_cycle.yaml")
    data = cfg.model_dump(mode="json")
    data.update(sections)
    return data


def test_masses_are_the_whole_model_and_spread_along_the_bars():
    cfg = load_config(ROOT / "configs" / "fivebar_pnp_cycle.yaml")
    mech, d, o = cfg.mech, cfg.resolved_design(), cfg.resolved_options()
    q, _ = mech.cycle_kinematics(d, o, np.array([cfg.cycle.start]), mech.kernel_branch(o))
    geometry = mech.link_geometry(d, o, np.array(cfg.cycle.start), q[0])
    names = [s.name for s in geometry.segments]
    m = bodies.segment_masses(geometry, o, DynamicsConfig(masses={"arm": 0.4, "platform": 0.3}), "mm", mech.name)
    assert m[names.index("arm1")] == 0.4 and m[names.index("arm2")] == 0.4  # per body of the group
    assert m[names.index("forearm1")] == 0.0 and m[names.index("base")] == 0.0  # unnamed groups: massless
    assert m[names.index("platform")] == 0.3  # a zero-length body: its mass at the point
    assert bodies.groups(geometry) == ("base", "arm", "forearm", "platform")
    # tube defaults: 40 x 3 mm aluminium (2700 kg/m^3): pi/4 (0.04^2 - 0.034^2) m^2 * 2700 * L
    arm = np.linalg.norm(geometry.segments[names.index("arm1")].b - geometry.segments[names.index("arm1")].a) / 1e3
    m_tube = bodies.segment_masses(geometry, o, None, "mm", mech.name)
    assert m_tube[names.index("arm1")] == pytest.approx(np.pi / 4 * (0.04**2 - 0.034**2) * 2700 * arm, rel=1e-12)


def test_massless_links_leave_the_payload_forces():
    cfg = load_config(ROOT / "configs" / "fivebar_pnp_cycle.yaml")
    _, bare = _run(cfg, DynamicsConfig(masses={}))
    _, arms = _run(cfg, DynamicsConfig(masses={"arm": 0.5}))
    F = bare.payload * (bare.traj.pdd * 1e-3 - bare.gravity)
    np.testing.assert_allclose(bare.force, np.einsum("nik,nk->ni", bare.force_map, F), rtol=1e-12, atol=1e-12)
    assert np.abs(arms.force - bare.force).max() > 0.1  # N m: the arms' inertia and weight


@pytest.mark.parametrize("sections, message", [
    ({"dynamics": {"masses": {"arms": 1.0}}}, "dynamics.masses.arms: unknown body group"),
    ({"dynamics": {"masses": {"arm": -1.0}}}, "must be a finite number >= 0"),
    ({"dynamics": {"masses": {"arm": float("nan")}}}, "must be a finite number >= 0"),
    ({"motors": {"peak_torque": 1, "rated_torque": 1, "max_speed": 1, "rotor_inertia": 0, "gear_ratio": 0}},
     "must be finite and > 0"),
    ({"motors": {"peak_torque": 1, "rated_torque": 1, "max_speed": 1, "gear_ratio": 5}}, "rotor_inertia: missing"),
    ({"motors": {"catalogue": "builtin", "model": "SGM7J-09A", "gear_ratio": 5}}, "did you mean"),
    ({"motors": {"catalogue": "/nonexistent/motors.csv", "model": "X", "gear_ratio": 5}}, "no such file"),
])
def test_bad_dynamics_and_motors_are_one_line_errors(sections, message):
    with pytest.raises(ScalesynthError) as err:
        config_from_dict(_fivebar_dict(**sections))
    assert message in str(err.value) and "\n" not in str(err.value)


def test_malformed_catalogue_names_the_line(tmp_path):
    path = tmp_path / "m.csv"
    path.write_text("model,peak_torque,rated_torque,max_speed,rotor_inertia\nA,1,0,3,0\n")
    with pytest.raises(ScalesynthError, match="line 2, rated_torque"):
        motors.read_catalogue(path)
    path.write_text("model,peak\nA,1\n")
    with pytest.raises(ScalesynthError, match="malformed"):
        motors.read_catalogue(path)


MOTOR = {"peak_torque": 4.46, "rated_torque": 1.27, "max_speed": 628.3, "rotor_inertia": 0.486e-4, "gear_ratio": 20}


def _limits_hold(cfg, period, dwell, mot):
    """Whether every motor limit holds when the cycle runs with this motion period (brute force: a new analysis)."""
    cyc = cfg.cycle.model_copy(update={"samples": 60, "period": period, "cycles_per_minute": None, "dwell_s": dwell})
    cyc._dynamics, cyc._motors = cfg.dynamics, cfg.motors
    res = analysis.analyse(cfg.mech, cfg.resolved_design(), cfg.resolved_options(), cyc, cfg.units.length)
    w = motors.time_weights(res.traj.t)
    rest = motors.rest_samples(res.traj, cyc.preset)
    tq = res.motor_torque
    T = res.traj.period
    rms = np.sqrt((T * (w @ tq**2) + 2 * dwell * np.mean(tq[list(rest)] ** 2, axis=0)) / (T + 2 * dwell))
    return (np.abs(res.motor_speed).max(axis=0) <= mot.max_speed * (1 + 1e-9)).all() and (
        np.abs(tq).max(axis=0) <= mot.peak_torque * (1 + 1e-9)).all() and (rms <= mot.rated_torque * (1 + 1e-9)).all()


@pytest.mark.parametrize("motor", [MOTOR, {**MOTOR, "rated_torque": 0.5}, {**MOTOR, "gear_ratio": 60}])
def test_cycle_time_is_the_shortest_period_within_the_motor_limits(motor):
    cfg = config_from_dict(_fivebar_dict(motors=motor, dynamics={"masses": {"arm": 0.4, "forearm": 0.5}}))
    cyc = cfg.cycle.model_copy(update={"samples": 60, "dwell_s": 0.035})
    cyc._dynamics, cyc._motors = cfg.dynamics, cfg.motors
    m = analysis.metrics(cfg.mech, cfg.resolved_design(), cfg.resolved_options(), cyc, "mm")
    mot = motors.resolve(cfg.motors, 2)
    motion = m["cycle_time_s"] - 0.07
    assert m["picks_per_minute"] == pytest.approx(60 / m["cycle_time_s"], rel=1e-12)
    assert _limits_hold(cfg, motion * (1 + 1e-6), 0.035, mot)  # just slower: every limit holds
    assert not _limits_hold(cfg, motion * (1 - 1e-3), 0.035, mot)  # faster: one breaks


def test_motors_too_weak_to_hold_the_payload_give_zero_picks():
    weak = {**MOTOR, "peak_torque": 0.01, "rated_torque": 0.005}
    cfg = config_from_dict(_fivebar_dict(motors=weak))
    cyc = cfg.cycle.model_copy(update={"samples": 60})
    cyc._dynamics, cyc._motors = cfg.dynamics, cfg.motors
    res = analysis.analyse(cfg.mech, cfg.resolved_design(), cfg.resolved_options(), cyc, "mm")
    vals, binding = analysis.motor_metrics(res, cyc)
    assert vals["picks_per_minute"] == 0.0 and binding == "peak_torque (holding the payload)"


def test_motor_columns_against_the_joint_columns():
    """tau_m = (force + J_r n^2 qdd) / n and w = n qd (rad/s) from cycle.csv's own columns."""
    cfg = config_from_dict(_fivebar_dict(motors=MOTOR))
    cyc = cfg.cycle.model_copy(update={"samples": 60})
    cyc._dynamics, cyc._motors = cfg.dynamics, cfg.motors
    res = analysis.analyse(cfg.mech, cfg.resolved_design(), cfg.resolved_options(), cyc, "mm")
    n, J = 20.0, 0.486e-4
    np.testing.assert_allclose(res.motor_speed, n * res.qd, rtol=1e-12)
    np.testing.assert_allclose(res.motor_torque, (res.force + J * n * n * res.qdd) / n, rtol=1e-12, atol=1e-12)
    assert "motor_torque2" in res.columns() and "force2" in res.columns()


def test_population_picks_equal_the_per_design_metrics():
    from scalesynth.cycle.population import population_metrics

    cfg = config_from_dict(_fivebar_dict(motors=MOTOR, dynamics={"masses": {"arm": 0.4, "forearm": 0.5}}))
    cyc = cfg.cycle.model_copy(update={"samples": 40})
    cyc._dynamics, cyc._motors = cfg.dynamics, cfg.motors
    d0 = cfg.resolved_design()
    designs = [d0, {**d0, **{k: v * 1.05 for k, v in d0.items() if k in ("l1", "l2")}}]
    pop = population_metrics(cfg.mech, designs, cfg.resolved_options(), cyc, "mm")
    for i, d in enumerate(designs):
        one = analysis.metrics(cfg.mech, d, cfg.resolved_options(), cyc, "mm")
        for k in ("picks_per_minute", "cycle_time_s", "cycle_max_actuator_force", "motor_rms_torque_ratio"):
            assert pop[k][i] == pytest.approx(one[k], rel=1e-9), k
