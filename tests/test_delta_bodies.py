"""Bodies of the described Delta family (mechanisms/describe/bodies.py): link capsules against an independent
solution of each leg's closure, adjacency and radii, the Adept cycle through `scalesynth cycle` (static torques
against finite differences of that independent IK) and the robot drawing of `scalesynth show`.

The independent IK: each leg is solved in its own frame (the pose turned back by the leg's angle) by bracketing
the closure |Q - E(q)| - l over q and refining with scipy's brentq; the rotary Delta takes the root whose elbow
is farther out (the issue's 'elbows out'), the linear Delta the carriage nearer the base (its 'near' branch)."""

import json
import math

import numpy as np
import pytest
from scipy.optimize import brentq
from typer.testing import CliRunner

from fd_checks import central_differences
from scalesynth.cli import app
from scalesynth.cycle.clearance import segment_distance
from scalesynth.errors import InvalidParameter
from scalesynth.mechanisms import get

from conftest import ROOT

DELTA, LINEAR = get("delta"), get("linear-delta")
# the Briot-Arakelian-Glazunov Delta of configs/delta.yaml; 0.1 m parallelogram width (delta.yaml)
DELTA_DESIGN = {"base_radius": 0.25, "platform_radius": 0.2, "upper_arm": 0.75, "forearm": 0.95}
LINEAR_DESIGN = {"base_radius": 0.4, "platform_radius": 0.05, "forearm": 0.6}
PHI = [0.0, 2 * math.pi / 3, 4 * math.pi / 3]  # legs at 0, 120, 240 degrees (the conventions)


def _turn(v, phi):
    c, s = math.cos(phi), math.sin(phi)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]])


def _roots(f, lo, hi, n=4001):
    """Every root of f on [lo, hi]: sign changes on a fine grid, refined by brentq."""
    t = np.linspace(lo, hi, n)
    v = np.array([f(x) for x in t])
    return [brentq(f, t[k], t[k + 1], xtol=1e-14) for k in range(n - 1) if v[k] == 0 or v[k] * v[k + 1] < 0]


def delta_elbows(d, pose):
    """Elbow E_i and platform joint Q_i of each rotary-Delta leg (mechanism frame), elbows out."""
    out = []
    for phi in PHI:
        p = _turn(pose, -phi)  # the leg's own frame: arm in the xz-plane, axis along y
        q_pt = p + np.array([d["platform_radius"], 0.0, 0.0])

        def elbow(t):
            return np.array([d["base_radius"] + d["upper_arm"] * math.cos(t), 0.0, -d["upper_arm"] * math.sin(t)])

        ts = _roots(lambda t, q_pt=q_pt: np.linalg.norm(q_pt - elbow(t)) - d["forearm"], -math.pi, math.pi)
        t = max(ts, key=lambda t: elbow(t)[0])
        out.append((t, _turn(elbow(t), phi), _turn(q_pt, phi)))
    return out


def linear_carriages(d, pose, stroke=(0.0, 0.8)):
    """Carriage depth s_i, carriage C_i and platform joint Q_i of each linear-Delta leg, the carriage nearer the
    base (the smaller depth)."""
    out = []
    for phi in PHI:
        p = _turn(pose, -phi)
        q_pt = p + np.array([d["platform_radius"], 0.0, 0.0])

        def carriage(s):
            return np.array([d["base_radius"], 0.0, -s])

        s = min(_roots(lambda s, q_pt=q_pt: np.linalg.norm(q_pt - carriage(s)) - d["forearm"], *stroke))
        out.append((s, _turn(carriage(s), phi), _turn(q_pt, phi)))
    return out


def _geometry(mech, design, pose, **options):
    opts = mech.resolve_options(options)
    (q,) = [s.values for s in mech.inverse_kinematics(design, opts, pose) if s.label == mech.kernel_branch(opts)]
    return q, mech.link_geometry(design, opts, pose, q)


def _by_name(geo):
    return {s.name: s for s in geo.segments}


DELTA_POSES = [(0.0, 0.0, -1.0), (0.31, -0.12, -0.85), (-0.4, 0.25, -1.3), (0.05, 0.45, -0.6)]


@pytest.mark.parametrize("pose", DELTA_POSES)
def test_delta_capsules_end_at_the_elbows_and_platform_joints(pose):
    q, geo = _geometry(DELTA, DELTA_DESIGN, pose)
    seg = _by_name(geo)
    w = 0.1
    for i, (theta, e, jq) in enumerate(delta_elbows(DELTA_DESIGN, np.array(pose)), 1):
        assert q[i - 1] == pytest.approx(theta, abs=1e-9)
        axis = np.array([-math.sin(PHI[i - 1]), math.cos(PHI[i - 1]), 0.0])  # the arm's actuated axis
        base = DELTA_DESIGN["base_radius"] * np.array([math.cos(PHI[i - 1]), math.sin(PHI[i - 1]), 0.0])
        arm = seg[f"upper_arm{i}"]
        np.testing.assert_allclose(arm.a, base, atol=1e-12)
        np.testing.assert_allclose(arm.b, e, atol=1e-9)
        # the parallelogram: two bars of the forearm's length, w apart along the arm axis, centred on E -> Q
        bar_a, bar_b = seg[f"forearm{i}a"], seg[f"forearm{i}b"]
        np.testing.assert_allclose(bar_a.a - bar_b.a, w * axis, atol=1e-12)
        np.testing.assert_allclose(bar_a.b - bar_b.b, w * axis, atol=1e-12)
        np.testing.assert_allclose(0.5 * (bar_a.a + bar_b.a), e, atol=1e-9)
        np.testing.assert_allclose(0.5 * (bar_a.b + bar_b.b), jq, atol=1e-12)
        for bar in (bar_a, bar_b):
            assert np.linalg.norm(bar.b - bar.a) == pytest.approx(0.95, rel=1e-9)
        elbow = seg[f"elbow{i}"]  # the elbow's short side, part of the upper arm
        assert elbow.body == f"upper_arm{i}"
        np.testing.assert_allclose(0.5 * (elbow.a + elbow.b), e, atol=1e-9)
    # the platform: a closed hexagon through the six bar ends, at the pose's height
    plat = [s for s in geo.segments if s.body == "platform"]
    assert len(plat) == 6
    ends = sorted(tuple(np.round(s.b, 9)) for s in geo.segments if s.body.startswith("forearm"))
    assert sorted(tuple(np.round(s.a, 9)) for s in plat) == ends == sorted(tuple(np.round(s.b, 9)) for s in plat)
    # the base: the triangle through the actuated-axis points
    assert len([s for s in geo.segments if s.body == "base"]) == 3


@pytest.mark.parametrize("pose", [(0.0, 0.0, -0.9), (0.15, -0.1, -0.7), (-0.12, 0.2, -1.1)])
def test_linear_delta_capsules_end_at_the_carriages_and_platform_joints(pose):
    q, geo = _geometry(LINEAR, LINEAR_DESIGN, pose)
    seg = _by_name(geo)
    for i, (s, c, jq) in enumerate(linear_carriages(LINEAR_DESIGN, np.array(pose)), 1):
        assert q[i - 1] == pytest.approx(s, abs=1e-9)
        base = LINEAR_DESIGN["base_radius"] * np.array([math.cos(PHI[i - 1]), math.sin(PHI[i - 1]), 0.0])
        np.testing.assert_allclose(seg[f"rail{i}"].a, base, atol=1e-12)  # the stroke [0, 0.8] down the rail
        np.testing.assert_allclose(seg[f"rail{i}"].b, base - [0.0, 0.0, 0.8], atol=1e-12)
        carriage = seg[f"carriage{i}"]
        np.testing.assert_allclose(0.5 * (carriage.a + carriage.b), c, atol=1e-9)
        assert np.linalg.norm(carriage.b - carriage.a) == pytest.approx(0.08, rel=1e-12)
        bar_a, bar_b = seg[f"forearm{i}a"], seg[f"forearm{i}b"]
        np.testing.assert_allclose(0.5 * (bar_a.b + bar_b.b), jq, atol=1e-12)
        for bar in (bar_a, bar_b):
            assert np.linalg.norm(bar.b - bar.a) == pytest.approx(0.6, rel=1e-9)


def test_a_zero_width_draws_one_bar_on_the_centre_line():
    desc = DELTA.description.model_dump()
    desc["legs"][0]["width"] = 0.0
    from scalesynth.mechanisms.describe import from_description, parse_description

    mech = from_description(parse_description(desc))
    pose = DELTA_POSES[1]
    _, geo = _geometry(mech, DELTA_DESIGN, pose)
    seg = _by_name(geo)
    for i, (_, e, jq) in enumerate(delta_elbows(DELTA_DESIGN, np.array(pose)), 1):
        np.testing.assert_allclose(seg[f"forearm{i}"].a, e, atol=1e-9)
        np.testing.assert_allclose(seg[f"forearm{i}"].b, jq, atol=1e-12)
        assert f"elbow{i}" not in seg and f"forearm{i}a" not in seg
    assert len([s for s in geo.segments if s.body == "platform"]) == 3


@pytest.mark.parametrize("mech, design, pose", [(DELTA, DELTA_DESIGN, DELTA_POSES[1]),
                                                (LINEAR, LINEAR_DESIGN, (0.15, -0.1, -0.7))])
def test_adjacent_bodies_meet_at_their_joint_and_groups_name_every_body(mech, design, pose):
    _, geo = _geometry(mech, design, pose)
    bodies = set(geo.bodies)
    for pair in geo.adjacent:
        a, b = sorted(pair)
        assert {a, b} <= bodies
        gap = min(segment_distance(s.a, s.b, t.a, t.b) for s in geo.segments if s.body == a
                  for t in geo.segments if t.body == b)
        if a.startswith("forearm") and b.startswith("rail"):
            # not a joint: exempt because the model puts the carriage's joint on the rail's line; the bars start
            # half the width (0.04 m) to either side of it
            assert gap <= 0.04 * (1 + 1e-12)
        else:
            assert gap < 1e-9, (a, b, gap)  # a joint: the capsules touch
    groups = {s.group for s in geo.segments}
    legs = {"upper_arm", "forearm"} if mech is DELTA else {"rail", "carriage", "forearm"}
    assert groups == {"base", "platform"} | legs
    for s in geo.segments:
        assert s.body.rstrip("123") == s.group
    # one parallelogram is one body: its two bars are never a checked pair; forearms of different legs are
    names = [(geo.segments[i].body, geo.segments[j].body) for i, j in geo.checked_pairs()]
    assert ("forearm1", "forearm1") not in names and ("forearm1", "forearm2") in names


def test_link_radius_by_group_and_by_body():
    pose = DELTA_POSES[0]
    _, geo = _geometry(DELTA, DELTA_DESIGN, pose)
    r = {s.body: s.radius for s in geo.segments}
    assert (r["base"], r["upper_arm1"], r["forearm2"], r["platform"]) == (0.04, 0.025, 0.01, 0.02)  # defaults, m
    _, geo = _geometry(DELTA, DELTA_DESIGN, pose, link_radius={"forearm": 0.005, "upper_arm2": 0.05})
    r = {s.body: s.radius for s in geo.segments}
    assert (r["forearm1"], r["forearm3"], r["upper_arm1"], r["upper_arm2"]) == (0.005, 0.005, 0.025, 0.05)
    _, geo = _geometry(DELTA, DELTA_DESIGN, pose, link_radius=0.03)
    assert {s.radius for s in geo.segments} == {0.03}
    with pytest.raises(InvalidParameter, match=r"^options.link_radius.elbow: unknown body"):
        DELTA.resolve_options({"link_radius": {"elbow": 0.01}})


def _finite_difference_velocity_map(solve, pose, h=1e-6):
    """dq/dx (3x3) by central differences of an independent IK ``solve(pose) -> q``."""
    return central_differences(solve, pose, h)


@pytest.mark.parametrize("config, solve", [
    ("delta.yaml", lambda p: [t for t, _, _ in delta_elbows(DELTA_DESIGN, p)]),
    ("linear_delta.yaml", lambda p: [s for s, _, _ in linear_carriages(LINEAR_DESIGN, p)]),
])
def test_the_adept_cycle_runs_through_the_cli(tmp_path, config, solve):
    """`scalesynth cycle` on the shipped config: exit 0, cycle.csv with every column, finite forces; at the first
    sample (at rest: poly345 starts with zero acceleration) the actuator forces of massless links
    (dynamics.masses {}) hold the 1 kg payload's weight: A^T tau = m g_up with A = dq/dx from finite differences of
    the independent IK."""
    out = tmp_path / "cyc"
    res = CliRunner().invoke(app, ["cycle", str(ROOT / "configs" / config), "--set", "cycle.samples=80",
                                   "--set", "dynamics.masses={}", "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert {p.name for p in out.iterdir()} >= {"cycle.csv", "cycle.json", "actuators.png", "path.png"}
    data = np.genfromtxt(out / "cycle.csv", delimiter=",", names=True)
    cols = set(data.dtype.names)
    assert {"t", "p_x", "p_z", "q1", "qd2", "qdd3", "force1", "force2", "force3", "lci", "clearance"} <= cols
    forces = np.column_stack([data[f"force{i}"] for i in (1, 2, 3)])
    assert np.all(np.isfinite(forces)) and np.all(np.abs(forces).max(axis=0) > 0)
    metrics = json.loads((out / "cycle.json").read_text())["metrics"]
    assert metrics["cycle_feasible"] == 1 and metrics["cycle_min_clearance"] > 0
    p0 = np.array([data["p_x"][0], data["p_y"][0], data["p_z"][0]])
    assert data["pdd_z"][0] == 0.0 and data["pdd_x"][0] == 0.0
    a = _finite_difference_velocity_map(solve, p0)
    np.testing.assert_allclose(a.T @ forces[0], [0.0, 0.0, 9.80665], atol=1e-6)


def test_show_draws_the_delta(tmp_path):
    out = tmp_path / "show"
    res = CliRunner().invoke(app, ["show", str(ROOT / "configs" / "delta.yaml"), "--resolution", "16",
                                   "--out", str(out), "--pose", "0.1,0.05,-1.0"])
    assert res.exit_code == 0, res.output
    assert (out / "robot.png").stat().st_size > 0
    robot = json.loads((out / "show.json").read_text())["robot"]
    assert robot["branch"] == "out/out/out" and robot["pose"] == [0.1, 0.05, -1.0]
    assert {s["body"] for s in robot["segments"]} == {"base", "platform", "upper_arm1", "upper_arm2", "upper_arm3",
                                                      "forearm1", "forearm2", "forearm3"}
