"""Mirror symmetries (Mechanism.mirror_axes) and the adaptive evaluator's half box (evaluate.mirror_halves).

A declared mirror axis a promises f(.., x_a, ..) = f(.., -x_a, ..) for every field and every design under those
options; the evaluator then computes only the half box x_a >= 0. These tests check each declaration at random
points of random designs, that the conditions the declarations name are needed (breaking one makes the fields
asymmetric and the declaration disappears), and that the half-box evaluation equals the full-box one.
"""

from __future__ import annotations

import numpy as np
import pytest

from scalesynth.evaluate import Tolerance, adaptive_population_stats, design_boxes
from scalesynth.kernels.grid import population_points_fields
from scalesynth.mechanisms import get

EDGES = np.array([0.0, 0.1, 0.3, 1.0])
# fields at mirror-image points agree to rounding: 1e-9 relative (every field is a closed form or a small SVD),
# except the stiffness fields (solves of stiffness matrices that are ill-conditioned near singular poses; the tool
# kernel adds a Newton solve to 1e-13): 1e-5 relative
REL = 1e-9
REL_STIFFNESS = 1e-5

# (mechanism, options, axes expected): the declarations under option sets that keep the symmetry
SYMMETRIC = [
    ("rps-upu", {}, (2,)),
    ("rps-upu", {"model": "C", "c3_variant": "plane", "link_radius": 7.0}, (2,)),
    ("rps-upu", {"model": "C", "c3_variant": "upu", "load": [30.0, 0.0, -100.0]}, (2,)),
    ("rps-upu-tool", {}, (1,)),
    ("rps-upu-tool", {"link_radius": {"leg1": 3.0, "leg2": 3.0, "leg3": 9.0}}, (1,)),
    ("ups-sspr", {}, (1,)),
    ("ups-sspr", {"l2_limits": [130.0, 200.0], "l3_limits": [130.0, 200.0], "load": [0.0, 40.0, -90.0]}, (1,)),
    ("2pauu-ppap", {}, (0, 1)),
    ("2pauu-ppap", {"mode": "--", "stroke_limits": [-0.5, 0.5], "theta1_limits": [-1.0, 1.2],
                    "theta2_limits": [-1.0, 1.2]}, (0, 1)),
    ("2pauu-ppap", {"mode": "+-"}, (1,)),
    ("planar-fivebar", {}, (0,)),
    ("planar-fivebar", {"mode": "-+", "forearm": "parallelogram"}, (0,)),
    ("planar-fivebar", {"alpha1_limits": [-4 * np.pi / 9, 7 * np.pi / 36],
                        "alpha2_limits": [29 * np.pi / 36, 13 * np.pi / 9]}, (0,)),
    # described: legs at 0, 120, 240 deg map onto themselves in y = 0 (describe/symmetry.py), not in x = 0
    ("delta", {}, (1,)),
    ("delta", {"theta_limits": [-0.6, 1.6], "cone_limit": 1.5}, (1,)),
    ("linear-delta", {}, (1,)),
    ("delta", {"stiffness_metrics": True}, (1,)),  # the per-voxel stiffness fields under the default load (-z)
]

# (mechanism, options, axis): one condition broken, so the axis is not declared and the fields are not symmetric
BROKEN = [
    ("rps-upu", {"load": [0.0, 50.0, -150.0]}, 2),
    ("rps-upu-tool", {"psi_range": [-0.2, 0.314]}, 1),
    ("ups-sspr", {"l3_limits": [120.0, 180.0]}, 1),
    ("ups-sspr", {"load": [60.0, 0.0, -150.0]}, 1),
    ("2pauu-ppap", {"mode": "+-"}, 0),
    ("2pauu-ppap", {"stroke_limits": [-0.3, 0.6]}, 1),
    ("2pauu-ppap", {"theta2_limits": [-1.0, 0.4]}, 0),
    ("planar-fivebar", {"mode": "++"}, 0),
    ("planar-fivebar", {"load": [80.0, -150.0]}, 0),
    ("planar-fivebar", {"alpha1_limits": [-4 * np.pi / 9, 7 * np.pi / 36]}, 0),
    ("delta", {"stiffness_metrics": True, "load": [0.0, 60.0, -150.0]}, 1),  # the deflection under a load across y = 0
]


def _designs(mech, rng, k=4):
    """The default design and k - 1 with every parameter scaled by a factor in [0.8, 1.2]."""
    base = mech.resolve_design({})
    out = [base]
    for _ in range(k - 1):
        out.append({n: v * rng.uniform(0.8, 1.2) for n, v in base.items()})
    return out


def _mirror_gap(name, options, axis, seed=0, n_points=3000):
    """Largest disagreement between the fields at random points of random designs' boxes and at their mirror
    images in ``axis``: (points whose reachability differs, worst relative field difference, the same for the
    stiffness fields, share of reachable points)."""
    mech = get(name)
    opts = mech.resolve_options(options)
    rng = np.random.default_rng(seed)
    ndim = len(mech.task_axes)
    stiff = [i for i, f in enumerate(mech.field_names) if f in ("stiffness_min", "deflection")]
    flips, worst, worst_stiff, reach_share = 0, 0.0, 0.0, []
    for design in _designs(mech, rng):
        lo, hi = mech.bounding_box(design, opts)
        half = max(abs(lo[axis]), abs(hi[axis]))
        lo, hi = lo.copy(), hi.copy()
        lo[axis], hi[axis] = -half, half
        pts = lo + rng.uniform(0.0, 1.0, (n_points, 3)) * (hi - lo)
        pts[:, ndim:] = 0.0
        mirrored = pts.copy()
        mirrored[:, axis] *= -1.0
        packed = mech.pack(design, opts)[None, :]
        f = population_points_fields(mech.field_kernel, mech.n_fields, packed, pts)[0]
        g = population_points_fields(mech.field_kernel, mech.n_fields, packed, mirrored)[0]
        reach = f[:, 0] >= 0.0
        flips += int(np.sum(reach != (g[:, 0] >= 0.0)))
        reach_share.append(reach.mean())
        if reach.any():
            scale = np.maximum(np.abs(f[reach]), np.abs(f[reach]).max(axis=0) * 1e-6 + 1e-300)
            rel = (np.abs(f - g)[reach] / scale).max(axis=0)
            plain = [i for i in range(mech.n_fields) if i not in stiff]
            worst = max(worst, float(rel[plain].max()))
            if stiff:
                worst_stiff = max(worst_stiff, float(rel[stiff].max()))
    return flips, worst, worst_stiff, float(np.mean(reach_share))


@pytest.mark.parametrize(("name", "options", "axes"), SYMMETRIC)
def test_declared_mirror_axes_are_symmetries(name, options, axes):
    mech = get(name)
    assert mech.mirror_axes(mech.resolve_options(options)) == axes
    for axis in axes:
        flips, worst, worst_stiff, reach = _mirror_gap(name, options, axis)
        assert 0.05 < reach < 0.95, "the sample must straddle the workspace boundary to test reachability"
        assert flips == 0
        assert worst <= REL
        assert worst_stiff <= REL_STIFFNESS


@pytest.mark.parametrize(("name", "options", "axis"), BROKEN)
def test_a_broken_condition_removes_the_axis_and_is_a_real_asymmetry(name, options, axis):
    mech = get(name)
    assert axis not in mech.mirror_axes(mech.resolve_options(options))
    flips, worst, worst_stiff, _ = _mirror_gap(name, options, axis)
    assert flips > 0 or worst > 1e-3 or worst_stiff > 1e-3


def _random_designs(mech, n, seed):
    rng = np.random.default_rng(seed)
    base = mech.resolve_design({})
    return [{k: v * rng.uniform(0.7, 1.3) for k, v in base.items()} for _ in range(n)]


def _full_and_half(name, axis, n, seed, intervals=True):
    """(mechanism, full-box result, half-box result) of the adaptive evaluator on n random designs whose boxes
    are symmetric on ``axis``, each with a non-empty workspace, at the same refinement levels."""
    mech = get(name)
    opts = mech.resolve_options({})
    designs = _random_designs(mech, n, seed)
    packed = np.stack([mech.pack(d, opts) for d in designs])
    full = adaptive_population_stats(mech, designs, opts, packed, Tolerance(), EDGES, mirror=False,
                                     intervals=intervals)
    half = adaptive_population_stats(mech, designs, opts, packed, Tolerance(), EDGES, intervals=intervals)
    lo, hi = design_boxes(mech, designs, opts)
    assert np.all(lo[:, axis] == -hi[:, axis])
    assert full.stats[:, 0].min() > 0.0
    assert np.array_equal(full.levels, half.levels)
    return mech, full, half


def test_half_box_on_the_column_axis_equals_the_full_box():
    """rps-upu's node plan (its columns along psi: the C-model's, here the P-model without intervals), mirror in psi
    (the column axis, 8 z-cells: the half box has 4 and the node at psi = 0): the same nodes and Gauss points to
    rounding, so every statistic matches the full box's to 1e-12 relative and the levels are equal; the kernel calls
    drop to about 5/9 of the nodes (measured 0.52x: 26 471 against 50 580 calls per design on seed 3 of the rps_upu
    bounds)."""
    mech, full, half = _full_and_half("rps-upu", 2, 6, 3, intervals=False)
    # count, LCI statistics and bands (what the refinement and the searched metrics read): 1e-12; every other
    # statistic to 1e-8 (measured: sigma_max's extremes 8e-12 and the stiffness fields' 1.8e-9, both from
    # near-singular poses where a rounding of the pose moves the value most)
    extensive = [0, 1, 2, *range(1 + 4 * mech.n_fields, full.stats.shape[1])]
    np.testing.assert_allclose(half.stats[:, extensive], full.stats[:, extensive], rtol=1e-12)
    # the LCI's min and max (in [0, 1]) to 1e-12 absolute, as on a cross axis: a minimum of 3.3e-7 differs by
    # 3e-17 (rounding of the mirrored pose near a singularity), 1e-10 relative
    np.testing.assert_allclose(half.stats[:, 3:5], full.stats[:, 3:5], rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(half.stats, full.stats, rtol=1e-8)
    np.testing.assert_allclose(half.error_volume, full.error_volume, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(half.error_gci, full.error_gci, rtol=1e-9, atol=1e-15)
    assert np.all(half.evaluations < 0.6 * full.evaluations)


@pytest.mark.parametrize(("name", "axis"), [("rps-upu-tool", 1), ("ups-sspr", 1), ("planar-fivebar", 0),
                                           ("rps-upu", 2), ("delta", 1)])
def test_half_box_on_a_cross_axis_equals_the_full_box(name, axis):
    """A mirror plane on a cross axis (kernels.adaptive's ``mirror``; the kernel's own tests check it against the
    NumPy twin): the mechanism's own plan on random designs, the half box (half the columns on that axis) against
    the full one; rps-upu (P-model): its z-columns (Mechanism.column_axis 0), psi a cross axis. Count and LCI
    statistics to 1e-12, the same levels, about half the calls (measured exactly half on the helper's 200 designs:
    the mirror plane takes no face columns)."""
    mech, full, half = _full_and_half(name, axis, 5, 4)
    extensive = [0, 1, 2, *range(1 + 4 * mech.n_fields, full.stats.shape[1])]
    np.testing.assert_allclose(half.stats[:, extensive], full.stats[:, extensive], rtol=1e-12)
    # the LCI's min and max (in [0, 1]) to 1e-12 absolute: a minimum of 8e-6 differs by 2e-16 (rps-upu-tool)
    np.testing.assert_allclose(half.stats[:, 3:5], full.stats[:, 3:5], rtol=0.0, atol=1e-12)
    # the stiffness fields: up to 1.9e-6 relative per ulp of the point near singular poses (the helper's
    # measurement on rps-upu-tool), so every statistic to 1e-5
    np.testing.assert_allclose(half.stats, full.stats, rtol=1e-5)
    assert np.all(half.evaluations <= 0.5 * full.evaluations + 1)


def test_reports_name_the_half_box_and_the_column_intervals():
    """evaluator_description (report.md, report.html, manifest.json) says what the config's design runs."""
    from pathlib import Path

    from scalesynth.config import load_config
    from scalesynth.evaluate import evaluator_description

    tool = Path(__file__).resolve().parents[1] / "configs" / "rps_upu_tool.yaml"
    assert evaluator_description(load_config(tool)) == ("tolerance volume 0.002, GCI 0.0005: adaptive evaluator (half "
                                                        "box of the mirror symmetry in y; column intervals)")
    free = load_config(tool, ["options.interference_free=true", "options.load=[0, 20, -150]"])
    assert evaluator_description(free) == "tolerance volume 0.002, GCI 0.0005: adaptive evaluator"
    rps = Path(__file__).resolve().parents[1] / "configs" / "rps_upu.yaml"
    assert evaluator_description(load_config(rps)) == ("tolerance volume 0.002, GCI 0.0005: adaptive evaluator (half "
                                                       "box of the mirror symmetry in psi; column intervals)")
    c_model = load_config(rps, ["options.model=C"])
    assert evaluator_description(c_model) == ("tolerance volume 0.002, GCI 0.0005: adaptive evaluator (half box of "
                                              "the mirror symmetry in psi)")
