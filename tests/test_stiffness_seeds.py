"""Pose-level stiffness models of seeds 000-002 (issue 12): 2pauu-ppap, pprs-rprs, rps-upu and rps-upu-tool.

For each mechanism: the reference solver's deflection against PyNite rebuilt from the reported ``model`` (an
independent frame FE package, checked on textbook cases in test_stiffness.py / test_stiffness_spatial.py) at poses
that include the workspace-box corners (the reachable grid points nearest each corner), the centre and near-singular
poses, to 0.1 % (issue 12); K symmetric positive definite; links 1e3 ... 1e5 times stiffer converge to the
actuator-only model built from the mechanism's own Jacobian; deflection linear in the load; a singular pose is
infinite, never NaN; bad input is one line naming it, exit 2."""

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

from scalesynth.cli import app
from scalesynth.mechanisms import get
from scalesynth.mechanisms.pprs_rprs import Geometry, chain_state, sigma_vector, twist_jacobian
from scalesynth.stiffness.solve import solve

from fe_pynite import solve_model

FE_TOL = 1e-3  # issue 12: 0.1 %


def fe_gap(model, rigid=1e4):
    """max |PyNite - ours| / |ours| of the deflection (PyNite rebuilt from the reported model dict)."""
    ours = solve(model).deflection
    fe = solve_model(model.to_dict(), rigid)
    return float(np.max(np.abs(fe - ours)) / np.linalg.norm(ours))


def scaled(C, length):
    """Compliance with rotations measured as arc lengths at ``length`` (every entry in length/N)."""
    s = np.r_[np.ones(3), np.full(C.shape[0] - 3, length)]
    return C * np.outer(s, s)


def cli(*args):
    return CliRunner().invoke(app, ["stiffness", *args])


def assert_converges(gaps):
    """Gaps to the rigid-link limit at three decades of link stiffness: < 1e-4 at the last, 10x smaller per decade."""
    assert gaps[2] < 1e-4
    assert gaps[0] / gaps[1] == pytest.approx(10, rel=0.05) and gaps[1] / gaps[2] == pytest.approx(10, rel=0.05)


def assert_spd(model, dofs):
    """Not singular, platform DOFs ``dofs``, K symmetric positive definite."""
    res = solve(model)
    assert not res.singular and res.dofs == dofs and res.K.shape == (len(dofs), len(dofs))
    assert np.max(np.abs(res.K - res.K.T)) <= 1e-10 * np.max(np.abs(res.K))
    assert np.linalg.eigvalsh(res.K)[0] > 0


def assert_linear(model_with_load):
    """Superposition: the deflection under f1 + f2 is the sum of those under f1 and f2 (to 1e-12)."""
    f1, f2 = [5.0, -7.0, -150.0], [30.0, 10.0, 2.0]
    d1, d2, d3 = (solve(model_with_load(f)).deflection for f in (f1, f2, list(np.add(f1, f2))))
    assert np.max(np.abs(d3 - d1 - d2)) < 1e-12 * np.linalg.norm(d3)


SPATIAL = ("x", "y", "z", "rx", "ry", "rz")


# ----- seed 001: pprs-rprs ----------------------------------------------------------------------------------------
PPRS = get("pprs-rprs")
PPRS_DESIGN = PPRS.resolve_design({})  # paper Table 1: r = 160, R = 180, L1 = 100, L2 = L3 = 120 mm
# O1 poses (mm) at zero orientation, mode +++, found on a 41^3 grid of the workspace box: its centroid, (0, 0, 200),
# the reachable grid points nearest four box corners, the lowest-LCI corner (-80, -62.97, 202.5; LCI 0.018), a pose
# 4.9 mm above the forward-singular surface (LCI 0.0019: det J_t vanishes at z = 120.0869, PPRS_SINGULAR) and the
# pose nearest a serial singularity (kappa3 = 3.5 mm: link 3 almost along e3)
PPRS_POSES = [(-35.0, -26.0, 178.8), (0.0, 0.0, 200.0), (20.0, 34.64, 227.5), (20.0, 34.64, 152.5),
              (-72.5, -86.5, 112.5), (-80.0, -62.97, 202.5), (-70.0, -62.97372056, 125.0),
              (-46.66666667, -73.07179677, 130.83333333)]
PPRS_SINGULAR = (-70.0, -62.97372055837116, 120.08686671)  # det J_t = 0 (bisected to round-off)


def pprs_model(pose, joints="ideal", **opts):
    return PPRS.stiffness_model(PPRS_DESIGN, PPRS.resolve_options(opts), pose, joints)


@pytest.mark.parametrize("joints", ["ideal", "bonded"])
@pytest.mark.parametrize("pose", PPRS_POSES)
def test_pprs_rprs_against_pynite(pose, joints):
    # bonded models are stiff everywhere, so PyNite's rigid-member penalty needs 1e5 there (its error ~ 1/penalty:
    # 4e-4 at 1e4, 4e-5 at 1e5); measured <= 9e-5
    m = pprs_model(pose, joints, load=[10.0, 20.0, -150.0])
    assert fe_gap(m, 1e4 if joints == "ideal" else 1e5) < FE_TOL


def test_pprs_rprs_rigid_links_give_the_jacobian_model():
    """Links e times stiffer: the 6x6 compliance of O1 tends to J_t^-1 K_q^-1 J_t^-T (J_t the twist Jacobian of the
    kinematics, q_dot = J_t [v; omega]; K_q = diag(k, k, k_beta, k, k, k)), the gap ~ 1/e."""
    pose = (-35.0, -26.0, 178.8)
    k, kb = 2e4, 1e8
    opts = PPRS.resolve_options({})
    geo = Geometry.of(PPRS_DESIGN, opts)
    jt = twist_jacobian(geo, chain_state(geo, np.array([*pose, 0.0, 0.0, 0.0]), sigma_vector("+++")))
    jinv = np.linalg.inv(jt)
    cj = jinv @ np.diag(1.0 / np.array([k, k, kb, k, k, k])) @ jinv.T
    r = PPRS_DESIGN["r"]
    gaps = []
    for e in (1e3, 1e4, 1e5):
        C = solve(pprs_model(pose, youngs_modulus=70 * e, actuator_stiffness=k, beta_stiffness=kb)).C
        gaps.append(np.max(np.abs(scaled(C - cj, r))) / np.max(np.abs(scaled(cj, r))))
    assert_converges(gaps)


def test_pprs_rprs_spd_and_linear():
    for pose in PPRS_POSES:
        assert_spd(pprs_model(pose), SPATIAL)
    assert_linear(lambda f: pprs_model(PPRS_POSES[0], load=f))
    # the default load is 150 N along -z (gravity) at O1
    assert pprs_model(PPRS_POSES[0]).to_dict()["load"]["force"] == [0.0, 0.0, -150.0]


def test_pprs_rprs_singular_pose_is_infinite():
    out = cli("pprs-rprs", "--pose=" + ",".join(repr(v) for v in PPRS_SINGULAR), "--json")
    assert out.exit_code == 0, out.output
    assert "NaN" not in out.output
    data = json.loads(out.output)
    assert data["singular"] and data["deflection"] == ["inf"] * 3 and data["stiffness_min"] == 0.0
    assert data["deflection_norm"] == "inf" and data["compliance"][0][0] == "inf"
    # 1 mm away: finite, and far softer than 5 mm away (stiffness ~ distance^2 near a forward singularity)
    near = solve(pprs_model((-70.0, -62.97372056, 121.0)))
    away = solve(pprs_model(PPRS_POSES[6]))
    assert not near.singular and np.all(np.isfinite(near.deflection))
    assert near.deflection_norm > 10 * away.deflection_norm


def test_pprs_rprs_cli_model_rebuilds_in_pynite():
    out = cli("pprs-rprs", "--pose=20,34.64,227.5", "--load=0,30,-150", "--json")
    assert out.exit_code == 0, out.output
    data = json.loads(out.output)
    assert data["branch"] == "+++" and data["dofs"] == ["x", "y", "z", "rx", "ry", "rz"]
    kinds = sorted((a["kind"], a["stiffness_unit"]) for a in data["model"]["actuators"])
    assert kinds == [("prismatic", "N/mm")] * 5 + [("revolute", "N*mm/rad")]
    gap = np.max(np.abs(np.subtract(data["deflection"], solve_model(data["model"]))))
    assert gap < FE_TOL * data["deflection_norm"]


@pytest.mark.parametrize("args, field", [
    (["--pose=0,0,150"], "pose"),  # below the sliders' reach
    (["--pose=0,0,200", "--load=1,2"], "--load"),
    (["--pose=0,0,200", "--set", "youngs_modulus=0"], "options.youngs_modulus"),
    (["--pose=0,0,200", "--set", "tube=[40, -3]"], "options.tube[1]"),
    (["--pose=0,0,200", "--set", "sections={column: [10, 6]}"], "options.sections.column"),
    (["--pose=0,0,200", "--set", "actuator_stiffness=-2e4"], "options.actuator_stiffness"),
    (["--pose=0,0,200", "--set", "beta_stiffness=0"], "options.beta_stiffness"),
    (["--pose=0,0,200", "--set", "load=[0, -150]"], "options.load"),
])
def test_pprs_rprs_bad_input(args, field):
    bad = cli("pprs-rprs", *args)
    assert bad.exit_code == 2 and bad.output.strip().startswith(f"error: {field}"), bad.output
    assert len(bad.output.strip().splitlines()) == 1


# ----- seed 002: rps-upu and rps-upu-tool -------------------------------------------------------------------------
RPS = get("rps-upu")
TOOL = get("rps-upu-tool")
RPS_DESIGN = RPS.resolve_design({})  # g = 80, h = 50, c = 50, e = 0 mm
# (z mm, theta rad, psi rad) in the default workspace (P-model box and strokes, and the C-model frame's strokes),
# found on a 31^3 grid: the centroid, the grid points nearest the box corners (+++, +-+, ++-: LCI 0.45, 0.21, 0.43
# of the C-model), the lowest-LCI corner (40, -0.314, -0.314; LCI 0.05), the highest-LCI point, and, with the
# stroke limits lifted, a pose 3 mm above the forward singularity of z = 0 (all legs in the base plane)
RPS_POSES = [((53.0, 0.019, 0.0), {}), ((66.67, 0.314, 0.314), {}), ((60.0, -0.314, 0.314), {}),
             ((43.33, 0.314, -0.293), {}), ((40.0, -0.314, -0.314), {}), ((46.67, 0.314, 0.0), {}),
             ((3.0, 0.05, -0.1), {"stroke_limits": None}),
             # a P-model pose whose C-model placement has leg 2 at 39.27 mm, below the stroke limits (solved and noted)
             ((39.5447, 0.1113, -0.3033), {})]
# chain-3 variant 'upu' (C-model): grid points nearest three corners, the lowest-LCI point (LCI 0.22), two generic
UPU_POSES = [(60.0, 0.314, 0.293), (53.33, -0.314, -0.314), (56.67, -0.314, 0.314), (26.67, -0.314, 0.0),
             (50.0, 0.0, 0.0), (50.0, 0.2, 0.1)]
# tool points T (mm) of rps-upu-tool: the centroid of its workspace (25^3 grid), the grid points nearest five box
# corners (LCI 0.26 ... 0.41), and one with lifted strokes 2 mm above the singular pose (z, theta, psi) = 0
TOOL_POSES = [((0.19, 0.0, 4.0), {}), ((14.156, 15.443, 14.212), {}), ((14.156, 15.443, -7.615), {}),
              ((-14.156, 9.009, 22.943), {}), ((-14.156, -9.009, -3.25), {}), ((14.156, -15.443, 14.212), {}),
              ((0.5, -0.5, -48.0), {"stroke_limits": None}),
              # its C-model pose has leg 1 at 90.01 mm, above the stroke limits (solved and noted)
              ((-7.525, -10.6872, 22.9668), {})]


def rps_model(mech, pose, joints="ideal", **opts):
    return mech.stiffness_model(RPS_DESIGN, mech.resolve_options(opts), pose, joints)


@pytest.mark.parametrize("joints", ["ideal", "bonded"])
@pytest.mark.parametrize("mech, pose, opts", [(RPS, p, o) for p, o in RPS_POSES]
                         + [(RPS, p, {"model": "C", "c3_variant": "upu"}) for p in UPU_POSES]
                         + [(TOOL, p, o) for p, o in TOOL_POSES])
def test_rps_upu_against_pynite(mech, pose, opts, joints):
    # PyNite's rigid-member penalty 1e4 for ideal joints, 1e5 for the stiffer bonded models; measured <= 6e-5
    # (ideal), <= 3.2e-4 (bonded, at the near-singular pose)
    m = rps_model(mech, pose, joints, load=[10.0, 20.0, -150.0], **opts)
    assert fe_gap(m, 1e4 if joints == "ideal" else 1e5) < FE_TOL


def _rps_jacobian_model(mech, pose, k, **opts):
    """T6 J K^-1 J^T T6^T: the actuator-only compliance of the platform's reference point from the mechanism's own
    C-model kinematics (J = d(z, theta, psi)/dq, T6 = d(v, omega)/d(z, theta, psi) of O', moved to the tool point
    T for rps-upu-tool)."""
    from scalesynth.mechanisms.rps_upu import _platform

    options = mech.resolve_options(opts)
    model = mech.stiffness_model(RPS_DESIGN, options, pose)
    x, _, _ = mech._stiffness_placement(RPS_DESIGN, options, pose)  # the frame's (z, theta, psi)
    c_opts = RPS.resolve_options({"model": "C", "c3_variant": options.get("c3_variant", "plane")})
    (q,) = RPS.inverse_kinematics(RPS_DESIGN, c_opts, x)
    J = RPS.jacobians(RPS_DESIGN, c_opts, x, q.values)["J"]
    _, p, _, _, t6 = _platform(RPS._geom(RPS_DESIGN), "C", c_opts["c3_variant"], x[None])
    t6 = t6[0]
    r = model.body("platform").ref - p[0]  # O' -> reference point
    move = np.eye(6)
    move[:3, 3:] = -np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])
    t6 = move @ t6
    return t6 @ J @ J.T @ t6.T / k


@pytest.mark.parametrize("mech, pose, opts", [(RPS, (53.0, 0.019, 0.0), {}), (RPS, (40.0, -0.314, -0.314), {}),
                                              (RPS, (50.0, 0.2, 0.1), {"model": "C", "c3_variant": "upu"}),
                                              (TOOL, (14.156, 15.443, -7.615), {})])
def test_rps_upu_rigid_links_give_the_jacobian_model(mech, pose, opts):
    """Links e times stiffer: the 6x6 compliance tends to the actuator-only model (rank 3: the constrained
    directions become rigid), the gap ~ 1/e. Decades 1e2 ... 1e4: these short legs (~60 mm) reach the solver's
    round-off floor (~1e-6) near 1e5."""
    k = 2e4
    cj = _rps_jacobian_model(mech, pose, k, **opts)
    h = RPS_DESIGN["h"]
    gaps = []
    for e in (1e2, 1e3, 1e4):
        C = solve(rps_model(mech, pose, youngs_modulus=70 * e, actuator_stiffness=k, **opts)).C
        gaps.append(np.max(np.abs(scaled(C - cj, h))) / np.max(np.abs(scaled(cj, h))))
    assert_converges(gaps)


def test_rps_upu_spd_and_linear():
    for mech, pose, opts in ([(RPS, p, o) for p, o in RPS_POSES] + [(TOOL, p, o) for p, o in TOOL_POSES]
                             + [(RPS, p, {"model": "C", "c3_variant": "upu"}) for p in UPU_POSES]):
        assert_spd(rps_model(mech, pose, **opts), SPATIAL)
    for mech, pose in ((RPS, RPS_POSES[0][0]), (TOOL, TOOL_POSES[1][0])):
        assert_linear(lambda f, mech=mech, pose=pose: rps_model(mech, pose, load=f))


def test_rps_upu_frame_is_the_constraint_consistent_placement():
    """The frame's joints are at the C-model pose (B1, B2 in x = 0, B3 in y = 0 for chain 3 'plane'), whatever the
    configured model; the tool model's reference point is the requested tool point."""
    m = rps_model(RPS, (40.0, -0.314, -0.314)).to_dict()
    heads = {j["name"]: j["at"] for j in m["joints"]}
    assert abs(heads["S1"][0]) < 1e-12 and abs(heads["S2"][0]) < 1e-12 and abs(heads["S3"][1]) < 1e-12
    assert m["platform"]["point"][0] == 0.0 and m["platform"]["point"][2] == 40.0  # O' = (0, y0, z)
    t = rps_model(TOOL, TOOL_POSES[2][0]).to_dict()
    assert np.max(np.abs(np.subtract(t["platform"]["point"], TOOL_POSES[2][0]))) < 1e-12
    heads = {j["name"]: j["at"] for j in t["joints"]}
    assert abs(heads["S1"][0]) < 1e-12 and abs(heads["S2"][0]) < 1e-12 and abs(heads["S3"][1]) < 1e-12


@pytest.mark.parametrize("name, pose", [("rps-upu", "0,0,0"), ("rps-upu-tool", "0,0,-50")])
def test_rps_upu_singular_pose_is_infinite(name, pose):
    """(z, theta, psi) = 0 (tool point (0, 0, -d)): every leg lies in the base plane, the platform can sink without
    deforming anything (a forward singularity; reachable once the stroke limits are lifted)."""
    out = cli(name, f"--pose={pose}", "--set", "stroke_limits=null", "--json")
    assert out.exit_code == 0, out.output
    assert "NaN" not in out.output
    data = json.loads(out.output)
    assert data["singular"] and data["deflection"] == ["inf"] * 3 and data["stiffness_min"] == 0.0
    # 3 mm above it: finite
    near = solve(rps_model(RPS, (3.0, 0.0, 0.0), stroke_limits=None))
    assert not near.singular and np.all(np.isfinite(near.deflection)) and near.deflection_norm > 0.1


@pytest.mark.parametrize("name, pose", [("rps-upu", "40,-0.314,-0.314"), ("rps-upu-tool", "14.156,15.443,-7.615")])
def test_rps_upu_cli_model_rebuilds_in_pynite(name, pose):
    out = cli(name, f"--pose={pose}", "--load=0,30,-150", "--json")
    assert out.exit_code == 0, out.output
    data = json.loads(out.output)
    assert data["dofs"] == ["x", "y", "z", "rx", "ry", "rz"]
    assert [a["kind"] for a in data["model"]["actuators"]] == ["prismatic"] * 3
    gap = np.max(np.abs(np.subtract(data["deflection"], solve_model(data["model"]))))
    assert gap < FE_TOL * data["deflection_norm"]


@pytest.mark.parametrize("name, args, field", [
    ("rps-upu", ["--pose=95,0,0"], "pose"),  # above the z range
    ("rps-upu", ["--pose=20,0,0"], "pose"),  # legs shorter than the stroke limits
    ("rps-upu", ["--pose=50,0,0", "--load=1,2"], "--load"),
    ("rps-upu", ["--pose=50,0,0", "--set", "youngs_modulus=-70"], "options.youngs_modulus"),
    ("rps-upu", ["--pose=50,0,0", "--set", "tube=[0, 3]"], "options.tube[0]"),
    ("rps-upu", ["--pose=50,0,0", "--set", "sections={leg: [10, 6]}"], "options.sections.leg"),
    ("rps-upu", ["--pose=50,0,0", "--set", "sections={link: [10, 2]}"], "options.sections.link"),
    ("rps-upu", ["--pose=50,0,0", "--set", "actuator_stiffness=0"], "options.actuator_stiffness"),
    ("rps-upu-tool", ["--pose=0,0,80"], "pose"),
    ("rps-upu-tool", ["--pose=0,0,10", "--set", "actuator_stiffness=-1"], "options.actuator_stiffness"),
    ("rps-upu-tool", ["--pose=0,0,10", "--load=1,2,3,4"], "--load"),
])
def test_rps_upu_bad_input(name, args, field):
    bad = cli(name, *args)
    assert bad.exit_code == 2 and bad.output.strip().startswith(f"error: {field}"), bad.output
    assert len(bad.output.strip().splitlines()) == 1


# ----- seed 000: 2pauu-ppap ---------------------------------------------------------------------------------------
PAUU = get("2pauu-ppap")
PAUU_DESIGN = PAUU.resolve_design({})  # Table-4 group 1 (m): m 0.857, n 0.706, l1 1.499, l2 1.5, c 0.1
# P (m), mode ++, from a 31^3 grid of the workspace box: its centroid (0, 0, 0.2), the figure's pose, the grid points
# nearest five box corners (two of them near-singular, LCI 0.0088 and 0.0091) and a pose 0.1 m above the forward
# singularity at (0, 0.5, 1.00703) (PAUU_SINGULAR; LCI 0.059)
PAUU_POSES = [(0.0, 0.0, 0.2), (0.25, 0.35, 1.6), (1.32906667, 1.4, 1.59953333), (1.32906667, -1.1, 2.19933333),
              (-1.89866667, -1.1, -1.19953333), (1.32906667, -1.3, -1.39946667), (-1.32906667, 1.4, -1.19953333),
              (0.0, 0.5, 1.107)]
PAUU_SINGULAR = (0.0, 0.5, 1.007026948643399)  # det Jx = 0 (the l2 links' xz-projections parallel), bisected


def pauu_model(pose, joints="ideal", **opts):
    return PAUU.stiffness_model(PAUU_DESIGN, PAUU.resolve_options(opts), pose, joints)


@pytest.mark.parametrize("joints", ["ideal", "bonded"])
@pytest.mark.parametrize("pose", PAUU_POSES)
def test_2pauu_ppap_against_pynite(pose, joints):
    # measured <= 1.5e-4 (the near-singular pose; PyNite's rigid-member penalty 1e4 ideal, 1e5 bonded)
    m = pauu_model(pose, joints, load=[10.0, 20.0, -150.0])
    assert fe_gap(m, 1e4 if joints == "ideal" else 1e5) < FE_TOL


def test_2pauu_ppap_rigid_links_give_the_jacobian_model():
    """Links e times stiffer: the compliance of P (platform DOFs x, y, z: the PPaP chain holds the rotations)
    tends to J K_q^-1 J^T, J = Jx^-1 Jq of the kinematics (P_dot = J q_dot), K_q = diag(k, k, k_d), gap ~ 1/e
    (1.5 m links of 40 x 3 tubes are soft: the gap is 1.2 % at 1e3, so the decades run 1e4 ... 1e6)."""
    pose = (0.25, 0.35, 1.6)
    k, kd = 1e5, 2e7
    opts = PAUU.resolve_options({})
    (q,) = [s.values for s in PAUU.inverse_kinematics(PAUU_DESIGN, opts, pose) if s.label == "++"]
    J = PAUU.jacobians(PAUU_DESIGN, opts, pose, q)["J"]
    cj = J @ np.diag([1 / k, 1 / k, 1 / kd]) @ J.T
    gaps = []
    for e in (1e4, 1e5, 1e6):
        res = solve(pauu_model(pose, youngs_modulus=70 * e, actuator_stiffness=k, stroke_stiffness=kd))
        assert res.dofs == ("x", "y", "z")
        gaps.append(np.max(np.abs(res.C - cj)) / np.max(np.abs(cj)))
    assert_converges(gaps)


def test_2pauu_ppap_spd_linear_and_parallelograms_matter():
    for pose in PAUU_POSES:
        assert_spd(pauu_model(pose), ("x", "y", "z"))
    assert_linear(lambda f: pauu_model(PAUU_POSES[1], load=f))
    # where the platform is off the xz-plane (y != 0) the arm links carry load (the U-U links' constraint couples and
    # their y forces bend the parallelograms out of plane): a 10x thinner-walled arm link makes the platform 41 %
    # softer at this corner (measured 1.409); at y = 0 the U-U links lie in the xz-plane, nothing loads the arm
    # links out of plane and, as in seed 004's five-bar, the moment balance of the hinge plate leaves them unloaded
    def ratio(pose):
        thin = solve(pauu_model(pose, sections={"arm_link": [0.04, 0.0003]})).deflection_norm
        return thin / solve(pauu_model(pose)).deflection_norm

    assert ratio(PAUU_POSES[2]) > 1.3
    assert ratio(PAUU_POSES[0]) == pytest.approx(1.0, abs=1e-8)


def test_2pauu_ppap_singular_pose_is_infinite():
    out = cli("2pauu-ppap", "--pose=" + ",".join(repr(v) for v in PAUU_SINGULAR), "--json")
    assert out.exit_code == 0, out.output
    assert "NaN" not in out.output
    data = json.loads(out.output)
    assert data["singular"] and data["deflection"] == ["inf"] * 3 and data["stiffness_min"] == 0.0
    assert data["dofs"] == ["x", "y", "z"] and data["units"]["length"] == "m"
    near = solve(pauu_model((0.0, 0.5, 1.057)))  # 5 cm above: finite, far softer than 10 cm above
    assert not near.singular and near.deflection_norm > 3 * solve(pauu_model(PAUU_POSES[7])).deflection_norm


def test_2pauu_ppap_cli_model_rebuilds_in_pynite():
    out = cli("2pauu-ppap", "--pose=1.32906667,-1.1,2.19933333", "--load=0,30,-150", "--json")
    assert out.exit_code == 0, out.output
    data = json.loads(out.output)
    assert data["branch"] == "++" and data["dofs"] == ["x", "y", "z"]
    kinds = sorted((a["kind"], a["stiffness_unit"]) for a in data["model"]["actuators"])
    assert kinds == [("prismatic", "N/m"), ("revolute", "N*m/rad"), ("revolute", "N*m/rad")]
    assert data["model"]["links"][0]["EA"] == pytest.approx(70e9 * math.pi / 4 * (0.04**2 - 0.034**2), rel=1e-12)
    gap = np.max(np.abs(np.subtract(data["deflection"], solve_model(data["model"]))))
    assert gap < FE_TOL * data["deflection_norm"]


@pytest.mark.parametrize("args, field", [
    (["--pose=0,0,5"], "pose"),  # out of reach
    (["--pose=0.25,0.35,1.6", "--load=1,2"], "--load"),
    (["--pose=0.25,0.35,1.6", "--set", "youngs_modulus=0"], "options.youngs_modulus"),
    (["--pose=0.25,0.35,1.6", "--set", "tube=[0.04, 0.03]"], "options.tube"),
    (["--pose=0.25,0.35,1.6", "--set", "sections={arm_link: [-0.04, 0.003]}"], "options.sections.arm_link[0]"),
    (["--pose=0.25,0.35,1.6", "--set", "actuator_stiffness=-1e5"], "options.actuator_stiffness"),
    (["--pose=0.25,0.35,1.6", "--set", "stroke_stiffness=0"], "options.stroke_stiffness"),
])
def test_2pauu_ppap_bad_input(args, field):
    bad = cli("2pauu-ppap", *args)
    assert bad.exit_code == 2 and bad.output.strip().startswith(f"error: {field}"), bad.output
    assert len(bad.output.strip().splitlines()) == 1
