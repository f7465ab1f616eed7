"""Mobility (issue 4): Grübler-Kutzbach counts from the joint lists and the screw-theory check.

Expected numbers and where they come from:
* counts: seed 000 paper §1.2 (F = sum f - sum xi_L = 13 - (6 + 4) = 3, 3T; with the parallelograms counted
  as one joint each n = 8, g = 9, sum f = 13, so the classical G-K gives 6(8 - 9 - 1) + 13 = 1 and the
  modified one needs nu = 2), spec mechanisms_001_003.md §1.2 (N = 11, g = 12, sum f = 18, F = 6, 3T3R),
  §2.2 (8, 9, 15, 3, 2R1T), §3.2 (9, 11, 21, 3, 2R1T), seed 004 (2-DOF planar: 3(5 - 5 - 1) + 5 = 2, 2T);
* constraint wrenches: spec §2.1/§2.3/F6 (seed 002: forces (1 0 0; 0 z +-h); chain 3 (0 1 0; -z 0 c) or
  (0 1 0; 0 0 c)), spec §3.2 (seed 003: a couple along z, forces along x and z through A0), and for seed 000
  the couple along the xz-projection of the U-U link (spec §1.5: its loss of rank is the forward
  singularity);
* textbook screw systems (single revolute, serial PPP, spherical joint, planar 3-RRR, 3-RPS, Stewart 6-UPS);
* an independent twin: the platform twists as the intersection of the chains' twist spans (scipy null spaces)
  instead of the reciprocal of the union of the wrenches.
"""

import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.linalg import null_space
from scipy.spatial.transform import Rotation
from typer.testing import CliRunner

from scalesynth.cli import app
from scalesynth.errors import InvalidParameter, InvalidPose
from scalesynth.mechanisms import get
from scalesynth.mechanisms.rps_upu import TOOL_MECHANISM
from scalesynth.mobility import (
    Joint,
    NoTopology,
    Topology,
    body_twists,
    chain_screws,
    grubler,
    mobility_report,
    modified_grubler,
    motion_name,
    rank,
    reciprocal,
    sample_configurations,
    screw_analysis,
    screw_mobility,
)

DELTA = np.block([[np.zeros((3, 3)), np.eye(3)], [np.eye(3), np.zeros((3, 3))]])
X, Y, Z = np.eye(3)


def R(point, axis):
    return Joint("R", point, (axis,))


def P(axis):
    return Joint("P", axes=(axis,))


def in_span(basis, v, tol=1e-8) -> bool:
    """v (6,) is a combination of the rows of basis (relative residual <= tol)."""
    basis = np.atleast_2d(basis)
    coef, *_ = np.linalg.lstsq(basis.T, v, rcond=None)
    return float(np.linalg.norm(basis.T @ coef - v)) <= tol * max(1.0, float(np.linalg.norm(v)))


def twin_dof(chains) -> tuple[int, int]:
    """(dof, rotations) of the platform as the intersection of the chains' twist spans: t = T_1 a_1 = T_k a_k,
    from scipy's null space of [T_1, -T_2, 0, ...; T_1, 0, -T_3, ...] (no reciprocal screws involved). The
    moments are divided by L = 1000 first so that one tolerance suits mm."""
    mats = [np.asarray(c, dtype=float).T * np.array([1, 1, 1, 1e-3, 1e-3, 1e-3])[:, None] for c in chains]
    mats = [m / np.linalg.norm(m, axis=0) for m in mats]
    first, others = mats[0], mats[1:]
    if not others:
        span = first
    else:
        system = np.vstack(
            [np.hstack([first] + [-m if j == k else np.zeros_like(m) for j, m in enumerate(others)])
             for k in range(len(others))]
        )
        coeffs = null_space(system, rcond=1e-9)[: first.shape[1]]
        span = first @ coeffs
    if span.size == 0:
        return 0, 0
    basis = null_space(null_space(span.T, rcond=1e-9).T, rcond=1e-9)  # orthonormal basis of the span
    return basis.shape[1], int(np.linalg.matrix_rank(basis[:3], tol=1e-8))


# ----- textbook screw systems ------------------------------------------------------------------------
def rps3(rot=np.eye(3), shift=np.zeros(3), scale=1.0):
    """3-RPS (revolutes tangent to the base circle, legs normal to them): the classic 2R1T mechanism, in a
    moved and scaled frame."""
    chains = []
    for k in range(3):
        a = 2 * math.pi * k / 3
        radial = np.array([math.cos(a), math.sin(a), 0.0])
        tangent = np.array([-math.sin(a), math.cos(a), 0.0])
        base = scale * 2.0 * radial
        top = scale * ((1.4 - 0.2 * k) * radial + (1.5 + 0.1 * k) * Z)
        joints = [R(rot @ base + shift, rot @ tangent), P(rot @ (top - base)), Joint("S", rot @ top + shift)]
        chains.append(chain_screws(joints))
    return chains


def test_single_revolute_chain_leaves_one_rotation():
    chain = chain_screws([R((1.0, 2.0, 3.0), Z)])
    res = screw_analysis([chain])
    assert (res.dof, res.motion, res.chain_constraints) == (1, "1R", (5,))
    assert in_span(res.twists, np.array([0, 0, 1, 2, -1, 0]))  # (w; r x w) with r = (1, 2, 3), w = z


def test_serial_ppp_and_three_parallel_ppp_chains_are_3t():
    ppp = chain_screws([P(X), P(Y), P(Z)])
    assert screw_mobility([ppp]) == (3, "3T")
    skewed = chain_screws([P((1, 1, 0)), P((0, 1, 1)), P((1, 0, 1))])
    res = screw_analysis([ppp, skewed, chain_screws([P((1, 2, 3)), P(Z), P(X)])])
    # every chain exerts the same three couples: lambda = 3 common constraints, none redundant
    assert (res.dof, res.motion, res.common, res.redundant) == (3, "3T", 3, 0)


def test_three_single_prismatic_chains_lock_the_platform():
    assert screw_mobility([chain_screws([P(X)]), chain_screws([P(Y)]), chain_screws([P(Z)])]) == (0, "0")


def test_spherical_joint_is_3r():
    res = screw_analysis([Joint("S", (0.3, -2.0, 5.0)).screws()])
    assert (res.dof, res.motion) == (3, "3R")
    # its wrenches are the three forces through the centre
    for f in np.eye(3):
        assert in_span(res.wrenches, np.concatenate([f, np.cross((0.3, -2.0, 5.0), f)]))


def test_planar_3rrr_is_2t1r_with_three_common_constraints():
    chains = []
    for k in range(3):
        a = 2 * math.pi * k / 3
        b = 5.0 * np.array([math.cos(a), math.sin(a), 0.0])
        chains.append(chain_screws([R(b, Z), R(0.5 * b + (0.3, 0.7, 0.0), Z), R(0.2 * b, Z)]))
    res = screw_analysis(chains)
    assert (res.dof, res.motion, res.common, res.redundant) == (3, "2T1R", 3, 0)


def test_3rps_is_2r1t_and_stewart_is_3t3r():
    assert screw_mobility(rps3()) == (3, "2R1T")
    rng = np.random.default_rng(1)
    legs = []
    for _ in range(6):
        a, b = rng.normal(size=3), rng.normal(size=3) + (0, 0, 3)
        u = np.cross(Z, a)
        legs.append(chain_screws([Joint("U", a, (u, np.cross(u, b - a))), P(b - a), Joint("S", b)]))
    res = screw_analysis(legs)
    assert (res.dof, res.motion, res.chain_ranks) == (6, "3T3R", (6,) * 6)


def test_wrenches_are_reciprocal_to_every_joint_screw():
    chains = rps3()
    res = screw_analysis(chains)
    for chain in chains:
        w = reciprocal(chain)
        assert np.allclose(w @ DELTA @ np.array(chain).T, 0.0, atol=1e-12)
    assert np.allclose(res.wrenches @ DELTA @ res.twists.T, 0.0, atol=1e-10)


@settings(max_examples=25, deadline=None)
@given(
    st.tuples(*(st.floats(-math.pi, math.pi),) * 3),
    st.tuples(*(st.floats(-500.0, 500.0),) * 3),
    st.sampled_from([1e-3, 1.0, 1e3]),
)
def test_frame_and_unit_changes_leave_the_mobility_unchanged(angles, shift, scale):
    rot = Rotation.from_euler("zyx", angles).as_matrix()
    res = screw_analysis(rps3(rot, np.array(shift), scale))
    assert (res.dof, res.motion, res.constraint_rank, res.common, res.redundant) == (3, "2R1T", 3, 0, 0)


def test_body_twists_of_the_s_plus_spr_loop_are_its_equivalent_2r():
    # spec §3.1 at beta = 0.4: the SPR revolute axis is the link's x axis Ry(beta) x, which is normal to M
    m, beta = np.array([0.0, -50.0, 0.0]), 0.4
    x_link = np.array([math.cos(beta), 0.0, -math.sin(beta)])
    b0 = 80.0 * np.array([math.sin(beta), 0.1, math.cos(beta)])
    spr = chain_screws([Joint("S", m), P(b0 - m), R(b0, x_link)])
    twists = body_twists(Joint("S", (0, 0, 0)).screws(), spr)
    assert len(twists) == 2
    assert in_span(np.array(twists), np.concatenate([Y, np.zeros(3)]))  # about y through A0
    assert in_span(np.array(twists), np.concatenate([x_link, np.zeros(3)]))  # about the link's x axis
    # the same space as the reciprocal of the subchains' wrenches together
    both = np.vstack([reciprocal(Joint("S", (0, 0, 0)).screws()), reciprocal(spr)])
    assert rank(np.vstack([reciprocal(both), np.array(twists)])) == 2


@pytest.mark.parametrize(
    "rotations, translations, name",
    [(0, 3, "3T"), (2, 1, "2R1T"), (3, 3, "3T3R"), (0, 2, "2T"), (3, 0, "3R"), (1, 2, "2T1R"),
     (1, 3, "3T1R")],
)
def test_motion_names_follow_the_papers(rotations, translations, name):
    assert motion_name(rotations, translations) == name


def test_bad_joints_and_topologies_name_the_field():
    with pytest.raises(InvalidParameter, match="joint.kind"):
        Joint("H", (0, 0, 0), (Z,))
    with pytest.raises(InvalidParameter, match="joint.point"):
        Joint("R", axes=(Z,))
    with pytest.raises(InvalidParameter, match="joint.axes"):
        Joint("U", (0, 0, 0), (Z,))
    with pytest.raises(InvalidPose, match="joint.axes"):
        Joint("R", (0, 0, 0), ((0, 0, 0),)).screws()
    with pytest.raises(InvalidPose, match="joint.point"):
        Joint("S", (0, math.nan, 0))
    with pytest.raises(InvalidParameter, match="topology.order"):
        Topology(5, (("c", ("R",)),), order=4)
    with pytest.raises(InvalidParameter, match="topology.chains"):
        Topology(5, (("c", ("Q",)),))


# ----- the five mechanisms ----------------------------------------------------------------------------------
# name: (n, g, sum f, classical, modified, nu, chain constraints, dof, motion); sources: module docstring
EXPECTED = {
    "2pauu-ppap": (8, 9, 13, 1, 3, 2, (1, 1, 3), 3, "3T"),
    "pprs-rprs": (11, 12, 18, 6, 6, 0, (0, 0, 0), 6, "3T3R"),
    "rps-upu": (8, 9, 15, 3, 3, 0, (1, 1, 1), 3, "2R1T"),
    "ups-sspr": (9, 11, 21, 3, 3, 0, (0, 0, 3), 3, "2R1T"),
    "planar-fivebar": (5, 5, 5, 2, 2, 0, (4, 3), 2, "2T"),
}


def defaults(name, **options):
    mech = get(name)
    return mech, mech.resolve_design({}), mech.resolve_options(options)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_counts_and_screw_theory_agree_with_the_papers(name):
    n, g, f, classical, modified, nu, constraints, dof, motion = EXPECTED[name]
    mech, design, options = defaults(name)
    top = mech.topology(design, options)
    assert (top.n_links, top.n_joints, top.sum_freedom) == (n, g, f)
    assert (grubler(top), modified_grubler(top), top.redundant) == (classical, modified, nu)
    rep = mobility_report(mech, design, options, samples=6, seed=3)
    ranks = {r.constraint_rank for r in rep.results}
    assert ranks == {6 - dof}  # the same rank at every random configuration
    g_ = rep.generic
    assert (g_.dof, g_.motion, g_.chain_constraints, g_.redundant) == (dof, motion, constraints, nu)
    assert rep.agrees and motion == mech.motion


@settings(max_examples=12, deadline=None)
@given(
    st.floats(0.2, 0.8), st.floats(0.2, 0.8), st.floats(0.5, 2.0), st.floats(0.5, 2.0), st.floats(0.05, 0.3),
    st.integers(0, 1000),
)
def test_pauu_ppap_is_3t_for_any_design(m, n, l1, l2, c, seed):
    # |m - n| <= 0.6 < l1 + l2: a non-empty workspace
    mech = get("2pauu-ppap")
    design = mech.resolve_design(dict(m=m, n=n, l1=l1, l2=l2, c=c))
    rep = mobility_report(mech, design, mech.resolve_options({}), samples=2, seed=seed)
    assert {(r.dof, r.motion, r.redundant) for r in rep.results} == {(3, "3T", 2)}


def test_parallelograms_expanded_into_revolutes():
    top = get("2pauu-ppap").topology({}, {}).expanded()
    # three planar 4R loops, each overconstrained by 3 in space: 1 - 9 = -8, nu = 2 + 9
    assert (top.n_links, top.n_joints, top.sum_freedom, grubler(top)) == (14, 18, 22, -8)
    assert modified_grubler(top) == 3
    planar = get("planar-fivebar").topology({}, {}).expanded()
    assert (planar.n_links, planar.n_joints, grubler(planar), modified_grubler(planar)) == (9, 11, 2, 2)


@pytest.mark.parametrize(
    "options", [{"model": "C"}, {"c3_variant": "upu"}, {"model": "C", "c3_variant": "upu"}]
)
def test_rps_upu_variants_are_2r1t(options):
    mech, design, opts = defaults("rps-upu", **options)
    rep = mobility_report(mech, design, opts, samples=4)
    assert (rep.generic.dof, rep.generic.motion, rep.agrees) == (3, "2R1T", True)


def test_rps_upu_tool_workspace_places_the_joints_through_its_pose():
    design, options = TOOL_MECHANISM.resolve_design({}), TOOL_MECHANISM.resolve_options({})
    rep = mobility_report(TOOL_MECHANISM, design, options, samples=3)
    assert (rep.generic.dof, rep.generic.motion) == (3, "2R1T")


def test_numeric_mobility_matches_the_intersection_twin():
    for name in sorted(EXPECTED):
        mech, design, options = defaults(name)
        for pose, q in sample_configurations(mech, design, options, 3, seed=7):
            chains = mech.joint_screws(design, options, pose, q)
            res = screw_analysis(chains)
            assert twin_dof(chains) == (res.dof, res.rotations), name


# ----- constraint wrenches stated in the spec -------------------------------------------------------
@pytest.mark.parametrize("variant", ["plane", "upu"])
def test_rps_upu_constraint_forces_at_home(variant):
    mech, design, options = defaults("rps-upu", c3_variant=variant)
    z, h, c = 60.0, design["h"], design["c"]
    chains = mech.joint_screws(design, options, (z, 0.0, 0.0))
    # spec §2.1: forces along x through B1, B2; chain 3: 'plane' a force along y through B3 (erratum F6),
    # 'upu' the printed moment (0 1 0; 0 0 c), a force along y through (c, 0, 0) (spec §2.3)
    chain3 = (0, 1, 0, -z, 0, c) if variant == "plane" else (0, 1, 0, 0, 0, c)
    expected = [(1, 0, 0, 0, z, h), (1, 0, 0, 0, z, -h), chain3]
    for chain, wrench in zip(chains, expected, strict=True):
        w = reciprocal(chain)
        assert w.shape[0] == 1 and in_span(w, np.array(wrench, dtype=float))


def test_ups_sspr_hybrid_chain_constraints_at_home():
    mech, design, options = defaults("ups-sspr")
    chains = mech.joint_screws(design, options, (0.0, 0.0, 0.0))
    w = reciprocal(chains[2])
    assert w.shape[0] == 3  # spec §3.2: one couple along z, forces along x and z through A0
    for wrench in ((0, 0, 0, 0, 0, 1), (1, 0, 0, 0, 0, 0), (0, 0, 1, 0, 0, 0)):
        assert in_span(w, np.array(wrench, dtype=float))
    assert [reciprocal(c).shape[0] for c in chains[:2]] == [0, 0]


def test_pauu_chain_constraint_is_a_couple_along_the_projected_link():
    mech, design, options = defaults("2pauu-ppap")
    m, n, l1, e = design["m"], design["n"], design["l1"], 2 * design["c"]
    for (x, y, z), (t1, t2, _) in sample_configurations(mech, design, options, 4, seed=5):
        chains = mech.joint_screws(design, options, (x, y, z), (t1, t2, y))
        for s, t, chain in ((1, t1, chains[0]), (-1, t2, chains[1])):
            c = np.array([s * (m + l1 * math.cos(t)), 0.0, e - l1 * math.sin(t)])  # spec §1.1, e = 2c
            w = np.array([x + s * n, y, z]) - c
            assert abs(np.linalg.norm(w) - design["l2"]) < 1e-9  # the joints assemble
            couple = reciprocal(chain)
            assert couple.shape[0] == 1 and in_span(couple, np.array([0, 0, 0, w[0], 0, w[2]]))


def test_fivebar_chain_constraints():
    mech, design, options = defaults("planar-fivebar")
    chains = mech.joint_screws(design, options, (0.0, -725.0), (-0.305041, -2.836552))  # spec §2.7 row 5
    right, left = (reciprocal(c) for c in chains)
    assert (right.shape[0], left.shape[0]) == (4, 3)
    for planar in ((0, 0, 1, 0, 0, 0), (0, 0, 0, 1, 0, 0), (0, 0, 0, 0, 1, 0)):
        assert in_span(right, np.array(planar, float)) and in_span(left, np.array(planar, float))
    assert in_span(right, np.array([0, 0, 0, 0, 0, 1.0]))  # the parallelograms forbid turning about z


# ----- the joints move the platform as the kinematics say ---------------------------------------------------
def platform_twist_basis(mech, design, options, pose, q):
    return screw_analysis(mech.joint_screws(design, options, pose, q)).twists


def test_translational_jacobians_lie_in_the_twist_space():
    for name in ("2pauu-ppap", "planar-fivebar"):
        mech, design, options = defaults(name)
        for pose, q in sample_configurations(mech, design, options, 3, seed=11):
            basis = platform_twist_basis(mech, design, options, pose, q)
            j = mech.jacobians(design, options, pose, q)["J"]  # dP/dq, spec §1.4 / §2.4
            for col in j.T:
                v = np.zeros(3)
                v[: col.size] = col
                assert in_span(basis, np.concatenate([np.zeros(3), v]), tol=1e-7), name


def test_ups_sspr_pose_rates_lie_in_the_twist_space():
    mech, design, options = defaults("ups-sspr")
    c = design["c"]
    for (alpha, beta, yy), q in sample_configurations(mech, design, options, 3, seed=2):
        basis = platform_twist_basis(mech, design, options, (alpha, beta, yy), q)
        rho = math.sqrt(c * c - yy * yy)
        p = np.array([math.sin(beta) * rho, yy, math.cos(beta) * rho])
        # spec §3.5: omega = beta' y + alpha' Ry(beta) x, v_B1 = P'; at the origin (omega; P' + P x omega)
        rates = [
            (np.array([math.cos(beta), 0.0, -math.sin(beta)]), np.zeros(3)),
            (Y, np.array([math.cos(beta) * rho, 0.0, -math.sin(beta) * rho])),
            (np.zeros(3), np.array([-math.sin(beta) * yy / rho, 1.0, -math.cos(beta) * yy / rho])),
        ]
        for omega, pdot in rates:
            assert in_span(basis, np.concatenate([omega, pdot + np.cross(p, omega)]), tol=1e-7)


def test_rps_upu_pose_rates_lie_in_the_twist_space():
    mech, design, options = defaults("rps-upu", model="C", c3_variant="upu")
    for x, q in sample_configurations(mech, design, options, 3, seed=4):
        basis = platform_twist_basis(mech, design, options, x, q)
        for k in range(3):
            dx = np.zeros(3)
            dx[k] = 1e-6
            hi, lo = (mech.platform_pose(design, options, x + s * dx) for s in (1, -1))
            rdot = (hi["R"] - lo["R"]) / 2e-6
            wx = rdot @ hi["R"].T  # skew(omega), to O(1e-6)
            omega = np.array([wx[2, 1], wx[0, 2], wx[1, 0]])
            p = 0.5 * (hi["p"] + lo["p"])
            twist = np.concatenate([omega, (hi["p"] - lo["p"]) / 2e-6 + np.cross(p, omega)])
            assert in_span(basis, twist, tol=1e-5)


def test_rps_upu_joints_assemble_in_the_c_model():
    mech, design, options = defaults("rps-upu", c3_variant="upu")
    for x, q in sample_configurations(mech, design, options, 3, seed=8):
        chains = mech.joint_screws(design, options, x, q)
        for chain in chains[:2]:
            assert abs(chain[1][3]) < 1e-12  # RPS legs normal to the revolute axis x
        # UPU: the leg is normal to the middle axes m (the U's second axis at A3)
        assert abs(np.dot(chains[2][1][:3], chains[2][2][3:])) < 1e-12


# ----- sampling and errors ---------------------------------------------------------------------------
def test_samples_are_feasible_and_reproducible():
    mech, design, options = defaults("ups-sspr")
    packed = mech.pack(design, options)
    a = sample_configurations(mech, design, options, 5, seed=9)
    b = sample_configurations(mech, design, options, 5, seed=9)
    for (pa, qa), (pb, qb) in zip(a, b, strict=True):
        assert np.array_equal(pa, pb) and np.array_equal(qa, qb)
        assert mech.point_kernel(packed, *pa) >= 0.0
        assert np.allclose(mech.inverse_kinematics(design, options, pa)[0].values, qa)


def test_empty_workspace_and_bad_sample_count():
    mech = get("planar-fivebar")
    design = mech.resolve_design({"r": 5000.0})  # the arms cannot meet: empty lens
    with pytest.raises(InvalidPose, match="samples"):
        sample_configurations(mech, design, mech.resolve_options({}), 2, max_draws=300)
    with pytest.raises(InvalidParameter, match="samples"):
        sample_configurations(mech, mech.resolve_design({}), mech.resolve_options({}), 0)


def test_mechanism_without_topology_is_a_clear_error():
    import dataclasses

    from scalesynth.mechanisms.pauu_ppap import MECHANISM as PAUU
    from scalesynth.mechanisms.pauu_ppap import PauuPpap

    class Bare(PauuPpap):  # a complete mechanism that declares no joints
        topology = None

    fields = {f.name: getattr(PAUU, f.name) for f in dataclasses.fields(PAUU)}
    bare = Bare(**{**fields, "name": "bare"})
    with pytest.raises(NoTopology, match="bare declares no joint topology"):
        mobility_report(bare, {}, {})


# ----- CLI -------------------------------------------------------------------------------------------
def test_cli_text_and_errors():
    runner = CliRunner()
    res = runner.invoke(app, ["mobility", "2pauu-ppap", "--samples", "3"])
    assert res.exit_code == 0, res.output
    assert "classical G-K  6(n - g - 1) + sum f = 1" in res.output
    assert "= 3   uses: nu = 2 redundant constraints" in res.output
    assert "-> dof 3, motion 3T" in res.output
    assert "agrees (counts, screws, declared motion): yes" in res.output
    res = runner.invoke(app, ["mobility", "no-such-mech"])
    assert res.exit_code == 2 and "unknown mechanism 'no-such-mech'" in res.output
    res = runner.invoke(app, ["mobility", "rps-upu", "--samples", "0"])
    assert res.exit_code == 2 and "--samples" in res.output
    res = runner.invoke(app, ["mobility", "planar-fivebar", "--set", "r=5000", "--samples", "1"])
    assert res.exit_code == 2 and "samples: found only 0 of 1" in res.output


def test_cli_json_is_one_object_on_stdout():
    env = dict(os.environ, MPLBACKEND="Agg")
    args = ["mobility", "planar-fivebar", "--samples", "3", "--json"]
    r = subprocess.run([sys.executable, "-m", "scalesynth", *args], capture_output=True, text=True, env=env)
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["grubler"]["classical"] == 2 and out["grubler"]["classical_formula"] == "3(n - g - 1) + sum f"
    assert out["numeric"]["motion"] == "2T" and out["numeric"]["lambda_in_space"] == 3
    assert out["numeric"]["constraint_rank"] == {"generic": 4, "min": 4, "max": 4}
    assert out["grubler"]["parallelograms_expanded"]["classical"] == 2 and out["agrees"] is True
