"""A description whose legs do not make its motion type is refused (describe/mobility_check.py): one line naming the
leg and the field, exit 2 through the CLI. The two broken Deltas are confirmed by scalesynth.mobility's screw
analysis (written for the seed mechanisms): each leg as its actuator R(B, n), then what its parallelogram lets the
platform do relative to the arm (a rotation about the elbow's hinge line, the swing about n, a translation along
n x f, and the swing about t = n x f / |n x f|, a translation along t x f), the platform's freedom the reciprocal of
all legs' constraint wrenches."""

import copy

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from scalesynth import mobility
from scalesynth.cli import app
from scalesynth.mechanisms.describe import from_description, parse_description

from conftest import ROOT

DELTA_DESC = yaml.safe_load((ROOT / "src" / "scalesynth" / "mechanisms" / "delta.yaml").read_text())


def _legs(*changes):
    """The Delta with its pattern written out as three legs, leg k updated by changes[k]."""
    desc = copy.deepcopy(DELTA_DESC)
    desc["name"] = "broken-delta"
    leg = desc["legs"][0]
    leg.pop("pattern")
    desc["legs"] = [{**leg, "angle_deg": a, **c} for a, c in zip((0, 120, 240), changes, strict=True)]
    return desc


IDENTICAL = _legs({}, {"angle_deg": 0}, {})  # legs 1 and 2 the same leg
PARALLEL = _legs({}, {"angle_deg": 180}, {"angle_deg": 0, "base": ["base_radius", 0.3, 0],  # every arm axis along y
                                          "platform": ["platform_radius", 0.3, 0]})


def _joint(kind, point, axis):
    point = None if point is None else tuple(float(v) for v in point)
    return mobility.Joint(kind, point, (tuple(float(v) for v in axis),)).screws()[0]


def _chains(desc, pose, locked):
    """Each leg's twists: its actuator (unless locked), then its parallelogram's."""
    mech = from_description(parse_description(desc))  # the caller switches the mobility check off
    d, o = mech.default_design(), mech.resolve_options({})
    (q,) = [s.values for s in mech.inverse_kinematics(d, o, pose) if s.label == mech.kernel_branch(o)]
    chains = []
    for leg, qi in zip(mech.legs(d, o), q, strict=True):
        e, n = leg.actuated_point(qi), leg.normal
        f = np.asarray(pose) + leg.platform - e
        t = np.cross(n, f)
        parallelogram = [_joint("R", e, n), _joint("P", None, t), _joint("P", None, np.cross(t, f))]
        chains.append(parallelogram if locked else [_joint("R", leg.base, n), *parallelogram])
    return chains


def test_the_screw_analysis_confirms_what_the_check_refuses(monkeypatch):
    from scalesynth.mechanisms.describe import mobility_check

    monkeypatch.setattr(mobility_check, "check_mobility", lambda d: None)
    pose = (0.05, -0.03, -1.0)
    assert mobility.screw_mobility(_chains(DELTA_DESC, pose, locked=False)) == (3, "3T")
    assert mobility.screw_mobility(_chains(DELTA_DESC, pose, locked=True))[0] == 0
    # every arm axis along y: the platform turns about y as well (3T1R, 4 DOF)
    assert mobility.screw_mobility(_chains(PARALLEL, (0.0, 0.15, -1.0), locked=False)) == (4, "3T1R")
    # two identical legs: 3T while driven, but one translation is left with the actuators locked
    assert mobility.screw_mobility(_chains(IDENTICAL, pose, locked=False)) == (3, "3T")
    assert mobility.screw_mobility(_chains(IDENTICAL, pose, locked=True))[0] == 1


@pytest.mark.parametrize("desc, start", [
    (IDENTICAL, "legs[1] (arm).base: repeats another leg, so the platform can translate with every actuator locked"),
    (PARALLEL, "legs[2] (arm).arm_zero: every leg's parallelogram hinges about (0, 1, 0), so the platform can turn"),
])
def test_a_description_of_the_wrong_mobility_is_one_line_exit_2(tmp_path, desc, start):
    _evaluate_is_one_line(tmp_path, desc, "delta.yaml", start)


def _evaluate_is_one_line(tmp_path, desc, config, start):
    """`evaluate` of configs/``config`` pointed at the description ``desc`` exits 2 with one line starting so."""
    (tmp_path / "robot.yaml").write_text(yaml.safe_dump(desc))
    cfg = yaml.safe_load((ROOT / "configs" / config).read_text())
    cfg["mechanism"] = {"description": "robot.yaml"}
    cfg.pop("cycle", None)
    (tmp_path / "run.yaml").write_text(yaml.safe_dump(cfg))
    out = CliRunner().invoke(app, ["evaluate", str(tmp_path / "run.yaml")])
    lines = [ln for ln in out.output.strip().splitlines() if not ln.startswith("note: compiling")]
    assert out.exit_code == 2 and len(lines) == 1, out.output
    assert lines[0].startswith("error: mechanism.description (robot.yaml): " + start), lines[0]
    assert len(lines[0]) <= 200 + len("error: ")


def test_the_builtin_descriptions_pass():
    for name in ("delta", "linear-delta", "planar-fivebar-described"):
        parse_description(yaml.safe_load((ROOT / "src" / "scalesynth" / "mechanisms" / f"{name}.yaml").read_text()))


# ----- motion 2T: the described five-bar and three broken copies -------------------------------------------------
FIVEBAR_DESC = yaml.safe_load((ROOT / "src" / "scalesynth" / "mechanisms" / "planar-fivebar-described.yaml")
                              .read_text())


def _fivebar(legs):
    return {**copy.deepcopy(FIVEBAR_DESC), "name": "broken-fivebar", "legs": legs}


RIGHT, LEFT = FIVEBAR_DESC["legs"]
TWIN = _fivebar([RIGHT, {**RIGHT, "name": "copy"}])  # the right leg twice
# a second crank on the right leg's pivot, its zero turned by 90 degrees: same elbow, same link
SAME_PIVOT = _fivebar([RIGHT, {**RIGHT, "name": "turned", "arm_zero": [0, 1, 0], "arm_positive": [-1, 0, 0]}])
EXTRA = _fivebar([RIGHT, LEFT, {**LEFT, "name": "extra", "base": [0, 0, 0]}])  # a third actuated leg
MISSING = _fivebar([RIGHT, {**LEFT, "links": {"arm": "l1"}}])  # the left link and its pin joint left out


def _planar_chains(desc, pose, locked):
    """Each leg as the platform point's translations (the platform does not turn, mobility_check.py): its actuated
    point's motion (unless locked), then its link's swing normal to the link."""
    mech = from_description(parse_description(desc))
    d, o = mech.default_design(), mech.resolve_options({})
    (q,) = [s.values for s in mech.inverse_kinematics(d, o, pose) if s.label == mech.kernel_branch(o)]
    chains = []
    for leg, qi in zip(mech.legs(d, o), q, strict=True):
        f = np.asarray(pose) + leg.platform - leg.actuated_point(qi)
        swing = [_joint("Pa", None, (-f[1], f[0], 0.0))]
        chains.append(swing if locked else [_joint("Pa", None, (*leg.actuated_velocity(qi), 0.0)), *swing])
    return chains


def test_the_screw_analysis_confirms_the_planar_check(monkeypatch):
    from scalesynth.mechanisms.describe import mobility_check

    monkeypatch.setattr(mobility_check, "check_mobility", lambda d: None)
    pose = (100.0, -800.0)  # mm, inside the five-bar's workspace (elbows out)
    assert mobility.screw_mobility(_planar_chains(FIVEBAR_DESC, pose, locked=False)) == (2, "2T")
    assert mobility.screw_mobility(_planar_chains(FIVEBAR_DESC, pose, locked=True))[0] == 0
    for broken in (TWIN, SAME_PIVOT):  # driven 2T, but the platform keeps a translation with the actuators locked
        assert mobility.screw_mobility(_planar_chains(broken, pose, locked=False)) == (2, "2T")
        assert mobility.screw_mobility(_planar_chains(broken, pose, locked=True)) == (1, "1T")


@pytest.mark.parametrize("desc, start", [
    (TWIN, "legs[1] (copy).base: repeats another leg, so the platform can move with every actuator locked"),
    (SAME_PIVOT, "legs[1] (turned).base: the platform can move with every actuator locked (the links are parallel)"),
    (EXTRA, "legs[2] (extra): motion 2T needs 2 actuated legs (a square Jacobian), these give 3"),
    (MISSING, "legs[1] (left).links: RR needs arm, forearm (missing forearm)"),
])
def test_a_planar_description_of_the_wrong_mobility_is_one_line_exit_2(tmp_path, desc, start):
    _evaluate_is_one_line(tmp_path, desc, "fivebar_described.yaml", start)
