"""Seed-001 2PPRS-RPRS: spec mechanisms_001_003.md §1 and tests/data/cases/ref001.json, the point kernel against its
NumPy twin (tests/naive.py), property tests, the drive curves and the `drives` command."""

import json
import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from fd_checks import central_differences
from scalesynth.cli import app
from scalesynth.config import load_config
from scalesynth.errors import InvalidParameter, InvalidPose
from scalesynth.evaluate import evaluate, evaluate_config, make_grid
from scalesynth.kernels import grid as kgrid
from scalesynth.mechanisms import get
from scalesynth.mechanisms.pprs_rprs import (
    BRANCHES,
    GRAM_MIN_RATIO,
    Geometry,
    _jacobi_6x6,
    _lci_6x6,
    _sv_6x6,
    chain_state,
    newton_fk,
    normalise_euler,
    sigma_vector,
)

from conftest import ROOT
from naive import pprs_fields, pprs_lci
from refdata import load_case

M = get("pprs-rprs")
D = M.resolve_design({})  # Table 1: r = 160, R = 180, L1 = 100, L2 = L3 = 120
OPT = M.resolve_options({})
REF = load_case("ref001.json")  # tests/data/cases/, provenance in tests/data/README.md
HOME = np.array([0.0, 0.0, 200.0, 0.0, 0.0, 0.0])
CONFIG = ROOT / "configs" / "pprs_rprs.yaml"
WIDE = {"w_limits": [-1e3, 1e3], "s_limits": [-1e3, 1e3], "beta_limits": [-math.pi, math.pi]}


def q_of(pose, options=OPT, branch="+++", design=D):
    return {s.label: s.values for s in M.inverse_kinematics(design, options, pose)}[branch]


# ----- spec §1.7 / ref001.json ---------------------------------------------------------------------------
# the printed table of spec §1.7: X (mm, deg) -> q = (w1, w2, beta rad, s1, s2, s3), 10 decimals
TABLE_17 = [
    ((0, 0, 200, 0, 0, 0), (160.0, 160.0, 1.3665068592, 100.0, 80.0, 114.8045250479)),
    ((-30, -20, 180, 0, 0, 0), (130.0, 157.6794919243, 1.5404990822, 82.0204102887, 65.5212475709, 92.7709389935)),
    ((-20, -30, 190, 5, -3, 4), (139.1727116609, 143.2719323169, 1.4728164172, 99.6741058590, 84.9539401082,
                                 124.1025303302)),
    ((-40, -10, 170, -6, 4, -5), (118.7358864025, 170.4172919222, 1.5956232073, 62.4648282873, 45.9070738766,
                                  80.4825203674)),
]


@pytest.mark.parametrize(("x_deg", "q"), TABLE_17)
def test_spec_table_ik(x_deg, q):
    pose = np.array(x_deg, dtype=float)
    pose[3:] = np.radians(pose[3:])
    got = q_of(pose)
    np.testing.assert_allclose(got, q, rtol=0, atol=1e-9)  # 10 printed decimals
    assert M.limit_violations(OPT, got) == []  # "all four cases are feasible"


@pytest.mark.parametrize("case", REF["cases"], ids=lambda c: str(c["X_deg"]))
def test_ref001_case(case):
    X, q = np.array(case["X"]), np.array(case["q"])
    got = q_of(X)
    np.testing.assert_allclose(got, q, rtol=0, atol=1e-9)
    assert math.degrees(got[2]) == pytest.approx(case["beta_deg"], abs=1e-9)
    jac = M.jacobians(D, OPT, X, got)
    np.testing.assert_allclose(jac["J"], np.array(case["J"]), rtol=0, atol=1e-9)
    # FK: Newton from X0 = (0, 0, s1 + L1, 0, 0, 0) returns X (label #1), and every reference mode is found
    fk = M.forward_kinematics(D, OPT, q)
    assert fk[0].label == "+++#1"
    assert np.abs(fk[0].values - X).max() <= 1e-10
    for mode in case["fk_solutions"]:
        assert min(np.abs(s.values - mode).max() for s in fk) <= 1e-8
    for s in fk:
        assert np.abs(q_of(s.values) - q).max() <= 1e-9


def test_home_intermediates():
    geo = Geometry.of(D, OPT)
    st_ = chain_state(geo, HOME, sigma_vector("+++"))
    # spec §1.7 "Intermediates at home"
    np.testing.assert_allclose(st_.lam, (0.0, 0.0, 80.0), atol=1e-12)
    assert st_.rho3 == pytest.approx(41.4359353945, abs=1e-9)
    assert st_.mu3 == pytest.approx(204.2472441479, abs=1e-9)
    assert st_.kappa[2] == pytest.approx(89.4427191, abs=1e-7)  # sqrt(120^2 - 80^2) = 40 sqrt(5)
    np.testing.assert_allclose(
        st_.centres, [(160, 0, 200), (-80, 138.5640646055, 200), (-80, -138.5640646055, 200)], atol=1e-9
    )


def test_home_pose_jacobian_printed():
    printed = [
        [1, 0, 0, 0, 0, 0],
        [-0.5, 0.866025, 0, 0, 0, 0],
        [-0.004152, -0.002397, 0.000993, -0.383537, 0.079461, -0.137631],
        [0, 0, 1, 0, -160, 0],
        [0, 0, 1, 0, 80, 138.564065],
        [0.622905, -0.673161, 0.979205, 140.165183, 78.336430, -135.682677],
    ]
    jac = M.jacobians(D, OPT, HOME, q_of(HOME))
    np.testing.assert_allclose(jac["J"], printed, rtol=0, atol=1e-6)  # 6 printed decimals
    # at zero orientation T only permutes the angular columns: J_t = J with columns (phi, theta, psi) reversed
    np.testing.assert_allclose(jac["Jt"][:, 3:], jac["J"][:, [5, 4, 3]], atol=1e-12)
    # spec §1.5: cond 6.68 with the beta row times R and the angle columns over r, 2.07e4 unscaled
    assert np.linalg.cond(jac["Js"]) == pytest.approx(6.68, abs=5e-3)
    assert np.linalg.cond(jac["J"]) == pytest.approx(2.07e4, rel=5e-3)
    assert 1.0 / M.lci(D, OPT, HOME, q_of(HOME)) == pytest.approx(6.68, abs=5e-3)


def _ik_jacobian(geo, X, sig):
    """dq/dX (6x6) by central differences of the chain IK: steps 1e-4 along the position coordinates of X, 1e-6
    along its orientation coordinates."""
    return central_differences(lambda x: chain_state(geo, x, sig).q, X, [1e-4] * 3 + [1e-6] * 3)


def test_jacobian_matches_central_differences_on_ref_cases():
    geo = Geometry.of(D, OPT)
    sig = sigma_vector("+++")
    for case in REF["cases"]:
        X = np.array(case["X"])
        num = _ik_jacobian(geo, X, sig)
        jac = M.jacobians(D, OPT, X, case["q"])["J"]
        np.testing.assert_allclose(num, jac, rtol=0, atol=2e-7 * np.abs(jac).max())


def test_azimuth_240_alternative_at_home():
    opts = M.resolve_options({"chain3_azimuth_deg": 240.0})
    q = q_of(HOME, opts)
    # spec §1.7: (160, 160, 1.4711276713 (84.2894068625 deg), 100, 80, 80.9975124)
    np.testing.assert_allclose(q[[0, 1, 3, 4]], (160, 160, 100, 80), atol=1e-9)
    # at home rho3 = R - u3.C3 = 180 - 160 = 20 and h3 = 200, so beta = atan(10) exactly; that is the printed
    # 84.2894068625 deg, while the printed radians 1.4711276713 carry a digit slip (atan(10) = 1.4711276743)
    assert q[2] == pytest.approx(math.atan(10.0), abs=1e-15)
    assert math.degrees(q[2]) == pytest.approx(84.2894068625, abs=1e-9)
    assert q[2] == pytest.approx(1.4711276713, abs=5e-9)
    assert q[5] == pytest.approx(80.9975124, abs=1e-7)  # mu3 - sqrt(L3^2 - 0^2) = sqrt(40400) - 120


def test_second_fk_mode_of_home_inputs():
    fk = M.forward_kinematics(D, OPT, q_of(HOME))
    # spec §1.4: (12.8313513614, 23.9127236395, 196.4410459531; -23.0552444334, 1.5196743441, -13.0626706594 deg)
    printed = np.array([12.8313513614, 23.9127236395, 196.4410459531, -23.0552444334, 1.5196743441, -13.0626706594])
    other = [s.values for s in fk if np.abs(s.values - HOME).max() > 1e-6]
    assert len(other) >= 1
    best = min(other, key=lambda v: np.abs(v[:3] - printed[:3]).max())
    assert np.abs(best[:3] - printed[:3]).max() <= 1e-9
    assert np.abs(np.degrees(best[3:]) - printed[3:]).max() <= 1e-9


def test_newton_from_x0_round_trip_statistics():
    """ref001.json roundtrip: of 656 random feasible poses (|angles| <= 10 deg), Newton from X0 returned 577
    (88 %) to the true pose (worst 5.2e-12) and 79 to another assembly mode or failed. A seeded sample of ours
    must behave alike: at least 80 % back to the pose at round-off level, every converged run an exact
    solution."""
    rng = np.random.default_rng(7)
    geo = Geometry.of(D, OPT)
    sig = sigma_vector("+++")
    cand = np.column_stack(
        [rng.uniform(-80, 20, 3000), rng.uniform(-90, 30, 3000), rng.uniform(105, 235, 3000),
         np.radians(rng.uniform(-10, 10, (3000, 3)))]
    )
    q = chain_state(geo, cand, sig).q
    lims = M.joint_limits(OPT)
    feasible = np.all((q >= lims[:, 0]) & (q <= lims[:, 1]), axis=1)
    X, q = cand[feasible][:300], q[feasible][:300]
    assert X.shape[0] == 300
    starts = np.zeros_like(X)
    starts[:, 2] = q[:, 3] + D["L1"]
    fk, ok = newton_fk(geo, sig, q, starts)
    err = np.abs(fk - X).max(axis=1)
    back = ok & (err <= 1e-10)
    assert back.mean() >= 0.80
    assert err[back].max() <= 1e-10
    assert np.abs(chain_state(geo, fk[ok], sig).q - q[ok]).max() <= 1e-9


# ----- IK branches, Euler duplicates, singularities --------------------------------------------------------
def test_all_eight_branches():
    sols = M.inverse_kinematics(D, OPT, HOME)
    assert [s.label for s in sols] == list(BRANCHES)
    geo = Geometry.of(D, OPT)
    kappa = chain_state(geo, HOME, sigma_vector("+++")).kappa
    base = q_of(HOME)
    for s in sols:
        sig = sigma_vector(s.label)
        np.testing.assert_array_equal(s.values[:3], base[:3])  # rails and beta do not depend on the branch
        # s_i = base_i + (1 - sigma_i) kappa_i: '-' puts D_i above C_i by kappa_i
        np.testing.assert_allclose(s.values[3:], base[3:] + (1 - sig) * kappa, atol=1e-12)
        assert M.branch_of(D, OPT, HOME, s.values) == s.label
    # x, y, z only: the options' orientation is used
    np.testing.assert_array_equal(q_of(HOME[:3]), base)


def test_unreachable_pose():
    assert M.inverse_kinematics(D, OPT, (0.0, 0.0, 1000.0, 0.0, 0.0, 0.0)) != []  # lambda does not depend on z
    assert M.inverse_kinematics(D, OPT, (0.0, 150.0, 200.0)) == []  # lambda1 = 150 > L1
    assert M.point_kernel(M.pack(D, OPT), 0.0, 150.0, 200.0) == -1.0
    with pytest.raises(InvalidPose, match="^pose:"):
        M.inverse_kinematics(D, OPT, (0.0, 1.0))


def test_euler_duplicates_are_normalised():
    X = np.array([-20.0, -30.0, 190.0, 0.08, -0.05, 0.07])
    dup = X + np.array([0, 0, 0, math.pi, 0, math.pi])
    dup[4] = math.pi - X[4]
    np.testing.assert_allclose(q_of(dup), q_of(X), atol=1e-10)  # the same platform pose
    np.testing.assert_allclose(normalise_euler(dup), X, atol=1e-12)
    np.testing.assert_allclose(normalise_euler(X), X, atol=0)


def test_serial_singularity():
    """kappa1 = 0 (spec §1.5 serial singularity). There the link D1C1 lies along e1, so the revolute at D1 and
    the slider s1 both move C1 along z: s1 no longer moves the platform and chain 1 gains a constraint force
    along e1 through C1, which is also a parallel singularity (sigma_min of A t = B q_dot goes to 0 like
    kappa1)."""
    opts = M.resolve_options(WIDE)
    pose = (0.0, 100.0, 200.0)  # lambda1 = y + r a2 = 100 = L1
    q = q_of(pose, opts)
    assert M.singularity(D, opts, pose, q) == "both"
    assert M.singularity(D, opts, (0.0, 99.9, 200.0), q_of((0.0, 99.9, 200.0), opts)) == "none"
    assert M.lci(D, opts, pose, q) == 0.0
    assert M.point_kernel(M.pack(D, opts), *pose) == 0.0


def test_forward_singularity_inside_the_workspace():
    """det J_t changes sign on the segment x = -80, y = -70, z in [155, 160] (all actuators within limits):
    bisect to the parallel singularity, where the LCI vanishes."""
    geo = Geometry.of(D, OPT)
    sig = sigma_vector("+++")

    def det(z):
        from scalesynth.mechanisms.pprs_rprs import twist_jacobian

        return np.linalg.det(twist_jacobian(geo, chain_state(geo, np.array([-80.0, -70.0, z, 0, 0, 0]), sig)))

    a, b = 155.0, 160.0
    assert det(a) * det(b) < 0
    for _ in range(60):
        m = 0.5 * (a + b)
        a, b = (m, b) if det(m) * det(a) > 0 else (a, m)
    pose = (-80.0, -70.0, a)
    q = q_of(pose)
    assert M.limit_violations(OPT, q) == []
    assert M.singularity(D, OPT, pose, q) == "forward"
    assert M.lci(D, OPT, pose, q) < 1e-12
    assert 0.0 <= M.point_kernel(M.pack(D, OPT), *pose) < 1e-12
    assert M.singularity(D, OPT, HOME, q_of(HOME)) == "none"


# ----- options -----------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("options", "field"),
    [
        ({"orientation": [0.0, 0.0]}, "orientation"),
        ({"orientation": [0.0, "a", 0.0]}, r"orientation\[1\]"),
        ({"sigma": "++"}, "sigma"),
        ({"sigma": "+x+"}, "sigma"),
        ({"w_limits": None}, "w_limits"),
        ({"s_limits": [100, 50]}, "s_limits"),
        ({"beta_limits": [60, 120]}, "beta_limits"),  # degrees by mistake
        ({"chain3_azimuth_deg": "210"}, "chain3_azimuth_deg"),
        ({"w_convention": "X"}, "w_convention"),
        ({"beta_length": 0}, "beta_length"),
        ({"angle_length": -1.0}, "angle_length"),
        ({"colour": 1}, "colour"),
    ],
)
def test_bad_options_name_the_field(options, field):
    with pytest.raises(InvalidParameter, match=rf"^options\.{field}"):
        M.resolve_options(options)


def test_bad_design_names_the_field():
    with pytest.raises(InvalidParameter, match=r"^design\.L2"):
        M.resolve_design({"L2": 0})


# ----- the point kernel -----------------------------------------------------------------------------------
def test_lci_6x6_matches_svd():
    rng = np.random.default_rng(3)
    for _ in range(1500):
        a = rng.normal(size=(6, 6)) * rng.choice([1e-3, 1.0, 1e3], size=(1, 6)) * rng.choice([1e-2, 1, 1e2], (6, 1))
        if rng.random() < 0.3:  # nearly dependent columns
            a[:, 5] = a[:, :5] @ rng.normal(size=5) + a[:, 0] * rng.choice([1e-2, 1e-4, 1e-6])
        sv = np.linalg.svd(a, compute_uv=False)
        ref = sv[-1] / sv[0]
        if ref < 1e-7:
            continue  # below that, LAPACK's own relative accuracy of sigma_min is no better than ours
        assert _lci_6x6(a.copy()) == pytest.approx(ref, rel=1e-7)
    assert _lci_6x6(np.eye(6)) == 1.0
    assert _lci_6x6(np.zeros((6, 6))) == 0.0


def _with_singular_values(rng, s):
    """A random 6x6 matrix U diag(s) V^T."""
    u, _, vt = np.linalg.svd(rng.normal(size=(2, 6, 6)))
    return (u[0] * s) @ vt[1]


@pytest.mark.parametrize(("lci", "gram"), [(0.7, True), (1e-2, True), (2e-3, True), (5e-4, False), (1e-5, False),
                                           (1e-7, False)])
def test_sv_6x6_gram_path_and_jacobi_fallback(lci, gram):
    # GRAM_MIN_RATIO (lambda_min / lambda_max of A^T A) sits at LCI 1e-3: above it the Gram/Laguerre result (which
    # differs from Jacobi's in the last bits), below it one-sided Jacobi, both against NumPy's SVD
    assert GRAM_MIN_RATIO == pytest.approx(1e-6)
    rng = np.random.default_rng(7)
    differ = 0
    for _ in range(300):
        s = np.exp(rng.uniform(math.log(lci), 0.0, 6))
        s[:2] = 1.0, lci
        a = _with_singular_values(rng, s) * rng.choice([1e-3, 1.0, 1e3])
        sv = np.linalg.svd(a, compute_uv=False)
        got = _sv_6x6(a)
        jac = _jacobi_6x6(a.copy())
        differ += got != jac
        rel = 2e-9 if gram else 1e-7  # the Gram path's bound (bracket + eps kappa^2); Jacobi's contract
        assert got[0] == pytest.approx(sv[-1] / sv[0], rel=rel)
        assert got[1] == pytest.approx(sv[-1], rel=rel)
        assert got[2] == pytest.approx(sv[0], rel=1e-12)
    if gram:
        assert differ >= 270  # the fast path ran (bit-equal to Jacobi at most by chance)
    else:
        assert differ == 0  # the fallback ran


@pytest.mark.parametrize("spread", [1e-3, 1e-6, 1e-8, 1e-12, 0.0])
@pytest.mark.parametrize("size", [2, 3, 6])
def test_sv_6x6_clustered_singular_values(spread, size):
    # Laguerre converges only linearly onto a cluster and may overshoot into it: the Sturm brackets must catch that
    # (fallback) or bound the error by GRAM_BRACKET
    rng = np.random.default_rng(8)
    for top in (True, False):
        for _ in range(100):
            s = rng.uniform(0.1, 0.9, 6) * (1.0 if top else 10.0)
            s[:size] = 1.0 + rng.uniform(-spread, spread, size)
            a = _with_singular_values(rng, s)
            sv = np.linalg.svd(a, compute_uv=False)
            got = _sv_6x6(a)
            assert got[0] == pytest.approx(sv[-1] / sv[0], rel=2e-9)
            assert got[1] == pytest.approx(sv[-1], rel=2e-9)
            assert got[2] == pytest.approx(sv[0], rel=2e-9)


def test_sv_6x6_degenerate():
    assert _sv_6x6(np.zeros((6, 6))) == (0.0, 0.0, 0.0)
    assert _sv_6x6(np.full((6, 6), np.nan)) == (0.0, 0.0, 0.0)
    assert _sv_6x6(np.diag([2.0, 2.0, 2.0, 2.0, 2.0, 0.0])) == (0.0, 0.0, 2.0)
    assert _sv_6x6(np.diag([3.0] * 6)) == (1.0, 3.0, 3.0)
    assert _sv_6x6(np.diag([1e200] * 6))[2] == math.inf  # A^T A overflows: Jacobi, as before the Gram path


def test_kernel_lci_of_real_jacobians():
    # the LCIs that matter: the Table-1 design's reachable nodes (LCI 1e-3 .. 0.2, so the Gram path) against the
    # NumPy twin (SVD of the homogenised J_t), within the Gram path's bound rather than the 1e-7 contract
    g = make_grid(M, D, OPT, 24)
    lci = kgrid.sample_grid(M.point_kernel, M.pack(D, OPT), g.lo, g.step, g.shape)
    X, Y, Z = (g.lo[a] + (np.arange(g.shape[a]) + 0.5) * g.step[a] for a in range(3))
    twin = pprs_fields(D, OPT, *np.meshgrid(X, Y, Z, indexing="ij"))
    reach = twin[..., 0] >= 0
    assert np.count_nonzero(reach) > 1000
    assert np.array_equal(lci >= 0, reach)
    assert np.mean(twin[reach, 0] >= 1e-3) > 0.95
    np.testing.assert_allclose(lci[reach], twin[reach, 0], rtol=2e-9, atol=0.0)


TWIN_CASES = [
    {},
    {"sigma": "+-+", **WIDE},
    {"orientation": [0.05, -0.04, 0.03]},
    {"chain3_azimuth_deg": 240.0, "beta_length": 100.0, "angle_length": 120.0},
    {"w_convention": "R", "w_limits": [0.0, 100.0]},
    {"sigma": "---"},
]


@pytest.mark.parametrize("options", TWIN_CASES)
def test_kernel_matches_numpy_twin(options):
    opts = M.resolve_options(options)
    # 20 cells per axis: the box follows the actuator limits alone, larger than the workspace's thin slab
    g = make_grid(M, D, opts, 20)
    lci = kgrid.sample_grid(M.point_kernel, M.pack(D, opts), g.lo, g.step, g.shape)
    X, Y, Z = (g.lo[a] + (np.arange(g.shape[a]) + 0.5) * g.step[a] for a in range(3))
    twin = pprs_lci(D, opts, *np.meshgrid(X, Y, Z, indexing="ij"))
    assert np.count_nonzero(twin >= 0) > 20  # a real test: the grid meets the workspace
    assert np.array_equal(lci >= 0, twin >= 0)  # same reachable voxels
    np.testing.assert_allclose(lci[lci >= 0], twin[twin >= 0], rtol=1e-7, atol=1e-12)
    assert not np.any(np.isnan(lci))


def test_kernel_matches_mechanism_lci():
    for case in REF["cases"]:
        opts = M.resolve_options({"orientation": case["X"][3:]})
        q = q_of(case["X"])
        assert M.point_kernel(M.pack(D, opts), *case["X"][:3]) == pytest.approx(M.lci(D, opts, case["X"], q),
                                                                                 rel=1e-9)


def test_kernel_never_nan():
    rng = np.random.default_rng(5)
    pts = rng.uniform([-400, -400, -200], [400, 400, 600], size=(20000, 3))
    for options in ({}, WIDE, {"sigma": "-+-", **WIDE}):
        v = kgrid.points_lci(M.point_kernel, M.pack(D, M.resolve_options(options)), pts)
        assert np.all((v == -1.0) | ((v >= 0.0) & (v <= 1.0)))


# ----- workspace, spec §1.8 ---------------------------------------------------------------------------------
def _node_workspace(h, options=None, design=None, box=None):
    """Kernel at the nodes (multiples of h) of the spec box x, y in [-300, 300], z in [0, 500], or of the nodes
    inside ``box`` = (lo, hi)."""
    d = M.resolve_design(design or {})
    o = M.resolve_options(options or {})
    first, last = box if box is not None else (np.array([-300.0, -300.0, 0.0]), np.array([300.0, 300.0, 500.0]))
    first, last = np.ceil(np.asarray(first) / h) * h, np.floor(np.asarray(last) / h) * h
    lo = first - h / 2  # cell-centred grid whose centres are the nodes
    shape = (np.round((last - first) / h) + 1).astype(np.int64)
    lci = kgrid.sample_grid(M.point_kernel, M.pack(d, o), lo, np.full(3, float(h)), shape)
    idx = np.argwhere(lci >= 0)
    pts = lo + (idx + 0.5) * h
    return pts, lci[lci >= 0]


@pytest.mark.parametrize(
    ("h", "options", "design", "count", "box"),
    [
        (5, {}, {}, 3669, ((-80, 20), (-90, 30), (105, 235))),
        (2, {}, {}, 55905, ((-80, 20), (-90, 34), (104, 236))),
        (5, {"chain3_azimuth_deg": 240.0}, {}, 5780, ((-80, 20), (-95, 30), (135, 235))),
        (5, {}, {"L1": 120.0}, 3288, ((-80, 20), (-90, 30), (125, 240))),  # "all links 120 (eq.12 literal)"
        (5, {"sigma": "---"}, {}, 181, ((-55, -10), (-60, 0), (5, 30))),  # D above C
        (5, {"w_convention": "R"}, {}, 0, None),
    ],
)
def test_spec_workspace_counts(h, options, design, count, box):
    d = M.resolve_design(design)
    o = M.resolve_options(options)
    lo, hi = M.bounding_box(d, o)
    # h = 5 over the whole spec box (which also checks the bounding box); h = 2 only at the nodes inside it
    pts, _ = _node_workspace(h, options, design, box=(lo, hi) if h == 2 else None)
    assert pts.shape[0] == count  # spec §1.8 table / ref001.json "workspace"
    if box is not None:
        np.testing.assert_allclose(np.column_stack([pts.min(axis=0), pts.max(axis=0)]), box, atol=1e-9)
        assert pts.shape[0] * h**3 == REF_VOLUME[(h, count)]
        assert np.all(pts >= lo) and np.all(pts <= hi)  # the bounding box holds the workspace


REF_VOLUME = {(5, 3669): 458625.0, (2, 55905): 447240.0, (5, 5780): 722500.0, (5, 3288): 411000.0,
              (5, 181): 22625.0}


def test_home_column():
    """spec §1.8 / ref001.json home_column_z: on x = y = 0 the workspace is z in [157.5, 223.127]."""
    p = M.pack(D, OPT)

    def edge(inside, outside):
        for _ in range(80):
            m = 0.5 * (inside + outside)
            inside, outside = (m, outside) if M.point_kernel(p, 0.0, 0.0, m) >= 0 else (inside, m)
        return inside

    assert M.point_kernel(p, 0.0, 0.0, 190.0) >= 0
    # lower end: s2 = z - L2 >= 37.5; upper end: s3 = sqrt(rho3^2 + z^2) - sqrt(L3^2 - 80^2) <= 137.5 with
    # rho3 = 180 - 80 sqrt(3): z = 223.12790..., which the spec prints truncated (223.127, "223.1270")
    rho3 = 180.0 - 80.0 * math.sqrt(3.0)
    top = math.sqrt((137.5 + math.sqrt(120.0**2 - 80.0**2)) ** 2 - rho3**2)
    assert edge(190.0, 100.0) == pytest.approx(REF["home_column_z"][0], abs=1e-9)
    assert edge(190.0, 300.0) == pytest.approx(top, abs=1e-9)
    assert edge(190.0, 300.0) == pytest.approx(REF["home_column_z"][1], abs=1e-3)


@settings(max_examples=25, deadline=None)
@given(
    st.floats(120, 200), st.floats(80, 160), st.floats(80, 160), st.floats(80, 160),
    st.tuples(*(st.floats(-0.15, 0.15, allow_subnormal=False),) * 3), st.sampled_from(["+++", "---", "+-+"]),
)
def test_bounding_box_holds_every_reachable_node(r, l1, l2, l3, orient, sigma):
    design = M.resolve_design({"r": r, "L1": l1, "L2": l2, "L3": l3})
    opts = M.resolve_options({"orientation": list(orient), "sigma": sigma})
    lo, hi = M.bounding_box(design, opts)
    pts, _ = _node_workspace(10, opts, design)
    assert np.all(pts >= lo - 1e-9) and np.all(pts <= hi + 1e-9)


def test_evaluate_and_config():
    cfg = load_config(CONFIG)
    assert cfg.mechanism == "pprs-rprs" and cfg.resolved_design() == D
    rep = evaluate_config(cfg)
    assert rep.measure_key == "volume_mm3"
    # the twin on the same grid gives the same count and GCI
    g = make_grid(M, D, OPT, 12)
    X, Y, Z = (g.lo[a] + (np.arange(g.shape[a]) + 0.5) * g.step[a] for a in range(3))
    twin = pprs_lci(D, OPT, *np.meshgrid(X, Y, Z, indexing="ij"))
    small = evaluate(M, D, OPT, resolution=12, length_unit="mm")
    assert small.metrics["voxels"] == np.count_nonzero(twin >= 0)
    assert small.gci == pytest.approx(twin[twin >= 0].mean(), rel=1e-9)
    assert small.metrics["min_lci"] == pytest.approx(twin[twin >= 0].min(), rel=1e-7, abs=1e-10)
    assert small.metrics["max_lci"] == pytest.approx(twin[twin >= 0].max(), rel=1e-7, abs=1e-10)
    # resolution 32 (the config's, cell-centred) against the node count at h = 2 mm (spec: 447240 mm3); node
    # counts run high because boundary nodes count in full (h = 5 gives 458625), so only within 3 %
    assert rep.measure == pytest.approx(447240.0, rel=0.03)
    assert rep.metrics["voxels"] > 0 and 0 < rep.gci < 1


# ----- properties ----------------------------------------------------------------------------------------
poses = st.tuples(
    st.floats(-70, 10), st.floats(-80, 20), st.floats(120, 225),
    *(st.floats(-math.radians(10), math.radians(10)),) * 3,
)


@settings(max_examples=60, deadline=None)
@given(poses, st.sampled_from(BRANCHES), st.tuples(*(st.floats(-1, 1),) * 6))
def test_ik_fk_round_trip(pose, branch, jitter):
    X = np.array(pose)
    opts = M.resolve_options({"sigma": branch})
    sols = M.inverse_kinematics(D, opts, X)
    assume(sols)  # hypothesis draws another pose instead of counting an unreachable one as a pass
    q = {s.label: s.values for s in sols}[branch]
    geo = Geometry.of(D, opts)
    assume(not np.any(chain_state(geo, X, sigma_vector(branch)).kappa < 1e-3))  # not next to a serial singularity
    # next to a parallel singularity Newton may step to the neighbouring mode
    assume(M.singularity(D, opts, X, q, tol=1e-4) == "none")
    # continuation: FK from a start 1 mm / 0.01 rad away returns the pose
    guess = X + np.array(jitter) * np.array([1, 1, 1, 0.01, 0.01, 0.01])
    fk = M.forward_kinematics(D, opts, q, guess=guess, starts=0)
    assert fk[0].label == f"{branch}#1"
    assert np.abs(fk[0].values - normalise_euler(X)).max() <= 1e-9
    for s in fk:  # every mode found is an exact solution
        assert np.abs(q_of(s.values, opts, branch) - q).max() <= 1e-9


@settings(max_examples=40, deadline=None)
@given(poses, st.sampled_from(BRANCHES))
def test_pose_jacobian_matches_central_differences(pose, branch):
    X = np.array(pose)
    geo = Geometry.of(D, OPT)
    sig = sigma_vector(branch)
    st_ = chain_state(geo, X, sig)
    assume(st_.ok and not np.any(st_.kappa < 1.0))
    num = _ik_jacobian(geo, X, sig)
    jac = M.jacobians(D, OPT, X, st_.q)["J"]
    # central-difference truncation grows as kappa shrinks; 1e-6 of the largest entry is ample here
    np.testing.assert_allclose(num, jac, rtol=0, atol=1e-6 * np.abs(jac).max())


# ----- drive curves (paper §5) -----------------------------------------------------------------------------


def test_drives_command(tmp_path):
    runner = CliRunner()
    res = runner.invoke(app, ["drives", str(CONFIG), "--samples", "81", "--out", str(tmp_path), "--json"])
    assert res.exit_code == 0, res.output
    summary = json.loads(res.stdout)
    lines = (tmp_path / "drives.csv").read_text().splitlines()
    assert lines[0] == "t,x,y,z,w1,w2,beta,s1,s2,s3"
    table = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    assert table.shape == (81, 10)
    np.testing.assert_allclose(table[-1, 1:], table[0, 1:], atol=1e-9)  # closed: ends where it starts
    np.testing.assert_allclose(table[:, 3], 200.0)
    # default square: side 20 mm centred at (-40, -25), E at the lower left
    np.testing.assert_allclose(table[0, 1:3], (-50.0, -35.0))
    np.testing.assert_allclose(table[20, 1:3], (-30.0, -35.0), atol=1e-9)
    for k, name in enumerate(M.joints):
        assert summary["ranges"][name] == pytest.approx([table[:, 4 + k].min(), table[:, 4 + k].max()], rel=1e-9)
    png = (tmp_path / "drives.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["drives.csv", "drives.json", "drives.png"]  # no temp files


def test_drives_command_bad_input(tmp_path):
    runner = CliRunner()
    res = runner.invoke(app, ["drives", str(CONFIG), "--side", "40", "--center", "-30,-30", "--out", str(tmp_path)])
    assert res.exit_code == 2
    # drives is an alias of cycle: the first corner outside the workspace (within the actuator limits) is named
    assert res.stderr.startswith("error: cycle.path[") and "outside the workspace" in res.stderr
    res = runner.invoke(app, ["drives", str(CONFIG), "--side", "-1", "--out", str(tmp_path)])
    assert res.exit_code == 2 and "--side" in res.stderr
    res = runner.invoke(app, ["drives", str(ROOT / "configs" / "paper_2pauu_ppap.yaml"), "--out", str(tmp_path)])
    assert res.exit_code == 2 and res.stderr.startswith("error: mechanism:")
    assert list(tmp_path.iterdir()) == []


def test_ik_and_fk_commands():
    runner = CliRunner()
    res = runner.invoke(app, ["ik", "pprs-rprs", "--pose", "0,0,200", "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert out["names"] == list(M.joints) and [s["branch"] for s in out["solutions"]] == list(BRANCHES)
    assert out["solutions"][0]["lci"] == pytest.approx(1 / 6.677029, rel=1e-6)
    assert out["solutions"][0]["singularity"] == "none"
    q = ",".join(repr(float(v)) for v in q_of(HOME))
    res = runner.invoke(app, ["fk", "pprs-rprs", "--inputs", q, "--json"])
    assert res.exit_code == 0, res.output
    sols = [s["values"] for s in json.loads(res.stdout)["solutions"]]
    assert np.abs(np.array(sols[0]) - HOME).max() <= 1e-10 and len(sols) >= 2
