"""Seed-002 2-RPS-UPU: spec mechanisms_001_003.md §2 (Table 2, Jacobians, C-model tables, §2.8 workspace) and
tests/data/cases/ref002.json; kernel vs the NumPy twin tests/naive.py::rps_upu_lci; IK/FK property tests."""

import json
import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

import scalesynth.mechanisms.rps_upu as rps
from scalesynth.cli import app
from scalesynth.errors import InvalidParameter, InvalidPose
from scalesynth.evaluate import evaluate, make_grid
from scalesynth.kernels import grid as kgrid
from scalesynth.mechanisms import get

from naive import assert_report_equals_grid_metrics, grid_metrics, grid_nodes, rps_upu_lci, rps_upu_tool_lci
from refdata import load_case

M = get("rps-upu")
REF = load_case("ref002.json")  # tests/data/cases/, provenance in tests/data/README.md
CASES = ("case1", "case2", "case3")
PAPER = M.resolve_design({})  # g = 80, h = 50, c = 50, e = 0 (spec §2.1)
P_OPT = M.resolve_options({})
PLANE = M.resolve_options({"model": "C"})
UPU = M.resolve_options({"model": "C", "c3_variant": "upu"})
FREE = {"stroke_limits": None}

# spec §2.7 Table 2, P-model: q -> the paper's solution and the other z > 0 branches (11 decimals)
TABLE2 = {
    "case1": ((80, 90, 80), [(79.36842875655, 0.30710989782, 0.11259002927),
                             (79.36842875655, 2.83448275577, -0.11259002927),
                             (30.83265341674, -1.27498596352, 1.23969835086),
                             (30.83265341674, -1.86660669007, -1.23969835086)]),
    "case2": ((60, 50, 40), [(45.23990061979, 0.70934701776, -0.16091511210),
                             (45.23990061979, 2.43224563583, 0.16091511210),
                             (13.74357138186, 0.91454874474, -0.71535458859),
                             (13.74357138186, 2.22704390885, 0.71535458859)]),
    "case3": ((70, 40, 60), [(40.55304387865, 0.13468761638, -0.42310444862),
                             (40.55304387865, 3.00690503721, 0.42310444862),
                             (27.90960638257, -0.11528868776, -0.63744618706),
                             (27.90960638257, -3.02630396583, 0.63744618706)]),
}  # fmt: skip
# spec §2.7: dq/d(z, theta, psi) at the exact solutions (6 decimals)
JAC_ROWS = {
    "case1": [(0.925171, 1.684826, -41.367300), (0.941369, -1.497623, 46.757805), (0.803165, -47.284299, 0)],
    "case2": [(0.855310, -3.934305, -38.918096), (0.783224, 4.721166, 21.066265), (0.316824, -42.909330, 0)],
    "case3": [(0.869954, -1.597059, -49.635417), (0.505233, 2.794853, 4.743355), (0.563983, -33.488140, 0)],
}
# spec §2.7 C-model, variant plane: IK at the printed pose (q, phi, y0) and FK of the paper's q ((z, theta, psi),
# phi, y0), 10 decimals
C_PLANE = {
    "case1": ((79.3686571829, 90.5352584888, 79.9834309244), 0.0341677800, -1.6281387707,
              (79.4418596321, 0.3080752389, 0.1007895236), 0.0306562121, -1.4604155304),
    "case2": ((61.7591503160, 47.2187376420, 39.8006136424), -0.1053330096, 3.9888820924,
              (45.9833232092, 0.7127540782, -0.1107337533), -0.0725807092, 2.7431868820),
    "case3": ((71.4207409204, 37.2869629304, 59.9254282938), -0.0603932639, 2.9904964250,
              (43.4183827684, 0.1795170554, -0.3446285556), -0.0640051280, 3.1466788994),
}  # fmt: skip


def fk(options, q, design=PAPER):
    return M.forward_kinematics(design, options, q)


def nearest(sols, x):
    """The FK solution closest to x (angles compared modulo 2 pi) and its distance."""
    x = np.asarray(x, dtype=float)

    def dist(v):
        return max(abs(v[0] - x[0]), *np.abs(np.angle(np.exp(1j * (v[1:] - x[1:])))))

    best = min(sols, key=lambda s: dist(s.values))
    return best, dist(best.values)


# ----- spec §2.7, P-model -----------------------------------------------------------------------------------
@pytest.mark.parametrize("case", CASES)
def test_table2_fk_all_branches_exact(case):
    q, branches = TABLE2[case]
    sols = fk(P_OPT, q)
    assert len(sols) == 4  # two z roots x the theta <-> pi - theta mirror (spec §2.4)
    for exact in branches:  # the spec's 11-decimal table
        _, d = nearest(sols, exact)
        assert d < 1e-8
    for exact in REF[case]["all_fk"]:  # ref002.json, full precision
        _, d = nearest(sols, exact)
        assert d < 1e-10
    # the paper's (physical) solution: cos theta > 0 and the larger z, labelled 1++
    assert sols[0].label == "1++"
    np.testing.assert_allclose(sols[0].values, branches[0], atol=1e-8)
    assert [s.label for s in sols] == ["1++", "1-+", "2++", "2-+"]


def test_table2_printed_values_within_last_digit():
    """The paper prints 8 decimals; all nine are within 1e-8 of the exact solution. Erratum F10 says they are
    truncated: true for eight of them, but case 2's z = 45.2399006198 is printed rounded up as 45.23990062."""
    truncated = []
    for case in CASES:
        exact = fk(P_OPT, REF[case]["q"])[0].values
        printed = np.array(REF[case]["printed"])
        assert np.abs(exact - printed).max() < 1e-8
        truncated.extend((exact - printed) * np.sign(exact) >= 0)
    assert truncated == [True] * 3 + [False, True, True] + [True] * 3


@pytest.mark.parametrize("case", CASES)
def test_ik_of_printed_pose_reproduces_q(case):
    sols = M.inverse_kinematics(PAPER, P_OPT, REF[case]["printed"])
    assert [s.label for s in sols] == ["+++"] == [M.kernel_branch(P_OPT)]
    assert np.abs(sols[0].values - REF[case]["q"]).max() < 4.3e-7  # spec §2.7


@pytest.mark.parametrize("case", CASES)
def test_jacobian_rows_at_exact_solutions(case):
    x = REF[case]["fk"]
    q = REF[case]["q"]
    jac = M.jacobians(PAPER, P_OPT, x, q)
    np.testing.assert_allclose(jac["dq_dx"], JAC_ROWS[case], atol=1e-6)  # spec table, 6 decimals
    np.testing.assert_allclose(jac["dq_dx"], REF[case]["jac"], rtol=1e-9, atol=1e-12)  # ref002.json
    # the forward Jacobian is its inverse; the LCI divides the angle columns by h = 50
    np.testing.assert_allclose(jac["J"] @ jac["dq_dx"], np.eye(3), atol=1e-12)
    sv = np.linalg.svd(np.array(REF[case]["jac"]) / [1.0, 50.0, 50.0], compute_uv=False)
    assert M.lci(PAPER, P_OPT, x, q) == pytest.approx(sv[-1] / sv[0], rel=1e-9)
    assert M.point_kernel(M.pack(PAPER, P_OPT), *x) == pytest.approx(sv[-1] / sv[0], rel=1e-9)
    assert M.singularity(PAPER, P_OPT, x, q) == "none"


def test_p_model_violates_rps_constraint_as_spec_says():
    """Spec §2.3: at the Table-2 solutions B1_x = -h sin(theta) sin(psi) != 0 (ref002.json B1x_B2x_B3y)."""
    for case in CASES:
        pose = M.platform_pose(PAPER, P_OPT, REF[case]["fk"])
        b1 = pose["p"] + pose["R"] @ [0.0, -50.0, 0.0]
        b2 = pose["p"] + pose["R"] @ [0.0, 50.0, 0.0]
        b3 = pose["p"] + pose["R"] @ [50.0, 0.0, 0.0]
        np.testing.assert_allclose([b1[0], b2[0], b3[1]], REF[case]["B1x_B2x_B3y"], atol=1e-9)


# ----- spec §2.7, C-model -------------------------------------------------------------------------------------
@pytest.mark.parametrize("case", CASES)
def test_c_model_plane_table(case):
    q_ik, phi_ik, y0_ik, x_fk, phi_fk, y0_fk = C_PLANE[case]
    printed = REF[case]["printed"]
    (sol,) = M.inverse_kinematics(PAPER, PLANE, printed)
    np.testing.assert_allclose(sol.values, q_ik, atol=1e-9)
    pose = M.platform_pose(PAPER, PLANE, printed)
    assert pose["phi"] == pytest.approx(phi_ik, abs=1e-9)
    assert pose["y0"] == pytest.approx(y0_ik, abs=1e-9)
    # the constraints the C-model restores: B1, B2 in x = 0 (R[0, 1] = 0) and, plane variant, B3 in y = 0
    assert pose["p"][0] == 0.0 and abs(pose["R"][0, 1]) < 1e-15
    assert abs(pose["p"][1] + 50.0 * pose["R"][1, 0]) < 1e-12
    best, d = nearest(fk(PLANE, REF[case]["q"]), x_fk)
    assert d < 1e-9 and best.label == "1++"
    np.testing.assert_allclose(best.values, REF[case]["C_plane_fk_of_q"]["x"], atol=1e-10)
    pose = M.platform_pose(PAPER, PLANE, best.values)
    assert pose["phi"] == pytest.approx(phi_fk, abs=1e-9)
    assert pose["y0"] == pytest.approx(y0_fk, abs=1e-9)


@pytest.mark.parametrize("case", CASES)
def test_c_model_upu_reference(case):
    ik_ref, fk_ref = REF[case]["C_upu_at_printed_pose"], REF[case]["C_upu_fk_of_q"]
    printed = REF[case]["printed"]
    (sol,) = M.inverse_kinematics(PAPER, UPU, printed)
    np.testing.assert_allclose(sol.values, ik_ref["q"], atol=1e-9)
    pose = M.platform_pose(PAPER, UPU, printed)
    assert pose["phi"] == pytest.approx(ik_ref["phi"], abs=1e-10)
    assert pose["y0"] == pytest.approx(ik_ref["y0"], abs=1e-9)
    best, d = nearest(fk(UPU, REF[case]["q"]), fk_ref["x"])
    assert d < 1e-9 and best.label == "1++"
    pose = M.platform_pose(PAPER, UPU, best.values)
    assert pose["phi"] == pytest.approx(fk_ref["phi"], abs=1e-9)
    assert pose["y0"] == pytest.approx(fk_ref["y0"], abs=1e-9)


@pytest.mark.parametrize("options", [PLANE, UPU], ids=["plane", "upu"])
def test_c_model_fk_branches_all_reproduce_q_and_include_mirrors(options):
    """Every reported branch solves the IK to round-off; for e = 0 the branch set is closed under the exact
    mirror symmetries (theta, psi) -> (pi - theta, -psi) and (theta, pi - psi)."""
    q = REF["case3"]["q"]
    sols = fk(options, q)
    assert len(sols) >= 4 and len({s.label for s in sols}) == len(sols)
    for s in sols:
        (ik,) = M.inverse_kinematics(PAPER, options, s.values)
        assert np.abs(ik.values - q).max() < 1e-11
    for s in sols:
        z, th, ps = s.values
        for image in ((z, math.pi - th, -ps), (z, th, math.pi - ps)):
            assert nearest(sols, image)[1] < 1e-8


# ----- spec §2.8 workspace ------------------------------------------------------------------------------------
def test_workspace_illustration_node_count():
    """ASSUMED q in [40, 90] mm, P-model, nodes z = -10:1:90, theta, psi = -0.31:0.01:0.31: 153595 of 400869
    nodes feasible, z in [27, 84] (spec §2.8)."""
    z = np.arange(-10, 91, 1.0)
    ang = np.arange(-31, 32) * 0.01
    pts = np.stack(np.meshgrid(z, ang, ang, indexing="ij"), axis=-1).reshape(-1, 3)
    assert pts.shape[0] == 400869
    lci = kgrid.points_lci(M.point_kernel, M.pack(PAPER, P_OPT), pts)
    ok = lci >= 0
    assert int(ok.sum()) == 153595
    assert pts[ok, 0].min() == 27.0 and pts[ok, 0].max() == 84.0
    assert np.all(lci[ok] > 0) and np.all(lci <= 1)
    # the NumPy twin agrees on every 5th node (all of them take it 1.3 s)
    sub = slice(None, None, 5)
    twin = rps_upu_lci(PAPER, P_OPT, pts[sub, 0], pts[sub, 1], pts[sub, 2])
    assert np.array_equal(twin >= 0, ok[sub])
    np.testing.assert_allclose(lci[sub][ok[sub]], twin[twin >= 0], rtol=1e-9)


def test_bounding_box_is_the_configured_box():
    lo, hi = M.bounding_box(PAPER, P_OPT)
    np.testing.assert_array_equal(lo, [-10.0, -0.314, -0.314])
    np.testing.assert_array_equal(hi, [90.0, 0.314, 0.314])
    opts = M.resolve_options({"z_range": [0, 50], "theta_range": [-1, 0.5], "psi_range": [-0.2, 0.3]})
    lo, hi = M.bounding_box(PAPER, opts)
    np.testing.assert_array_equal(lo, [0.0, -1.0, -0.2])
    np.testing.assert_array_equal(hi, [50.0, 0.5, 0.3])
    assert M.measure_key("mm") == "volume_mm_rad2"


TWIN_CASES = [
    ({}, {}),
    ({"e": 15.0, "g": 70.0, "h": 40.0, "c": 60.0}, {"stroke_limits": [35.0, 95.0]}),
    ({}, {"model": "C"}),
    ({"e": -20.0}, {"model": "C", "c3_variant": "upu"}),
    ({"h": 30.0}, {"model": "C", "c3_variant": "upu", "stroke_limits": None, "characteristic_length": 70.0,
                   "theta_range": [-1.5, 1.5], "psi_range": [-1.6, 1.6]}),
    ({"e": 10.0}, {"stroke_limits": None, "z_range": [-60, 60], "theta_range": [-3, 3], "psi_range": [-3, 3]}),
]  # fmt: skip


@pytest.mark.parametrize(("design", "options"), TWIN_CASES)
def test_kernel_matches_numpy_twin(design, options):
    design = M.resolve_design(design)
    options = M.resolve_options(options)
    g = make_grid(M, design, options, 20)
    lci = kgrid.sample_grid(M.point_kernel, M.pack(design, options), g.lo, g.step, g.shape)
    twin = rps_upu_lci(design, options, *grid_nodes(g.lo, g.step, g.shape))
    assert np.array_equal(lci >= 0, twin >= 0)  # same reachable voxels
    assert np.count_nonzero(lci >= 0) > 100
    np.testing.assert_allclose(lci[lci >= 0], twin[twin >= 0], rtol=1e-7, atol=1e-12)
    edges = (0.0, 0.1, 0.3, 1.0)
    ref = grid_metrics(twin, g.cell_measure, edges)
    rep = evaluate(M, design, options, resolution=20, band_edges=edges)
    assert rep.measure_key == "volume_mm_rad2"
    assert_report_equals_grid_metrics(rep, ref)


@pytest.mark.parametrize("options", [P_OPT, PLANE, UPU], ids=["P", "plane", "upu"])
def test_kernel_matches_svd_lci_at_random_poses(options):
    rng = np.random.default_rng(7)
    for _ in range(200):
        design = M.resolve_design({"g": rng.uniform(40, 120), "h": rng.uniform(20, 80), "c": rng.uniform(20, 80),
                                   "e": rng.uniform(-30, 30)})  # fmt: skip
        opts = dict(options, stroke_limits=None)
        pose = (rng.uniform(-10, 90), rng.uniform(-0.8, 0.8), rng.uniform(-0.8, 0.8))
        (sol,) = M.inverse_kinematics(design, opts, pose)
        ref = M.lci(design, opts, pose, sol.values)
        assert M.point_kernel(M.pack(design, opts), *pose) == pytest.approx(ref, rel=1e-9, abs=1e-13)


def test_characteristic_length_divides_the_angle_columns():
    x, q = REF["case1"]["fk"], REF["case1"]["q"]
    raw = np.array(REF["case1"]["jac"])
    for length in (10.0, 50.0, 200.0):
        opts = M.resolve_options({"characteristic_length": length})
        sv = np.linalg.svd(raw / [1.0, length, length], compute_uv=False)
        assert M.lci(PAPER, opts, x, q) == pytest.approx(sv[-1] / sv[0], rel=1e-9)
        assert M.point_kernel(M.pack(PAPER, opts), *x) == pytest.approx(sv[-1] / sv[0], rel=1e-9)
    # default L = h
    opts = M.resolve_options({"characteristic_length": 30.0})
    assert M.lci(M.resolve_design({"h": 30.0}), P_OPT, x, q) == pytest.approx(
        M.lci(M.resolve_design({"h": 30.0}), opts, x, q), rel=1e-12
    )


def test_stroke_limits_decide_reachability():
    x = REF["case1"]["fk"]  # q = (80, 90, 80)
    assert M.point_kernel(M.pack(PAPER, P_OPT), *x) > 0  # 90 is inside [40, 90] (closed interval)
    tight = M.resolve_options({"stroke_limits": [40.0, 89.0]})
    assert M.point_kernel(M.pack(PAPER, tight), *x) == -1.0
    assert M.point_kernel(M.pack(PAPER, M.resolve_options(FREE)), 500.0, 0.0, 0.0) > 0


# ----- Jacobians and singularities ----------------------------------------------------------------------------
def test_p_model_twist_jacobian_equals_spec_formula():
    """§2.5: the twist form q' = u.v + (r x u).omega with T = d(v, omega)/d(z, theta, psi) equals the closed-form
    rows of the P-model, here with e != 0 (row 3 has c e sin(theta))."""
    rng = np.random.default_rng(3)
    for _ in range(50):
        g, h, c, e = rng.uniform(40, 120), rng.uniform(20, 80), rng.uniform(20, 80), rng.uniform(-30, 30)
        design = M.resolve_design({"g": g, "h": h, "c": c, "e": e})
        z, th, ps = rng.uniform(1, 90), rng.uniform(-1, 1), rng.uniform(-1, 1)
        (sol,) = M.inverse_kinematics(design, P_OPT, (z, th, ps))
        q1, q2, q3 = sol.values
        st, ct, sp, cp = math.sin(th), math.cos(th), math.sin(ps), math.cos(ps)
        rows = [
            [(z - h * ct * sp) / q1, h * z * st * sp / q1, (g * h * sp - h * z * ct * cp) / q1],
            [(z + h * ct * sp) / q2, -h * z * st * sp / q2, (g * h * sp + h * z * ct * cp) / q2],
            [(z - c * st) / q3, (c * e * st - c * z * ct) / q3, 0.0],
        ]
        jac = M.jacobians(design, P_OPT, (z, th, ps), sol.values)["dq_dx"]
        np.testing.assert_allclose(jac, rows, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("options", [P_OPT, PLANE, UPU], ids=["P", "plane", "upu"])
def test_jacobian_matches_central_differences_of_ik(options):
    rng = np.random.default_rng(11)
    design = M.resolve_design({"e": 12.0})
    for _ in range(20):
        x = np.array([rng.uniform(10, 90), rng.uniform(-0.7, 0.7), rng.uniform(-0.7, 0.7)])
        (sol,) = M.inverse_kinematics(design, options, x)
        jac = M.jacobians(design, options, x, sol.values)["dq_dx"]
        num = np.zeros((3, 3))
        for k in range(3):
            step = 1e-3 if k == 0 else 1e-5
            vals = {}
            for m in (-2, -1, 1, 2):
                xx = x.copy()
                xx[k] += m * step
                vals[m] = M.inverse_kinematics(design, options, xx)[0].values
            num[:, k] = (vals[-2] - 8 * vals[-1] + 8 * vals[1] - vals[2]) / (12 * step)
        np.testing.assert_allclose(jac, num, rtol=1e-7, atol=1e-7)


def test_forward_singularity_theta_half_pi():
    """P-model, e = 0, psi = 0: det dq/dx = 2 c h z^3 cos^2(theta) / (q1^2 q3) vanishes at theta = pi/2."""
    pose = (80.0, math.pi / 2, 0.0)
    opts = M.resolve_options(FREE)
    (sol,) = M.inverse_kinematics(PAPER, opts, pose)
    np.testing.assert_allclose(sol.values, (math.sqrt(80**2 + 30**2),) * 2 + (30.0,), atol=1e-12)
    assert M.singularity(PAPER, opts, pose, sol.values) == "forward"
    assert M.lci(PAPER, opts, pose, sol.values) < 1e-12
    assert M.point_kernel(M.pack(PAPER, opts), *pose) < 1e-12
    # the assembly modes merge there: FK still returns the pose
    assert nearest(fk(opts, sol.values), pose)[1] < 1e-6
    # and just off it the mechanism is regular
    near = (80.0, math.pi / 2 - 0.3, 0.0)
    (sol,) = M.inverse_kinematics(PAPER, opts, near)
    assert M.singularity(PAPER, opts, near, sol.values) == "none"


def test_zero_leg_length_is_both_singular():
    """g = h puts B1 on A1 and B2 on A2 at z = theta = psi = 0: q1 = q2 = 0 (inverse); the zero legs also make
    the constraint rows vanish (forward), so 'both'."""
    design = M.resolve_design({"g": 50.0, "h": 50.0})
    opts = M.resolve_options({"stroke_limits": [0.0, 100.0]})
    (sol,) = M.inverse_kinematics(design, opts, (0.0, 0.0, 0.0))
    np.testing.assert_allclose(sol.values, (0.0, 0.0, 50.0), atol=1e-12)
    assert M.singularity(design, opts, (0.0, 0.0, 0.0), sol.values) == "both"
    assert M.lci(design, opts, (0.0, 0.0, 0.0), sol.values) == 0.0
    assert M.point_kernel(M.pack(design, opts), 0.0, 0.0, 0.0) == 0.0


def test_c_model_degenerate_parametrisation():
    """cos psi = 0 with sin theta = 0 leaves the parasitic yaw undefined; cos theta = 0 makes the upu y0 unbounded."""
    pose = (50.0, 0.0, math.pi / 2)
    assert M.inverse_kinematics(PAPER, PLANE, pose) == []
    assert M.point_kernel(M.pack(PAPER, M.resolve_options({"model": "C", **FREE})), *pose) == -1.0
    with pytest.raises(InvalidPose, match="^pose:"):
        M.platform_pose(PAPER, PLANE, pose)
    assert M.inverse_kinematics(PAPER, UPU, (50.0, math.pi / 2, 0.3)) == []
    assert len(M.inverse_kinematics(PAPER, PLANE, (50.0, math.pi / 2, 0.3))) == 1


# ----- FK algorithms ------------------------------------------------------------------------------------------
def test_quartic_and_bracketing_agree_for_e_zero():
    rng = np.random.default_rng(5)
    compared = 0
    for _ in range(40):
        design = M.resolve_design({"g": rng.uniform(40, 120), "h": rng.uniform(20, 80), "c": rng.uniform(20, 80)})
        geom = M._geom(design)
        x = (rng.uniform(5, 90), rng.uniform(-1, 1), rng.uniform(-1, 1))
        q = M.inverse_kinematics(design, P_OPT, x)[0].values
        out = []
        for cands in (rps.fk_p_quartic(geom, q), rps.fk_p_bracket(geom, q)):
            xs, res = rps._newton(geom, "P", "plane", q, cands)
            ok = (res <= 1e-9 * q.max()) & (xs[:, 0] > 0)  # forward_kinematics keeps z > 0 the same way
            out.append(sorted(map(tuple, np.round(rps._distinct(xs[ok], res[ok]), 7))))
        assert out[0] == out[1]
        compared += len(out[0])
    assert compared >= 80


def test_e_nonzero_fk_matches_table_style_solution():
    """With e != 0 the quartic does not apply; bracketing finds the pose and its mirror branch."""
    design = M.resolve_design({"e": 25.0})
    pose = (60.0, 0.2, -0.1)
    q = M.inverse_kinematics(design, P_OPT, pose)[0].values
    sols = fk(P_OPT, q, design)
    assert nearest(sols, pose)[1] < 1e-10
    with pytest.raises(ValueError, match="e = 0"):
        rps.fk_p_quartic(M._geom(design), q)


@pytest.mark.parametrize("pose", [(75.0, 0.0, 0.0), (75.0, 1.0, 0.0)])
def test_bracketing_finds_roots_at_the_interval_ends(pose):
    """psi = 0 gives q1 = q2 (D = 0): the root sits where cos psi = 1, an end of the bracketing interval, and F
    touches zero there without a sign change (found by hypothesis)."""
    design = M.resolve_design({"g": 40.0, "h": 20.0, "c": 20.0, "e": 1.0})
    q = M.inverse_kinematics(design, P_OPT, pose)[0].values
    assert nearest(fk(P_OPT, q, design), pose)[1] < 1e-9


def test_fk_unreachable_inputs_give_no_solution():
    assert fk(P_OPT, (1.0, 1.0, 1.0)) == []
    assert fk(PLANE, (1.0, 1.0, 1.0)) == []


designs = st.fixed_dictionaries(
    {
        "g": st.floats(40, 120),
        "h": st.floats(20, 80),
        "c": st.floats(20, 80),
        "e": st.one_of(st.just(0.0), st.floats(-30, 30)),
    }
)
poses = st.tuples(st.floats(2, 100), st.floats(-1.2, 1.2), st.floats(-1.2, 1.2))


def _round_trip(design, options, pose):
    design = M.resolve_design(design)
    opts = dict(options, stroke_limits=None)
    sols = M.inverse_kinematics(design, opts, pose)
    assume(sols)
    q = sols[0].values
    # FK is ill-conditioned next to singular poses (merging branches); away from them it must find the pose
    assume(M.lci(design, opts, pose, q) > 1e-3)
    out = M.forward_kinematics(design, opts, q)
    assert nearest(out, pose)[1] < 1e-8
    for s in out:
        assert s.values[0] > 0
        back = M.inverse_kinematics(design, opts, s.values)[0].values
        assert np.abs(back - q).max() < 1e-9 * max(1.0, q.max())


@settings(max_examples=120, deadline=None)
@given(designs, poses)
def test_p_model_ik_fk_round_trip(design, pose):
    _round_trip(design, P_OPT, pose)


@settings(max_examples=12, deadline=None)
@given(designs, st.tuples(st.floats(5, 90), st.floats(-0.7, 0.7), st.floats(-0.7, 0.7)), st.sampled_from([PLANE, UPU]))
def test_c_model_ik_fk_round_trip(design, pose, options):
    _round_trip(design, options, pose)


# ----- validation and CLI -------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("options", "field"),
    [
        ({"model": "X"}, "options.model"),
        ({"c3_variant": "upv"}, "options.c3_variant"),
        ({"stroke_limits": [90, 40]}, "options.stroke_limits"),
        ({"stroke_limits": [-5, 40]}, "options.stroke_limits"),
        ({"z_range": None}, "options.z_range"),
        ({"theta_range": [0.3]}, "options.theta_range"),
        ({"characteristic_length": 0}, "options.characteristic_length"),
        ({"characteristic_length": "h"}, "options.characteristic_length"),
        ({"tool": 1}, "options.tool"),
    ],
)
def test_bad_options_name_the_field(options, field):
    with pytest.raises(InvalidParameter, match=f"^{field}: "):
        M.resolve_options(options)


def test_bad_design_and_inputs():
    assert M.resolve_design({"e": -12.5})["e"] == -12.5  # e may be negative or zero
    with pytest.raises(InvalidParameter, match="^design.g: must be > 0"):
        M.resolve_design({"g": 0})
    with pytest.raises(InvalidPose, match="^inputs: leg lengths must be >= 0"):
        M.forward_kinematics(PAPER, P_OPT, (80, -1, 80))
    with pytest.raises(InvalidPose, match="^pose:"):
        M.inverse_kinematics(PAPER, P_OPT, (80, 0.1))


def test_cli_fk_and_ik():
    runner = CliRunner()
    r = runner.invoke(app, ["fk", "rps-upu", "--inputs", "80,90,80", "--json"])
    assert r.exit_code == 0, r.output
    out = json.loads(r.stdout)
    assert out["names"] == ["z", "theta", "psi"]
    assert [s["branch"] for s in out["solutions"]] == ["1++", "1-+", "2++", "2-+"]
    np.testing.assert_allclose(out["solutions"][0]["values"], REF["case1"]["fk"], atol=1e-10)
    r = runner.invoke(app, ["ik", "rps-upu", "--pose", "79.36842875,0.30710989,0.11259002", "--set", "model=C",
                            "--json"])  # fmt: skip
    assert r.exit_code == 0, r.output
    sol = json.loads(r.stdout)["solutions"][0]
    assert sol["branch"] == "+++" and sol["singularity"] == "none" and 0 < sol["lci"] < 1
    np.testing.assert_allclose(sol["values"], C_PLANE["case1"][0], atol=1e-6)
    r = runner.invoke(app, ["fk", "rps-upu", "--inputs", "80,90,80", "--set", "model=Q"])
    assert r.exit_code == 2 and "options.model" in r.output


def test_config_loads_and_evaluates(root):
    from scalesynth.config import load_config

    cfg = load_config(root / "configs" / "rps_upu.yaml")
    assert cfg.mechanism == "rps-upu" and cfg.units.length == "mm"
    assert cfg.resolved_design() == {"g": 80.0, "h": 50.0, "c": 50.0, "e": 0.0}
    assert cfg.algorithm.pop_size == 100 and cfg.algorithm.n_gen == 100
    rep = evaluate(cfg.mech, cfg.resolved_design(), cfg.resolved_options(), resolution=cfg.grid.resolution,
                   length_unit=cfg.units.length)  # fmt: skip
    assert rep.measure_key == "volume_mm_rad2"
    # box 100 mm x 0.628^2 rad^2; the feasible share on nodes is 153595/400869 = 0.383 (spec §2.8)
    assert rep.measure == pytest.approx(100 * 0.628**2 * 153595 / 400869, rel=0.02)
    assert 0.3 < rep.gci < 0.5


# ----- tool-point position workspace (spec §2.8) --------------------------------------------------------------
TOOL = rps.TOOL_MECHANISM
T_OPT = TOOL.resolve_options({})  # d = 50 mm, q in [40, 90] (ASSUMED), the paper's pose box


def test_tool_point_inverse_and_forward():
    """T = O' + R (0, 0, -d) of the case-1 solution; its principal pose gives back q = (80, 90, 80)."""
    x = np.array(REF["case1"]["fk"])
    tp = TOOL.tool_point(PAPER, T_OPT, x)
    z, th, ps = x
    np.testing.assert_allclose(tp, [-50 * math.sin(th) * math.cos(ps), 50 * math.sin(ps),
                                    z - 50 * math.cos(th) * math.cos(ps)], atol=1e-12)  # fmt: skip
    poses = {s.label: s.values for s in TOOL.poses_of_tool_point(PAPER, T_OPT, tp)}
    assert set(poses) == {"++", "-+", "+-", "--"}
    np.testing.assert_allclose(poses["++"], x, atol=1e-12)
    for v in poses.values():  # every pose branch places the tool at T
        np.testing.assert_allclose(TOOL.tool_point(PAPER, T_OPT, v), tp, atol=1e-10)
    sols = {s.label: s.values for s in TOOL.inverse_kinematics(PAPER, T_OPT, tp)}
    np.testing.assert_allclose(sols[TOOL.kernel_branch(T_OPT)], (80, 90, 80), atol=1e-10)
    fk_t = TOOL.forward_kinematics(PAPER, T_OPT, (80, 90, 80))
    assert fk_t[0].label == "1++"
    np.testing.assert_allclose(fk_t[0].values, tp, atol=1e-10)
    assert TOOL.inverse_kinematics(PAPER, T_OPT, (0.0, 60.0, 10.0)) == []  # |T_y| > d
    assert TOOL.point_kernel(TOOL.pack(PAPER, T_OPT), 0.0, 60.0, 10.0) == -1.0
    assert TOOL.measure_key("mm") == "volume_mm3"


@pytest.mark.parametrize(
    ("design", "options"),
    [({}, {}), ({"e": 15.0}, {"tool_offset": 80.0, "stroke_limits": [30.0, 100.0]}),
     ({}, {"theta_range": [-1.0, 1.0], "psi_range": [-1.2, 1.2], "stroke_limits": None})],
)  # fmt: skip
def test_tool_kernel_matches_numpy_twin(design, options):
    design = TOOL.resolve_design(design)
    options = TOOL.resolve_options(options)
    g = make_grid(TOOL, design, options, 20)
    lci = kgrid.sample_grid(TOOL.point_kernel, TOOL.pack(design, options), g.lo, g.step, g.shape)
    twin = rps_upu_tool_lci(design, options, *grid_nodes(g.lo, g.step, g.shape))
    assert np.array_equal(lci >= 0, twin >= 0)
    assert np.count_nonzero(lci >= 0) > 100
    np.testing.assert_allclose(lci[lci >= 0], twin[twin >= 0], rtol=1e-7, atol=1e-12)
    rep = evaluate(TOOL, design, options, resolution=20)
    assert rep.measure_key == "volume_mm3" and rep.metrics["voxels"] == np.count_nonzero(twin >= 0)


def test_tool_workspace_is_the_image_of_the_pose_workspace():
    """Sampled poses in the box: the tool kernel at T(pose) is feasible iff the (z, theta, psi) kernel is, with
    the LCI of dq/dT = dq/dx dx/dT; every T(pose) lies in the tool bounding box."""
    rng = np.random.default_rng(2)
    lo, hi = TOOL.bounding_box(PAPER, T_OPT)
    pk, tk = M.pack(PAPER, P_OPT), TOOL.pack(PAPER, T_OPT)
    feasible = 0
    for _ in range(400):
        pose = (rng.uniform(-10, 90), rng.uniform(-0.314, 0.314), rng.uniform(-0.314, 0.314))
        tp = TOOL.tool_point(PAPER, T_OPT, pose)
        assert np.all(tp >= lo) and np.all(tp <= hi)
        a, b = M.point_kernel(pk, *pose), TOOL.point_kernel(tk, *tp)
        assert (a >= 0) == (b >= 0)
        if b >= 0:
            feasible += 1
            q = M.inverse_kinematics(PAPER, P_OPT, pose)[0].values
            assert TOOL.lci(PAPER, T_OPT, tp, q) == pytest.approx(b, rel=1e-9)
    assert feasible > 50


def test_tool_jacobian_matches_central_differences():
    rng = np.random.default_rng(4)
    for _ in range(10):
        pose = (rng.uniform(20, 90), rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5))
        tp = TOOL.tool_point(PAPER, T_OPT, pose)
        q = M.inverse_kinematics(PAPER, P_OPT, pose)[0].values
        jac = TOOL.jacobians(PAPER, T_OPT, tp, q)
        num = np.zeros((3, 3))
        for k in range(3):
            vals = {}
            for m in (-2, -1, 1, 2):
                t = tp.copy()
                t[k] += m * 1e-3
                vals[m] = {s.label: s.values for s in TOOL.inverse_kinematics(PAPER, T_OPT, t)}["++"]
            num[:, k] = (vals[-2] - 8 * vals[-1] + 8 * vals[1] - vals[2]) / 12e-3
        np.testing.assert_allclose(jac["dq_dT"], num, rtol=1e-7, atol=1e-8)
        np.testing.assert_allclose(jac["J"] @ jac["dq_dT"], np.eye(3), atol=1e-10)
        assert TOOL.singularity(PAPER, T_OPT, tp, q) == "none"


def test_tool_singular_where_t_stops_fixing_theta():
    """cos theta = 0: dT/d(z, theta, psi) has det -d^2 cos(theta) cos(psi)^2 = 0."""
    pose = (80.0, math.pi / 2, 0.0)
    tp = TOOL.tool_point(PAPER, T_OPT, pose)
    np.testing.assert_allclose(tp, (-50.0, 0.0, 80.0), atol=1e-12)
    q = M.inverse_kinematics(PAPER, P_OPT, pose)[0].values
    assert TOOL.singularity(PAPER, T_OPT, tp, q) == "forward"
    assert TOOL.lci(PAPER, T_OPT, tp, q) < 1e-12


def test_tool_options_validation():
    with pytest.raises(InvalidParameter, match="^options.tool_offset: "):
        TOOL.resolve_options({"tool_offset": 0})
    with pytest.raises(InvalidParameter, match="^options.model: unknown option"):
        TOOL.resolve_options({"model": "C"})
    assert TOOL.resolve_options(T_OPT) == T_OPT  # resolving twice is a no-op
