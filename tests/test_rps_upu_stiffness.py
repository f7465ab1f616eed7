"""Seed 002 (rps-upu, rps-upu-tool): the per-voxel stiffness fields (stiffness_min slot 4, deflection slot 5) against
the pose-level frame model (RpsUpu.stiffness_model / RpsUpuTool.stiffness_model, FE-checked against PyNite in
test_stiffness_seeds.py) solved by the NumPy reference solver stiffness.solve, and the evaluator's statistics.

The frame sits at the constraint-consistent (C-model) placement of the voxel's pose (the P-model violates the RPS
joint constraints); the tool workspace's kernel finds the C-model pose that puts the tool at T by Newton, as the pose
level does. The rule for a placement whose legs leave the stroke limits (the fields are its structure's all the
same, and the pose level says so in the model's notes) is tested here too."""

import numpy as np
import pytest

from scalesynth.config import config_from_dict
from scalesynth.evaluate import evaluate, make_grid
from scalesynth.kernels import grid as kgrid
from scalesynth.mechanisms import get
from scalesynth.mechanisms import rps_upu as R
from scalesynth.stiffness import legs
from scalesynth.stiffness.solve import solve

RPS = get("rps-upu")
TOOL = get("rps-upu-tool")
DESIGN = RPS.resolve_design({})  # g = 80, h = 50, c = 50, e = 0 mm
KMIN, DEFL = 4, 5
# (mechanism, design, options): the paper model with either chain-3 variant, the C-model with either, the tool
# workspace, and other designs, sections, actuator stiffnesses and loads (every term of the closed form exercised)
CASES = [
    (RPS, {}, {}),
    (RPS, {}, {"c3_variant": "upu"}),
    (RPS, {}, {"model": "C"}),
    (RPS, {"g": 70.0, "h": 40.0, "c": 60.0, "e": 15.0},
     {"model": "C", "c3_variant": "upu", "sections": {"leg": [20.0, 2.0]}, "actuator_stiffness": 5e3,
      "load": [30.0, -20.0, -150.0]}),
    (RPS, {"g": 90.0, "h": 55.0, "c": 45.0, "e": -10.0}, {"load": [0.0, 80.0, -10.0], "youngs_modulus": 200.0}),
    (TOOL, {}, {}),
    (TOOL, {"g": 75.0, "h": 45.0, "c": 55.0}, {"tool_offset": 35.0, "load": [20.0, 10.0, -150.0],
                                               "sections": {"leg": [30.0, 4.0]}, "actuator_stiffness": 1e4}),
]


def fields_at(mech, p, pose):
    out = np.full(mech.n_fields, np.nan)
    mech.field_kernel(p, *map(float, pose), out)
    assert not np.any(np.isnan(out))
    return out


def test_slots():
    for mech in (RPS, TOOL):
        assert mech.field_names[3:] == ("clearance", "stiffness_min", "deflection")
        assert mech.pack(DESIGN, mech.resolve_options({})).shape[0] >= R.N_PACKED
    assert (R._F_STIFFNESS_MIN, R._F_DEFLECTION) == (KMIN, DEFL)


@pytest.mark.parametrize(("mech", "design", "opts"), CASES)
def test_fields_equal_the_reference_solver_at_random_reachable_poses(mech, design, opts):
    """15 random reachable poses per case in the bounding box: stiffness_min (N/mm) and deflection (mm) equal the
    reference solver on stiffness_model's frame to 1e-7 relative (measured <= 7e-12); unreachable poses write 0."""
    design = mech.resolve_design(design)
    opt = mech.resolve_options(opts)
    p = mech.pack(design, opt)
    lo, hi = mech.bounding_box(design, opt)
    rng = np.random.default_rng(21 + int(design["g"]) + len(opts))
    checked = 0
    for _ in range(3000):
        pose = lo + rng.uniform(size=3) * (hi - lo)
        out = fields_at(mech, p, pose)
        if out[0] < 0:
            assert out[KMIN] == 0.0 and out[DEFL] == 0.0
            continue
        res = solve(mech.stiffness_model(design, opt, pose))
        assert not res.singular and res.dofs == ("x", "y", "z", "rx", "ry", "rz")
        assert out[KMIN] == pytest.approx(res.stiffness_min, rel=1e-7), pose
        assert out[DEFL] == pytest.approx(res.deflection_norm, rel=1e-7), pose
        checked += 1
        if checked == 15:
            break
    assert checked == 15


@pytest.mark.parametrize("mech", [RPS, TOOL])
def test_grid_and_statistics_equal_the_reference(mech):
    """Every reachable cell of a 6^3 grid of the default design equals the reference solver at its centre, and
    evaluate's workspace statistics are the NumPy reductions of those values."""
    opt = mech.resolve_options({})
    g = make_grid(mech, DESIGN, opt, 6)
    vals = kgrid.sample_fields(mech.field_kernel, mech.n_fields, mech.pack(DESIGN, opt), g.lo, g.step, g.shape)
    kmin, defl = [], []
    for idx in np.ndindex(*g.shape):
        if vals[idx][0] < 0:
            continue
        res = solve(mech.stiffness_model(DESIGN, opt, g.lo + (np.array(idx) + 0.5) * g.step))
        assert vals[idx][KMIN] == pytest.approx(res.stiffness_min, rel=1e-7)
        assert vals[idx][DEFL] == pytest.approx(res.deflection_norm, rel=1e-7)
        kmin.append(res.stiffness_min)
        defl.append(res.deflection_norm)
    assert len(defl) > 20
    rep = evaluate(mech, DESIGN, opt, resolution=6)
    assert rep.metrics["max_deflection_mm"] == pytest.approx(max(defl), rel=1e-7)
    assert rep.metrics["mean_deflection_mm"] == pytest.approx(np.mean(defl), rel=1e-7)
    assert rep.metrics["min_stiffness_min_N_per_mm"] == pytest.approx(min(kmin), rel=1e-7)


def test_approaching_the_forward_singularity():
    """(z, 0, 0) with the stroke limits lifted: at z = 0 every leg lies in the base plane and the platform sinks
    freely. Approaching it the deflection grows 100x per decade of z (~ z^-2: the legs' axial stiffness acts on the
    vertical through sin^2 of their elevation), with the reference solver's values; within 1e-3 mm both call the pose
    singular (the kernel writes stiffness_min 0 and the 1e12 cap, never NaN)."""
    opt = RPS.resolve_options({"stroke_limits": None})
    p = RPS.pack(DESIGN, opt)
    previous = None
    for z in (10.0, 1.0, 0.1, 0.01):
        out = fields_at(RPS, p, (z, 0.0, 0.0))
        res = solve(RPS.stiffness_model(DESIGN, opt, (z, 0.0, 0.0)))
        assert out[DEFL] == pytest.approx(res.deflection_norm, rel=1e-6)
        assert out[KMIN] == pytest.approx(res.stiffness_min, rel=1e-6)
        if previous is not None:
            assert 80.0 < out[DEFL] / previous < 120.0
        previous = out[DEFL]
    for z in (1e-3, 0.0):
        out = fields_at(RPS, p, (z, 0.0, 0.0))
        assert solve(RPS.stiffness_model(DESIGN, opt, (z, 0.0, 0.0))).singular
        assert out[KMIN] == 0.0 and out[DEFL] == legs.DEFLECTION_CAP
    # no load: no deflection even at the singular pose
    p0 = RPS.pack(DESIGN, RPS.resolve_options({"stroke_limits": None, "load": [0.0, 0.0, 0.0]}))
    assert fields_at(RPS, p0, (0.0, 0.0, 0.0))[DEFL] == 0.0


def _placements_outside_the_strokes(mech, opts, n):
    """Up to n reachable poses of the default design whose frame (the C-model placement) has a leg outside the
    stroke limits: its notes say so."""
    opt = mech.resolve_options(opts)
    lo, hi = mech.bounding_box(DESIGN, opt)
    rng = np.random.default_rng(5)
    found = []
    for _ in range(20000):
        pose = lo + rng.uniform(size=3) * (hi - lo)
        if mech.point_kernel(mech.pack(DESIGN, opt), *pose) < 0:
            continue
        model = mech.stiffness_model(DESIGN, opt, pose)
        if any("leave the stroke limits" in note for note in model.notes):
            found.append((pose, model))
            if len(found) == n:
                break
    return opt, found


@pytest.mark.parametrize(("mech", "opts"), [(RPS, {}), (RPS, {"c3_variant": "upu"}), (TOOL, {})])
def test_placements_outside_the_stroke_limits_follow_the_same_rule(mech, opts):
    """A reachable pose of the configured (P-model) workspace whose constraint-consistent placement has a leg
    outside the stroke limits is not refused: the pose level solves the frame there and says so in its notes, and
    the kernel writes the same values (the fields are the structure's; the stroke limits bound the actuators'
    travel, not the stiffness). On the default design such poses exist near the workspace's stroke boundary."""
    opt, found = _placements_outside_the_strokes(mech, opts, 3)
    assert len(found) == 3
    p = mech.pack(DESIGN, opt)
    for pose, model in found:
        out = fields_at(mech, p, pose)
        res = solve(model)
        assert out[0] >= 0 and out[KMIN] == pytest.approx(res.stiffness_min, rel=1e-7)
        assert out[DEFL] == pytest.approx(res.deflection_norm, rel=1e-7)


def test_tool_kernel_places_the_tool_like_the_pose_level():
    """The kernel's Newton solve and the pose level's find the same C-model pose: the platform reference point of the
    pose-level model is the tool point, and the deflections agree to 1e-9 at the box-corner tool points of
    test_stiffness_seeds (default options)."""
    opt = TOOL.resolve_options({})
    p = TOOL.pack(DESIGN, opt)
    for t in ((14.156, 15.443, 14.212), (14.156, 15.443, -7.615), (-14.156, 9.009, 22.943), (-14.156, -9.009, -3.25)):
        model = TOOL.stiffness_model(DESIGN, opt, t)
        assert np.max(np.abs(np.subtract(model.body("platform").ref, t))) < 1e-12
        out = fields_at(TOOL, p, t)
        assert out[DEFL] == pytest.approx(solve(model).deflection_norm, rel=1e-9)


def test_a_synthesis_with_a_deflection_constraint_runs(tmp_path):
    """A small NSGA-II run of rps-upu maximising volume and min_stiffness_min under max_deflection <= 0.015 mm (the
    largest deflection of O' under 150 N over the workspace): the results carry the stiffness columns, the
    constraint binds in the population and every front design meets it."""
    from scalesynth.optimize import run

    cfg = config_from_dict({
        "name": "rps_stiff", "mechanism": "rps-upu", "units": {"length": "mm"}, "design": {},
        "bounds": {"g": [60.0, 100.0], "h": [40.0, 60.0], "c": [40.0, 60.0]}, "grid": {"resolution": 8},
        "algorithm": {"pop_size": 8, "n_gen": 2, "seed": 3},
        "objectives": [{"metric": "volume"}, {"metric": "min_stiffness_min", "sense": "max"}],
        "constraints": [{"metric": "max_deflection", "max": 0.015}],
    })
    result = run(cfg, tmp_path / "out", plots=False)
    pop = result.population
    assert {"max_deflection_mm", "min_stiffness_min_N_per_mm", "mean_deflection_mm"} <= set(pop.columns)
    assert np.all(np.isfinite(pop["max_deflection_mm"]) | (pop["voxels"] == 0))  # null over an empty workspace
    assert (pop["max_deflection_mm"] > 0.015).any() and (pop["max_deflection_mm"] <= 0.015).any()  # seed 3: 0.007-0.025
    front = result.pareto
    assert len(front) and (front["max_deflection_mm"] <= 0.015).all()


def test_the_command_prints_the_placement_notes():
    """`scalesynth stiffness` prints the model's notes, so a user sees that the frame's legs leave the stroke limits
    (a P-model pose whose C-model placement has leg 2 at 39.27 mm, below the 40 mm limit)."""
    from typer.testing import CliRunner

    from scalesynth.cli import app

    out = CliRunner().invoke(app, ["stiffness", "rps-upu", "--pose=39.5447,0.1113,-0.3033"])
    assert out.exit_code == 0, out.output
    notes = [line for line in out.output.splitlines() if line.startswith("  note: ")]
    assert any("leave the stroke limits [40, 90]" in n and "39.27" in n for n in notes), out.output
