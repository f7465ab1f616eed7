"""Stiffness (issue 12): the FE checker (PyNite) on textbook cases with closed-form answers, then scalesynth's frame
solver and the five-bar's per-voxel Numba field against PyNite, the hand-solved pinned five-bar, the actuator-only
Jacobian model, linearity, symmetry/definiteness, singular poses, the CLI and bad input."""

import json
import math

import numpy as np
import pandas as pd
import pytest
from Pynite import FEModel3D
from typer.testing import CliRunner

from scalesynth.cli import app
from scalesynth.commands.fivebar import task_map
from scalesynth.config import load_config
from scalesynth.evaluate import evaluate_config
from scalesynth.mechanisms import get
from scalesynth.mechanisms.planar_fivebar import DEFLECTION_CAP, point_fields
from scalesynth.optimize import run
from scalesynth.stiffness.model import Body, FrameModel, Joint, Link
from scalesynth.stiffness.sections import tube_section
from scalesynth.stiffness.solve import solve

from conftest import ROOT
from fe_pynite import solve_model

M = get("planar-fivebar")
DESIGN = M.resolve_design({})  # r = 200, l1 = 475, l2 = 875 mm (illustrative, spec §2.7)
LIMITS = {"alpha1_limits": [-4 * math.pi / 9, 7 * math.pi / 36], "alpha2_limits": [29 * math.pi / 36, 13 * math.pi / 9]}
CORNERS = [(500.0, -850.0), (500.0, -600.0), (-500.0, -600.0), (-500.0, -850.0)]  # seed-004 task box (paper §4)
# + the centre, a pose 0.1 mm inside the outer reach of chain 1 (near an inverse singularity: arm and forearm
# almost collinear) and one near the inner reach boundary of chain 2
NEAR_OUTER = (200.0 + (1350.0 - 0.1) * math.cos(-1.9), (1350.0 - 0.1) * math.sin(-1.9))
NEAR_INNER = (-200.0 + (400.0 + 0.1) * math.cos(-1.9), (400.0 + 0.1) * math.sin(-1.9))
POSES = [*CORNERS, (0.0, -725.0), (300.0, -1000.0), NEAR_OUTER, NEAR_INNER]
VARIANTS = [(f, j) for f in ("single", "parallelogram") for j in ("ideal", "bonded")]


def options(**kw):
    return M.resolve_options(kw)


def model(opt, pose, joints="ideal", design=DESIGN):
    return M.stiffness_model(design, opt, pose, joints)


def rel(a, b):
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))) / np.max(np.abs(b)))


# ----- the checker first: PyNite on textbook cases ----------------------------------------------------------------
E, A, I, L, P = 70e3, 348.7, 60066.0, 500.0, -150.0  # N/mm^2, mm^2, mm^4, mm, N


def _pynite_beam(nodes):
    fe = FEModel3D()
    for name, x in nodes:
        fe.add_node(name, x, 0.0, 0.0)
    fe.add_material("al", E, E / 2.66, 0.33, 0.0)
    fe.add_section("tube", A, I, I, 2 * I)
    return fe


def _planar_support(fe, name, dx=False, dy=False, rz=False):
    fe.def_support(name, dx, dy, True, True, True, rz)


def test_checker_cantilever_tip_load_and_tip_spring():
    k = 50.0  # N/mm, translational spring from the tip to ground
    fe = _pynite_beam([("A", 0.0), ("B", L)])
    fe.add_member("m", "A", "B", "al", "tube")
    _planar_support(fe, "A", True, True, True)
    _planar_support(fe, "B")
    fe.def_support_spring("B", "DY", k, None)
    fe.add_node_load("B", "FY", P)
    fe.analyze_linear(check_stability=False)
    exact = P / (3 * E * I / L**3 + k)  # beam and spring in parallel at the tip
    assert fe.nodes["B"].DY["Combo 1"] == pytest.approx(exact, rel=1e-9)


def test_checker_propped_cantilever():
    fe = _pynite_beam([("A", 0.0), ("M", L / 2), ("B", L)])
    fe.add_member("m1", "A", "M", "al", "tube")
    fe.add_member("m2", "M", "B", "al", "tube")
    _planar_support(fe, "A", True, True, True)
    _planar_support(fe, "M")
    _planar_support(fe, "B", False, True, False)  # roller
    fe.add_node_load("M", "FY", P)
    fe.analyze_linear(check_stability=False)
    # midspan deflection 7 P L^3 / (768 E I), prop reaction 5 P / 16 (Roark, fixed-simply supported, centre load)
    assert fe.nodes["M"].DY["Combo 1"] == pytest.approx(7 * P * L**3 / (768 * E * I), rel=1e-9)
    assert fe.nodes["B"].RxnFY["Combo 1"] == pytest.approx(-5 * P / 16, rel=1e-9)


def _two_bar_truss():
    """Bars from (-400, 0) and (400, 0) pinned to the apex (0, -300) carrying the load; platform = the apex pin."""
    apex = np.array([0.0, -300.0])
    links, joints = [], []
    z = (np.array([0.0, 0.0, 1.0]),)
    for i, bx in enumerate((-400.0, 400.0)):
        base = np.array([bx, 0.0])
        links.append(Link(f"bar{i}", "bar", base, apex, E * A, E * I, E * I, 0.0))
        joints.append(Joint(f"foot{i}", "revolute", base, (f"bar{i}.a", "base"), z))
        joints.append(Joint(f"apex{i}", "revolute", apex, (f"bar{i}.b", "platform"), z))
    bodies = (Body("base", np.zeros(2)), Body("platform", apex, "point"))
    return FrameModel(2, "mm", tuple(links), tuple(joints), bodies, "platform", np.array([0.0, P]))


def test_pinned_two_bar_truss_closed_form():
    model = _two_bar_truss()
    sin = 300.0 / 500.0  # bar length 500 mm
    exact = P * 500.0 / (2 * E * A * sin**2)  # each bar carries P / (2 sin), apex drops L N / (E A sin)
    for defl in (solve_model(model.to_dict()), solve(model).deflection):
        assert defl[1] == pytest.approx(exact, rel=1e-9)
        assert defl[0] == pytest.approx(0.0, abs=1e-12 * abs(exact))


def test_cantilever_on_a_torsional_actuator_closed_form():
    k = 2e8  # N mm/rad
    tip = np.array([L, 0.0])
    model = FrameModel(
        2, "mm", (Link("arm", "arm", np.zeros(2), tip, E * A, E * I, E * I, 0.0),),
        (Joint("act", "revolute", np.zeros(2), ("arm.a", "base"), (np.array([0.0, 0.0, 1.0]),), k),
         Joint("tip", "fixed", tip, ("arm.b", "platform"))),
        (Body("base", np.zeros(2)), Body("platform", tip)), "platform", np.array([0.0, P]))
    exact = P * L**3 / (3 * E * I) + P * L * L / k
    res = solve(model)
    assert res.deflection[1] == pytest.approx(exact, rel=1e-10)
    assert solve_model(model.to_dict())[1] == pytest.approx(exact, rel=1e-9)
    # tip compliance matrix of a cantilever on a spring: [[L/EA, 0, 0], [0, L^3/3EI + L^2/k, L^2/2EI + L/k], ...]
    c = np.array([[L / (E * A), 0, 0], [0, L**3 / (3 * E * I) + L * L / k, L * L / (2 * E * I) + L / k],
                  [0, L * L / (2 * E * I) + L / k, L / (E * I) + 1 / k]])
    assert rel(res.C, c) < 1e-10


def hand_fivebar(opt, pose):
    """The pinned five-bar by hand: each forearm is a two-force member, so chain i is a spring of compliance
    l2/EA_forearm + u_i . C_Q u_i along its forearm direction u_i, C_Q the tip compliance of the arm (a cantilever
    on the actuator spring); K = sum u_i u_i^T / c_i, deflection K^-1 F."""
    r, l1, l2 = DESIGN["r"], DESIGN["l1"], DESIGN["l2"]
    arm, fore = tube_section(opt, "arm", "mm"), tube_section(opt, "forearm", "mm")
    q = {s.label: s.values for s in M.inverse_kinematics(DESIGN, opt, pose)}[opt["mode"]]
    K = np.zeros((2, 2))
    for b, qi in zip(((r, 0.0), (-r, 0.0)), M.elbows(DESIGN, q), strict=True):
        a = (qi - np.array(b)) / l1
        t = np.array([-a[1], a[0]])
        u = (np.array(pose) - qi) / l2
        cq = np.outer(a, a) * l1 / arm.EA + np.outer(t, t) * (l1**3 / (3 * arm.EI) + l1**2 / opt["actuator_stiffness"])
        K += np.outer(u, u) / (l2 / fore.EA + u @ cq @ u)
    return K, np.linalg.solve(K, opt["load"])


@pytest.mark.parametrize("pose", POSES)
def test_pinned_fivebar_by_hand(pose):
    opt = options()
    K, defl = hand_fivebar(opt, pose)
    assert rel(solve_model(model(opt, pose).to_dict()), defl) < 1e-9  # the checker
    res = solve(model(opt, pose))
    assert rel(res.deflection, defl) < 1e-9
    assert rel(res.K, K) < 1e-9


@pytest.mark.parametrize("e", [1e-3, 1.0, 1e4])
@pytest.mark.parametrize("k", [1e4, 1e8, 1e12])  # 1e12: the largest magnitude an option accepts (MAX_MAGNITUDE)
def test_reference_solver_keeps_accuracy_with_stiff_and_soft_parts(e, k):
    """Links 1e-3 ... 1e4 times aluminium with actuators of 1e4 ... 1e12 N mm/rad: the saddle-point solve agrees with
    the hand solution to 1e-5 (measured <= 8e-7; a Schur-complement condensation lost 0.1 % and more here)."""
    opt = options(youngs_modulus=70.0 * e, actuator_stiffness=k)
    C = np.linalg.inv(hand_fivebar(opt, (300.0, -700.0))[0])
    assert rel(solve(model(opt, (300.0, -700.0))).C, C) < 1e-5


# ----- every modelled variant against PyNite at >= 5 poses (task-box corners and near-singular poses) ---------------
@pytest.mark.parametrize("forearm,joints", VARIANTS)
@pytest.mark.parametrize("pose", POSES)
def test_fivebar_against_pynite(pose, forearm, joints):
    opt = options(forearm=forearm)
    fe = solve_model(model(opt, pose, joints).to_dict())
    ours = solve(model(opt, pose, joints)).deflection
    assert rel(ours, fe) < 1e-3  # issue 12: 0.1 %; measured <= 1e-4 (PyNite's rigid members are a penalty)


def test_cli_model_rebuilds_in_pynite():
    """The model printed by `scalesynth stiffness --json` is complete: PyNite rebuilt from it gives its deflection."""
    out = CliRunner().invoke(app, ["stiffness", "planar-fivebar", "--pose=-500,-850", "--set", "forearm=parallelogram",
                                   "--joints=bonded", "--load=20,-150", "--json"])
    assert out.exit_code == 0, out.output
    data = json.loads(out.output)
    assert data["model"]["load"]["force"] == [20.0, -150.0]
    assert rel(data["deflection"], solve_model(data["model"])) < 1e-3
    assert data["units"]["stiffness_min"] == "N/mm"


# ----- properties -------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("forearm,joints", VARIANTS)
def test_stiffness_symmetric_positive_definite(forearm, joints):
    opt = options(forearm=forearm)
    for pose in POSES:
        res = solve(model(opt, pose, joints))
        assert not res.singular
        assert rel(res.K, res.K.T) < 1e-12
        assert np.linalg.eigvalsh(res.K)[0] > 0
        assert res.stiffness_min == pytest.approx(1 / np.linalg.eigvalsh(res.C_t)[-1], rel=1e-12)


@pytest.mark.parametrize("forearm", ["single", "parallelogram"])
def test_rigid_links_give_the_jacobian_model(forearm):
    """Links e times stiffer: the compliance tends to J K_q^-1 J^T (J = forward Jacobian, mm/rad), the gap ~ 1/e."""
    pose = (300.0, -700.0)
    q = {s.label: s.values for s in M.inverse_kinematics(DESIGN, options(), pose)}["+-"]
    J = M.jacobians(DESIGN, options(), pose, q)["J"]
    k = 1e8
    cj = J @ J.T / k
    gaps = []
    for e in (1e3, 1e4, 1e5):
        res = solve(model(options(forearm=forearm, youngs_modulus=70 * e, actuator_stiffness=k), pose))
        gaps.append(rel(res.C_t, cj))
    assert gaps[2] < 1e-4
    assert gaps[0] / gaps[1] == pytest.approx(10, rel=0.05) and gaps[1] / gaps[2] == pytest.approx(10, rel=0.05)


def test_deflection_linear_in_the_load():
    f1, f2 = np.array([30.0, -150.0]), np.array([-70.0, 40.0])
    for forearm, joints in VARIANTS:
        d = {}
        for name, f in (("1", f1), ("2", f2), ("sum", 2.5 * f1 - 3 * f2)):
            d[name] = solve(model(options(forearm=forearm, load=list(f)), (-200.0, -800.0), joints)).deflection
        assert rel(d["sum"], 2.5 * d["1"] - 3 * d["2"]) < 1e-12


# a design with a forward singularity: l2 = 500, elbows Q1 = (500, y0), Q2 = (-500, y0) 2 l2 apart, P between them
SING = M.resolve_design({"r": 200.0, "l1": 475.0, "l2": 500.0})
Y0 = -475.0 * math.sin(math.acos(300.0 / 475.0))


def test_singular_pose_is_infinite_never_nan():
    mode = next(s.label for s in M.inverse_kinematics(SING, options(), (0.0, Y0))
                if np.allclose(M.elbows(SING, s.values), [(500.0, Y0), (-500.0, Y0)], atol=1e-6))
    assert mode == "+-"  # elbows out
    opt = options(mode=mode)
    assert M.singularity(SING, opt, (0.0, Y0), {s.label: s.values for s in M.inverse_kinematics(
        SING, opt, (0.0, Y0))}[mode], tol=1e-9) in ("forward", "both")
    res = solve(model(opt, (0.0, Y0), design=SING))
    assert res.singular and res.C is None and math.isinf(res.deflection_norm) and res.stiffness_min == 0.0
    out = fields(M.pack(SING, opt), 0.0, Y0)  # the field contract has no inf: capped
    assert out[0] >= 0 and out[3] == 0.0 and out[4] == DEFLECTION_CAP == 1e12
    out = CliRunner().invoke(app, ["stiffness", "planar-fivebar", "--set", "l2=500", "--set", f"mode={mode}",
                                   f"--pose=0,{Y0!r}", "--json"])
    assert out.exit_code == 0 and "NaN" not in out.output
    data = json.loads(out.output)
    assert data["singular"] and data["deflection_norm"] == "inf" and data["compliance"][0][0] == "inf"
    # 1 mm away the pose is regular, with a large but finite deflection
    near = solve(model(opt, (0.0, Y0 - 1.0), design=SING))
    assert not near.singular and 10 * solve(model(opt, (0.0, Y0 - 100.0), design=SING)).deflection_norm < \
        near.deflection_norm < math.inf


# ----- the per-voxel Numba field equals the NumPy reference --------------------------------------------------------
def fields(packed, x, y):
    out = np.zeros(M.n_fields)
    point_fields(packed, float(x), float(y), 0.0, out)
    assert M.field_names[3:5] == ("stiffness_min", "deflection")
    return out


def test_numba_field_equals_reference():
    rng = np.random.default_rng(12)
    opt = options(**LIMITS, tube=[30.0, 2.0], sections={"arm": [50.0, 4.0]}, actuator_stiffness=3e7,
                  load=[25.0, -150.0])
    packed = M.pack(DESIGN, opt)
    checked = 0
    for x, y in zip(rng.uniform(-700, 700, 400), rng.uniform(-1300, -300, 400), strict=True):
        out = fields(packed, x, y)
        if out[0] < 0:
            assert out[3] == 0 and out[4] == 0
            continue
        kmin, defl = out[3], out[4]
        for forearm in ("single", "parallelogram"):  # ideal joints: the parallelograms carry nothing (docs)
            res = solve(model({**opt, "forearm": forearm}, (x, y)))
            assert kmin == pytest.approx(res.stiffness_min, rel=1e-8)
            assert defl == pytest.approx(res.deflection_norm, rel=1e-8)
        checked += 1
    assert checked > 100


# ----- seed 004: parallelogram forearms stiffer vertically (paper §4.3), figures in docs/stiffness.md ----------------
def test_seed004_parallelograms_stiffer_vertically_with_bonded_joints():
    for pose in [*CORNERS, (0.0, -725.0)]:
        dy = {f: solve(model(options(forearm=f), pose, "bonded")).deflection[1] for f in ("single", "parallelogram")}
        assert dy["single"] < 0 and dy["parallelogram"] < 0
        assert abs(dy["parallelogram"]) < abs(dy["single"])
        # ideal (moment-free) joints: a force at P puts no load in the parallelograms' second bars
        ideal = {f: solve(model(options(forearm=f), pose)).deflection for f in ("single", "parallelogram")}
        assert rel(ideal["parallelogram"], ideal["single"]) < 1e-8


# ----- bad input: one line naming it, exit 2 -------------------------------------------------------------------------
@pytest.mark.parametrize("args,field", [
    (["--set", "youngs_modulus=0"], "options.youngs_modulus"),
    (["--set", "tube=[40,-3]"], "options.tube[1]"),
    (["--set", "tube=[40,30]"], "options.tube"),
    (["--set", "sections={arm: [0, 1]}"], "options.sections.arm[0]"),
    (["--set", "sections={wing: [40, 3]}"], "options.sections.wing"),
    (["--set", "actuator_stiffness=-5"], "options.actuator_stiffness"),
    (["--set", "poisson_ratio=0.7"], "options.poisson_ratio"),
    (["--set", "load=[1,2,3]"], "options.load"),
    (["--load=1,2,3"], "--load"),
    (["--set", "forearm=double"], "options.forearm"),
    (["--joints=glued"], "--joints"),
    (["--set", "parallelogram_spacing=0"], "options.parallelogram_spacing"),
])
def test_bad_input_exit_2(args, field):
    out = CliRunner().invoke(app, ["stiffness", "planar-fivebar", "--pose=0,-725", *args])
    assert out.exit_code == 2
    lines = out.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {field}"), out.output


def test_pose_outside_workspace_exit_2():
    for pose in ("0,-2000", "400,-500"):  # out of reach; reachable but outside the arm limits
        out = CliRunner().invoke(app, ["stiffness", "planar-fivebar", f"--pose={pose}",
                                       "--set", f"alpha1_limits={LIMITS['alpha1_limits']}",
                                       "--set", f"alpha2_limits={LIMITS['alpha2_limits']}"])
        assert out.exit_code == 2 and out.output.strip().startswith("error: pose:"), out.output


# ----- catalogue metrics: evaluate reports them, synthesis constrains them -------------------------------------------
def test_evaluate_reports_stiffness_metrics_equal_to_reference():
    """`evaluate configs/fivebar_packing.yaml` has the stiffness statistics; over the task box they equal the
    NumPy reference solved at every cell centre."""
    cfg = load_config(ROOT / "configs" / "fivebar_packing.yaml", ["grid.resolution=16", "task.resolution=8"])
    rep = evaluate_config(cfg).to_dict()
    opt = cfg.resolved_options()
    defl, kmin = [], []
    for x in -500 + (np.arange(8) + 0.5) * 125.0:
        for y in -850 + (np.arange(8) + 0.5) * 250.0 / 8:
            res = solve(model(opt, (x, y), design=cfg.resolved_design()))
            defl.append(res.deflection_norm)
            kmin.append(res.stiffness_min)
    assert rep["task_coverage"] == 1.0
    assert rep["task_max_deflection_mm"] == pytest.approx(max(defl), rel=1e-9)
    assert rep["task_mean_deflection_mm"] == pytest.approx(np.mean(defl), rel=1e-9)
    assert rep["task_min_stiffness_min_N_per_mm"] == pytest.approx(min(kmin), rel=1e-9)
    for key in ("max_deflection_mm", "min_stiffness_min_N_per_mm", "mean_deflection_mm"):
        assert math.isfinite(rep[key]) and rep[key] > 0


def test_synthesis_with_a_deflection_constraint(tmp_path):
    """configs/fivebar_stiffness.yaml (task_max_deflection <= 0.1 mm) runs; feasibility follows the constraint."""
    cfg = load_config(ROOT / "configs" / "fivebar_stiffness.yaml",
                      ["algorithm.pop_size=8", "algorithm.n_gen=2", "grid.resolution=16", "task.resolution=8",
                       "design.r=200"])
    run(cfg, tmp_path / "out", plots=False)
    pop = pd.read_csv(tmp_path / "out" / "population.csv")
    assert "task_max_deflection_mm" in pop.columns
    ok = (pop["task_max_deflection_mm"] <= 0.1) & (pop["task_coverage"] >= 1.0) & (pop["path_min_lci"] >= 0.3)
    assert (pop["feasible"].astype(bool) == ok).all()
    front = pd.read_csv(tmp_path / "out" / "pareto.csv")
    assert (front["task_max_deflection_mm"] <= 0.1).all()


def test_plot_task_maps_the_deflection(tmp_path):
    """`plot-task --field deflection`: its extremes are the task-box statistics of evaluate; unknown field: exit 2."""
    cfgp = str(ROOT / "configs" / "fivebar_stiffness.yaml")
    out = CliRunner().invoke(app, ["plot-task", cfgp, "--field", "deflection", "--resolution", "16",
                                   "--out", str(tmp_path / "d.png"), "--json"])
    assert out.exit_code == 0, out.output
    data = json.loads(out.output)
    assert (tmp_path / "d.png").stat().st_size > 0
    cfg = load_config(cfgp, ["task.resolution=16"])
    rep = evaluate_config(cfg).to_dict()
    tm = task_map(cfg, 16, "deflection")
    shown = tm.values[tm.lci >= 0]
    assert shown.max() == pytest.approx(rep["task_max_deflection_mm"], rel=1e-12)
    assert shown.min() == pytest.approx(rep["task_min_deflection_mm"], rel=1e-12)
    assert data["task_max_deflection_mm"] == pytest.approx(rep["task_max_deflection_mm"], rel=1e-12)
    bad = CliRunner().invoke(app, ["plot-task", cfgp, "--field", "bogus", "--out", str(tmp_path / "x.png")])
    assert bad.exit_code == 2 and "--field" in bad.output and not (tmp_path / "x.png").exists()
