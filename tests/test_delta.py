"""The rotary Delta, the first described mechanism (describe/, mechanisms/delta.yaml): leg IK and the Jacobian
against finite differences of the forward kinematics and a NumPy twin (tests/naive_delta.py), FK round trips, the
kernel's fields against the twin, conditioning on the central axis against its closed form, the published workspace
of Briot, Arakelian and Glazunov, Williams' published IK/FK examples (rotary and linear), the linear-Delta leg
(P-Pa), and bad descriptions."""

import json
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from fd_checks import assembly_error, fk_jacobian, reachable_points
from naive_delta import delta_fields, delta_jacobian, delta_thetas
from scalesynth.config import load_config
from scalesynth.errors import ConfigError, InvalidParameter
from scalesynth.evaluate import evaluate_config
from scalesynth.kernels import grid as kgrid
from scalesynth.mechanisms import get
from scalesynth.mechanisms.describe import from_description, kernel, parse_description

from conftest import ROOT

DELTA = get("delta")
PUBLISHED = json.loads((ROOT / "tests" / "data" / "delta_published.json").read_text())
RNG_SEED = 20260


def _random_designs(rng, k):
    return [DELTA.resolve_design({"base_radius": rng.uniform(0.1, 0.4), "platform_radius": rng.uniform(0.02, 0.1),
                                  "upper_arm": rng.uniform(0.3, 0.8), "forearm": rng.uniform(0.7, 1.3)})
            for _ in range(k)]


def _reachable_points(design, options, rng, k):
    """k random platform centres that the kernel finds reachable, below the base."""
    reach = design["upper_arm"] + design["forearm"]
    return reachable_points(kernel.point_fields, DELTA.pack(design, options), [-reach, -reach, -reach],
                            [reach, reach, -0.05], rng, k, n_fields=DELTA.n_fields)


def test_the_delta_follows_the_issue_conventions():
    """Leg 1 along +x: its axis through (R, 0, 0) along y; theta = 0 puts the elbow at (R + L, 0, 0), theta = pi/2
    straight below the axis, theta > 0 lowers it; legs 2, 3 at 120 and 240 degrees."""
    d, o = DELTA.resolve_design({}), DELTA.resolve_options({})
    legs = DELTA.legs(d, o)
    R, L = d["base_radius"], d["upper_arm"]
    np.testing.assert_allclose(legs[0].base, [R, 0, 0], atol=1e-15)
    np.testing.assert_allclose(np.cross(legs[0].u, legs[0].w), [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(legs[0].actuated_point(0.0), [R + L, 0, 0], atol=1e-15)
    np.testing.assert_allclose(legs[0].actuated_point(math.pi / 2), [R, 0, -L], atol=1e-15)
    for leg, phi in zip(legs, np.radians([0, 120, 240]), strict=True):
        np.testing.assert_allclose(leg.base, R * np.array([math.cos(phi), math.sin(phi), 0]), atol=1e-15)
        np.testing.assert_allclose(leg.platform, d["platform_radius"] * np.array([math.cos(phi), math.sin(phi), 0]),
                                   atol=1e-15)
    assert DELTA.kernel_branch(o) == "out/out/out" and DELTA.joints == ("theta1", "theta2", "theta3")


def test_leg_ik_closes_every_chain_and_the_kernel_takes_the_elbows_out_root():
    rng = np.random.default_rng(RNG_SEED)
    out = np.zeros((3, 6))
    for design in _random_designs(rng, 4):
        options = DELTA.resolve_options({})
        legs = DELTA.legs(design, options)
        packed = DELTA.pack(design, options)
        for p in _reachable_points(design, options, rng, 5):
            kernel.leg_values(packed, *p, out)
            twin, ok = delta_thetas(design, *p)
            assert ok
            for i, leg in enumerate(legs):
                roots = leg.roots(p)
                for q in roots.values():  # both roots close the chain: |Q - E| = l
                    assert np.linalg.norm(p + leg.platform - leg.actuated_point(q)) == pytest.approx(leg.forearm,
                                                                                                   rel=1e-12)
                assert math.cos(roots[1.0]) >= math.cos(roots[-1.0])  # +1 = elbow out
                assert out[i, 5] == pytest.approx(roots[1.0], abs=1e-9)
                assert math.remainder(out[i, 5] - twin[i], 2 * math.pi) == pytest.approx(0.0, abs=1e-9)


def test_jacobian_equals_finite_differences_of_the_forward_kinematics_and_the_twin():
    """J = dx/dq against central differences of the closed-form FK (three spheres) in each arm angle, h = 1e-6 rad
    (error O(h^2) ~ 1e-12, rounding ~ 1e-10): 1e-6 relative; and against the NumPy twin's Jx^-1 Jq."""
    rng = np.random.default_rng(RNG_SEED + 1)
    h = 1e-6
    for design in _random_designs(rng, 3):
        options = DELTA.resolve_options({})
        for p in _reachable_points(design, options, rng, 4):
            q = {s.label: s.values for s in DELTA.inverse_kinematics(design, options, p)}["out/out/out"]
            jac = DELTA.jacobians(design, options, p, q)["J"]
            fd = fk_jacobian(DELTA, design, options, p, q, h)
            np.testing.assert_allclose(jac, fd, rtol=1e-6, atol=1e-6 * np.abs(jac).max())
            np.testing.assert_allclose(jac, delta_jacobian(design, p, q)[2], rtol=1e-9, atol=1e-12)
            a = DELTA.velocity_map(design, options, p, q)
            np.testing.assert_allclose(a @ jac, np.eye(3), atol=1e-9)


def test_forward_kinematics_round_trips_the_inverse():
    rng = np.random.default_rng(RNG_SEED + 2)
    for design in _random_designs(rng, 3):
        options = DELTA.resolve_options({})
        for p in _reachable_points(design, options, rng, 5):
            for sol in DELTA.inverse_kinematics(design, options, p):
                assert assembly_error(DELTA.forward_kinematics(design, options, sol.values), p) <= 1e-9


def test_kernel_fields_equal_the_numpy_twin_on_random_designs_and_points():
    """LCI, sigma_min, sigma_max at 400 random points per design (with and without theta limits) against the twin's
    SVD: the same reach everywhere, the values to 1e-7 relative (closed-form 3x3 singular values)."""
    rng = np.random.default_rng(RNG_SEED + 3)
    for k, design in enumerate(_random_designs(rng, 3)):
        options = DELTA.resolve_options({"theta_limits": [-0.3, 1.4] if k % 2 else None})
        reach = design["upper_arm"] + design["forearm"]
        pts = rng.uniform([-0.6 * reach, -0.6 * reach, -reach], [0.6 * reach, 0.6 * reach, 0.2], size=(400, 3))
        fields = kgrid.population_points_fields(DELTA.field_kernel, DELTA.n_fields,
                                                DELTA.pack(design, options)[None, :], pts)[0]
        twin = delta_fields(design, options, pts[:, 0], pts[:, 1], pts[:, 2])
        ok = fields[:, 0] >= 0
        assert np.array_equal(ok, twin[:, 0] >= 0) and 40 <= ok.sum() < 400
        np.testing.assert_allclose(fields[ok][:, :3], twin[ok], rtol=1e-7, atol=1e-12)
        assert (fields[~ok] == [-1.0] + [0.0] * (DELTA.n_fields - 1)).all()


def _axis_theta(a, L, l, z):
    """The elbows-out arm angle on the central axis, solved numerically (brentq) from the leg's closure
    (a + L cos t)^2 + (z + L sin t)^2 = l^2: the root with the larger cos t."""
    g = lambda t: (a + L * math.cos(t)) ** 2 + (z + L * math.sin(t)) ** 2 - l * l  # noqa: E731
    grid = np.linspace(-math.pi, math.pi, 2001)
    vals = [g(t) for t in grid]
    roots = [brentq(g, grid[i], grid[i + 1], xtol=1e-15) for i in range(len(grid) - 1) if vals[i] * vals[i + 1] < 0]
    return max(roots, key=math.cos)


def test_conditioning_on_the_central_axis_has_its_closed_form():
    """On the axis x = y = 0 every leg has the same theta, its forearm lies in its leg's vertical plane with horizontal
    part rho = a + L cos theta (a = R - r) and vertical part h = |z + L sin theta|, and J = Jx^-1 Jq with
    Jq = jq I, jq = L (a sin theta - z cos theta). Summing the rows, Jx^T Jx = diag(3 rho^2 / 2, 3 rho^2 / 2,
    3 h^2), so J's singular values are |jq| / (sqrt(3/2) rho) (twice) and |jq| / (sqrt(3) h), and
    LCI = min(rho / (sqrt(2) h), sqrt(2) h / rho): isotropic (LCI = 1) where rho = sqrt(2) h, i.e. where the three
    forearms are mutually orthogonal (each at atan(sqrt 2) = 54.74 deg from the vertical)."""
    design = DELTA.resolve_design({})
    options = DELTA.resolve_options({})
    a, L, l = design["base_radius"] - design["platform_radius"], design["upper_arm"], design["forearm"]
    packed = DELTA.pack(design, options)
    out = np.zeros(DELTA.n_fields)
    for z in (-0.4, -0.7, -1.0, -1.3, -1.6):
        t = _axis_theta(a, L, l, z)
        rho, h = abs(a + L * math.cos(t)), abs(z + L * math.sin(t))
        jq = abs(L * (a * math.sin(t) - z * math.cos(t)))
        sv = sorted([jq / (math.sqrt(1.5) * rho), jq / (math.sqrt(3.0) * h)])
        kernel.point_fields(packed, 0.0, 0.0, z, out)
        # rtol 1e-7: two of the singular values are equal here (symmetry), where the kernel's closed-form 3x3
        # singular values (kernels.conditioning.sv_3x3) keep only about half the digits (sqrt(eps) ~ 1.5e-8)
        np.testing.assert_allclose(out[:3], [sv[0] / sv[1], sv[0], sv[1]], rtol=1e-7)
    # the isotropic point: h = l / sqrt(3), rho = l sqrt(2/3); elbow out: cos theta = (rho - a) / L, the arm below
    # the base (sin theta > 0), the platform below the elbow
    h, rho = l / math.sqrt(3.0), l * math.sqrt(2.0 / 3.0)
    ct = (rho - a) / L
    z_iso = -h - L * math.sqrt(1.0 - ct * ct)
    kernel.point_fields(packed, 0.0, 0.0, z_iso, out)
    assert out[0] == pytest.approx(1.0, abs=1e-9)
    kernel.point_fields(packed, 0.0, 0.0, z_iso - 0.05, out)
    assert out[0] < 0.99


def test_workspace_of_the_briot_arakelian_glazunov_delta():
    """configs/delta.yaml is their design (R 0.25, r 0.2, L 0.75, l 0.95 m, theta in [0, 90 deg], z <= -0.3 m):
    its workspace, published as 'about 1.48 m^3' (tests/data/delta_published.json), here by the adaptive evaluator
    at volume tolerance 0.2 % (the description's calibrated plan). Tolerance 0.01 m^3 (0.7 %): the published
    figure's rounding (+-0.005) plus their 0.02 m grid's error. Measured: 1.4814 m^3 (1.4825 by the per-design
    ladder, 1.4787 on a uniform 60^3 grid, 1.4815 with NumPy at 0.01 m)."""
    case = PUBLISHED["briot_arakelian_glazunov"]
    cfg = load_config(ROOT / "configs" / "delta.yaml", ["grid.tolerance.volume=0.002", "grid.tolerance.gci=0.0005"])
    assert cfg.resolved_design() == case["design"]
    lo, hi = cfg.resolved_options()["theta_limits"]
    assert (lo, hi) == pytest.approx(tuple(math.radians(v) for v in case["theta_limits_deg"]), abs=1e-15)
    assert cfg.grid.region["z"][1] == case["z_max"]
    assert cfg.grid.region["z"][0] <= -(0.75 + 0.95)  # below the lowest reachable point
    rep = evaluate_config(cfg)
    assert rep.measure == pytest.approx(case["volume_m3"], abs=0.01)
    assert 0.0 < rep.gci < 1.0


def _from_williams(p):
    """A point of Williams' frame (leg 1 along -y) in the Delta's (leg 1 along +x): turned +90 deg about z."""
    return np.array([-p[1], p[0], p[2]])


def test_published_inverse_and_forward_kinematics_of_williams_deltas():
    """Williams' worked examples (tests/data/delta_williams_kinematics.json: his printed snapshots of a rotary Delta
    with ABB IRB 360-1/1600 proportions and a linear Delta 3D printer, with his geometry and frame mapped as written
    there): the elbows-out IK ('kinked out'), the 'near' linear IK ('lower solution') and the 'low' FK give his
    numbers. Tolerances: linear, half a unit of the last printed digit; rotary, 0.1 deg and 1 mm, his 0.05 deg and
    0.5 mm of rounding plus 0.55 mm by which his nominal FK height (-1.065 m) differs from the exact one of his stated
    dimensions (-1.06445 m: sqrt(l^2 - (w_B + L - u_P)^2)), an offset of his own computation. A wrong convention
    (leg order, the sign or zero of theta, the elbow branch, the frame) is off by degrees or centimetres."""
    data = json.loads((ROOT / "tests" / "data" / "delta_williams_kinematics.json").read_text())
    case = data["rotary"]
    dims = case["dimensions_m"]
    design = DELTA.resolve_design({"base_radius": dims["s_B"] * math.sqrt(3) / 6,
                                   "platform_radius": dims["s_P"] / math.sqrt(3),
                                   "upper_arm": dims["L"], "forearm": dims["l"]})
    options = DELTA.resolve_options({})
    for ex in case["inverse"]:
        q = {s.label: s.values for s in DELTA.inverse_kinematics(design, options, _from_williams(ex["p_m"]))}
        np.testing.assert_allclose(np.degrees(q["out/out/out"]), ex["theta_deg"], rtol=0, atol=0.1, err_msg=ex["where"])
    for ex in case["forward"]:
        sols = {s.label: s.values for s in DELTA.forward_kinematics(design, options, np.radians(ex["theta_deg"]))}
        np.testing.assert_allclose(sols["low"], _from_williams(ex["p_m"]), rtol=0, atol=1e-3, err_msg=ex["where"])

    case = data["linear"]
    dims = case["dimensions_m"]
    linear = get("linear-delta")
    design = linear.resolve_design({"base_radius": dims["s_B"] * math.sqrt(3) / 6,
                                    "platform_radius": dims["s_P"] / math.sqrt(3), "forearm": dims["l"]})
    options = linear.resolve_options({})
    assert linear.kernel_branch(options) == "near/near/near"
    for ex in case["inverse"]:
        q = {s.label: s.values for s in linear.inverse_kinematics(design, options, _from_williams(ex["p_m"]))}
        np.testing.assert_allclose(q["near/near/near"], ex["s_m"], rtol=0, atol=0.5 * 10.0 ** -ex["decimals"],
                                   err_msg=ex["where"])
    for ex in case["forward"]:
        sols = {s.label: s.values for s in linear.forward_kinematics(design, options, np.array(ex["s_m"]))}
        np.testing.assert_allclose(sols["low"], _from_williams(ex["p_m"]), rtol=0, atol=0.5 * 10.0 ** -ex["decimals"],
                                   err_msg=ex["where"])


LINEAR = {
    "name": "linear-delta-test", "title": "linear Delta (test)", "motion": "3T",
    "parameters": {"rail_radius": {"default": 0.3, "doc": "rails' circle"},
                   "platform_radius": {"default": 0.05, "doc": "platform joints' circle"},
                   "forearm": {"default": 0.5, "doc": "rod length"}},
    "options": {"stroke": {"kind": "range", "default": [0.0, 1.0], "doc": "carriage range"}},
    "legs": [{"type": "P-Pa", "pattern": {"count": 3, "start_deg": 90}, "base": ["rail_radius", 0, 0],
              "platform": ["platform_radius", 0, 0], "links": {"forearm": "forearm"}, "limits": "stroke"}],
}


def test_the_linear_delta_leg_and_its_jacobian():
    """P-Pa: both roots close the chain, 'far' is the higher carriage, the kernel's value is it, and J = dx/dq
    (dimensionless) equals central differences of the FK (h = 1e-6 m)."""
    mech = from_description(parse_description(LINEAR))
    assert mech.joints == ("s1", "s2", "s3") and mech.fields[1].unit == "1"
    design, options = mech.resolve_design({}), mech.resolve_options({})
    legs, packed = mech.legs(design, options), mech.pack(design, options)
    lo, hi = mech.bounding_box(design, options)
    # 'far' on a rail pointing up: the platform joint lies below its carriage, from the top of the stroke down to
    # its bottom minus the rod
    assert (lo[2], hi[2]) == pytest.approx((0.0 - 0.5, 1.0))
    out, vals = np.zeros(DELTA.n_fields), np.zeros((3, 6))
    h = 1e-6
    for p in ([0.0, 0.0, 0.2], [0.05, -0.03, 0.4], [-0.08, 0.02, 0.1]):
        p = np.array(p)
        kernel.leg_values(packed, *p, vals)
        for i, leg in enumerate(legs):
            roots = leg.roots(p)
            assert roots[1.0] > roots[-1.0] and vals[i, 5] == pytest.approx(roots[1.0], abs=1e-12)
            for q in roots.values():
                assert np.linalg.norm(p + leg.platform - leg.actuated_point(q)) == pytest.approx(0.5, rel=1e-12)
        q = {s.label: s.values for s in mech.inverse_kinematics(design, options, p)}["far/far/far"]
        jac = mech.jacobians(design, options, p, q)["J"]
        fd = fk_jacobian(mech, design, options, p, q, h)
        np.testing.assert_allclose(jac, fd, rtol=1e-6, atol=1e-7)
        kernel.point_fields(packed, *p, out)
        sv = np.linalg.svd(jac, compute_uv=False)
        np.testing.assert_allclose(out[:3], [sv[-1] / sv[0], sv[-1], sv[0]], rtol=1e-9)
    with pytest.raises(InvalidParameter, match=r"^options.stroke: a P-Pa leg needs a stroke range"):
        mech.resolve_options({"stroke": None})


def _bad(**changes):
    data = json.loads(json.dumps(LINEAR))
    leg = data["legs"][0]
    for key, value in changes.items():
        if key.startswith("leg_"):
            leg[key[4:]] = value
        else:
            data[key] = value
    return data


@pytest.mark.parametrize(("data", "message"), [
    (_bad(leg_type="P-Pb"),
     "d: legs[0] (leg).type: unknown leg type 'P-Pb' (did you mean 'P-Pa'?; library: R-Pa, P-Pa, RUS, R-SS, UPS, "
     "SPS, RR, PR)"),
    (_bad(leg_base=["rail_radus", 0, 0]),
     "d: legs[0] (leg).base.x: unknown parameter 'rail_radus' (did you mean 'rail_radius'?; known: "
     "rail_radius, platform_radius, forearm)"),
    (_bad(leg_links={}), "d: legs[0] (leg).links: P-Pa needs forearm (missing forearm)"),
    (_bad(leg_links={"forearm": "forearm", "upper_arm": 0.3}),
     "d: legs[0] (leg).links.upper_arm: not a link of P-Pa (links: forearm)"),
    (_bad(leg_limits="strok"),
     "d: legs[0] (leg).limits: unknown option 'strok' (did you mean 'stroke'?; known: stroke)"),
    (_bad(leg_arm_zero=[1, 0, 0]), "d: legs[0] (leg).arm_zero: P-Pa has no arm_zero (frame: rail)"),
    (_bad(leg_pattern={"count": 4}),
     "d: legs[0] (leg).pattern.count: motion 3T needs 3 actuated legs (a square Jacobian), these give 4"),
    (_bad(leg_branch="up"), "d: legs[0] (leg).branch: 'up' is not a branch of P-Pa (branches: far, near)"),
    (_bad(leg_base=["__import__('os')", 0, 0]),
     "d: legs[0] (leg).base.x: \"__import__('os')\": only numbers, parameters, pi, + - * / ** and sqrt, sin, cos, "
     "tan, radians are allowed"),
    (_bad(motion="6D"), "d: motion: '6D' is not handled yet (did you mean '6DOF'?; handled: 2T, 3T, 6DOF)"),
    (_bad(leg_colour="red"), "d: legs[0].colour: unknown key"),
])
def test_a_bad_description_is_one_line_naming_the_leg_and_the_field(data, message):
    with pytest.raises(ConfigError) as err:
        parse_description(data, "d")
    assert str(err.value) == message and len(message) <= 200


def test_the_builtin_description_file_is_the_registered_delta(tmp_path):
    """mechanisms/delta.yaml loads into the registered mechanism's parameters and options; an edited copy with an
    unknown parameter in an attachment fails on load, naming the file, the leg and the field."""
    from scalesynth.mechanisms.describe import BUILTIN_DIR, load_description

    desc = load_description(BUILTIN_DIR / "delta.yaml")
    assert list(desc.parameters) == list(DELTA.parameter_names) == ["base_radius", "platform_radius", "upper_arm",
                                                                    "forearm"]
    from scalesynth.mechanisms.describe.bodies import RESERVED_OPTIONS

    # the description's options, then those every described mechanism has (bodies, stiffness)
    assert DELTA.option_names == ("theta_limits", "cone_limit", *RESERVED_OPTIONS)
    bad = tmp_path / "my_delta.yaml"
    bad.write_text((BUILTIN_DIR / "delta.yaml").read_text().replace("base: [base_radius", "base: [base_radiu"))
    with pytest.raises(ConfigError, match=r"^my_delta.yaml: legs\[0\] \(arm\).base.x: unknown param"):
        load_description(bad)
