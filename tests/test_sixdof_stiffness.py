"""Stiffness frames of the described 6-DOF mechanisms (mechanisms/describe/frame6.py): the reference solver against
PyNite rebuilt from the reported model (tests/fe_pynite.py, an independent frame FE package) at three poses each,
to 0.1 % as for the seed mechanisms; the hexapod's exactly the classical Gough-Stewart stiffness K = J^T diag(k_i) J
(Gosselin 1990, "Stiffness mapping for parallel manipulators", IEEE Trans. Robot. Autom. 6(3)) with the joint
points of tests/naive_sixdof.py; the Hexa's links made stiffer converging to its actuator-only stiffness
A^T k A (A = dq/d(v, omega), the velocity map); the `stiffness` command on both configs; bad input one line."""

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

from naive_sixdof import hexapod_points, rotation
from scalesynth.cli import app
from scalesynth.mechanisms import get
from scalesynth.stiffness.solve import solve

from conftest import ROOT
from fe_pynite import solve_model

FE_TOL = 1e-3  # issue 12's 0.1 %, as test_stiffness_seeds.py
TILTED = [0.12, -0.08, 0.3]  # rad
HEXA, HEXAPOD = get("hexa"), get("hexapod")
HEXA_POSES = [((0.0, 0.0, -0.7), None), ((0.1, -0.05, -0.8), None), ((0.08, -0.05, -0.6), TILTED)]
HEXAPOD_POSES = [((0.0, 0.0, 0.7), None), ((0.12, -0.08, 0.8), None), ((0.1, 0.05, 0.75), TILTED)]


def model(mech, pose, orientation=None, joints="ideal", **opts):
    if orientation is not None:
        opts["orientation"] = orientation
    return mech.stiffness_model(mech.default_design(), mech.resolve_options(opts), pose, joints)


@pytest.mark.parametrize("joints", ["ideal", "bonded"])
@pytest.mark.parametrize("mech, pose, orientation", [*((HEXA, p, o) for p, o in HEXA_POSES),
                                                     *((HEXAPOD, p, o) for p, o in HEXAPOD_POSES)])
def test_the_frame_agrees_with_pynite(mech, pose, orientation, joints):
    m = model(mech, pose, orientation, joints, load=[10.0, -20.0, -150.0])
    res = solve(m)
    assert not res.singular and res.dofs == ("x", "y", "z", "rx", "ry", "rz")
    assert np.max(np.abs(res.K - res.K.T)) <= 1e-9 * np.max(np.abs(res.K)) and np.linalg.eigvalsh(res.K)[0] > 0
    fe = solve_model(m.to_dict())
    assert np.max(np.abs(fe - res.deflection)) < FE_TOL * np.linalg.norm(res.deflection)


@pytest.mark.parametrize("pose, orientation", HEXAPOD_POSES)
def test_the_hexapod_is_the_gough_stewart_stiffness(pose, orientation):
    """K = sum_i k_i m_i m_i^T, m_i = [n_i; rho_i x n_i] the unit leg's Pluecker line (n_i from B_i to Q_i =
    P + R r_i, rho_i = R r_i), each leg a bar of axial compliance 1/k_i = 1/k + L_i / EA (actuator spring in series
    with the cylinder and the piston, together the leg's length): exact, so to round-off."""
    k = 2e7  # N/m, the default
    d = HEXAPOD.default_design()
    ea = 70e9 * math.pi / 4 * (0.04**2 - 0.034**2)  # N, the default 40 x 3 mm aluminium tube
    b, r = hexapod_points(d)
    rho = r @ rotation(orientation or (0.0, 0.0, 0.0)).T
    expected = np.zeros((6, 6))
    for bi, ri in zip(b, rho, strict=True):
        leg = np.asarray(pose) + ri - bi
        length = np.linalg.norm(leg)
        n = leg / length
        m = np.concatenate([n, np.cross(ri, n)])
        expected += np.outer(m, m) / (1.0 / k + length / ea)
    res = solve(model(HEXAPOD, pose, orientation))
    np.testing.assert_allclose(res.K, expected, rtol=0, atol=1e-9 * np.abs(expected).max())


def test_stiffer_hexa_links_converge_to_the_actuator_stiffness():
    """Links e times stiffer: K tends to A^T k A (A the velocity map, q_dot = A [v; omega], k the arm actuators'
    torsional stiffness), the gap shrinking ~10x per decade of e."""
    pose, kq = (0.1, -0.05, -0.8), 1e4
    d = HEXA.default_design()
    opts = HEXA.resolve_options({})
    (q,) = [s.values for s in HEXA.inverse_kinematics(d, opts, pose) if s.label == HEXA.kernel_branch(opts)]
    a = HEXA.velocity_map(d, opts, pose, q)
    ka = kq * a.T @ a
    gaps = []
    for e in (1e2, 1e3, 1e4):
        res = solve(model(HEXA, pose, youngs_modulus=70 * e, actuator_stiffness=kq))
        gaps.append(np.max(np.abs(res.K - ka)) / np.max(np.abs(ka)))
    assert gaps[2] < 1e-3
    assert gaps[0] / gaps[1] == pytest.approx(10, rel=0.1) and gaps[1] / gaps[2] == pytest.approx(10, rel=0.1)


@pytest.mark.parametrize("name, pose, groups, kind", [("hexa", "0.1,-0.05,-0.8", ["rod", "upper_arm"], "revolute"),
                                                      ("hexapod", "0.12,-0.08,0.8", ["leg"], "prismatic")])
def test_the_stiffness_command_on_the_configs(name, pose, groups, kind):
    out = CliRunner().invoke(app, ["stiffness", str(ROOT / "configs" / f"{name}.yaml"), f"--pose={pose}",
                                   "--load=0,30,-150", "--json"])
    assert out.exit_code == 0, out.output
    data = json.loads(out.output)
    assert data["mechanism"] == name and data["units"]["length"] == "m"
    assert sorted({link["group"] for link in data["model"]["links"]}) == groups and len(data["model"]["links"]) == 12
    assert [a["kind"] for a in data["model"]["actuators"]] == [kind] * 6
    gap = np.max(np.abs(np.subtract(data["deflection"], solve_model(data["model"]))))
    assert gap < FE_TOL * data["deflection_norm"]


@pytest.mark.parametrize("args, field", [
    (["--pose=0,0,3"], "pose"),  # legs at most 1 m long: out of reach
    (["--pose=0,0,0.7", "--set", "sections={rod: [0.04, 0.003]}"], "options.sections.rod"),
    (["--pose=0,0,0.7", "--set", "actuator_stiffness=-1"], "options.actuator_stiffness"),
])
def test_bad_input_is_one_line(args, field):
    out = CliRunner().invoke(app, ["stiffness", str(ROOT / "configs" / "hexapod.yaml"), *args])
    assert out.exit_code == 2 and out.output.strip().startswith(f"error: {field}"), out.output
    assert len(out.output.strip().splitlines()) == 1
