"""Per-voxel fields of every mechanism: the Numba field kernels against their NumPy twins (tests/naive.py), and the
workspace/task statistics of every field against plain NumPy reductions of the same per-voxel values."""

import numpy as np
import pytest

from naive_delta import delta_fields, linear_delta_fields
from naive_sixdof import hexa_fields, hexapod_fields
from scalesynth.config import load_config
from scalesynth.evaluate import evaluate_config, make_grid
from scalesynth.kernels import grid as kgrid
from scalesynth.kernels.conditioning import SIGMA_CAP, sv_2x2, sv_3x3
from scalesynth.mechanisms import available, get
from scalesynth.metrics import option_set
from test_registry import config_for

from naive import (
    fivebar_fields,
    grid_nodes,
    pauu_fields,
    pprs_fields,
    rps_upu_fields,
    rps_upu_tool_fields,
    ups_sspr_fields,
)

TWINS = {
    "2pauu-ppap": pauu_fields,
    "delta": delta_fields,
    "hexa": hexa_fields,
    "hexapod": hexapod_fields,
    "linear-delta": linear_delta_fields,
    "planar-fivebar": lambda d, o, x, y, z: fivebar_fields(d, o, x, y),
    "planar-fivebar-described": lambda d, o, x, y, z: fivebar_fields(d, o, x, y),  # mode "+-", its legs' branches
    "pprs-rprs": pprs_fields,
    "rps-upu": rps_upu_fields,
    "rps-upu-tool": rps_upu_tool_fields,
    "ups-sspr": ups_sspr_fields,
}


def test_every_mechanism_has_a_twin_and_the_base_fields():
    assert set(TWINS) == set(available())
    for name in available():
        mech = get(name)
        assert mech.field_names[:3] == ("lci", "sigma_min", "sigma_max")
        assert len(set(mech.field_names)) == mech.n_fields
        assert all(f.unit and f.description for f in mech.fields)


@pytest.mark.parametrize("name", sorted(TWINS))
def test_field_kernel_matches_numpy_svd_twin(name):
    """LCI, sigma_min and sigma_max of the homogenised dx/dq at every node of a grid over the config's design,
    against NumPy's SVD of the twin's Jacobian (written independently from the spec)."""
    mech = get(name)
    cfg = load_config(config_for(name))
    design, options = cfg.resolved_design(), cfg.resolved_options()
    g = make_grid(mech, design, options, 41 if mech.planar else 11)
    fields = kgrid.sample_fields(mech.field_kernel, mech.n_fields, mech.pack(design, options), g.lo, g.step, g.shape)
    twin = TWINS[name](design, options, *grid_nodes(g.lo, g.step, g.shape))
    reach = fields[..., 0] >= 0
    assert np.array_equal(reach, twin[..., 0] >= 0)
    assert reach.sum() >= 20
    assert np.all(np.isfinite(fields))
    regular = reach & (fields[..., 0] > 1e-6)
    np.testing.assert_allclose(fields[regular][:, :3], twin[regular], rtol=1e-6)
    assert (fields[~reach][:, 1:] == 0).all()
    # sigma_min <= sigma_max and LCI = sigma_min / sigma_max where both are regular
    f = fields[regular]
    assert np.all(f[:, 1] <= f[:, 2] * (1 + 1e-12))
    np.testing.assert_allclose(f[:, 0], f[:, 1] / f[:, 2], rtol=1e-9)


@pytest.mark.parametrize("name", sorted(TWINS))
def test_field_statistics_equal_numpy_reductions(name):
    """mean/std/min/max of every field over the workspace and the cell measure, from the per-voxel arrays that
    WorkspaceReport keeps (keep_grid=True): the documented way to get every field per voxel."""
    cfg = load_config(config_for(name), ["grid.resolution=10"])
    rep = evaluate_config(cfg, keep_grid=True)
    mech = cfg.mech
    reach = rep.lci_grid >= 0
    assert reach.sum() == rep.metrics["voxels"] > 0
    options = cfg.resolved_options()
    for f in mech.fields:
        if not all(option_set(options, o) for o in f.needs_options):  # e.g. seed 000's clearance without link_radius
            assert not any(k.startswith((f"mean_{f.name}", f"min_{f.name}")) for k in rep.metrics), (name, f.name)
            continue
        v = rep.field(f.name)[reach]
        names = {"mean": "gci", "std": "fci", "min": "min_lci", "max": "max_lci"} if f.name == "lci" else None
        for stat, fn in (("mean", np.mean), ("std", np.std), ("min", np.min), ("max", np.max)):
            key = names[stat] if names else next(
                k for k in rep.metrics if k == f"{stat}_{f.name}" or k.startswith(f"{stat}_{f.name}_"))
            assert rep.metrics[key] == pytest.approx(fn(v), rel=1e-9, abs=1e-12), (name, key)
    with pytest.raises(KeyError, match="not a field"):
        rep.field("nope")


def test_closed_form_singular_values_match_svd():
    rng = np.random.default_rng(1)
    for _ in range(2000):
        a = rng.normal(size=(3, 3)) * rng.choice([1e-3, 1, 1e3], size=(3, 1))
        ref = np.linalg.svd(a, compute_uv=False)
        lci, smin, smax = sv_3x3(*a.ravel())
        assert smax == pytest.approx(ref[0], rel=1e-9)
        assert smin == pytest.approx(ref[-1], rel=1e-6, abs=1e-12 * ref[0])
        b = a[:2, :2]
        ref2 = np.linalg.svd(b, compute_uv=False)
        lci2, smin2, smax2 = sv_2x2(b[0, 0], b[0, 1], b[1, 0], b[1, 1])
        assert smax2 == pytest.approx(ref2[0], rel=1e-12)
        assert smin2 == pytest.approx(ref2[-1], rel=1e-9, abs=1e-14 * ref2[0])
    assert sv_3x3(*np.zeros(9)) == (0.0, 0.0, 0.0)
    assert sv_3x3(*np.eye(3).ravel() * 2.0) == (1.0, pytest.approx(2.0), pytest.approx(2.0))


def test_fivebar_resolution_is_sigma_max_times_actuator_resolution():
    """Seed 004: the largest output motion for arm increments of norm 1 mrad is sigma_max(J) x 1 mrad, J of the
    mechanism's NumPy Jacobian (mm/rad)."""
    mech = get("planar-fivebar")
    design, options = mech.default_design(), mech.resolve_options({})
    pose = (100.0, -900.0)
    q = {s.label: s.values for s in mech.inverse_kinematics(design, options, pose)}["+-"]
    j = mech.jacobians(design, options, pose, q)["J"]
    out = np.empty(mech.n_fields)
    mech.field_kernel(mech.pack(design, options), *pose, 0.0, out)
    assert out[2] == pytest.approx(np.linalg.svd(j, compute_uv=False)[0], rel=1e-9)
    angles = np.linspace(0, 2 * np.pi, 3601)
    worst = max(np.linalg.norm(j @ (1e-3 * np.array([np.cos(t), np.sin(t)]))) for t in angles)
    assert worst == pytest.approx(out[2] * 1e-3, rel=1e-6)
    assert out[2] < SIGMA_CAP
