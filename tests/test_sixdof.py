"""Described 6-DOF mechanisms (describe/sixdof.py, describe/kernel6.py; built-ins hexapod and hexa): leg IK and
the velocity map against finite differences, the kernel's legs and fields against NumPy (tests/naive_sixdof.py),
forward kinematics round trips, the exact conditioning of the cubic hexapod (Geng and Haynes 1994) and the exact
reach of a hexapod whose legs' spheres share one centre, bad descriptions and the CLI on both configs."""

import math

import numpy as np
import pytest

from cli_main import run_main
from fd_checks import reachable_points
from naive_sixdof import hexa_fields, hexa_thetas, hexapod_fields
from scalesynth.config import load_config
from scalesynth.errors import ConfigError, InvalidParameter
from scalesynth.evaluate import evaluate_config, make_grid
from scalesynth.kernels import grid as kgrid
from scalesynth.mechanisms import get
from scalesynth.mechanisms.describe import from_description, kernel6, parse_description
from scalesynth.mechanisms.describe.sixdof import _rodrigues, rotation

from conftest import ROOT
from naive import grid_nodes

RNG_SEED = 2028
TWINS = {"hexapod": hexapod_fields, "hexa": hexa_fields}
TILTED = [0.12, -0.08, 0.3]  # rad: a constant orientation that is not the identity


def _random_design(mech, rng):
    if mech.name == "hexapod":
        return mech.resolve_design({"base_radius": rng.uniform(0.35, 0.6), "platform_radius": rng.uniform(0.15, 0.35),
                                    "base_half_angle": rng.uniform(0.05, 0.4),
                                    "platform_half_angle": rng.uniform(0.6, 0.95)})
    return mech.resolve_design({"base_radius": rng.uniform(0.15, 0.35), "arm_spacing": rng.uniform(0.03, 0.1),
                                "platform_radius": rng.uniform(0.06, 0.15), "platform_half_angle":
                                rng.uniform(0.6, 0.95), "arm": rng.uniform(0.2, 0.4), "rod": rng.uniform(0.5, 0.9)})


def _reachable(mech, design, options, rng, k, min_lci=1e-3):
    """k random platform centres the kernel finds reachable with LCI above min_lci."""
    lo, hi = mech.bounding_box(design, options)
    lo = np.where(np.arange(3) == 2, np.maximum(lo, 0.0) if mech.name == "hexapod" else lo, lo)
    hi = np.where(np.arange(3) == 2, np.minimum(hi, 0.0) if mech.name == "hexa" else hi, hi)
    return reachable_points(kernel6.point_fields, mech.pack(design, options), lo, hi, rng, k, min_lci=min_lci,
                            n_fields=mech.n_fields)


@pytest.mark.parametrize("name", ["hexapod", "hexa"])
def test_leg_ik_equals_the_kernel_and_the_twin_and_closes_every_chain(name):
    mech = get(name)
    rng = np.random.default_rng(RNG_SEED)
    out = np.zeros((6, 7))
    for orientation in ([0.0, 0.0, 0.0], TILTED):
        options = mech.resolve_options({"orientation": orientation})
        design = _random_design(mech, rng)
        legs, rot, packed = mech.legs(design, options), rotation(orientation), mech.pack(design, options)
        branch = mech.kernel_branch(options)
        for p in _reachable(mech, design, options, rng, 4):
            kernel6.leg_values(packed, *p, out)
            (q,) = [s.values for s in mech.inverse_kinematics(design, options, p) if s.label == branch]
            np.testing.assert_allclose(out[:, 5], q, rtol=1e-12, atol=1e-12)
            assert (out[:, 0] == 1).all() and (out[:, 6] == 0).all()
            for leg, qi, row in zip(legs, q, out, strict=True):
                f = leg.rod_vector(p, rot, qi)  # closure: the rod (RUS) has its length, the leg (UPS) is q
                assert np.linalg.norm(f) == pytest.approx(leg.rod if leg.rus else qi, rel=1e-12)
                np.testing.assert_allclose(row[1:4], f / np.linalg.norm(f), atol=1e-12)
            if name == "hexa":  # the twin's elbows-out angles, from its own formulas
                np.testing.assert_allclose(q, hexa_thetas(design, options, p), atol=1e-10)
            else:
                np.testing.assert_allclose(q, [np.linalg.norm(p + rot @ leg.r - leg.base) for leg in legs],
                                           rtol=1e-12)


@pytest.mark.parametrize("name", ["hexapod", "hexa"])
def test_velocity_map_equals_finite_differences_of_the_ik(name):
    """A = Jq^-1 Jx: q_dot = A [v; omega]. Columns 1-3 by central differences of the IK in the platform centre,
    columns 4-6 in a small turn exp(h e_k) of the orientation (the IK of each leg at an explicit rotation)."""
    mech = get(name)
    rng = np.random.default_rng(RNG_SEED + 1)
    options = mech.resolve_options({"orientation": TILTED})
    design = _random_design(mech, rng)
    legs, rot = mech.legs(design, options), rotation(TILTED)

    def ik(p, r):
        return np.array([leg.roots(p, r)[leg.branch] for leg in legs])

    h = 1e-6
    for p in _reachable(mech, design, options, rng, 3, min_lci=0.02):
        q = ik(p, rot)
        a = mech.velocity_map(design, options, p, q)
        fd = np.zeros((6, 6))
        for k in range(3):
            e = np.eye(3)[k] * h
            fd[:, k] = (ik(p + e, rot) - ik(p - e, rot)) / (2 * h)
            fd[:, 3 + k] = (ik(p, _rodrigues(np.eye(3)[k] * h) @ rot) - ik(p, _rodrigues(-np.eye(3)[k] * h) @ rot)) / (
                2 * h)
        np.testing.assert_allclose(a, fd, rtol=1e-6, atol=1e-6 * np.abs(a).max())
        # the homogenised dx/dq is its inverse with the rotation rows times L
        jac = mech.jacobians(design, options, p, q)
        np.testing.assert_allclose(jac["H"], np.diag([1, 1, 1] + [jac["L"]] * 3) @ np.linalg.inv(a), rtol=1e-9,
                                   atol=1e-9 * np.abs(jac["H"]).max())


@pytest.mark.parametrize("name", ["hexapod", "hexa"])
@pytest.mark.parametrize("orientation", [[0.0, 0.0, 0.0], TILTED])
def test_kernel_fields_equal_the_numpy_twin_on_a_grid(name, orientation):
    """Same reach mask; LCI, sigma_min and sigma_max within 1e-7 relative wherever the LCI exceeds 1e-6."""
    mech = get(name)
    rng = np.random.default_rng(RNG_SEED + 2)
    for _ in range(2):
        design = _random_design(mech, rng)
        extra = {"theta_limits": [-0.5, 1.6]} if name == "hexa" else {}
        options = mech.resolve_options({"orientation": orientation, **extra})
        g = make_grid(mech, design, options, 13)
        fields = kgrid.sample_fields(mech.field_kernel, mech.n_fields, mech.pack(design, options), g.lo, g.step,
                                     g.shape)
        twin = TWINS[name](design, options, *grid_nodes(g.lo, g.step, g.shape))
        reach = fields[..., 0] >= 0
        assert np.array_equal(reach, twin[..., 0] >= 0)
        assert reach.sum() >= 20
        regular = reach & (twin[..., 0] > 1e-6)
        np.testing.assert_allclose(fields[regular][:, :3], twin[regular], rtol=1e-7)
        # NumPy's LCI of the mechanism's own Jacobian agrees too, on a few nodes
        for idx in np.argwhere(regular)[:: max(1, regular.sum() // 5)]:
            p = g.lo + (idx + 0.5) * g.step
            (q,) = [s.values for s in mech.inverse_kinematics(design, options, p)
                    if s.label == mech.kernel_branch(options)]
            assert mech.lci(design, options, p, q) == pytest.approx(fields[tuple(idx)][0], rel=1e-7)


@pytest.mark.parametrize("name", ["hexapod", "hexa"])
def test_forward_kinematics_round_trips_the_inverse(name):
    mech = get(name)
    rng = np.random.default_rng(RNG_SEED + 3)
    options = mech.resolve_options({"orientation": TILTED})
    design = _random_design(mech, rng)
    for p in _reachable(mech, design, options, rng, 4):
        (q,) = [s.values for s in mech.inverse_kinematics(design, options, p) if s.label == mech.kernel_branch(options)]
        fk = mech.forward_kinematics(design, options, q)
        assert fk, p
        best = min((s.values for s in fk), key=lambda v: np.abs(v[:3] - p).max())
        np.testing.assert_allclose(best, np.concatenate([p, TILTED]), atol=1e-9)
        for s in fk:  # every assembly returned closes the chains: its IK gives q back
            options_s = mech.resolve_options({**options, "orientation": list(s.values[3:])})
            (back,) = [b.values for b in mech.inverse_kinematics(design, options_s, s.values[:3])
                       if b.label == mech.kernel_branch(options)] or [None]
            if back is not None and name == "hexapod":
                np.testing.assert_allclose(back, q, rtol=1e-9)


def _cubic_hexapod(a, length):
    """The cubic hexapod of side a (Geng and Haynes 1994): six legs along the cube edges that join the three
    vertices next to one end of a main diagonal to the three next to the other, the diagonal vertical. Returns the
    mechanism and the platform centre at the cube's centre."""
    z = np.ones(3) / math.sqrt(3)
    x = np.array([1.0, -1.0, 0.0]) / math.sqrt(2)
    frame = np.array([x, np.cross(z, x), z])  # rows: the mechanism axes in cube coordinates
    e = np.eye(3)
    centre = frame @ np.full(3, 0.5 * a)
    legs = []
    for i, j in ((0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)):
        legs.append({"type": "UPS", "name": f"edge{i}{j}", "base": [float(v) for v in frame @ (a * e[i])],
                     "platform": [float(v) for v in frame @ (a * (e[i] + e[j])) - centre], "limits": "stroke"})
    desc = parse_description({
        "name": "cubic-hexapod", "title": "cubic hexapod", "motion": "6DOF",
        "parameters": {"side": {"default": a, "doc": "cube side (the legs' geometry is fixed numbers)"}},
        "options": {"stroke": {"kind": "range", "default": [0.5 * a, 1.5 * a], "doc": "leg lengths"}},
        "legs": legs})
    mech = from_description(desc)
    return mech, centre, mech.resolve_options({"characteristic_length": length})


@pytest.mark.parametrize(("factor", "expected"), [(1.0, 0.5), (0.5, 0.5), (2.0, 0.25), (0.25, 0.25)])
def test_cubic_hexapod_conditioning_has_its_closed_form(factor, expected):
    """Cubic hexapod, platform centre at the cube's centre, side a: Geng and Haynes (1994) show its Jacobian is
    decoupled there with translational block sum n n^T = 2 I. Each leg line passes at a/sqrt(2) from the centre
    with moment m = (e_i - c) x e_j; sum m m^T = a^2 (I + 1 1^T) / 2 in cube coordinates (trace 3 a^2, and
    (m . 1)^2 = a^2 for every edge), eigenvalues 2 a^2 along the diagonal, a^2 / 2 across. With characteristic
    length L the homogenised inverse Jacobian has singular values sqrt(2) (x3), a / (sqrt(2) L) (x2) and
    sqrt(2) a / L: LCI = min / max, 1/2 for L in [a/2, a] and 1/4 at L = 2a or a/4."""
    a = 0.4
    mech, centre, options = _cubic_hexapod(a, factor * a)
    design = mech.resolve_design({})
    out = np.zeros(mech.n_fields)
    mech.field_kernel(mech.pack(design, options), *centre, out)
    svs = sorted([math.sqrt(2)] * 3 + [a / (math.sqrt(2) * factor * a)] * 2 + [math.sqrt(2) / factor])
    assert out[0] == pytest.approx(expected, rel=1e-12)
    assert out[0] == pytest.approx(svs[0] / svs[-1], rel=1e-12)
    assert out[1] == pytest.approx(1 / svs[-1], rel=1e-12) and out[2] == pytest.approx(1 / svs[0], rel=1e-12)


def test_a_hexapod_whose_leg_spheres_share_a_centre_reaches_a_spherical_shell():
    """With base_radius = platform_radius and equal half-angles every base joint B_i equals its platform offset r_i,
    so leg i reaches P exactly when lo <= |P| <= hi: the workspace above the base is the half shell of volume
    2/3 pi (hi^3 - lo^3) = 1.6420 m3 for leg lengths [0.6, 1.0] m (all legs parallel: singular, LCI 0, still
    reached)."""
    cfg = load_config(ROOT / "configs" / "hexapod.yaml", [
        "design.platform_radius=0.5", "design.platform_half_angle=0.17453292519943295",
        "grid.tolerance.volume=0.002"])
    rep = evaluate_config(cfg)
    exact = 2.0 / 3.0 * math.pi * (1.0 - 0.6 ** 3)
    assert rep.measure == pytest.approx(exact, rel=0.004)
    assert rep.gci < 1e-12  # 0 up to the rounding of the singular values (1e-17)


@pytest.mark.parametrize(("change", "message"), [
    (lambda d: d.update(motion="3T"), "legs[0] (leg-a).type: a UPS leg makes motion 6DOF, not 3T"),
    (lambda d: d["legs"].pop(), "legs: motion 6DOF needs 6 actuated legs (a square Jacobian), these give 3"),
    (lambda d: d["legs"][0].update(type="R-Pa", links={"upper_arm": 1, "forearm": 1}),
     "legs[0] (leg-a).type: a R-Pa leg makes motion 3T, not 6DOF"),
    (lambda d: d["legs"][0].update(rail=[0, 0, 1]), "legs[0] (leg-a).rail: UPS has no rail"),
    (lambda d: d["legs"][0].update(cone_axis=[0, 0, 5]), "legs[0] (leg-a).cone_axis: expected a unit vector"),
])
def test_a_bad_6dof_description_is_one_line_naming_the_leg_and_the_field(change, message):
    import yaml

    data = yaml.safe_load((ROOT / "src" / "scalesynth" / "mechanisms" / "hexapod.yaml").read_text())
    change(data)
    with pytest.raises(ConfigError) as err:
        parse_description(data)
    assert message in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize(("options", "message"), [
    ({"orientation": [0, 0]}, "options.orientation: expected [roll, pitch, yaw]"),
    ({"orientation": [0, 0, "x"]}, "options.orientation: expected [roll, pitch, yaw]"),
    ({"characteristic_length": -1}, "options.characteristic_length: expected null"),
    ({"leg_length": None}, "options.leg_length: a UPS leg needs a length range"),
])
def test_bad_6dof_options_name_the_option(options, message):
    with pytest.raises(InvalidParameter, match=message.replace("[", r"\[")):
        get("hexapod").resolve_options(options)


@pytest.mark.parametrize("name", ["hexapod", "hexa"])
def test_evaluate_runs_on_the_config(name, capsys):
    code, out, err = run_main(["evaluate", ROOT / "configs" / f"{name}.yaml", "--resolution", "10"], capsys)
    assert code == 0, err
    assert "volume_m3" in out and "gci" in out
