"""The per-voxel stiffness_min, deflection and clearance fields of described 2T (planar) mechanisms (describe/
kernel2.py; opt-in with options.stiffness_metrics, clearance_metrics, interference_free): the stiffness against the
stiffness frame of `stiffness` (describe/frame2.py, solved per pose by stiffness.solve) and against the hand-written
five-bar's field kernel, the clearance against the cycle's (cycle.clearance of link_geometry), both against the NumPy
twins of tests/naive_planar.py, and the catalogue, the flags and `evaluate` on configs/fivebar_described.yaml."""

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

import naive_planar
from scalesynth import metrics
from scalesynth.cli import app
from scalesynth.config import config_from_dict, load_config
from scalesynth.cycle.clearance import clearance
from scalesynth.errors import ConfigError, InvalidParameter
from scalesynth.evaluate import evaluate_config
from scalesynth.kernels import grid as kgrid
from scalesynth.mechanisms import get
from scalesynth.mechanisms.describe import from_description, kernel2, parse_description
from scalesynth.stiffness.legs import DEFLECTION_CAP, response_2x2
from scalesynth.stiffness.sections import tube_section
from scalesynth.stiffness.solve import solve

from conftest import ROOT

HAND = get("planar-fivebar")
FIVEBAR = get("planar-fivebar-described")
LIMITS = {"alpha1_limits": [-1.3962634015954636, 0.6108652381980153],
          "alpha2_limits": [2.530727415391778, 4.537856055185257]}
ST, DEF, CL = kernel2.F_STIFFNESS_MIN, kernel2.F_DEFLECTION, kernel2.F_CLEARANCE
# an RR pair in metres meeting at a common platform offset, leg 1's crank zero pointing down (-y) turning to +x
TURNED_RR = {
    "name": "turned-rr-test", "title": "RR pair, one crank zero turned (test)", "motion": "2T", "length_unit": "m",
    "parameters": {"a": {"default": 0.15, "doc": "pivot half distance"}, "L": {"default": 0.3, "doc": "crank"},
                   "l": {"default": 0.45, "doc": "link"}, "rp": {"default": 0.04, "doc": "platform offset"}},
    "options": {"lim": {"kind": "range", "default": [-2.5, 2.0], "doc": "crank range"}},
    "legs": [{"type": "RR", "base": ["a", 0, 0], "platform": ["rp", 0, 0], "links": {"arm": "L", "forearm": "l"},
              "arm_zero": [0, -1, 0], "arm_positive": [1, 0, 0], "branch": "-", "limits": "lim"},
             {"type": "RR", "base": ["-a", 0, 0], "platform": ["rp", 0, 0], "links": {"arm": "L", "forearm": "l"},
              "branch": "-"}],
}
# a biglide: two PR legs on rails slanting up and out, links pinned at one platform point
BIGLIDE = {
    "name": "biglide-pin-test", "title": "PR pair (test)", "motion": "2T", "length_unit": "m",
    "parameters": {"gap": {"default": 0.2, "doc": "rail origins' half distance"},
                   "link": {"default": 0.5, "doc": "link length"}},
    "options": {"stroke": {"kind": "range", "default": [-0.6, 0.6], "doc": "carriage range"}},
    "legs": [{"type": "PR", "base": ["gap", 0, 0], "platform": [0, 0, 0], "links": {"forearm": "link"},
              "rail": [0.6, 0.8, 0], "branch": "far", "limits": "stroke"},
             {"type": "PR", "base": ["-gap", 0, 0], "platform": [0, 0, 0], "links": {"forearm": "link"},
              "rail": [-0.6, 0.8, 0], "branch": "far", "limits": "stroke"}],
}
MECHS = {"fivebar": FIVEBAR, "turned-rr": from_description(parse_description(TURNED_RR)),
         "biglide": from_description(parse_description(BIGLIDE))}


def _case(name, rng):
    """(mechanism, design, options) with random lengths (x U(0.8, 1.25) of the defaults), random sections, actuator
    springs, load and capsule radii, every new field on."""
    mech = MECHS[name]
    d = {k: v * rng.uniform(0.8, 1.25) for k, v in mech.default_design().items()}
    mm = mech.default_length_unit == "mm"
    tube = [float(rng.uniform(30, 80)), float(rng.uniform(2, 6))] if mm else [float(rng.uniform(0.03, 0.08)),
                                                                              float(rng.uniform(0.002, 0.006))]
    rotary = name != "biglide"
    k = float(rng.uniform(0.3, 3.0)) * (1e8 if mm else 1e5) if rotary else float(rng.uniform(0.3, 3.0)) * 2e7
    scale = 1000.0 if mm else 1.0
    opts = {"stiffness_metrics": True, "clearance_metrics": True, "tube": tube, "actuator_stiffness": k,
            "load": [float(rng.uniform(-100, 100)), float(rng.uniform(-200, 0))],
            "link_radius": {g: float(rng.uniform(0.005, 0.06)) * scale for g in ("base", "platform", "forearm")
                            + (("arm",) if rotary else ("rail", "carriage"))}}
    if rotary:
        opts["sections"] = {"arm": [1.5 * tube[0], 1.2 * tube[1]]}
    if name == "fivebar":
        opts.update(LIMITS)
    return mech, d, mech.resolve_options(opts)


def _reachable(mech, d, opts, rng, n):
    """n random points of the bounding box that the field kernel finds reachable."""
    lo, hi = (v[:2] for v in mech.bounding_box(d, opts))
    packed, out, pts = mech.pack(d, opts), np.zeros(mech.n_fields), []
    for _ in range(100000):
        p = rng.uniform(lo, hi)
        mech.field_kernel(packed, *p, 0.0, out)
        if out[0] >= 0.0:
            pts.append(p)
            if len(pts) == n:
                return pts
    raise AssertionError("too few reachable points")


def _q(mech, d, opts, p):
    (q,) = [s.values for s in mech.inverse_kinematics(d, opts, p) if s.label == mech.kernel_branch(opts)]
    return q


def _twin_legs(name, d, opts):
    """The mechanism as naive_planar's plain legs, written from the description by hand."""
    if name == "fivebar":
        return [{"type": "RR", "base": (d["r"], 0.0), "arm": d["l1"], "link": d["l2"], "sigma": 1.0},
                {"type": "RR", "base": (-d["r"], 0.0), "arm": d["l1"], "link": d["l2"], "sigma": -1.0}]
    if name == "turned-rr":
        return [{"type": "RR", "base": (d["a"], 0.0), "platform": (d["rp"], 0.0), "arm": d["L"], "link": d["l"],
                 "sigma": -1.0, "zero": -math.pi / 2},
                {"type": "RR", "base": (-d["a"], 0.0), "platform": (d["rp"], 0.0), "arm": d["L"], "link": d["l"],
                 "sigma": -1.0}]
    rail = math.atan2(0.8, 0.6)
    return [{"type": "PR", "base": (d["gap"], 0.0), "rail": rail, "link": d["link"], "sigma": 1.0,
             "limits": opts["stroke"]},
            {"type": "PR", "base": (-d["gap"], 0.0), "rail": math.pi - rail, "link": d["link"], "sigma": 1.0,
             "limits": opts["stroke"]}]


@pytest.mark.parametrize("name, seed", [("fivebar", 1), ("fivebar", 2), ("turned-rr", 3), ("biglide", 4)])
def test_stiffness_equals_the_frame_solved_per_pose(name, seed):
    """stiffness_min and deflection of the kernel equal stiffness.solve of frame2's frame (ideal joints) at random
    reachable poses of random designs and sections: the same idealisation, so the same numbers to rounding
    (asserted 1e-9 relative; measured 6e-14)."""
    rng = np.random.default_rng(seed)
    mech, d, opts = _case(name, rng)
    packed, out = mech.pack(d, opts), np.zeros(mech.n_fields)
    seen = []
    for p in _reachable(mech, d, opts, rng, 8):
        mech.field_kernel(packed, *p, 0.0, out)
        ref = solve(mech.stiffness_model(d, opts, p))
        assert not ref.singular
        assert out[ST] == pytest.approx(ref.stiffness_min, rel=1e-9), p
        assert out[DEF] == pytest.approx(np.linalg.norm(ref.deflection), rel=1e-9), p
        seen.append(out[DEF])
    assert max(seen) > 1.01 * min(seen)  # the poses differ: a constant would not pass


def test_every_field_equals_the_hand_written_fivebar():
    """The described five-bar's six fields equal the hand-written planar-fivebar's (the 5R, forearm 'single') on a
    grid of random designs, sections, springs and loads (default capsule radii: the same bodies and radii);
    asserted 1e-9 relative (measured 9e-16: the same closed form)."""
    rng = np.random.default_rng(11)
    for _ in range(4):
        d = {"r": rng.uniform(50, 400), "l1": rng.uniform(250, 800), "l2": rng.uniform(500, 1400)}
        common = {**LIMITS, "tube": [float(rng.uniform(30, 80)), 3.0], "sections": {"arm": [100.0, 6.0]},
                  "actuator_stiffness": float(rng.uniform(1e7, 1e9)), "load": [30.0, -150.0]}
        ours_o = FIVEBAR.resolve_options({**common, "stiffness_metrics": True, "clearance_metrics": True})
        hand_o = HAND.resolve_options({**common, "mode": "+-"})
        ours_p, hand_p = FIVEBAR.pack(d, ours_o), HAND.pack(d, hand_o)
        lo, hi = (v[:2] for v in HAND.bounding_box(d, hand_o))
        a, b = np.zeros(6), np.zeros(6)
        n = 0
        for x in np.linspace(lo[0], hi[0], 17):
            for y in np.linspace(lo[1], hi[1], 17):
                FIVEBAR.field_kernel(ours_p, x, y, 0.0, a)
                HAND.field_kernel(hand_p, x, y, 0.0, b)
                assert (a[0] >= 0) == (b[0] >= 0)
                if a[0] > 1e-6:
                    np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-9)
                    n += 1
        assert n >= 20


@pytest.mark.parametrize("name, seed", [("fivebar", 5), ("turned-rr", 6), ("biglide", 7)])
def test_clearance_equals_the_cycle_clearance(name, seed):
    """The clearance slot equals cycle.clearance of link_geometry (the capsules `cycle` and `show` use) at the
    joint values of NumPy's inverse kinematics; asserted 1e-9 of the links (measured 1.1e-13 mm on the five-bar)."""
    rng = np.random.default_rng(seed)
    mech, d, opts = _case(name, rng)
    packed, out = mech.pack(d, opts), np.zeros(mech.n_fields)
    scale = max(d.values())
    seen = []
    for p in _reachable(mech, d, opts, rng, 12):
        mech.field_kernel(packed, *p, 0.0, out)
        ref = clearance(mech.link_geometry(d, opts, p, _q(mech, d, opts, p))).value
        assert out[CL] == pytest.approx(ref, rel=1e-9, abs=1e-9 * scale), p
        seen.append(ref)
    assert max(seen) > min(seen)


@pytest.mark.parametrize("name, seed", [("fivebar", 8), ("turned-rr", 9), ("biglide", 10)])
def test_new_fields_equal_the_numpy_twins(name, seed):
    """stiffness_min, deflection and clearance against naive_planar's twins (two-force links, 2 x 2 compliances,
    eigvalsh; plane segment distances by hand), fed the same sections and radii."""
    rng = np.random.default_rng(seed)
    mech, d, opts = _case(name, rng)
    legs = _twin_legs(name, d, opts)
    unit = mech.default_length_unit
    arm = tube_section(opts, "arm", unit) if name != "biglide" else None
    bar = tube_section(opts, "forearm", unit)
    sec = [{"EA_arm": arm.EA if arm else 0.0, "EI_arm": arm.EI if arm else 0.0, "EA_link": bar.EA,
            "k": opts["actuator_stiffness"]}] * 2
    rad = opts["link_radius"]
    radii = {b: rad[b.rstrip("12")] for b in ("base", "platform", "arm1", "arm2", "forearm1", "forearm2", "rail1",
                                               "rail2", "carriage1", "carriage2") if b.rstrip("12") in rad}
    packed, out = mech.pack(d, opts), np.zeros(mech.n_fields)
    for p in _reachable(mech, d, opts, rng, 8):
        mech.field_kernel(packed, *p, 0.0, out)
        qs = [naive_planar.leg_q(leg, p) for leg in legs]
        kmin, defl = naive_planar.stiffness(legs, sec, p, qs, np.asarray(opts["load"]))
        assert out[ST] == pytest.approx(kmin, rel=1e-8)
        assert out[DEF] == pytest.approx(defl, rel=1e-8)
        assert out[CL] == pytest.approx(naive_planar.clearance(legs, radii, p, qs), rel=1e-9,
                                        abs=1e-9 * max(d.values()))


def test_response_2x2_caps_singular_stiffness_and_matches_numpy():
    """stiffness.legs.response_2x2: lambda_min and |K^-1 F| of a regular K (NumPy's eigvalsh and solve), (0, cap) at
    an eigenvalue ratio <= 1e-11 (the reference solver's test), 0 deflection under no load; never NaN."""
    rng = np.random.default_rng(3)
    for _ in range(200):
        a = rng.normal(size=(2, 2)) * rng.choice([1e-2, 1.0, 1e3])
        k = a @ a.T
        f = rng.normal(size=2) * 100
        kmin, defl = response_2x2(k[0, 0], k[0, 1], k[1, 1], *f)
        if np.linalg.eigvalsh(k)[0] > 1e-9 * np.linalg.eigvalsh(k)[1]:
            assert kmin == pytest.approx(np.linalg.eigvalsh(k)[0], rel=1e-9)
            assert defl == pytest.approx(np.linalg.norm(np.linalg.solve(k, f)), rel=1e-9)
    u = np.array([0.6, 0.8])
    k = 1e5 * np.outer(u, u)  # one leg's spring only: rank 1
    assert response_2x2(k[0, 0], k[0, 1], k[1, 1], 0.0, -150.0) == (0.0, DEFLECTION_CAP)
    assert response_2x2(k[0, 0], k[0, 1], k[1, 1], 0.0, 0.0) == (0.0, 0.0)
    assert response_2x2(0.0, 0.0, 0.0, 1.0, 0.0) == (0.0, DEFLECTION_CAP)
    assert response_2x2(math.nan, 0.0, 1.0, 1.0, 0.0) == (0.0, DEFLECTION_CAP)


def test_flags_off_leave_zeros_and_the_same_bits():
    """Without the options the three slots are 0 and slots 0-2 are the same bits as with them; point_lci (the
    LCI kernel) gives slots 0-2 of point_fields bit for bit; the field's catalogue entries name their option."""
    d = FIVEBAR.default_design()
    on = FIVEBAR.pack(d, FIVEBAR.resolve_options({"stiffness_metrics": True, "clearance_metrics": True}))
    off = FIVEBAR.pack(d, FIVEBAR.resolve_options({}))
    a, b, c = np.zeros(6), np.zeros(6), np.full(6, 7.0)
    for p in ((0.0, -725.0), (300.0, -600.0), (-50.0, -868.75)):
        FIVEBAR.field_kernel(on, *p, 0.0, a)
        FIVEBAR.field_kernel(off, *p, 0.0, b)
        FIVEBAR.lci_kernel(off, *p, 0.0, c)
        assert np.array_equal(a[:3], b[:3]) and np.array_equal(c[:3], b[:3]) and a[0] > 0
        assert np.all(b[3:] == 0.0) and np.all(a[3:] > 0.0) and np.all(c[3:] == 7.0)
    assert FIVEBAR.lci_kernel is kernel2.point_lci
    assert FIVEBAR.field_names[3:] == ("stiffness_min", "deflection", "clearance")
    assert [f.needs_options for f in FIVEBAR.fields[3:]] == [("stiffness_metrics",), ("stiffness_metrics",),
                                                              ("clearance_metrics",)]
    assert FIVEBAR.kernel_clearance(FIVEBAR.resolve_options({"interference_free": True}))
    assert not FIVEBAR.kernel_clearance(FIVEBAR.resolve_options({}))


def test_evaluators_run_the_lci_kernel_while_the_fields_are_off():
    """stats_kernel: point_lci unless a design sets a flag (then point_fields; lci_only: point_lci), and its
    statistics rows equal point_fields' bit for bit with the flags off (slots 3-5: the buffers' zeros), so an
    evaluation without the fields compiles neither stage."""
    d = FIVEBAR.default_design()
    off = FIVEBAR.pack(d, FIVEBAR.resolve_options(LIMITS))
    on = FIVEBAR.pack(d, FIVEBAR.resolve_options({**LIMITS, "stiffness_metrics": True}))
    free = FIVEBAR.pack(d, FIVEBAR.resolve_options({**LIMITS, "interference_free": True}))
    assert FIVEBAR.stats_kernel(off[None]) is kernel2.point_lci
    assert FIVEBAR.stats_kernel(np.stack([off, on])) is kernel2.point_fields
    assert FIVEBAR.stats_kernel(free[None]) is kernel2.point_fields
    assert FIVEBAR.stats_kernel(np.stack([off, on]), lci_only=True) is kernel2.point_lci
    lo, hi = FIVEBAR.bounding_box(d, FIVEBAR.resolve_options(LIMITS))
    shape = np.array([48, 40, 1], dtype=np.int64)
    step = np.r_[(hi[:2] - lo[:2]) / shape[:2], 1.0]
    edges = np.array([0.0, 0.1, 0.3, 1.0])
    rows = [kgrid.population_stats(k, 6, off[None], lo[None], step[None], shape, edges)
            for k in (kernel2.point_lci, kernel2.point_fields)]
    assert rows[0][0, 0] > 100 and np.array_equal(rows[0], rows[1])


def test_interference_free_in_every_kernel():
    """A fat platform ball (it meets the base near the pivots): interference_free keeps exactly the reachable poses
    whose clearance is >= 0, in the field, LCI and reach kernels alike."""
    d = FIVEBAR.default_design()
    fat = FIVEBAR.resolve_options({"clearance_metrics": True, "link_radius": {"platform": 300.0}})
    plain = FIVEBAR.pack(d, fat)
    free = FIVEBAR.pack(d, FIVEBAR.resolve_options({**fat, "interference_free": True}))
    rng, kept, out = np.random.default_rng(12), [], np.zeros(6)
    for p in _reachable(FIVEBAR, d, fat, rng, 60):
        FIVEBAR.field_kernel(plain, *p, 0.0, out)
        gap = out[CL]
        for kernel in (FIVEBAR.field_kernel, FIVEBAR.lci_kernel, FIVEBAR.reach_kernel):
            kernel(free, *p, 0.0, out)
            assert (out[0] >= 0.0) == (gap >= 0.0)
        kept.append(gap >= 0.0)
    assert 0 < sum(kept) < len(kept)


def test_options_are_checked():
    """The flags take booleans; the stiffness fields need one platform pin (frame2's condition), the clearance
    does not."""
    with pytest.raises(InvalidParameter, match="stiffness_metrics"):
        FIVEBAR.resolve_options({"stiffness_metrics": "yes"})
    with pytest.raises(InvalidParameter, match="interference_free"):
        FIVEBAR.resolve_options({"interference_free": 1})
    offset = dict(TURNED_RR, legs=[TURNED_RR["legs"][0], dict(TURNED_RR["legs"][1], platform=["-rp", 0, 0])])
    mech = from_description(parse_description(offset))
    d = mech.default_design()
    with pytest.raises(InvalidParameter, match=r"^legs\[1\] \(leg\)\.platform: the per-voxel stiffness fields need"):
        mech.pack(d, mech.resolve_options({"stiffness_metrics": True}))
    packed = mech.pack(d, mech.resolve_options({"clearance_metrics": True}))
    p = _reachable(mech, d, mech.resolve_options({}), np.random.default_rng(1), 1)[0]
    out = np.zeros(6)
    mech.field_kernel(packed, *p, 0.0, out)
    ref = clearance(mech.link_geometry(d, mech.resolve_options({}), p, _q(mech, d, mech.resolve_options({}), p)))
    assert out[CL] == pytest.approx(ref.value, abs=1e-12)


def test_the_catalogue_has_the_new_metrics():
    """The described five-bar's catalogue lists the stiffness and clearance metrics with their options (as the hand
    five-bar's lists them without); a config naming one without its option is refused in one line."""
    cat = metrics.catalogue(FIVEBAR)
    for name, need in (("max_deflection", "stiffness_metrics"), ("task_max_deflection", "stiffness_metrics"),
                       ("min_stiffness_min", "stiffness_metrics"), ("min_clearance", "clearance_metrics"),
                       ("task_min_clearance", "clearance_metrics")):
        want = ("task", f"options.{need}") if name.startswith("task_") else (f"options.{need}",)
        assert name in cat and cat[name].needs == want, name
        assert name in metrics.catalogue(HAND)
    data = load_config(ROOT / "configs" / "fivebar_described.yaml").model_dump(exclude_none=True)
    data["objectives"] = [{"metric": "max_deflection", "sense": "min"}]
    with pytest.raises(ConfigError, match="needs options.stiffness_metrics"):
        config_from_dict(data)


def test_evaluate_the_described_fivebar_with_its_new_fields():
    """`scalesynth evaluate configs/fivebar_described.yaml` with the stiffness fields: mean deflection 1.151 mm, max
    1.485 mm, min stiffness 60.5 N/mm (the numbers of the first build of these fields, issue 28), as the hand
    five-bar's evaluate of the same design; interference_free (default radii) takes the area from 642 679 to
    642 476 mm^2, the hand five-bar's own."""
    runner = CliRunner()
    cfg = str(ROOT / "configs" / "fivebar_described.yaml")
    r = runner.invoke(app, ["evaluate", cfg, "--set", "options.stiffness_metrics=true", "--json"])
    assert r.exit_code == 0, r.output
    m = json.loads(r.stdout)
    assert m["mean_deflection_mm"] == pytest.approx(1.151, abs=5e-4)
    assert m["max_deflection_mm"] == pytest.approx(1.485, abs=5e-4)
    assert m["min_stiffness_min_N_per_mm"] == pytest.approx(60.5, abs=0.05)
    assert m["area_mm2"] == pytest.approx(642679, abs=0.5)
    r = runner.invoke(app, ["evaluate", cfg, "--set", "options.interference_free=true", "--json"])
    free = json.loads(r.stdout)
    assert free["area_mm2"] == pytest.approx(642476, abs=0.5)
    data = load_config(ROOT / "configs" / "fivebar_described.yaml").model_dump(exclude_none=True)
    data.update(mechanism="planar-fivebar", options={**data["options"], "mode": "+-"})
    hand = evaluate_config(config_from_dict(data)).metrics
    for k in ("area_mm2", "mean_deflection_mm", "max_deflection_mm", "min_stiffness_min_N_per_mm"):
        assert m[k] == pytest.approx(hand[k], rel=1e-9), k
    data["options"]["interference_free"] = True
    assert free["area_mm2"] == pytest.approx(evaluate_config(config_from_dict(data)).metrics["area_mm2"], rel=1e-12)


def test_task_max_deflection_is_the_worst_cell():
    """A task box below and left of the workspace's softest region (x = 0, y about -850 mm, where the deflection
    peaks): task_max_deflection is the largest deflection of the kernel over the box's 5 x 5 cell centres, at its
    upper right one (-50, -868.75) mm: 1.48005 mm under the default sections and load (the number of the first
    build of these fields, issue 28)."""
    data = load_config(ROOT / "configs" / "fivebar_described.yaml").model_dump(exclude_none=True)
    data["options"]["stiffness_metrics"] = True
    data["task"] = {"box": {"x": [-140, -40], "y": [-925, -862.5]}, "resolution": 5}
    rep = evaluate_config(config_from_dict(data)).metrics
    opts = FIVEBAR.resolve_options(data["options"])
    packed, out = FIVEBAR.pack(FIVEBAR.default_design(), opts), np.zeros(6)
    cells = {}
    for x in -140 + (np.arange(5) + 0.5) * 20:
        for y in -925 + (np.arange(5) + 0.5) * 12.5:
            FIVEBAR.field_kernel(packed, x, y, 0.0, out)
            cells[(x, y)] = out[DEF]
    worst = max(cells, key=cells.get)
    assert worst == (-50.0, -868.75)
    assert rep["task_max_deflection_mm"] == pytest.approx(cells[worst], rel=1e-12)
    assert rep["task_max_deflection_mm"] == pytest.approx(1.48005, abs=5e-6)


def test_the_cycle_reads_the_kernels_fields_like_the_hand_written():
    """configs/fivebar_packing.yaml's Adept cycle on the described five-bar with both flags on (the cycle then reads
    the clearance, and the deflection, from the field kernel): every cycle metric equals the hand-written
    mechanism's (1e-9 relative), clearance and deflection included."""
    import yaml

    data = yaml.safe_load((ROOT / "configs" / "fivebar_packing.yaml").read_text())
    data.pop("output", None)
    data["objectives"] = [{"metric": "cycle_min_clearance", "sense": "max"}]
    data["constraints"] = []
    hand = evaluate_config(config_from_dict(data)).metrics
    data["mechanism"] = "planar-fivebar-described"
    del data["options"]["mode"]
    data["options"].update(stiffness_metrics=True, clearance_metrics=True)
    ours = evaluate_config(config_from_dict(data)).metrics
    keys = [k for k in ours if k.startswith("cycle_")]
    assert "cycle_min_clearance_mm" in keys and hand["cycle_feasible"] == 1.0
    for k in keys:
        assert ours[k] == pytest.approx(hand[k], rel=1e-9), k
