"""Seed-003 2-UPS/(S+SPR)R: spec mechanisms_001_003.md §3 (§3.7, tests/data/cases/ref003.json), the kernel
against its NumPy twin (tests/naive.py), and property tests (IK/FK round trips, Jacobians vs differences).

Dimensions a = 100, b = 80 are the spec's PLACEHOLDERS (not in the paper); c = 120 is the paper's.
"""

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq, fsolve
from typer.testing import CliRunner

from scalesynth.cli import app
from scalesynth.config import load_config
from scalesynth.errors import InvalidParameter, InvalidPose
from scalesynth.evaluate import evaluate, make_grid
from scalesynth.kernels import grid as kgrid
from scalesynth.mechanisms import available, get

from conftest import ROOT
from naive import assert_report_equals_grid_metrics, grid_metrics, grid_nodes, ups_sspr_lci
from refdata import load_case

M = get("ups-sspr")
DESIGN = M.resolve_design({})  # a = 100, b = 80 (placeholders), c = 120
OPT = M.resolve_options({})
PACKED = M.pack(DESIGN, OPT)
NO_LIMITS = {"l1_limits": None, "l2_limits": None, "l3_limits": None}
REF = load_case("ref003.json")  # tests/data/cases/, provenance in tests/data/README.md

# spec §3.7 table: pose -> (l1, l2, l3), 10 decimals
TABLE = {
    (0.0, 0.0, 0.0): (94.3398113206, 163.2755195317, 163.2755195317),
    (0.2, -0.1, 15.0): (99.4987437107, 173.7277358451, 186.2456339443),
    (-0.3, 0.25, -20.0): (86.9865890047, 151.4829092553, 119.3282901161),
    (0.35, 0.3, 30.0): (104.4030650891, 210.6881119708, 174.6691271321),
}


def lengths(pose, design=DESIGN):
    sols = M.inverse_kinematics(design, OPT, pose)
    assert [s.label for s in sols] == [M.kernel_branch(OPT)]
    return sols[0].values


def fk(q, design=DESIGN):
    return M.forward_kinematics(design, OPT, q)


def closest(sols, pose):
    """Distance (alpha wrapped) from pose to the nearest solution, and that solution."""

    def dist(s):
        d = np.abs(s.values - np.asarray(pose, dtype=float))
        d[0] = abs(math.remainder(s.values[0] - pose[0], 2 * math.pi))
        return d.max()

    best = min(sols, key=dist)
    return dist(best), best


def test_registered_with_units():
    assert "ups-sspr" in available()
    assert M.task_axes == ("alpha", "beta", "Y") and M.joints == ("l1", "l2", "l3")
    assert M.measure_key("mm") == "volume_mm_rad2"
    assert DESIGN == {"a": 100.0, "b": 80.0, "c": 120.0}


# ----- spec §3.7 / ref003.json ------------------------------------------------------------------------------
@pytest.mark.parametrize("pose", list(TABLE))
def test_spec_table_lengths(pose):
    assert lengths(pose) == pytest.approx(TABLE[pose], abs=6e-11)


@pytest.mark.parametrize("case", REF, ids=lambda c: str(c["x"]))
def test_ref003_lengths_and_jacobian(case):
    assert lengths(case["x"]) == pytest.approx(case["l"], rel=1e-13)
    # spec §3.5's J = dl/d(alpha, beta, Y) is Jx here (Jx xdot = ldot); the spec's 1e-16..1e-15 entries in
    # column beta of row l1 are its round-off: l1 depends on Y only
    jac = M.jacobians(DESIGN, OPT, case["x"])
    np.testing.assert_allclose(jac["Jx"], case["J"], rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(jac["J"] @ jac["Jx"], np.eye(3), atol=1e-12)


def test_table_jacobian_at_home():
    expected = [[0, 0, 0.353333], [41.575278, 63.648885, 0.652691], [41.575278, -63.648885, 0.652691]]
    np.testing.assert_allclose(M.jacobians(DESIGN, OPT, (0, 0, 0))["Jx"], expected, atol=5e-7)
    # row l1: (2/3) a_m / l1 exactly (spec §3.5)
    assert M.jacobians(DESIGN, OPT, (0, 0, 0))["Jx"][0, 2] == pytest.approx(2 / 3 * 50 / TABLE[(0, 0, 0)][0], rel=1e-10)


def test_passive_joints_case2():
    got = M.passive_joints(DESIGN, (0.2, -0.1, 15.0))
    assert got["alpha_L"] == pytest.approx(-0.1253278312, abs=5e-11)  # spec §3.7
    assert got["gamma"] == pytest.approx(0.3253278312, abs=5e-11)
    assert got["alpha_L"] == pytest.approx(-math.asin(15 / 120), rel=1e-15)


@pytest.mark.parametrize("case", REF, ids=lambda c: str(c["x"]))
def test_ref003_fk_branches(case):
    sols = fk(case["l"])
    assert sorted(s.label for s in sols) == ["+", "-"]  # two Z > 0 assembly modes (spec §3.4)
    for branch in case["branches"]:
        dist, _ = closest(sols, branch)
        assert dist < 1e-9
    # the pose itself is in mode '-', the flipped platform in mode '+'
    dist, sol = closest(sols, case["x"])
    assert dist < 1e-9 and sol.label == "-"


def test_table_second_branches():
    # spec §3.7 table, 9 decimals
    for pose, second in (
        ((-0.3, 0.25, -20.0), (2.936320669, 0.194814279, -20.0)),
        ((0.35, 0.3, 30.0), (1.566937181, 0.234066929, 30.0)),
    ):
        plus = {s.label: s.values for s in fk(lengths(pose))}["+"]
        np.testing.assert_allclose(plus, second, atol=6e-10)


# ----- geometry facts of spec §3.3 / §3.8 -------------------------------------------------------------------
@settings(max_examples=50, deadline=None)
@given(st.floats(-1.5, 1.5), st.floats(-1.5, 1.5), st.floats(-119, 119))
def test_mirror_symmetry_swaps_l2_l3(alpha, beta, y):
    l = lengths((alpha, beta, y))
    m = lengths((alpha, -beta, y))
    assert m == pytest.approx([l[0], l[2], l[1]], rel=1e-13, abs=1e-12)
    # and the (symmetric-limits) workspace is symmetric too
    assert M.point_kernel(PACKED, alpha, -beta, y) == pytest.approx(M.point_kernel(PACKED, alpha, beta, y), rel=1e-9)


def test_l1_slab():
    # spec §3.8: l1 in [80, 110] <=> Y in [-37.5, 48] (placeholder dimensions)
    lo, hi = M.bounding_box(DESIGN, OPT)
    np.testing.assert_allclose(lo, [-0.5, -0.5, -37.5], rtol=1e-14)
    np.testing.assert_allclose(hi, [0.5, 0.5, 48.0], rtol=1e-14)
    assert lengths((0, 0, -37.5))[0] == pytest.approx(80.0, rel=1e-14)
    assert lengths((0, 0, 48.0))[0] == pytest.approx(110.0, rel=1e-14)
    # l2 = l3 = 163.3 at alpha = beta = 0, inside [120, 220]: only l1 decides along Y there
    for y, inside in ((-37.51, False), (-37.49, True), (47.99, True), (48.01, False)):
        assert (M.point_kernel(PACKED, 0.0, 0.0, y) >= 0) == inside
    assert M.y_of_l1(DESIGN, 80.0) == pytest.approx(-37.5, rel=1e-14)


def test_box_defaults_and_clipping():
    lo, hi = M.bounding_box(DESIGN, M.resolve_options(NO_LIMITS))
    assert (lo[2], hi[2]) == pytest.approx((-119.88, 119.88), rel=1e-14)  # Y_range null = +-0.999 c
    lo, hi = M.bounding_box(DESIGN, M.resolve_options(dict(NO_LIMITS, Y_range=[-500, 10])))
    assert (lo[2], hi[2]) == (-120.0, 10.0)
    lo, hi = M.bounding_box(DESIGN, M.resolve_options({"Y_range": [60, 90]}))  # disjoint from the l1 slab
    assert hi[2] == lo[2]
    assert M.point_kernel(PACKED, 0.0, 0.0, 0.0) == pytest.approx(M.lci(DESIGN, OPT, (0, 0, 0)), rel=1e-12)
    assert M.point_kernel(PACKED, 0.6, 0.0, 0.0) == -1.0  # outside alpha_range
    assert M.point_kernel(PACKED, 0.0, -0.6, 0.0) == -1.0  # outside beta_range


# ----- LCI ---------------------------------------------------------------------------------------------------
def test_lci_at_home_from_spec_jacobian():
    # 1/cond_2 of the spec's J at home (ref003.json) with the angle columns over L = c = 120
    spec_j = np.array(REF[0]["J"]) / np.array([120.0, 120.0, 1.0])
    sv = np.linalg.svd(spec_j, compute_uv=False)
    expected = sv[-1] / sv[0]
    assert expected == pytest.approx(0.145263776, abs=1e-9)
    assert M.lci(DESIGN, OPT, (0, 0, 0)) == pytest.approx(expected, rel=1e-12)
    assert M.point_kernel(PACKED, 0.0, 0.0, 0.0) == pytest.approx(expected, rel=1e-9)
    opt = M.resolve_options({"characteristic_length": 60.0})
    sv = np.linalg.svd(np.array(REF[0]["J"]) / np.array([60.0, 60.0, 1.0]), compute_uv=False)
    assert M.point_kernel(M.pack(DESIGN, opt), 0.0, 0.0, 0.0) == pytest.approx(sv[-1] / sv[0], rel=1e-9)


@settings(max_examples=40, deadline=None)
@given(st.floats(0.2, 5.0), st.floats(-0.5, 0.5), st.floats(-0.5, 0.5), st.floats(-0.9, 0.9))
def test_lci_is_scale_free(k, alpha, beta, u):
    """Homogenisation: scaling every length (a, b, c, Y, and L = c) by k leaves the LCI unchanged."""
    y = u * 120
    scaled = M.resolve_design({"a": 100 * k, "b": 80 * k, "c": 120 * k})
    assert M.lci(scaled, OPT, (alpha, beta, y * k)) == pytest.approx(M.lci(DESIGN, OPT, (alpha, beta, y)), rel=1e-9)


TWIN_CASES = [
    ({}, {}),
    ({"a": 70.0, "b": 110.0, "c": 125.0}, dict(NO_LIMITS, alpha_range=[-1.2, 1.0], characteristic_length=50.0)),
    ({}, {"l2_limits": [150.0, 190.0], "l3_limits": [140.0, 200.0], "beta_range": [-0.2, 0.7]}),
    ({"a": 140.0}, {"Y_range": [-60.0, 30.0], "l1_limits": None}),
]


@pytest.mark.parametrize(("design", "options"), TWIN_CASES)
def test_kernel_matches_numpy_twin(design, options):
    design = M.resolve_design(design)
    options = M.resolve_options(options)
    g = make_grid(M, design, options, 20)
    al, be, yy = grid_nodes(g.lo, g.step, g.shape)
    twin = ups_sspr_lci(design, options, al, be, yy)
    lci = kgrid.sample_grid(M.point_kernel, M.pack(design, options), g.lo, g.step, g.shape)
    assert np.array_equal(lci >= 0, twin >= 0)  # same reachable voxels
    assert 0 < np.count_nonzero(lci >= 0) < lci.size or options["l1_limits"] is None
    np.testing.assert_allclose(lci[lci >= 0], twin[twin >= 0], rtol=1e-7, atol=1e-12)
    edges = (0.0, 0.1, 0.3, 1.0)
    ref = grid_metrics(twin, g.cell_measure, edges)
    rep = evaluate(M, design, options, resolution=20, band_edges=edges)
    assert rep.measure_key == "volume_mm_rad2"
    assert_report_equals_grid_metrics(rep, ref, gci_rel=1e-7)


def test_resolution_convergence():
    """Default box: the 64-per-axis grid is within 0.1 % (volume) and 1e-3 (GCI) of a 2x finer grid."""
    coarse = evaluate(M, DESIGN, OPT, resolution=64)
    fine = evaluate(M, DESIGN, OPT, resolution=128)
    assert abs(coarse.measure / fine.measure - 1) < 1e-3
    assert abs(coarse.gci - fine.gci) < 1e-3
    assert fine.measure < 1.0 * 1.0 * 85.5  # inside the box alpha x beta x Y = 1 x 1 x 85.5


def test_config_loads_and_evaluates():
    cfg = load_config(ROOT / "configs" / "ups_sspr.yaml", ["grid.resolution=16"])
    assert cfg.mechanism == "ups-sspr" and cfg.units.length == "mm"
    assert cfg.resolved_design() == DESIGN
    assert [o.metric for o in cfg.objectives] == ["volume", "gci"]
    assert (cfg.algorithm.pop_size, cfg.algorithm.n_gen) == (100, 100)
    for key, (lo, hi) in cfg.bounds.items():
        assert lo <= DESIGN[key] <= hi
    rep = evaluate(M, cfg.resolved_design(), cfg.resolved_options(), resolution=16)
    assert rep.measure > 0 and 0 < rep.gci < 1


# ----- round trips and Jacobians -----------------------------------------------------------------------------
poses = st.tuples(st.floats(-0.5, 0.5), st.floats(-0.5, 0.5), st.floats(-60, 60))


@settings(max_examples=200, deadline=None)
@given(poses)
def test_ik_fk_round_trip(pose):
    # spec §3.4: |alpha|, |beta| <= 0.5, |Y| <= 60 return to <= 9e-14 there; here <= 1e-9
    q = lengths(pose)
    sols = fk(q)
    dist, sol = closest(sols, pose)
    assert dist <= 1e-9
    assert sol.label == "-"
    for s in sols:  # every assembly mode reproduces the inputs
        assert lengths(s.values) == pytest.approx(q, rel=1e-11)


def test_fk_out_of_reach():
    assert fk((200.0, 160.0, 160.0)) == []  # l1 = 200 needs Y = 466 > c
    assert fk((94.34, 5.0, 5.0)) == []  # UPS legs far too short
    assert M.inverse_kinematics(DESIGN, OPT, (0.0, 0.0, 121.0)) == []


@settings(max_examples=60, deadline=None)
@given(st.floats(-1.5, 1.5), st.floats(-1.2, 1.2), st.floats(-110, 110))
def test_jx_matches_central_differences_of_ik(alpha, beta, y):
    x = np.array([alpha, beta, y])
    jac = M.jacobians(DESIGN, OPT, x)["Jx"]
    num = np.zeros((3, 3))
    for k, h in enumerate((1e-4, 1e-4, 1e-2)):
        e = np.zeros(3)
        e[k] = h
        f = {s: lengths(x + s * e) for s in (-2, -1, 1, 2)}
        num[:, k] = (f[-2] - 8 * f[-1] + 8 * f[1] - f[2]) / (12 * h)  # fourth-order central difference
    np.testing.assert_allclose(num, jac, rtol=1e-6, atol=1e-6 * np.abs(jac).max())


@pytest.mark.parametrize("case", REF, ids=lambda c: str(c["x"]))
def test_forward_jacobian_matches_fk_differences(case):
    q = np.array(case["l"])
    jac = M.jacobians(DESIGN, OPT, case["x"])["J"]
    h = 1e-3
    num = np.zeros((3, 3))
    for k in range(3):
        f = {}
        for s in (-1, 1):
            qq = q.copy()
            qq[k] += s * h
            f[s] = closest(fk(qq), case["x"])[1].values
        num[:, k] = (f[1] - f[-1]) / (2 * h)
    np.testing.assert_allclose(num, jac, atol=1e-6 * np.abs(jac).max())


# ----- singularities ----------------------------------------------------------------------------------------
def test_regular_poses():
    for pose in TABLE:
        assert M.singularity(DESIGN, OPT, pose, lengths(pose)) == "none"


def test_forward_singularity_between_the_modes():
    """At beta = 0, Y = 0 the (alpha, beta) block of rows l2, l3 is [[j, k], [j, -k]]: singular where
    dl2/dalpha = 0, found here by root bracketing (it separates mode '-' from the flipped mode '+')."""
    alpha = brentq(lambda t: M.jacobians(DESIGN, OPT, (t, 0.0, 0.0))["Jx"][1, 0], 0.0, math.pi, xtol=1e-15)
    pose = (alpha, 0.0, 0.0)
    assert M.singularity(DESIGN, OPT, pose, lengths(pose)) == "forward"
    assert M.lci(DESIGN, OPT, pose) < 1e-12
    wide = M.resolve_options(dict(NO_LIMITS, alpha_range=[-math.pi, math.pi]))
    assert M.point_kernel(M.pack(DESIGN, wide), alpha, 0.0, 0.0) == pytest.approx(0.0, abs=1e-9)
    assert M.singularity(DESIGN, OPT, (alpha - 1e-3, 0.0, 0.0)) == "none"
    sols = fk(lengths((alpha - 0.05, 0.0, 0.0)))
    assert closest(sols, (alpha - 0.05, 0.0, 0.0))[1].label == "-"
    assert closest(fk(lengths((alpha + 0.05, 0.0, 0.0))), (alpha + 0.05, 0.0, 0.0))[1].label == "+"


def test_forward_singularity_at_the_pole():
    # rho = 0 (|Y| = c): the spheres |P| = c and |(2/3)P - M| = l1 touch (spec §3.5)
    pose = (0.1, 0.2, 120.0)
    assert M.singularity(DESIGN, OPT, pose, lengths(pose)) == "forward"
    assert M.lci(DESIGN, OPT, pose) == 0.0
    assert M.jacobians(DESIGN, OPT, pose)["J"] is None
    near = M.resolve_options(dict(NO_LIMITS, Y_range=[-120.0, 120.0]))
    assert M.point_kernel(M.pack(DESIGN, near), 0.1, 0.2, 120.0) == -1.0  # |Y| = c is outside the open domain
    assert 0.0 <= M.point_kernel(M.pack(DESIGN, near), 0.1, 0.2, 120.0 - 1e-9) < 1e-3


def test_inverse_singularity_zero_length_leg():
    """l2 = 0 (B2 = A2) is reachable without limits; the pose solves P + R B2' = A2 (3 equations)."""
    s2 = math.sqrt(2)

    def b2_minus_a2(x):
        al, be, y = x
        rho = math.sqrt(120**2 - y * y)
        rb = (-80 / s2 * math.cos(be) + math.sin(be) * math.sin(al) * 80 / s2, math.cos(al) * 80 / s2,
              80 / s2 * math.sin(be) + math.cos(be) * math.sin(al) * 80 / s2)
        return [math.sin(be) * rho + rb[0] + 50 * math.sqrt(3), y + rb[1] + 50, math.cos(be) * rho + rb[2]]

    pose = fsolve(b2_minus_a2, [-2.0, -0.86, -26.5], xtol=1e-14)
    assert lengths(pose)[1] < 1e-10
    assert M.singularity(DESIGN, OPT, pose, lengths(pose)) == "inverse"
    assert M.lci(DESIGN, OPT, pose) == 0.0
    # l1 = 0 needs a_m = 2c/3 and Y = -c, where also rho = 0
    design = M.resolve_design({"a": 160.0})
    # l1^2 = (2c/3 - a_m)^2 cancels to round-off (~1e-12 mm^2), so l1 is ~1e-6 mm, still below tol c = 1.2e-5
    assert lengths((0.0, 0.0, -120.0), design)[0] == pytest.approx(0.0, abs=1e-5)
    assert M.singularity(design, OPT, (0.0, 0.0, -120.0), None) == "both"


# ----- bad input ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("options", "field"),
    [
        ({"l1_limits": [110, 80]}, "options.l1_limits"),
        ({"l2_limits": [-1, 80]}, "options.l2_limits"),
        ({"l3_limits": "wide"}, "options.l3_limits"),
        ({"alpha_range": None}, "options.alpha_range"),
        ({"beta_range": [-2.0, 0.5]}, "options.beta_range"),
        ({"Y_range": [10, 10]}, "options.Y_range"),
        ({"characteristic_length": 0}, "options.characteristic_length"),
        ({"characteristic_length": True}, "options.characteristic_length"),
        ({"mode": "+"}, "options.mode"),
    ],
)
def test_bad_options_name_the_field(options, field):
    with pytest.raises(InvalidParameter, match=f"^{field}"):
        M.resolve_options(options)


def test_bad_design_and_pose():
    with pytest.raises(InvalidParameter, match="^design.c"):
        M.resolve_design({"c": -1})
    with pytest.raises(InvalidPose, match="^pose"):
        M.inverse_kinematics(DESIGN, OPT, (0.0, 0.0))
    with pytest.raises(InvalidPose, match="^inputs"):
        M.forward_kinematics(DESIGN, OPT, (1.0, math.nan, 2.0))


def test_cli_ik_and_fk_json():
    runner = CliRunner()
    res = runner.invoke(app, ["ik", "ups-sspr", "--pose", "0.2,-0.1,15", "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert out["names"] == ["l1", "l2", "l3"]
    assert out["solutions"][0]["values"] == pytest.approx(TABLE[(0.2, -0.1, 15.0)], abs=6e-11)
    assert out["solutions"][0]["singularity"] == "none"
    res = runner.invoke(app, ["fk", "ups-sspr", "--inputs", ",".join(map(str, REF[2]["l"])), "--json"])
    assert res.exit_code == 0, res.output
    got = {s["branch"]: s["values"] for s in json.loads(res.stdout)["solutions"]}
    assert got["-"] == pytest.approx(REF[2]["x"], abs=1e-9)
    assert got["+"] == pytest.approx(REF[2]["branches"][1], abs=1e-9)
    res = runner.invoke(app, ["ik", "ups-sspr", "--pose", "0,0,0", "--set", "b=-3"])
    assert res.exit_code == 2 and "design.b" in res.output
