"""The stiffness frame of described 2T mechanisms (describe/frame2.py): the described five-bar's frame solves to the
hand-written planar-fivebar's (forearm 'single', the 5R: the same idealisation, so the same K to 1e-9), and PyNite
(tests/fe_pynite.py, a maintained FE package) rebuilt from the printed model gives the same deflection on random
poses of the five-bar and of a biglide (two PR legs; its rails along y, where PyNite's support springs act). NumPy
only: nothing here compiles a kernel."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from scalesynth.cli import app
from scalesynth.errors import InvalidParameter
from scalesynth.mechanisms import get
from scalesynth.mechanisms.describe import from_description, parse_description
from scalesynth.stiffness.solve import solve

from fe_pynite import solve_model

HAND = get("planar-fivebar")
FIVEBAR = get("planar-fivebar-described")
# two PR legs on vertical rails x = +-gap, links pinned at the platform point
BIGLIDE_Y = {
    "name": "biglide-y-test", "title": "PR pair on rails along y (test)", "motion": "2T", "length_unit": "m",
    "parameters": {"gap": {"default": 0.3, "doc": "rail half distance"}, "link": {"default": 0.6, "doc": "link"}},
    "options": {"stroke": {"kind": "range", "default": [-0.5, 0.5], "doc": "carriage range"}},
    "legs": [{"type": "PR", "name": "right", "base": ["gap", 0, 0], "platform": [0, 0, 0],
              "links": {"forearm": "link"}, "rail": [0, 1, 0], "branch": "far", "limits": "stroke"},
             {"type": "PR", "name": "left", "base": ["-gap", 0, 0], "platform": [0, 0, 0],
              "links": {"forearm": "link"}, "rail": [0, 1, 0], "branch": "far", "limits": "stroke"}],
}


def _poses(mech, design, options, k, seed):
    """k random points of the bounding box inside the workspace (the frame's own test: it raises outside)."""
    from scalesynth.errors import InvalidPose

    rng = np.random.default_rng(seed)
    lo, hi = (v[:2] for v in mech.bounding_box(design, options))
    out = []
    while len(out) < k:
        p = rng.uniform(lo, hi)
        try:
            mech.stiffness_model(design, options, p)
        except InvalidPose:
            continue
        out.append(p)
    return out


@pytest.mark.parametrize("joints", ["ideal", "bonded"])
def test_described_fivebar_frame_equals_the_hand_written(joints):
    """Random designs and poses: the platform stiffness K (x, y; bonded also rz) of both frames agrees to 1e-9
    relative (measured: 4e-14), as does the deflection under the default 150 N along -y."""
    rng = np.random.default_rng(20263)
    for _ in range(3):
        design = {"r": rng.uniform(50, 400), "l1": rng.uniform(250, 800), "l2": rng.uniform(500, 1400)}
        for p in _poses(FIVEBAR, design, FIVEBAR.resolve_options({}), 3, int(rng.integers(1 << 30))):
            hand = solve(HAND.stiffness_model(design, HAND.resolve_options({}), p, joints))
            ours = solve(FIVEBAR.stiffness_model(design, FIVEBAR.resolve_options({}), p, joints))
            assert ours.dofs == hand.dofs
            assert np.abs(ours.K - hand.K).max() <= 1e-9 * np.abs(hand.K).max()
            assert np.linalg.norm(ours.deflection - hand.deflection) <= 1e-9 * np.linalg.norm(hand.deflection)


@pytest.mark.parametrize("joints", ["ideal", "bonded"])
@pytest.mark.parametrize("which", ["fivebar", "biglide"])
def test_planar_frame_against_pynite(which, joints):
    """PyNite's deflection of the printed model equals the reference solver's to 1e-9 relative on 4 random poses
    (measured: 2e-13; no rigid bodies of several points, so no penalty members)."""
    mech = FIVEBAR if which == "fivebar" else from_description(parse_description(BIGLIDE_Y))
    design, options = mech.default_design(), mech.resolve_options({})
    for p in _poses(mech, design, options, 4, 20264):
        model = mech.stiffness_model(design, options, p, joints)
        ours, fe = solve(model).deflection, solve_model(model.to_dict())
        assert np.linalg.norm(ours - fe) <= 1e-9 * np.linalg.norm(fe), (p, ours, fe)


def test_cli_stiffness_of_the_described_fivebar():
    """`scalesynth stiffness planar-fivebar-described --json` prints the hand-written 5R's deflection at (0, -725)
    mm (-1.35027 mm under 150 N, its own solve) and a model PyNite rebuilds; a stiffness block sets defaults."""
    out = CliRunner().invoke(app, ["stiffness", "planar-fivebar-described", "--pose=0,-725", "--load=20,-150",
                                   "--json"])
    assert out.exit_code == 0, out.output
    data = json.loads(out.output)
    opts = HAND.resolve_options({"load": [20.0, -150.0]})
    hand = solve(HAND.stiffness_model(HAND.default_design(), opts, (0.0, -725.0))).deflection
    np.testing.assert_allclose(data["deflection"], hand, rtol=1e-9, atol=1e-12 * np.abs(hand).max())
    np.testing.assert_allclose(solve_model(data["model"]), hand, rtol=1e-9, atol=1e-12 * np.abs(hand).max())
    desc = parse_description({**BIGLIDE_Y, "stiffness": {"sections": {"forearm": [0.05, 0.004]},
                                                         "actuator_stiffness": 3.0e7}})
    options = from_description(desc).resolve_options({})
    assert options["sections"] == {"forearm": [0.05, 0.004]} and options["actuator_stiffness"] == 3.0e7


def test_unequal_platform_offsets_are_refused_in_one_line():
    """Links pinned at two platform points leave the platform free to turn in this frame: one line naming the
    leg's platform field."""
    desc = parse_description({**BIGLIDE_Y, "legs": [BIGLIDE_Y["legs"][0],
                                                    {**BIGLIDE_Y["legs"][1], "platform": [-0.05, 0, 0]}]})
    mech = from_description(desc)
    with pytest.raises(InvalidParameter) as err:
        mech.stiffness_model(mech.default_design(), mech.resolve_options({}), (0.0, 0.0))
    line = str(err.value)
    assert line.startswith("legs[1] (left).platform: the planar stiffness frame needs every link pinned at one "
                           "platform point") and "\n" not in line and len(line) <= 200
