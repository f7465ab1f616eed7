"""Shared tests over every registered mechanism: a new mechanism file is covered by these at once."""

from pathlib import Path

import numpy as np
import pytest
import yaml

from scalesynth.config import config_from_dict, load_config
from scalesynth.errors import InvalidParameter
from scalesynth.evaluate import evaluate_config, make_grid
from scalesynth.kernels import grid as kgrid
from scalesynth.mechanisms import available, get
from scalesynth.optimize import run
from scalesynth.validate_results import check_results

CONFIGS = Path(__file__).resolve().parents[1] / "configs"


def config_for(name: str) -> Path:
    """The config in configs/ for this mechanism (the first one, by file name)."""
    for path in sorted(CONFIGS.glob("*.yaml")):
        if yaml.safe_load(path.read_text()).get("mechanism") == name:
            return path
    raise AssertionError(f"no config in configs/ for mechanism {name}")


MECHS = available()


def test_registry_lists_every_seed_mechanism():
    assert {"2pauu-ppap", "planar-fivebar", "rps-upu", "ups-sspr", "pprs-rprs"} <= set(MECHS)
    # described mechanisms (the Delta) come from no seed paper: their seed is ''
    assert {get(m).seed for m in MECHS} - {""} == {"000", "001", "002", "003", "004"}


@pytest.mark.parametrize("name", MECHS)
def test_config_loads_and_evaluates_to_finite_metrics(name):
    cfg = load_config(config_for(name), ["grid.resolution=12"])
    rep = evaluate_config(cfg)
    assert rep.measure_key == get(name).measure_key(cfg.units.length)
    assert rep.metrics["voxels"] > 0 and rep.measure > 0
    assert all(np.isfinite(v) for v in rep.metrics.values())
    assert 0 < rep.gci <= 1 and rep.metrics["min_lci"] <= rep.gci <= rep.metrics["max_lci"]


def _reachable_points(name, k=12):
    mech = get(name)
    cfg = load_config(config_for(name))
    design, options = cfg.resolved_design(), cfg.resolved_options()
    g = make_grid(mech, design, options, 10)
    lci = kgrid.sample_grid(mech.point_kernel, mech.pack(design, options), g.lo, g.step, g.shape)
    idx = np.argwhere(lci >= 0)
    assert len(idx) > 0
    pick = idx[np.linspace(0, len(idx) - 1, min(k, len(idx))).astype(int)]
    ndim = len(mech.task_axes)
    pts = [tuple(float(g.lo[a] + (i[a] + 0.5) * g.step[a]) for a in range(ndim)) for i in pick]
    return mech, design, options, pts, [float(lci[tuple(i)]) for i in pick]


@pytest.mark.parametrize("name", MECHS)
def test_kernel_lci_equals_numpy_lci_of_its_branch(name):
    mech, design, options, pts, values = _reachable_points(name)
    branch = mech.kernel_branch(options)
    for pose, value in zip(pts, values, strict=True):
        sols = {s.label: s.values for s in mech.inverse_kinematics(design, options, pose)}
        assert branch in sols, f"{name}: kernel-reachable pose {pose} has no IK branch {branch}"
        assert mech.lci(design, options, pose, sols[branch]) == pytest.approx(value, rel=1e-6, abs=1e-9)


@pytest.mark.parametrize("name", MECHS)
def test_fk_of_ik_recovers_the_pose(name):
    mech, design, options, pts, _ = _reachable_points(name, k=5)
    branch = mech.kernel_branch(options)
    for pose in pts:
        q = {s.label: s.values for s in mech.inverse_kinematics(design, options, pose)}[branch]
        fk = mech.forward_kinematics(design, options, q)
        assert fk, f"{name}: no FK solution for the IK of {pose}"
        err = min(np.abs(np.asarray(s.values[: len(pose)]) - pose).max() for s in fk)
        assert err <= 1e-6 * max(1.0, np.abs(pose).max())


@pytest.mark.parametrize("name", MECHS)
def test_invalid_design_value_names_the_parameter(name):
    mech = get(name)
    p = next(p for p in mech.parameters if p.positive)
    with pytest.raises(InvalidParameter, match=f"design.{p.name}"):
        mech.resolve_design({p.name: -1.0})
    with pytest.raises(InvalidParameter, match=f"design.{p.name}"):
        mech.resolve_design({p.name: float("nan")})
    with pytest.raises(InvalidParameter, match="unknown parameter"):
        mech.resolve_design({"no_such_parameter": 1.0})


@pytest.mark.parametrize("name", MECHS)
def test_config_optimises(name, tmp_path):
    data = yaml.safe_load(config_for(name).read_text())
    data["grid"]["resolution"] = 8
    if data.get("task") is not None:
        data["task"]["resolution"] = 8
    data["algorithm"].update(pop_size=8, n_gen=2)
    res = run(config_from_dict(data), tmp_path, plots=False)
    assert res.manifest["status"] == "finished" and res.manifest["evaluations"] == 16
    assert check_results(tmp_path, require_report=False) == []
