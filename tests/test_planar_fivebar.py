"""Seed-004 planar five-bar: spec mechanisms_000_004.md §2 (reference cases §2.7, tests/data/cases/ref000_004.txt), the
kernel against its NumPy twin (tests/naive.py), and property tests (IK/FK round trips, J vs FK differences)."""

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from fd_checks import assembly_error, fk_jacobian
from scalesynth.cli import app
from scalesynth.config import load_config
from scalesynth.errors import InvalidParameter, InvalidPose
from scalesynth.evaluate import evaluate, evaluate_config, make_grid, sample_path
from scalesynth.kernels import grid as kgrid
from scalesynth.mechanisms import get

from conftest import ROOT
from naive import assert_report_equals_grid_metrics, fivebar_arm_angles, fivebar_lci, grid_metrics, grid_nodes
from refdata import seed004_points

M = get("planar-fivebar")
ILLUSTRATIVE = dict(r=200.0, l1=475.0, l2=875.0)  # spec §2.7 (not from the paper)
DESIGN = M.resolve_design(ILLUSTRATIVE)
OPT = M.resolve_options({})  # mode "+-": elbows out
PACKED = M.pack(DESIGN, OPT)
# spec §2.5: corrected arm limits (rad)
LIMITS = {"alpha1_limits": [-4 * math.pi / 9, 7 * math.pi / 36], "alpha2_limits": [29 * math.pi / 36, 13 * math.pi / 9]}
# the packing rectangle of spec §2.7, 201 x 51 nodes with the endpoints
RX, RY = np.meshgrid(np.linspace(-500, 500, 201), np.linspace(-850, -600, 51), indexing="ij")


def six(value, printed):
    """value rounds to the spec's 6-decimal figure."""
    return value == pytest.approx(printed, abs=5e-7)


def branches(pose, design=DESIGN):
    return {s.label: s.values for s in M.inverse_kinematics(design, OPT, pose)}


def kernel(x, y, packed=PACKED):
    return M.point_kernel(packed, float(x), float(y), 0.0)


# ----- spec §2.7 reference cases ---------------------------------------------------------------------------
# |J (1, 1)^T| (mm) at the reference points: spec §2.7 table (not in ref000_004.txt)
RESOLUTION = {"a": 752.163804, "b": 612.735263, "c": 612.735263, "d": 752.163804, "o": 546.660466}
# point: ((x, y), (alpha1, alpha2, beta1, beta2), J rows, LCI, |J (1, 1)^T|), from tests/data/cases/ref000_004.txt
SPEC_POINTS = {k: (*v[:4], RESOLUTION[k]) for k, v in seed004_points().items()}
OTHER_FK = {k: v[4] for k, v in seed004_points().items()}  # the second assembly mode (x, y) mm


@pytest.mark.parametrize("name", list(SPEC_POINTS))
def test_spec_reference_points(name):
    pose, (a1, a2, b1, b2), j_rows, lci, resolution = SPEC_POINTS[name]
    q = branches(pose)[M.kernel_branch(OPT)]
    assert six(q[0], a1) and six(q[1], a2)
    beta = M.forearm_angles(DESIGN, pose, q)
    assert six(beta[0], b1) and six(beta[1], b2)
    jac = M.jacobians(DESIGN, OPT, pose, q)
    for got, exp in zip(jac["J"].ravel(), np.ravel(j_rows), strict=True):
        assert six(got, exp)
    assert six(M.lci(DESIGN, OPT, pose, q), lci)
    assert six(kernel(*pose), lci)
    res = M.resolution_index(DESIGN, OPT, pose)
    assert six(res, resolution)
    assert M.resolution_index(DESIGN, OPT, pose, (2.0, 2.0)) == pytest.approx(2 * res, rel=1e-15)  # linear
    assert M.singularity(DESIGN, OPT, pose, q) == "none"


def test_other_roots_and_second_assembly_mode_at_point_a():
    """Spec §2.7: alpha1(sigma=-1) = -2.478446, alpha2(sigma=+1) = -0.009324; other FK mode (-111.788536, 390.318432)
    (also in cases/ref000_004.txt)."""
    sols = branches((500, -850))
    assert six(sols["-+"][0], -2.478446) and six(sols["--"][0], -2.478446)
    assert six(sols["++"][1], -0.009324) and six(sols["-+"][1], -0.009324)
    fk = {s.label: s.values for s in M.forward_kinematics(DESIGN, OPT, sols["+-"])}
    assert set(fk) == {"+", "-"}
    np.testing.assert_allclose(fk["+"], (500, -850), atol=1e-9)  # '+' is the lower (packing-side) mode
    assert six(fk["-"][0], OTHER_FK["a"][0]) and six(fk["-"][1], OTHER_FK["a"][1])


def test_ik_equals_half_angle_form_of_the_paper():
    """Spec §2.2: alpha(sigma) = 2 atan[(-E + sigma sqrt(D^2 + E^2 - F^2)) / (F - D)], same angles mod 2 pi."""
    r, l1, l2 = ILLUSTRATIVE.values()
    for name, (pose, *_rest) in SPEC_POINTS.items():
        x, y = pose
        sols = branches(pose)
        for chain, u in ((0, x - r), (1, x + r)):
            d, e, f = -2 * l1 * u, -2 * l1 * y, u * u + y * y + l1 * l1 - l2 * l2
            for sigma, ch in ((1, "+"), (-1, "-")):
                half = 2 * math.atan((-e + sigma * math.sqrt(d * d + e * e - f * f)) / (f - d))
                label = ch + "+" if chain == 0 else "+" + ch
                assert math.remainder(sols[label][chain] - half, 2 * math.pi) == pytest.approx(0, abs=1e-12), name


def _fk_spec_form(design, q):
    """Spec §2.3 (eqs. 4-6 corrected): A + B cos(beta1) + C sin(beta1) = 0 solved with delta = tan(beta1 / 2)."""
    r, l1, l2 = design["r"], design["l1"], design["l2"]
    a1, a2 = q
    a = 4 * r * r + 4 * r * l1 * (math.cos(a1) - math.cos(a2)) + 2 * l1 * l1 * (1 - math.cos(a1 - a2))
    b = 2 * l2 * (2 * r + l1 * (math.cos(a1) - math.cos(a2)))
    c = 2 * l1 * l2 * (math.sin(a1) - math.sin(a2))
    out = []
    for sign in (1, -1):
        beta1 = 2 * math.atan((-c + sign * math.sqrt(c * c - a * a + b * b)) / (a - b))
        out.append((r + l1 * math.cos(a1) + l2 * math.cos(beta1), l1 * math.sin(a1) + l2 * math.sin(beta1)))
    return out


@pytest.mark.parametrize("q", [(0.015438, -1.754420), (0.3, 2.9), (-1.0, -2.0), (1.2, 1.9)])
def test_fk_matches_the_spec_algebraic_form(q):
    ours = [s.values for s in M.forward_kinematics(DESIGN, OPT, q)]
    spec = _fk_spec_form(DESIGN, q)
    assert len(ours) == 2
    for p in spec:
        assert min(np.abs(v - p).max() for v in ours) < 1e-9


def test_jacobian_equals_paper_form():
    """Spec §2.4: J = [[-l1 s_a1 - l2 s_b1 K11, -l2 s_b1 K12], [l1 c_a1 + l2 c_b1 K11, l2 c_b1 K12]]."""
    l1, l2 = DESIGN["l1"], DESIGN["l2"]
    for pose, *_rest in SPEC_POINTS.values():
        q = branches(pose)["+-"]
        a1, a2 = q
        b1, b2 = M.forearm_angles(DESIGN, pose, q)
        k11 = -l1 * math.sin(b2 - a1) / (l2 * math.sin(b2 - b1))
        k12 = l1 * math.sin(b2 - a2) / (l2 * math.sin(b2 - b1))
        paper = [
            [-l1 * math.sin(a1) - l2 * math.sin(b1) * k11, -l2 * math.sin(b1) * k12],
            [l1 * math.cos(a1) + l2 * math.cos(b1) * k11, l2 * math.cos(b1) * k12],
        ]
        np.testing.assert_allclose(M.jacobians(DESIGN, OPT, pose, q)["J"], paper, rtol=1e-12, atol=1e-9)


# ----- the packing rectangle (spec §2.5, §2.7) -----------------------------------------------------------------
def test_rectangle_statistics_kernel_and_twin():
    """Spec §2.7: GCI = 0.860168, FCI = 0.055456, max|LCI - GCI| = 0.137568, LCI in (0.738853, 0.997737)."""
    pts = np.stack([RX.ravel(), RY.ravel(), np.zeros(RX.size)], axis=1)
    lci = kgrid.points_lci(M.point_kernel, PACKED, pts)
    twin = fivebar_lci(DESIGN, OPT, RX.ravel(), RY.ravel())
    assert (lci >= 0).all() and (twin >= 0).all()
    np.testing.assert_allclose(lci, twin, rtol=1e-7)
    for v in (lci, twin):
        gci = v.mean()
        assert six(gci, 0.860168)
        assert six(np.sqrt(np.mean((v - gci) ** 2)), 0.055456)
        assert six(np.abs(v - gci).max(), 0.137568)
        assert six(v.min(), 0.738853) and six(v.max(), 0.997737)


def test_rectangle_arm_angle_image_and_limits():
    """Spec §2.5: the elbows-out IK image of the rectangle is alpha1 in [-79.48, 34.68] deg, alpha2 in
    [145.32, 259.48] deg (mod 360), inside the corrected limits [-80, 35] and [145, 260] deg."""
    a1, a2 = fivebar_arm_angles(DESIGN, OPT, RX, RY)
    a1 = np.degrees(a1)
    a2 = np.degrees(a2) % 360
    assert (round(a1.min(), 2), round(a1.max(), 2)) == (-79.48, 34.68)
    assert (round(a2.min(), 2), round(a2.max(), 2)) == (145.32, 259.48)
    # the mechanism's IK gives the same angles at the extreme corners d, b, c, a
    for pose, k, deg in (((-500, -850), 0, -79.48), ((500, -600), 0, 34.68), ((-500, -600), 1, 145.32)):
        assert round(math.degrees(branches(pose)["+-"][k]), 2) == deg
    assert round(math.degrees(branches((500, -850))["+-"][1]) % 360, 2) == 259.48
    # with the limits every node stays reachable (alpha2's interval wraps past pi: modulo 2 pi) ...
    limited = M.pack(DESIGN, M.resolve_options(LIMITS))
    pts = np.stack([RX.ravel(), RY.ravel(), np.zeros(RX.size)], axis=1)
    assert (kgrid.points_lci(M.point_kernel, limited, pts) >= 0).all()
    # ... and pulling any of the four ends in by 0.6 deg cuts off a corner
    cut = math.radians(0.6)
    for name, end, corner in (
        ("alpha1_limits", 0, (-500, -850)),
        ("alpha1_limits", 1, (500, -600)),
        ("alpha2_limits", 0, (-500, -600)),
        ("alpha2_limits", 1, (500, -850)),
    ):
        lim = list(LIMITS[name])
        lim[end] += cut if end == 0 else -cut
        packed = M.pack(DESIGN, M.resolve_options(dict(LIMITS, **{name: lim})))
        assert kernel(*corner, packed=packed) == -1.0, (name, end)
        assert kernel(0, -725, packed=packed) >= 0


def test_packing_config_task_metrics():
    """configs/fivebar_packing.yaml: the illustrative design covers the rectangle within the limits; the task
    metrics equal the twin on the same cell-centred nodes and the path LCI on the sampled path."""
    cfg = load_config(ROOT / "configs" / "fivebar_packing.yaml")
    assert cfg.resolved_design() == DESIGN
    opts = cfg.resolved_options()
    assert opts["mode"] == "+-"
    np.testing.assert_allclose(opts["alpha1_limits"], LIMITS["alpha1_limits"], rtol=1e-15)
    np.testing.assert_allclose(opts["alpha2_limits"], LIMITS["alpha2_limits"], rtol=1e-15)
    n = cfg.task.resolution  # the task box's own uniform grid (the workspace is in the tolerance form)
    assert n == 32
    rep = evaluate_config(cfg)
    assert rep.measure_key == "area_mm2"
    assert rep.metrics["task_coverage"] == 1.0
    step = np.array([1000.0, 250.0]) / n
    xs = -500 + (np.arange(n) + 0.5) * step[0]
    ys = -850 + (np.arange(n) + 0.5) * step[1]
    twin = fivebar_lci(DESIGN, opts, *np.meshgrid(xs, ys, indexing="ij"))
    assert rep.metrics["task_gci"] == pytest.approx(twin.mean(), rel=1e-9)
    assert rep.metrics["task_fci"] == pytest.approx(twin.std(), rel=1e-7)
    assert rep.metrics["task_gci"] == pytest.approx(0.860168, abs=2e-3)  # cell-centred grid vs spec's nodes
    pts = sample_path(cfg.task.path, cfg.task.path_samples)
    path = fivebar_lci(DESIGN, opts, pts[:, 0], pts[:, 1])
    assert rep.metrics["path_min_lci"] == pytest.approx(path.min(), rel=1e-9)


# ----- kernel vs NumPy twin on whole-workspace grids --------------------------------------------------------------
TWIN_CASES = [
    (ILLUSTRATIVE, {}),
    (ILLUSTRATIVE, {"mode": "++"}),
    (ILLUSTRATIVE, {"mode": "-+"}),
    (ILLUSTRATIVE, {"mode": "--"}),
    (ILLUSTRATIVE, LIMITS),
    (ILLUSTRATIVE, {"alpha2_limits": [-3.5, -1.0], "mode": "++"}),
    (ILLUSTRATIVE, {"alpha1_limits": [-1.0, 3.0], "alpha2_limits": [2.0, 8.0], "mode": "--"}),  # wider than pi
    (dict(r=100.0, l1=900.0, l2=500.0), {"alpha1_limits": [-2.0, 0.5]}),  # l1 > l2: a hole around each pivot
    (dict(r=380.0, l1=260.0, l2=520.0), {"mode": "-+"}),
]


@pytest.mark.parametrize(("design", "options"), TWIN_CASES)
def test_kernel_matches_numpy_twin(design, options):
    design = M.resolve_design(design)
    opts = M.resolve_options(options)
    g = make_grid(M, design, opts, 61)
    X, Y, _ = grid_nodes(g.lo, g.step, g.shape)
    twin = fivebar_lci(design, opts, X, Y)
    lci = kgrid.sample_grid(M.point_kernel, M.pack(design, opts), g.lo, g.step, g.shape)
    assert (lci >= 0).sum() > 100
    assert np.array_equal(lci >= 0, twin >= 0)  # same reachable cells
    np.testing.assert_allclose(lci[lci >= 0], twin[twin >= 0], rtol=1e-7, atol=1e-10)
    ref = grid_metrics(twin, g.cell_measure, (0.0, 0.1, 0.3, 1.0))
    rep = evaluate(M, design, opts, resolution=61)
    assert_report_equals_grid_metrics(rep, ref, fci=True)


@settings(max_examples=60, deadline=None)
@given(st.floats(-2 * math.pi, 2 * math.pi), st.floats(0.05, 7.0), st.sampled_from(["alpha1_limits", "alpha2_limits"]))
def test_arm_limits_modulo_two_pi_match_twin(lo, width, name):
    """The kernel's atan2-free arc test agrees with the twin's (alpha - lo) mod 2 pi <= hi - lo, for intervals
    anywhere, narrower or wider than pi, or a full turn and more (no restriction)."""
    opts = M.resolve_options({name: [lo, lo + width]})
    rng = np.random.default_rng(7)
    xy = rng.uniform(-1150, 1150, size=(400, 2))
    lci = kgrid.points_lci(M.point_kernel, M.pack(DESIGN, opts), np.c_[xy, np.zeros(400)])
    twin = fivebar_lci(DESIGN, opts, xy[:, 0], xy[:, 1])
    alpha = fivebar_arm_angles(DESIGN, opts, xy[:, 0], xy[:, 1])[0 if name == "alpha1_limits" else 1]
    with np.errstate(invalid="ignore"):
        gap = np.minimum(np.abs(np.sin(alpha - lo)), np.abs(np.sin(alpha - lo - width)))
    clear = ~(gap < 1e-9)  # a point on a limit may fall either way by round-off
    assert np.array_equal((lci >= 0)[clear], (twin >= 0)[clear])
    if width >= 2 * math.pi:
        assert np.array_equal(lci >= 0, kgrid.points_lci(M.point_kernel, PACKED, np.c_[xy, np.zeros(400)]) >= 0)


def test_bounding_box_is_tight_and_contains_fk_samples():
    """|x| <= l1 + l2 - r, |y| <= sqrt((l1 + l2)^2 - r^2): both attained (fully stretched chains)."""
    lo, hi = M.bounding_box(DESIGN, OPT)
    np.testing.assert_allclose(hi[:2], (1150.0, math.sqrt(1350.0**2 - 200.0**2)), rtol=1e-15)
    np.testing.assert_allclose(lo[:2], -hi[:2])
    assert len(branches((1150.0, 0.0))) == 4 and len(branches((0.0, -hi[1] * (1 - 1e-12)))) == 4
    rng = np.random.default_rng(4)
    for q in rng.uniform(-math.pi, math.pi, size=(400, 2)):
        for s in M.forward_kinematics(DESIGN, OPT, q):
            assert np.all(s.values >= lo[:2] - 1e-9) and np.all(s.values <= hi[:2] + 1e-9)
    empty_lo, empty_hi = M.bounding_box(M.resolve_design(dict(r=900.0, l1=300.0, l2=500.0)), OPT)
    assert np.array_equal(empty_lo, empty_hi)
    rep = evaluate(M, dict(r=900.0, l1=300.0, l2=500.0), resolution=8)
    assert rep.measure == 0.0 and rep.gci == 0.0 and rep.metrics["voxels"] == 0


# ----- singular and degenerate cases ---------------------------------------------------------------------------
def test_inverse_singularity_on_the_outer_reach_circle():
    """P = B1 + (l1 + l2)(-0.6, -0.8): chain 1 stretched, alpha1 a double root, sin(beta1 - alpha1) = 0."""
    pose = (200.0 - 810.0, -1080.0)
    sols = branches(pose)
    expected = math.atan2(-0.8, -0.6)
    for label in ("++", "+-", "-+", "--"):
        assert sols[label][0] == pytest.approx(expected, abs=1e-12)
    q = sols["+-"]
    assert M.singularity(DESIGN, OPT, pose, q) == "inverse"
    assert M.jacobians(DESIGN, OPT, pose, q)["Jq"][0, 0] == pytest.approx(0.0, abs=1e-9)
    assert M.lci(DESIGN, OPT, pose, q) == 0.0
    assert kernel(*pose) == 0.0


def test_tangent_forearms_give_one_double_fk_solution():
    """r = 500, l1 = 475, l2 = 875: alpha2 = pi - alpha1 with cos(alpha1) = 750/950 puts the elbows 2 l2 apart,
    so the forearms are collinear (forward singularity) and P = (0, l1 sin(alpha1))."""
    design = M.resolve_design(dict(r=500.0, l1=475.0, l2=875.0))
    a1 = -math.acos(750.0 / 950.0)
    q = (a1, math.pi - a1)
    sols = M.forward_kinematics(design, OPT, q)
    assert len(sols) == 1 and sols[0].label == "double"
    np.testing.assert_allclose(sols[0].values, (0.0, 475.0 * math.sin(a1)), atol=1e-9)
    pose = sols[0].values
    assert M.singularity(design, OPT, pose, q) == "forward"
    assert M.lci(design, OPT, pose, q) == pytest.approx(0.0, abs=1e-12)  # round-off off the exact tangency
    label = next(s.label for s in M.inverse_kinematics(design, OPT, pose) if _angle_err(s.values, q) < 1e-7)
    assert M.point_kernel(M.pack(design, M.resolve_options({"mode": label})), *pose, 0.0) == pytest.approx(0, abs=1e-6)


def test_coincident_elbows_and_out_of_reach_fk():
    a1 = math.acos(-200.0 / 475.0)  # Q1 = Q2 = (0, l1 sin(a1)) when alpha2 = pi - alpha1
    assert M.forward_kinematics(DESIGN, OPT, (a1, math.pi - a1)) == []
    assert M.forward_kinematics(M.resolve_design(dict(r=900.0, l1=100.0, l2=500.0)), OPT, (0.0, math.pi)) == []


def test_kernel_never_nan_and_out_of_reach():
    rng = np.random.default_rng(1)
    for design in (ILLUSTRATIVE, dict(r=100.0, l1=500.0, l2=500.0), dict(r=50.0, l1=900.0, l2=300.0)):
        d = M.resolve_design(design)
        for mode in ("++", "+-", "-+", "--"):
            p = M.pack(d, M.resolve_options({"mode": mode, **LIMITS}))
            pts = rng.uniform(-2000, 2000, size=(500, 2))
            special = [(d["r"], 0.0), (-d["r"], 0.0), (0.0, 0.0), (1e300, 0.0), (0.0, -1e-300)]
            for x, y in [*pts, *special]:
                v = M.point_kernel(p, float(x), float(y), 0.0)
                assert v == -1.0 or 0.0 <= v <= 1.0
    assert kernel(5000.0, 0.0) == -1.0 and branches((5000.0, 0.0)) == {}


# ----- validation --------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("options", "field"),
    [
        ({"mode": "+x"}, "options.mode"),
        ({"alpha1_limits": [1.0, 0.0]}, "options.alpha1_limits"),
        ({"alpha2_limits": "wide"}, "options.alpha2_limits"),
        ({"alpha2_limits": [0.0, "nan"]}, "options.alpha2_limits[1]"),
        ({"theta1_limits": [0, 1]}, "options.theta1_limits"),
    ],
)
def test_bad_options_name_the_field(options, field):
    with pytest.raises(InvalidParameter, match=r"^" + field.replace(".", r"\.").replace("[", r"\[") + ": "):
        M.resolve_options(options)


def test_bad_inputs_name_the_field():
    with pytest.raises(InvalidParameter, match=r"^design\.l2: "):
        M.resolve_design({"l2": -1})
    with pytest.raises(InvalidPose, match=r"^pose: "):
        M.inverse_kinematics(DESIGN, OPT, (1.0, 2.0, 3.0))
    with pytest.raises(InvalidPose, match=r"^inputs: "):
        M.forward_kinematics(DESIGN, OPT, (1.0,))
    with pytest.raises(InvalidPose, match=r"^inputs: arm angles do not assemble"):
        M.jacobians(DESIGN, OPT, (500, -850), (0.0, 0.0))
    with pytest.raises(InvalidPose, match=r"^pose: .* out of reach"):
        M.resolution_index(DESIGN, OPT, (5000.0, 0.0))
    with pytest.raises(InvalidPose, match=r"^dalpha: "):
        M.resolution_index(DESIGN, OPT, (500, -850), (1.0, math.inf))


def test_cli_ik_fk_json():
    runner = CliRunner()
    res = runner.invoke(app, ["ik", "planar-fivebar", "--pose", "500,-850", "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert out["names"] == ["alpha1", "alpha2"]
    row = next(r for r in out["solutions"] if r["branch"] == "+-")
    assert six(row["values"][1], -1.754420) and six(row["lci"], 0.775080)
    res = runner.invoke(app, ["fk", "planar-fivebar", "--inputs", "0.3,2.9", "--set", "r=150"])
    assert res.exit_code == 0 and res.stdout.count("x=") == 2
    res = runner.invoke(app, ["ik", "planar-fivebar", "--pose", "1,2,3"])
    assert res.exit_code == 2 and "--pose" in res.stderr


# ----- properties ----------------------------------------------------------------------------------------------
designs = st.fixed_dictionaries(
    {"r": st.floats(50, 400), "l1": st.floats(250, 800), "l2": st.floats(500, 1400)}  # the config's bounds
)
angles = st.tuples(st.floats(-math.pi, math.pi), st.floats(-math.pi, math.pi))


def _angle_err(a, b):
    return float(np.abs(np.angle(np.exp(1j * (np.asarray(a) - np.asarray(b))))).max())


@settings(max_examples=150, deadline=None)
@given(designs, angles)
def test_fk_then_ik_round_trip(raw, q):
    design = M.resolve_design(raw)
    scale = design["l1"] + design["l2"]
    for s in M.forward_kinematics(design, OPT, q):
        if s.label == "double" or M.singularity(design, OPT, s.values, q, tol=1e-6) != "none":
            continue
        sols = M.inverse_kinematics(design, OPT, s.values)
        assert min(_angle_err(b.values, q) for b in sols) < 1e-9
        # IK then FK: every non-singular branch assembles back to the pose
        for b in sols:
            if M.singularity(design, OPT, s.values, b.values, tol=1e-6) != "none":
                continue
            assert assembly_error(M.forward_kinematics(design, OPT, b.values), s.values) < 1e-9 * scale
        # the kernel's working mode is one of the labelled branches: same LCI as the NumPy reference
        label = next(b.label for b in sols if _angle_err(b.values, q) < 1e-9)
        p = M.pack(design, M.resolve_options({"mode": label}))
        # (abs: next to a singularity the LCI is ~0 and the pose's round-off dominates, as in the grid test)
        assert M.point_kernel(p, *s.values, 0.0) == pytest.approx(M.lci(design, OPT, s.values, q), rel=1e-7, abs=1e-10)


@settings(max_examples=100, deadline=None)
@given(designs, angles)
def test_jacobian_matches_central_differences_of_fk(raw, q):
    design = M.resolve_design(raw)
    for s in M.forward_kinematics(design, OPT, q):
        if s.label == "double" or M.singularity(design, OPT, s.values, q, tol=1e-3) != "none":
            continue
        if M.lci(design, OPT, s.values, q) < 1e-3:
            continue  # FK is ill-conditioned next to singular poses; finite differences say nothing there
        jac = M.jacobians(design, OPT, s.values, q)["J"]
        h = 1e-5  # truncation error grows near singular poses; rounding stays ~1e-8 mm here
        num = fk_jacobian(M, design, OPT, s.values, q, h, order=4)
        assert np.abs(num - jac).max() < 1e-6 * np.abs(jac).max()


# ----- plot-task command ---------------------------------------------------------------------------------------
def test_plot_task_writes_png_with_the_task_metrics(tmp_path):
    from scalesynth.commands.fivebar import task_map

    out = tmp_path / "plots" / "task.png"
    res = CliRunner().invoke(
        app, ["plot-task", str(ROOT / "configs" / "fivebar_packing.yaml"), "--out", str(out), "--resolution", "40",
              "--json"]
    )
    assert res.exit_code == 0, res.output
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert [p.name for p in out.parent.iterdir()] == ["task.png"]  # no temporary file left behind
    shown = json.loads(res.stdout)
    cfg = load_config(ROOT / "configs" / "fivebar_packing.yaml")
    cfg.task.resolution = 40  # --resolution sets the map's task-box cells
    rep = evaluate_config(cfg)  # the same cell-centred nodes as the map
    assert shown["task_coverage"] == rep.metrics["task_coverage"] == 1.0
    assert shown["task_gci"] == pytest.approx(rep.metrics["task_gci"], rel=1e-12)
    tm = task_map(cfg)
    twin = fivebar_lci(DESIGN, cfg.resolved_options(), *np.meshgrid(tm.xs, tm.ys, indexing="ij"))
    np.testing.assert_allclose(tm.lci, twin, rtol=1e-7)
    assert tm.path.shape == (7, 2)


def test_plot_task_needs_planar_mechanism_and_task(tmp_path):
    runner = CliRunner()
    res = runner.invoke(app, ["plot-task", str(ROOT / "configs" / "paper_2pauu_ppap.yaml")])
    assert res.exit_code == 2 and "mechanism: plot-task needs a planar mechanism" in res.stderr
    cfg = tmp_path / "no_task.yaml"
    cfg.write_text("name: t\nmechanism: planar-fivebar\nunits: {length: mm}\n")
    res = runner.invoke(app, ["plot-task", str(cfg), "--out", str(tmp_path / "x.png")])
    assert res.exit_code == 2 and res.stderr.startswith("error: task: ")
    assert not (tmp_path / "x.png").exists()
