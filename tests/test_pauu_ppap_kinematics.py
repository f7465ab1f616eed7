"""Seed-000 kinematics against tests/data/cases/ref000_004.txt (spec mechanisms_000_004.md §1.8) and property tests."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fd_checks import assembly_error, fk_jacobian
from scalesynth.mechanisms import get

from refdata import seed000_modes, seed000_table2_roots, seed000_table3

M = get("2pauu-ppap")
TABLE = dict(m=1.0, n=0.5, l1=0.6, l2=1.2, c=0.1)  # spec §1.8
OPT = M.resolve_options({})
P_TABLE2 = (-0.9165, -0.5846, 0.8792)
ROOTS = seed000_table2_roots()  # theta1 (+, -), theta2 (+, -) rad, e = 2c and e = c


def ik(design, pose, options=OPT):
    return {s.label: s.values for s in M.inverse_kinematics(M.resolve_design(design), options, pose)}


def test_table2_ik_all_branches():
    sols = ik(TABLE, P_TABLE2)
    # spec §1.8 convention T, e = 2c (6 digits)
    (t1p, t1m), (t2p, t2m) = ROOTS["e=2c"]
    expected = {"++": (t1p, t2p), "+-": (t1p, t2m), "-+": (t1m, t2p), "--": (t1m, t2m)}
    for label, (t1, t2) in expected.items():
        assert sols[label][0] == pytest.approx(t1, abs=1e-6)
        assert sols[label][1] == pytest.approx(t2, abs=1e-6)
        assert sols[label][2] == pytest.approx(-0.5846, abs=1e-12)
    # and the paper's printed Table 2 to ~3e-4 (its residual, spec §1.8)
    paper = {"+": (-2.2855, 0.6583), "-": (-3.1033, -2.6997)}
    assert sols["++"][0] == pytest.approx(paper["+"][0], abs=3e-4)
    assert sols["--"][0] == pytest.approx(paper["-"][0], abs=3e-4)
    assert sols["++"][1] == pytest.approx(paper["+"][1], abs=3e-4)
    assert sols["--"][1] == pytest.approx(paper["-"][1], abs=3e-4)


def test_text_offset_e_equals_c():
    sols = ik(TABLE, P_TABLE2, M.resolve_options({"e": 0.1}))
    (t1p, t1m), (t2p, t2m) = ROOTS["e=c"]  # ref000_004.txt "[text offset e=c]"
    assert sols["+-"][0] == pytest.approx(t1p, abs=1e-6)
    assert sols["-+"][0] == pytest.approx(t1m, abs=1e-6)
    assert sols["++"][1] == pytest.approx(t2p, abs=1e-6)
    assert sols["--"][1] == pytest.approx(t2m, abs=1e-6)


# mode: (the two FK solutions, det Jx, diag Jq[:2], LCI 2-norm, J rows), from ref000_004.txt
SPEC_MODES = seed000_modes()


@pytest.mark.parametrize("mode", list(SPEC_MODES))
def test_modes_round_trip_jacobians_lci(mode):
    design = M.resolve_design(TABLE)
    q = ik(TABLE, P_TABLE2)[mode]
    both, det_jx, diag_jq, lci, j_rows = SPEC_MODES[mode]
    other = max(both, key=lambda p: np.abs(np.array(p) - P_TABLE2).max())  # the solution that is not the pose
    fk = [s.values for s in M.forward_kinematics(design, OPT, q)]
    assert len(fk) == 2
    # one assembly mode is the pose itself (exactly, to round-off), the other is the spec's
    dist_self = min(np.abs(v - P_TABLE2).max() for v in fk)
    dist_other = min(np.abs(v - other).max() for v in fk)
    assert dist_self < 1e-12
    assert dist_other < 1e-6
    jac = M.jacobians(design, OPT, P_TABLE2, q)
    assert np.linalg.det(jac["Jx"]) == pytest.approx(det_jx, abs=1e-6)
    assert np.diag(jac["Jq"])[:2] == pytest.approx(diag_jq, abs=1e-6)
    np.testing.assert_allclose(jac["J"], np.array(j_rows, dtype=float), atol=1e-6)
    assert M.lci(design, OPT, P_TABLE2, q) == pytest.approx(lci, abs=1e-6)
    opts = M.resolve_options({"mode": mode})
    assert M.point_kernel(M.pack(design, opts), *P_TABLE2) == pytest.approx(lci, abs=1e-6)
    assert M.singularity(design, OPT, P_TABLE2, q) == "none"


TABLE3 = seed000_table3()  # ref000_004.txt "000: Table 3 rounded inputs"


@pytest.mark.parametrize(("q", "expected"), TABLE3)
def test_table3_fk_both_modes(q, expected):
    sols = [s.values for s in M.forward_kinematics(M.resolve_design(TABLE), OPT, q)]
    assert len(sols) == 2
    for exp in expected:
        assert min(np.abs(s - exp).max() for s in sols) < 1e-6


def test_forward_singular_case_tangent_circles():
    design = M.resolve_design(TABLE)
    d = math.sqrt(1.44 - 1.21)
    sols = M.forward_kinematics(design, OPT, (0.0, 0.0, d))
    assert len(sols) == 1 and sols[0].label == "double"
    np.testing.assert_allclose(sols[0].values, (0.0, 0.479583, 0.2), atol=1e-6)
    jac = M.jacobians(design, OPT, sols[0].values, (0.0, 0.0, d))
    assert abs(np.linalg.det(jac["Jx"])) < 1e-12
    # det Jx = 0 (spec); here also Jq11 = Jq22 = -l1 (a sin 0 + b cos 0) = 0 because b = z - e = 0, so both types
    assert np.diag(jac["Jq"])[:2] == pytest.approx((0.0, 0.0), abs=1e-12)
    assert M.singularity(design, OPT, sols[0].values, (0.0, 0.0, d)) == "both"
    assert M.point_kernel(M.pack(design, OPT), *sols[0].values) == pytest.approx(0.0, abs=1e-6)


def test_coincident_circles_have_no_isolated_solution():
    design = M.resolve_design(dict(TABLE, m=0.5))  # delta = 0: theta1 = theta2 = pi/2 puts both centres at (0, e - l1)
    assert M.forward_kinematics(design, OPT, (math.pi / 2, math.pi / 2, 0.0)) == []


def test_inverse_singular_case():
    design = M.resolve_design(TABLE)
    pose = (-0.4, 0.0, 0.2 + 0.9 * math.sqrt(3))  # chain-1 outer circle at 120 deg (spec: z = 1.758846)
    sols = ik(TABLE, pose)
    assert sols["++"][0] == pytest.approx(-2.094395, abs=1e-6)
    assert sols["-+"][0] == pytest.approx(-2.094395, abs=1e-6)  # double root
    assert {round(sols["++"][1], 6), round(sols["+-"][1], 6)} == {-0.875884, -2.393833}
    jac = M.jacobians(design, OPT, pose, sols["++"])
    assert np.diag(jac["Jq"]) == pytest.approx((0.0, -0.644981, 1.0), abs=1e-6)
    assert M.singularity(design, OPT, pose, sols["++"]) == "inverse"


def test_generic_point_group1():
    g1 = dict(m=0.857, n=0.706, l1=1.499, l2=1.5, c=0.1)
    design = M.resolve_design(g1)
    pose = (0.3, 0.4, 1.2)
    sols = ik(g1, pose)
    assert sols["+-"][0] == pytest.approx(-0.251672, abs=1e-6)
    assert sols["-+"][0] == pytest.approx(-2.594097, abs=1e-6)
    assert sols["++"][1] == pytest.approx(-0.850142, abs=1e-6)
    assert sols["--"][1] == pytest.approx(-3.138821, abs=1e-6)
    jac = M.jacobians(design, OPT, pose, sols["++"])
    np.testing.assert_allclose(
        jac["J"], [(-0.238951, -1.271344, -0.408137), (0, 0, 1), (-2.724462, -2.642798, -1.486661)], atol=1e-6
    )
    assert M.lci(design, OPT, pose, sols["++"]) == pytest.approx(0.168742, abs=1e-6)
    assert M.point_kernel(M.pack(design, OPT), *pose) == pytest.approx(0.168742, abs=1e-6)


def test_unreachable_pose_has_no_branch():
    assert ik(TABLE, (5.0, 0.0, 0.0)) == {}
    assert M.point_kernel(M.pack(M.resolve_design(TABLE), OPT), 5.0, 0.0, 0.0) == -1.0


# ----- properties -----------------------------------------------------------------------------------------
designs = st.fixed_dictionaries(
    {
        "m": st.floats(0.5, 1.5),
        "n": st.floats(0.2, 1.0),
        "l1": st.floats(0.5, 1.5),
        "l2": st.floats(0.5, 1.5),
        "c": st.floats(0.1, 0.5),
    }
)


def _reachable_pose(design, u):
    """A reachable pose from FK of random inputs (u in [0,1]^3); None if those inputs do not assemble."""
    t1 = -math.pi + 2 * math.pi * u[0]
    t2 = -math.pi + 2 * math.pi * u[1]
    d = (2 * u[2] - 1) * 0.95 * design["l2"]
    sols = M.forward_kinematics(design, OPT, (t1, t2, d))
    return (t1, t2, d), sols


@settings(max_examples=150, deadline=None)
@given(designs, st.tuples(*(st.floats(0, 1),) * 3))
def test_fk_then_ik_round_trip(raw, u):
    design = M.resolve_design(raw)
    q, sols = _reachable_pose(design, u)
    for s in sols:
        if s.label == "double" or M.singularity(design, OPT, s.values, q, tol=1e-6) != "none":
            continue
        branches = M.inverse_kinematics(design, OPT, s.values)
        errs = [np.abs(np.angle(np.exp(1j * (b.values[:2] - np.array(q[:2]))))).max() for b in branches]
        assert min(errs) < 1e-9
        # IK then FK: every non-singular branch assembles back to the pose (with m = n an asymmetric branch has
        # coincident FK circles, a forward singularity with infinitely many assemblies, spec §1.2)
        for b in branches:
            if M.singularity(design, OPT, s.values, b.values, tol=1e-6) != "none":
                continue
            assert assembly_error(M.forward_kinematics(design, OPT, b.values), s.values) < 1e-9


@settings(max_examples=100, deadline=None)
@given(designs, st.tuples(*(st.floats(0, 1),) * 3))
def test_jacobian_matches_central_differences_of_fk(raw, u):
    design = M.resolve_design(raw)
    q, sols = _reachable_pose(design, u)
    for s in sols:
        if s.label == "double" or M.singularity(design, OPT, s.values, q, tol=1e-3) != "none":
            continue
        if M.lci(design, OPT, s.values, q) < 1e-3:
            continue  # FK is ill-conditioned next to singular poses; finite differences say nothing there
        jac = M.jacobians(design, OPT, s.values, q)["J"]
        h = 2e-5  # 4th-order stencil: truncation ~h^4, round-off ~1e-16/h
        num = fk_jacobian(M, design, OPT, s.values, q, h, order=4)
        scale = max(1.0, np.abs(jac).max())
        assert np.abs(num - jac).max() < 1e-6 * scale
