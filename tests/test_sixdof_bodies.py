"""Bodies of the described 6-DOF mechanisms (describe/bodies.py link_geometry6, sixdof.py): link capsules against
the independent textbook geometry of tests/naive_sixdof.py (no description machinery), adjacency and radii, the
branch-only cycle kinematics against the base class's loop, the Adept cycle through `scalesynth cycle`, whose
actuator forces at rest are checked by virtual work against the potential energy as a function of the joint
values (forward kinematics, then the bodies at the full pose: tau_i = dV/dq_i by central differences; this holds
the moments the actuators spend keeping the platform's orientation), and the robot drawing of `scalesynth show`."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from naive_sixdof import hexa_points, hexa_thetas, hexapod_points, rotation
from scalesynth.cli import app
from scalesynth.config import load_config
from scalesynth.cycle import analysis
from scalesynth.cycle.clearance import segment_distance
from scalesynth.dynamics import bodies
from scalesynth.mechanisms import get
from scalesynth.mechanisms.base import Mechanism

from conftest import ROOT

TILTED = [0.12, -0.08, 0.3]  # rad: a constant orientation that is not the identity
G = 9.80665  # m/s^2, the cycle's default gravity (-z)
CASES = [("hexa", (0.0, 0.0, -0.7), None), ("hexa", (0.08, -0.05, -0.6), TILTED),
         ("hexapod", (0.0, 0.0, 0.7), None), ("hexapod", (0.1, 0.05, 0.75), TILTED)]


def _geometry(name, pose, orientation):
    mech = get(name)
    opts = mech.resolve_options({} if orientation is None else {"orientation": orientation})
    d = mech.default_design()
    (q,) = [s.values for s in mech.inverse_kinematics(d, opts, pose) if s.label == mech.kernel_branch(opts)]
    return mech, d, opts, q, mech.link_geometry(d, opts, pose, q)


@pytest.mark.parametrize("name, pose, orientation", CASES)
def test_capsules_join_the_independent_joint_points(name, pose, orientation):
    mech, d, opts, q, geo = _geometry(name, pose, orientation)
    seg = {s.name: s for s in geo.segments}
    rot = rotation(orientation or (0.0, 0.0, 0.0))
    p = np.array(pose)
    if name == "hexa":
        c, e, r = hexa_points(d)
        theta = hexa_thetas(d, opts, p)
        np.testing.assert_allclose(q, theta, atol=1e-10)
        for i in range(6):
            elbow = c[i] + d["arm"] * (np.cos(theta[i]) * e[i] - np.sin(theta[i]) * np.array([0.0, 0.0, 1.0]))
            arm, rod = seg[f"upper_arm{i + 1}"], seg[f"rod{i + 1}"]
            np.testing.assert_allclose(arm.a, c[i], atol=1e-12)
            np.testing.assert_allclose(arm.b, elbow, atol=1e-10)
            np.testing.assert_allclose(rod.a, elbow, atol=1e-10)
            np.testing.assert_allclose(rod.b, p + rot @ r[i], atol=1e-12)
            assert np.linalg.norm(rod.b - rod.a) == pytest.approx(d["rod"], rel=1e-10)
        legs = {"upper_arm", "rod"}
    else:
        b, r = hexapod_points(d)
        for i in range(6):
            leg = seg[f"leg{i + 1}"]
            np.testing.assert_allclose(leg.a, b[i], atol=1e-12)
            np.testing.assert_allclose(leg.b, p + rot @ r[i], atol=1e-12)
            assert np.linalg.norm(leg.b - leg.a) == pytest.approx(q[i], rel=1e-12)
        legs = {"leg"}
    # base and platform: closed hexagons through the six base points and the six platform joints
    for body, pts in (("base", c if name == "hexa" else b), ("platform", p + r @ rot.T)):
        ring = [s for s in geo.segments if s.body == body]
        assert len(ring) == 6
        ends = sorted(tuple(np.round(v, 9)) for v in pts)
        assert sorted(tuple(np.round(s.a, 9)) for s in ring) == ends == sorted(tuple(np.round(s.b, 9)) for s in ring)
    assert {s.group for s in geo.segments} == {"base", "platform"} | legs
    assert [s.body for s in geo.segments][0] == "base" and geo.segments[-1].body == "platform"


@pytest.mark.parametrize("name, pose, orientation", [CASES[1], CASES[3]])
def test_adjacent_bodies_meet_at_their_joint(name, pose, orientation):
    _, _, _, _, geo = _geometry(name, pose, orientation)
    for pair in geo.adjacent:
        a, b = sorted(pair)
        assert {a, b} <= set(geo.bodies)
        gap = min(segment_distance(s.a, s.b, t.a, t.b) for s in geo.segments if s.body == a
                  for t in geo.segments if t.body == b)
        assert gap < 1e-9, (a, b, gap)
    names = {(geo.segments[i].body, geo.segments[j].body) for i, j in geo.checked_pairs()}
    leg = "rod" if name == "hexa" else "leg"
    assert (f"{leg}1", f"{leg}2") in names and (f"{leg}1", "platform") not in names
    assert len(geo.adjacent) == (18 if name == "hexa" else 12)


def test_link_radius_defaults_and_overrides():
    _, _, _, _, geo = _geometry("hexa", (0.0, 0.0, -0.7), None)
    r = {s.body: s.radius for s in geo.segments}
    assert (r["base"], r["upper_arm1"], r["rod4"], r["platform"]) == (0.04, 0.025, 0.01, 0.02)  # defaults, m
    mech = get("hexapod")
    opts = mech.resolve_options({"link_radius": {"leg": 0.03, "leg2": 0.05}})
    (q,) = [s.values for s in mech.inverse_kinematics(mech.default_design(), opts, (0.0, 0.0, 0.7))]
    r = {s.body: s.radius for s in mech.link_geometry(mech.default_design(), opts, (0.0, 0.0, 0.7), q).segments}
    assert (r["leg1"], r["leg2"], r["leg6"], r["base"]) == (0.03, 0.05, 0.03, 0.04)


@pytest.mark.parametrize("name, z", [("hexa", -0.7), ("hexapod", 0.7)])
def test_cycle_kinematics_equal_the_base_class_loop(name, z):
    mech = get(name)
    d = mech.default_design()
    for orientation in ([0.0, 0.0, 0.0], TILTED):
        o = mech.resolve_options({"orientation": orientation})
        poses = np.array([[0.0, 0.0, z], [0.1, -0.05, z + 0.05], [3.0, 0.0, z]])  # the last out of reach
        for label in (mech.kernel_branch(o), "in/out/in/out/out/out", "nonsense"):
            fast = mech.cycle_kinematics(d, o, poses, label)
            slow = Mechanism.cycle_kinematics(mech, d, o, poses, label)
            for a, b in zip(fast, slow, strict=True):
                np.testing.assert_allclose(a, b, rtol=1e-13, atol=1e-15)  # NaN rows equal too
        assert np.all(np.isnan(fast[0][2]))


def _static_forces_by_virtual_work(cfg, res):
    """tau = dV/dq at the cycle's first sample (at rest): V(q) the potential energy of every link segment and the
    payload at the assembly forward kinematics finds nearest the sample, turned to its own orientation."""
    mech, d, o = cfg.mech, cfg.resolved_design(), cfg.resolved_options()
    p0, q0 = res.traj.p[0], res.q[0]
    masses = bodies.segment_masses(mech.link_geometry(d, o, p0, q0), o, None, "m", mech.name)
    assert masses.sum() > 1.0  # kg: the check is not the payload's alone

    def potential(q):
        pose = min((s.values for s in mech.forward_kinematics(d, o, q)), key=lambda v: np.abs(v[:3] - p0).max())
        a, b, _ = mech.link_geometry(d, dict(o, orientation=list(pose[3:])), pose[:3], q).as_arrays()
        return float(masses @ (G * (a[:, 2] + b[:, 2]) / 2)) + res.payload * G * pose[2]

    h = 1e-6  # rad or m; FK converges to ~1e-13 relative, so the difference keeps ~1e-7 of tau
    return np.array([(potential(q0 + h * e) - potential(q0 - h * e)) / (2 * h) for e in np.eye(6)])


@pytest.mark.parametrize("name", ["hexa", "hexapod"])
def test_the_adept_cycle_runs_and_holds_the_robot_at_rest(tmp_path, name):
    """`scalesynth cycle` on the shipped config: exit 0, every file, finite forces; at the first sample (poly345
    starts at rest) the actuator forces equal dV/dq (module docstring) to 1e-6 of their largest: the links'
    weights and their moments about the held platform orientation included (without those moments the gap is
    0.5 % (hexapod) to 6 % (hexa))."""
    out = tmp_path / "cyc"
    res = CliRunner().invoke(app, ["cycle", str(ROOT / "configs" / f"{name}.yaml"), "--set", "cycle.samples=60",
                                   "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert {p.name for p in out.iterdir()} >= {"cycle.csv", "cycle.json", "actuators.png", "path.png"}
    data = np.genfromtxt(out / "cycle.csv", delimiter=",", names=True)
    forces = np.column_stack([data[f"force{i}"] for i in range(1, 7)])
    assert np.all(np.isfinite(forces)) and np.all(np.abs(forces).max(axis=0) > 0)
    metrics = json.loads((out / "cycle.json").read_text())["metrics"]
    assert metrics["cycle_feasible"] == 1 and metrics["cycle_min_clearance"] > 0
    cfg = load_config(ROOT / "configs" / f"{name}.yaml")
    cyc = cfg.cycle.model_copy(update={"samples": 60})
    run = analysis.analyse(cfg.mech, cfg.resolved_design(), cfg.resolved_options(), cyc, "m")
    assert run.traj.pdd[0].tolist() == [0.0, 0.0, 0.0] and run.traj.pd[0].tolist() == [0.0, 0.0, 0.0]
    np.testing.assert_allclose(run.force[0], forces[0], rtol=1e-6)  # the CLI's numbers are the analysis'
    tau = _static_forces_by_virtual_work(cfg, run)
    np.testing.assert_allclose(run.force[0], tau, rtol=0, atol=1e-6 * np.abs(tau).max())


@pytest.mark.parametrize("name, pose", [("hexa", "0.05,0.02,-0.7"), ("hexapod", "0.05,0.02,0.7")])
def test_show_draws_the_robot(tmp_path, name, pose):
    out = tmp_path / "show"
    res = CliRunner().invoke(app, ["show", str(ROOT / "configs" / f"{name}.yaml"), "--resolution", "12",
                                   "--out", str(out), "--pose", pose])
    assert res.exit_code == 0, res.output
    assert (out / "robot.png").stat().st_size > 0
    robot = json.loads((out / "show.json").read_text())["robot"]
    legs = [f"upper_arm{i}" for i in range(1, 7)] + [f"rod{i}" for i in range(1, 7)] if name == "hexa" else \
        [f"leg{i}" for i in range(1, 7)]
    assert {s["body"] for s in robot["segments"]} == {"base", "platform", *legs}
