"""Described 2T (planar) mechanisms (describe/planar.py, kernel2.py): RR and PR legs' IK, FK round trips and the
Jacobian against finite differences of the FK, the kernel against a NumPy twin (tests/naive_planar.py), and the
described five-bar (mechanisms/planar-fivebar-described.yaml) against the hand-written planar-fivebar: the same
reach mask and fields on random designs, working modes and arm limits, the same area and GCI, the same bodies."""

import math

import numpy as np
import pytest

import naive_planar
from fd_checks import assembly_error, fk_jacobian, reachable_points
from scalesynth.config import config_from_dict
from scalesynth.errors import ConfigError
from scalesynth.evaluate import evaluate_config
from scalesynth.kernels import grid as kgrid
from scalesynth.mechanisms import get
from scalesynth.mechanisms.describe import builtin_path, from_description, kernel2, parse_description

HAND = get("planar-fivebar")
FIVEBAR = get("planar-fivebar-described")
RNG_SEED = 20262

# an RR pair with platform offsets, leg 1's crank zero pointing down (-y) and turning towards +x
OFFSET_RR = {
    "name": "offset-rr-test", "title": "RR pair with platform offsets (test)", "motion": "2T", "length_unit": "m",
    "parameters": {"a": {"default": 0.15, "doc": "pivot half distance"}, "L": {"default": 0.3, "doc": "crank"},
                   "l": {"default": 0.45, "doc": "link"}, "rp": {"default": 0.04, "doc": "platform offset"}},
    "options": {"lim": {"kind": "range", "default": [-2.5, 2.0], "doc": "crank range"}},
    "legs": [{"type": "RR", "base": ["a", 0, 0], "platform": ["rp", 0, 0], "links": {"arm": "L", "forearm": "l"},
              "arm_zero": [0, -1, 0], "arm_positive": [1, 0, 0], "branch": "-", "limits": "lim"},
             {"type": "RR", "base": ["-a", 0, 0], "platform": ["-rp", 0.01, 0], "links": {"arm": "L", "forearm": "l"},
              "branch": "-"}],
}
# a biglide: two PR legs on rails slanting up and out, platform below
BIGLIDE = {
    "name": "biglide-test", "title": "PR pair (test)", "motion": "2T", "length_unit": "m",
    "parameters": {"gap": {"default": 0.2, "doc": "rail origins' half distance"},
                   "link": {"default": 0.5, "doc": "link length"}},
    "options": {"stroke": {"kind": "range", "default": [-0.6, 0.6], "doc": "carriage range"}},
    "legs": [{"type": "PR", "base": ["gap", 0, 0], "platform": [0.05, 0, 0], "links": {"forearm": "link"},
              "rail": [0.6, 0.8, 0], "branch": "far", "limits": "stroke"},
             {"type": "PR", "base": ["-gap", 0, 0], "platform": [-0.05, 0, 0], "links": {"forearm": "link"},
              "rail": [-0.6, 0.8, 0], "branch": "far", "limits": "stroke"}],
}


def _mechanisms():
    return {"fivebar": FIVEBAR, "offset-rr": from_description(parse_description(OFFSET_RR)),
            "biglide": from_description(parse_description(BIGLIDE))}


def _twin_legs(name, design, options):
    """The mechanism as the NumPy twin's plain legs, written from the description by hand."""
    if name == "fivebar":
        r, l1, l2 = design["r"], design["l1"], design["l2"]
        return [{"type": "RR", "base": (r, 0.0), "arm": l1, "link": l2, "sigma": 1.0, "limits": None},
                {"type": "RR", "base": (-r, 0.0), "arm": l1, "link": l2, "sigma": -1.0, "limits": None}]
    if name == "offset-rr":
        a, L, l, rp = design["a"], design["L"], design["l"], design["rp"]
        return [{"type": "RR", "base": (a, 0.0), "platform": (rp, 0.0), "arm": L, "link": l, "sigma": -1.0,
                 "zero": -math.pi / 2, "limits": options["lim"]},
                {"type": "RR", "base": (-a, 0.0), "platform": (-rp, 0.01), "arm": L, "link": l, "sigma": -1.0}]
    g, l = design["gap"], design["link"]
    rail = math.atan2(0.8, 0.6)
    return [{"type": "PR", "base": (g, 0.0), "platform": (0.05, 0.0), "rail": rail, "link": l, "sigma": 1.0,
             "limits": options["stroke"]},
            {"type": "PR", "base": (-g, 0.0), "platform": (-0.05, 0.0), "rail": math.pi - rail, "link": l,
             "sigma": 1.0, "limits": options["stroke"]}]


def _box_points(mech, design, options, rng, k):
    lo, hi = mech.bounding_box(design, options)
    return rng.uniform(lo[:2], hi[:2], size=(k, 2))


def _point_fields_2t(packed, x, y, out):
    kernel2.point_fields(packed, x, y, 0.0, out)


def _reachable(mech, design, options, rng, k):
    """k random points where the kernel's LCI exceeds 1e-2 (away from singularities, for finite differences)."""
    lo, hi = mech.bounding_box(design, options)
    return reachable_points(_point_fields_2t, mech.pack(design, options), lo[:2], hi[:2], rng, k, min_lci=1e-2,
                            n_fields=mech.n_fields)


@pytest.mark.parametrize("name", ["fivebar", "offset-rr", "biglide"])
def test_ik_fk_and_jacobian_against_finite_differences(name):
    """Every IK branch closes both legs (|link| = l to 1e-9), FK of the kernel's branch's joint values returns the
    pose, and J = dx/dq equals central differences of the FK (h = 1e-6 of the length scale) to 1e-6 relative."""
    mech = _mechanisms()[name]
    rng = np.random.default_rng(RNG_SEED)
    design, options = mech.resolve_design({}), mech.resolve_options({})
    legs = mech.legs(design, options)
    scale = max(leg.arm + leg.forearm for leg in legs)
    for p in _reachable(mech, design, options, rng, 8):
        sols = {s.label: s.values for s in mech.inverse_kinematics(design, options, p)}
        assert len(sols) == 4
        for q in sols.values():
            for leg, qi in zip(legs, q, strict=True):
                assert np.linalg.norm(p + leg.platform - leg.actuated_point(qi)) == pytest.approx(leg.forearm,
                                                                                                   rel=1e-9)
        q = sols[mech.kernel_branch(options)]
        assert assembly_error(mech.forward_kinematics(design, options, q), p) <= 1e-9 * scale
        h = 1e-6 * (1.0 if legs[0].rotary else scale)
        fd = fk_jacobian(mech, design, options, p, q, h)
        j_an = mech.jacobians(design, options, p, q)["J"]
        np.testing.assert_allclose(j_an, fd, rtol=1e-6, atol=1e-6 * np.abs(j_an).max())


@pytest.mark.parametrize("name", ["fivebar", "offset-rr", "biglide"])
def test_kernel_equals_the_numpy_twin(name):
    """On 400 random points of the box: the same reach mask (limits included) and LCI, sigma_min, sigma_max within
    1e-9 relative of the twin's SVD; the kernel's joint values are the twin's (modulo 2 pi for a crank)."""
    mech = _mechanisms()[name]
    rng = np.random.default_rng(RNG_SEED + 1)
    design, options = mech.resolve_design({}), mech.resolve_options({})
    if name == "fivebar":
        options = mech.resolve_options({"alpha1_limits": [-1.3962634015954636, 0.6108652381980153],
                                        "alpha2_limits": [2.530727415391778, 4.537856055185257]})
    legs = _twin_legs(name, design, options)
    if name == "fivebar":
        legs[0]["limits"], legs[1]["limits"] = options["alpha1_limits"], options["alpha2_limits"]
    pts = _box_points(mech, design, options, rng, 400)
    want = naive_planar.fields(legs, pts)
    got = kgrid.population_points_fields(mech.field_kernel, mech.n_fields, mech.pack(design, options)[None, :],
                                         np.column_stack([pts, np.zeros(len(pts))]))[0][:, :3]
    reach = want[:, 0] >= 0.0
    assert 40 < reach.sum() < 400  # both reachable and unreachable points
    np.testing.assert_array_equal(got[:, 0] >= 0.0, reach)
    np.testing.assert_allclose(got[reach], want[reach], rtol=1e-9, atol=0.0)
    packed, out = mech.pack(design, options), np.zeros((2, 5))
    for p in pts[reach][:20]:
        kernel2.leg_values(packed, p[0], p[1], out)
        for leg, row in zip(legs, out, strict=True):
            q = naive_planar.leg_q(leg, p)
            diff = row[4] - q
            if leg["type"] == "RR":
                diff = (diff + math.pi) % (2 * math.pi) - math.pi
            assert abs(diff) <= 1e-9 * (1.0 if leg["type"] == "RR" else leg["link"])


def _described(mode):
    """The described five-bar in working mode ``mode`` ('+-' etc.): its description with the legs' branches set."""
    import yaml

    data = yaml.safe_load(builtin_path("planar-fivebar-described").read_text())
    data["legs"][0]["branch"], data["legs"][1]["branch"] = mode[0], mode[1]
    data["name"] = "fivebar-mode-test"
    return from_description(parse_description(data))


def test_described_fivebar_equals_the_hand_written_on_random_designs():
    """12 random designs (r, l1, l2 over the config's bounds), each in a random working mode and with random arm
    limits or none: on the same 61 x 53 grid over the hand-written box, the same reach mask, LCI, sigma_min and
    sigma_max within 1e-9 relative, so the same area (cell count) and GCI (mean LCI, 1e-12 relative); the same
    bounding box (1e-12 relative)."""
    rng = np.random.default_rng(RNG_SEED + 2)
    mechs = {}
    for _ in range(12):
        design = {"r": rng.uniform(50, 400), "l1": rng.uniform(250, 800), "l2": rng.uniform(500, 1400)}
        mode = "".join(rng.choice(["+", "-"], size=2))
        opts = {}
        if rng.random() < 0.6:
            for name in ("alpha1_limits", "alpha2_limits"):
                lo = rng.uniform(-math.pi, math.pi)
                opts[name] = [lo, lo + rng.uniform(0.5, 5.5)]
        mech = mechs.setdefault(mode, _described(mode))
        d = mech.resolve_design(design)
        hand_opts = HAND.resolve_options({**opts, "mode": mode})
        desc_opts = mech.resolve_options(opts)
        lo, hi = HAND.bounding_box(d, hand_opts)
        dlo, dhi = mech.bounding_box(d, desc_opts)
        np.testing.assert_allclose(np.r_[dlo, dhi], np.r_[lo, hi], rtol=1e-12, atol=1e-12 * hi.max())
        shape = np.array([61, 53, 1], dtype=np.int64)
        step = np.r_[(hi[:2] - lo[:2]) / shape[:2], 1.0]
        hand = kgrid.sample_fields(HAND.field_kernel, 6, HAND.pack(d, hand_opts), lo, step, shape)[..., :3]
        ours = kgrid.sample_fields(mech.field_kernel, 6, mech.pack(d, desc_opts), lo, step, shape)[..., :3]
        reach = hand[..., 0] >= 0.0
        assert reach.sum() > 50, (design, mode, opts)
        np.testing.assert_array_equal(ours[..., 0] >= 0.0, reach)
        np.testing.assert_allclose(ours[reach], hand[reach], rtol=1e-9, atol=0.0)
        edges = np.array([0.0, 0.1, 0.3, 1.0])
        sh = kgrid.population_stats(HAND.field_kernel, 6, HAND.pack(d, hand_opts)[None], lo[None], step[None],
                                    shape, edges)[0]
        so = kgrid.population_stats(mech.field_kernel, 6, mech.pack(d, desc_opts)[None], lo[None], step[None],
                                    shape, edges)[0]
        assert so[0] == sh[0]  # reachable cells: the area
        col = kgrid.field_column(0, kgrid.STAT_SUM)
        assert so[col] == pytest.approx(sh[col], rel=1e-12)  # the LCI's sum: the GCI


def test_described_fivebar_evaluates_like_the_hand_written():
    """evaluate on the same uniform grid (the spec's corrected arm limits): area and GCI of the packing design equal
    the hand-written mechanism's (1e-12 relative); the design metrics too."""
    limits = {"alpha1_limits": [-1.3962634015954636, 0.6108652381980153],
              "alpha2_limits": [2.530727415391778, 4.537856055185257]}
    base = {"name": "cmp", "units": {"length": "mm"}, "design": {"r": 200, "l1": 475, "l2": 875},
            "grid": {"resolution": 96}}
    reps = [evaluate_config(config_from_dict({**base, "mechanism": name, "options": opts}))
            for name, opts in (("planar-fivebar", {**limits, "mode": "+-"}), ("planar-fivebar-described", limits))]
    assert reps[0].measure > 0
    assert reps[1].measure == pytest.approx(reps[0].measure, rel=1e-12)
    assert reps[1].gci == pytest.approx(reps[0].gci, rel=1e-12)
    d = FIVEBAR.resolve_design({})
    o = FIVEBAR.resolve_options({})
    for dm, hm in zip(FIVEBAR.design_metrics, HAND.design_metrics, strict=True):
        assert dm.name == hm.name and dm.value(d, o) == pytest.approx(hm.value(d, HAND.resolve_options({})))


def test_described_fivebar_has_the_hand_written_bodies_and_kinematics():
    """At a pose of the packing rectangle: the same IK (every mode), FK, Jacobian, LCI and capsules (same bodies,
    ends and radii) as planar-fivebar."""
    d = FIVEBAR.resolve_design({})
    o, ho = FIVEBAR.resolve_options({}), HAND.resolve_options({})
    pose = np.array([120.0, -760.0])
    ours = {s.label.replace("/", ""): s.values for s in FIVEBAR.inverse_kinematics(d, o, pose)}
    hand = {s.label: s.values for s in HAND.inverse_kinematics(d, ho, pose)}
    assert set(ours) == set(hand)
    for k in hand:
        np.testing.assert_allclose(ours[k], hand[k], rtol=0, atol=1e-12)
    q = hand["+-"]
    np.testing.assert_allclose(FIVEBAR.jacobians(d, o, pose, q)["J"], HAND.jacobians(d, ho, pose, q)["J"],
                               rtol=1e-12)
    assert FIVEBAR.lci(d, o, pose, q) == pytest.approx(HAND.lci(d, ho, pose, q), rel=1e-12)
    fk_o = sorted(tuple(s.values) for s in FIVEBAR.forward_kinematics(d, o, q))
    fk_h = sorted(tuple(s.values) for s in HAND.forward_kinematics(d, ho, q))
    np.testing.assert_allclose(fk_o, fk_h, rtol=0, atol=1e-9)
    geo_o, geo_h = FIVEBAR.link_geometry(d, o, pose, q), HAND.link_geometry(d, ho, pose, q)
    assert geo_o.adjacent == geo_h.adjacent
    by_o, by_h = ({s.body: s for s in g.segments} for g in (geo_o, geo_h))
    assert set(by_o) == set(by_h)
    for body, s in by_h.items():
        assert by_o[body].radius == s.radius
        np.testing.assert_allclose([by_o[body].a, by_o[body].b], [s.a, s.b], rtol=0, atol=1e-9)


@pytest.mark.parametrize("change, message", [
    (lambda d: d["legs"][0].__setitem__("base", ["r", 0, 5]), "legs[0] (right).base.z: motion 2T is planar"),
    (lambda d: d["legs"][0].__setitem__("arm_zero", [0, 0, 1]), "legs[0] (right).arm_zero: motion 2T is planar"),
    (lambda d: d.__setitem__("motion", "3T"), "legs[0] (right).type: a RR leg makes motion 2T, not 3T"),
    (lambda d: d["legs"].pop(), "legs: motion 2T needs 2 actuated legs"),
    (lambda d: d.__setitem__("stiffness", {"sections": {"upper_arm": [40, 3]}}),
     "stiffness.sections.upper_arm: unknown link group"),
    (lambda d: d["legs"][1].__setitem__("branch", "out"), "legs[1] (left).branch: 'out' is not a branch of RR"),
])
def test_bad_planar_descriptions_name_the_leg_and_field(change, message):
    import yaml

    data = yaml.safe_load(builtin_path("planar-fivebar-described").read_text())
    change(data)
    with pytest.raises(ConfigError) as err:
        parse_description(data, "d.yaml")
    line = str(err.value)
    assert line.startswith("d.yaml: " + message) and "\n" not in line and len(line) <= 200


def test_described_fivebar_runs_the_packing_cycle_like_the_hand_written():
    """configs/fivebar_packing.yaml's Adept cycle (1 kg, 60 cycles/min, link dynamics from the bodies) on both: the
    same actuator speeds, accelerations and forces, minimum LCI and clearance (1e-9 relative)."""
    import yaml

    from conftest import ROOT

    data = yaml.safe_load((ROOT / "configs" / "fivebar_packing.yaml").read_text())
    data.pop("output", None)
    data["objectives"] = [{"metric": "cycle_max_actuator_force", "sense": "min"},
                          {"metric": "cycle_min_clearance", "sense": "max"}]
    data["constraints"] = []
    hand = evaluate_config(config_from_dict(data)).metrics
    data["mechanism"] = "planar-fivebar-described"
    del data["options"]["mode"]
    ours = evaluate_config(config_from_dict(data)).metrics
    keys = [k for k in ours if k.startswith("cycle_")]
    assert len(keys) >= 6 and hand["cycle_feasible"] == 1.0
    for k in keys:
        assert ours[k] == pytest.approx(hand[k], rel=1e-9), k
