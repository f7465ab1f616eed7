"""Published workspaces of two more mechanisms (issue 28): Masory and Wang's 'normalized' Stewart platform
(the built-in hexapod; Fig. 9, volume against the joint angle limit) and Ren, Zheng and Wang's nine rotary Deltas
(the built-in delta; Table 2 and group 8's largest horizontal section). Data and provenance:
tests/data/hexapod_masory_wang.json and tests/data/delta_ren_2026.json; NumPy twins written from the papers'
equations: tests/naive_sixdof.py masory_wang_level_volume, tests/naive_delta.py ren_thetas / ren_volume."""

import json
import math

import numpy as np
import pytest

from naive_delta import ren_thetas, ren_volume
from naive_sixdof import masory_wang_level_volume
from scalesynth.config import load_config
from scalesynth.evaluate import evaluate_config
from scalesynth.kernels import grid as kgrid
from scalesynth.mechanisms import get

from conftest import ROOT
from refdata import DATA

MW = json.loads((DATA / "hexapod_masory_wang.json").read_text())
REN = json.loads((DATA / "delta_ren_2026.json").read_text())


def _mw_design():
    p = MW["normalized_platform"]
    return {"base_radius": p["base_radius"], "platform_radius": p["platform_radius"],
            "base_half_angle": math.radians(p["base_half_angle_deg"]),
            "platform_half_angle": math.radians(p["platform_half_angle_deg"])}


def test_the_hexapod_places_masory_and_wangs_joints():
    """The paper's eq. (1) joints (B_i, P_i) and the built-in hexapod's legs (base joint, platform offset) at the
    mapped design (base_half_angle = alpha_b, platform_half_angle = alpha_p) are the same six pairs, to 1e-12."""
    mech = get("hexapod")
    design = mech.resolve_design(_mw_design())
    p, j = MW["normalized_platform"], MW["joints"]
    centres, signs = np.radians(j["base_angles_centres_deg"]), np.array(j["base_angles_offsets_deg"])
    ab = centres + signs * math.radians(p["base_half_angle_deg"])
    ap = centres + signs * math.radians(p["platform_half_angle_deg"])
    paper = [np.array([p["base_radius"] * math.cos(a), p["base_radius"] * math.sin(a), 0.0,
                       p["platform_radius"] * math.cos(b), p["platform_radius"] * math.sin(b), 0.0])
             for a, b in zip(ab, ap, strict=True)]
    ours = [np.concatenate([leg.base, leg.r]) for leg in mech.legs(design, mech.resolve_options({}))]
    for leg in ours:
        assert min(np.abs(leg - q).max() for q in paper) < 1e-12
    for q in paper:
        assert min(np.abs(leg - q).max() for leg in ours) < 1e-12


def test_masory_and_wangs_fig9_volumes():
    """Fig. 9 (platform level): workspace volume against the joint limit 30..55 deg, read from the scan as 12.1,
    24.5, 39.2, 53.4, 65.6, 74.4 (Rp^3). The built-in hexapod (cone_limit = the joint limit, both joints perpendicular
    to their plates as in Fig. 9), by the adaptive evaluator at volume tolerance 0.2 %, meets the exact-column NumPy
    twin of the paper's eq. (1)-(5) within that tolerance (measured 12.211, 24.193, 38.223, 52.424, 64.947, 74.192
    against 12.214, 24.199, 38.231, 52.434, 64.976, 74.209: at most 0.05 % under), and the published curve within
    0.6 + 2 % of it: 0.6 twice the +-0.3 of reading the plot, 2 % an allowance for the paper's slicing method,
    whose slice thickness is not printed (largest gap 0.98 at 40 deg, 2.5 %, against 1.38 allowed). The box's top is
    z = 8; the next test takes z = 7.5."""
    fig = MW["figure_9"]
    tol = fig["tolerance"]
    p = MW["normalized_platform"]
    design = _mw_design()
    for deg, published in zip(fig["joint_limit_deg"], fig["volume"], strict=True):
        twin = masory_wang_level_volume(p["platform_radius"], p["base_radius"], design["platform_half_angle"],
                                        design["base_half_angle"], *p["leg_length"], math.radians(deg))
        cfg = load_config(ROOT / "configs" / "hexapod.yaml", [
            *(f"design.{k}={v!r}" for k, v in design.items()),
            f"options.leg_length={p['leg_length']}", f"options.cone_limit={math.radians(deg)!r}",
            "options.orientation=[0.0, 0.0, 0.0]", "grid.region.z=[0.0, 8.0]", "grid.tolerance.volume=0.002"])
        ours = evaluate_config(cfg).measure
        assert ours == pytest.approx(twin, rel=0.002), deg
        allowed = tol["absolute"] + tol["relative"] * published
        assert abs(ours - published) <= allowed, deg
        assert abs(twin - published) <= allowed, deg


def test_masory_and_wang_at_40_deg_in_the_box_up_to_lmax():
    """The same case as above at 40 deg with the box's top at Lmax = 7.5 (the natural bound; the workspace's top is
    at 7.22) meets the volume tolerance asked, 0.2 %, against the twin (38.231): measured 38.221. With one
    z-confirmation per ladder rung it gave 38.082, 0.39 % under, its estimate 0.06 %: the rim wedge (z 5.63-5.83)
    lay between two z-nodes on the first three rungs, which agreed on the miss (scalesynth.calibration,
    NODE_ZCONFIRM)."""
    p = MW["normalized_platform"]
    design = _mw_design()
    cfg = load_config(ROOT / "configs" / "hexapod.yaml", [
        *(f"design.{k}={v!r}" for k, v in design.items()),
        f"options.leg_length={p['leg_length']}", f"options.cone_limit={math.radians(40.0)!r}",
        "options.orientation=[0.0, 0.0, 0.0]", "grid.region.z=[0.0, 7.5]", "grid.tolerance.volume=0.002"])
    twin = masory_wang_level_volume(p["platform_radius"], p["base_radius"], design["platform_half_angle"],
                                    design["base_half_angle"], *p["leg_length"], math.radians(40.0))
    assert evaluate_config(cfg).measure == pytest.approx(twin, rel=0.002)


def _ren_group(g):
    row = next(r for r in REN["groups"]["rows"] if r[0] == g)
    return dict(zip(REN["groups"]["columns"], row, strict=True))


def _ren_config(row, overrides=()):
    lo, hi = (math.radians(v) for v in REN["conventions"]["theta_limits_deg"])
    return load_config(ROOT / "configs" / "delta.yaml", [
        f"design.upper_arm={row['L_mm'] / 1000}", f"design.forearm={row['l_mm'] / 1000}",
        f"design.base_radius={row['R_mm'] / 1000}", f"design.platform_radius={row['r_mm'] / 1000}",
        f"options.theta_limits=[{lo!r}, {hi!r}]",
        f"grid.region.z=[-0.8, {REN['conventions']['z_max_mm'] / 1000}]", *overrides])


@pytest.mark.parametrize("group", [7, 8])
def test_ren_deltas_layout_and_twin(group):
    """Groups 7 and 8 of Ren, Zheng and Wang's Table 2 (group 7: the largest gap to the printed volume, +82 %; group
    8: the design they chose). The built-in delta's elbows-out arm angles equal those of their eq. (6)-(10)
    (tests/naive_delta.py ren_thetas) at random reachable points, to 1e-9 rad: the same layout and theta; and its
    volume (theta in [-15, 90] deg, z <= 0, the adaptive evaluator at 0.2 %) equals the twin's on a 5 mm grid within
    0.6 % (the evaluator's 0.2 % plus the grid's count error; measured 4.0171 vs 4.0210 and 9.1309 vs 9.1302 x 10^7
    mm^3). Table 2's own volumes (2.21 and 8.37 x 10^7 mm^3) are recorded in the data file, not asserted: their
    'reachable point density method' is not specified enough to reproduce (scalesynth's volumes are 7-10 % above
    theirs on eight groups, 82 % above on group 7)."""
    row = _ren_group(group)
    L, l, R, r = (row[k] / 1000 for k in ("L_mm", "l_mm", "R_mm", "r_mm"))
    limits = [math.radians(v) for v in REN["conventions"]["theta_limits_deg"]]
    cfg = _ren_config(row, ["grid.tolerance.volume=0.002"])
    mech = cfg.mech
    design, options = mech.resolve_design(cfg.resolved_design()), cfg.resolved_options()
    rng = np.random.default_rng(28)
    checked = 0
    while checked < 20:
        p = rng.uniform([-0.4, -0.4, -(L + l)], [0.4, 0.4, 0.0])
        th, ok = ren_thetas(L, l, R, r, *p)
        if not ok or np.any(th < limits[0]) or np.any(th > limits[1]):
            continue
        q = {s.label: s.values for s in mech.inverse_kinematics(design, options, p)}
        np.testing.assert_allclose(q["out/out/out"], th, rtol=0, atol=1e-9)
        checked += 1
    twin = ren_volume(L, l, R, r, limits, 0.005, REN["conventions"]["z_max_mm"] / 1000)
    assert evaluate_config(cfg).measure == pytest.approx(twin, rel=0.006)


def test_ren_group8_largest_horizontal_section():
    """Group 8's largest horizontal section, published as 403 321 mm^2 at z = -325 mm (p. 10, Fig. 10): the built-in
    delta's reachable cells on 2 mm plane grids every 0.5 mm from z = -350 to -320 mm (the field kernel) peak at
    about 400 600 mm^2 at z = -335.5 mm (0.7 % under). Allowances (tests/data/delta_ren_2026.json): 1.3 % on the area
    (half the paper's 1.05 deg arm step, 2.3 mm at the elbow, along the section's perimeter) and 13.7 mm on the
    height (three such elbow steps). Above its peak the section shrinks fast (329 000 mm^2 at -325 mm), so the
    peak's height is what is compared."""
    pub = REN["group8_largest_section"]
    tol = pub["tolerance"]
    cfg = _ren_config(_ren_group(8))
    mech = cfg.mech
    packed = mech.pack(mech.resolve_design(cfg.resolved_design()), cfg.resolved_options())
    h, half = 0.002, 0.4
    n = int(round(2 * half / h))

    def area(z):
        cells = kgrid.sample_fields(mech.field_kernel, mech.n_fields, packed, np.array([-half, -half, z - 0.5 * h]),
                                    np.array([h, h, h]), np.array([n, n, 1], dtype=np.int64))
        assert not (cells[0, :, 0, 0] >= 0).any() and not (cells[:, 0, 0, 0] >= 0).any()  # the box holds it
        return float((cells[..., 0] >= 0).sum()) * h * h * 1e6  # mm^2

    zs = np.arange(-0.350, -0.3199, 0.0005)
    areas = [area(z) for z in zs]
    k = int(np.argmax(areas))
    assert 0 < k < len(zs) - 1  # an interior peak
    assert areas[k] == pytest.approx(pub["area_mm2"], rel=tol["area_relative"])
    assert abs(zs[k] * 1000 - pub["z_mm"]) <= tol["z_mm"]
