"""Every number written is finite (issue 11 item 5). Inputs whose arithmetic would overflow are refused at
validation, naming the field: any number beyond mechanisms.base.MAX_MAGNITUDE = 1e12 (config units). At that
bound every mechanism still gives finite metrics, checked here for all parameters and range options at +-1e12."""

import json

import numpy as np
import pytest

from scalesynth.config import config_from_dict
from scalesynth.errors import ConfigError, InvalidParameter, InvalidPose
from scalesynth.evaluate import evaluate, evaluate_population
from scalesynth.mechanisms import available, get
from scalesynth.mechanisms.base import MAX_MAGNITUDE
from scalesynth.metrics import nullable_columns

from conftest import SMALL


def _widened_options(mech):
    """Each [lo, hi] option widened to [-1e12, 1e12] where the mechanism accepts it (else [0, 1e12], else kept)."""
    options = mech.resolve_options({})
    for key, value in list(options.items()):
        if isinstance(value, (list, tuple)) and len(value) == 2:
            for candidate in ([-MAX_MAGNITUDE, MAX_MAGNITUDE], [0.0, MAX_MAGNITUDE]):
                try:
                    mech.resolve_options({**options, key: candidate})
                except InvalidParameter:
                    continue
                options[key] = candidate
                break
    return mech.resolve_options(options)


@pytest.mark.parametrize("name", available())
def test_metrics_are_finite_at_the_magnitude_bound(name):
    mech = get(name)
    base = mech.resolve_design({})
    designs = [
        {k: MAX_MAGNITUDE for k in base},  # every parameter at the bound
        {**base, next(iter(base)): MAX_MAGNITUDE},  # one parameter at the bound
        {k: (v if v != 0 else 1.0) * 1e9 for k, v in base.items()},
    ]
    for options in (mech.resolve_options({}), _widened_options(mech)):
        metrics = evaluate_population(mech, designs, options, resolution=8)
        nullable = nullable_columns(mech, mech.default_length_unit, 3)  # statistics over nothing: NaN (issue 27)
        for key, values in metrics.items():
            arr = np.asarray(values, dtype=float)
            ok = np.isfinite(arr) | (np.isnan(arr) & (metrics["voxels"] == 0) if key in nullable else False)
            assert ok.all(), (name, key)
        report = evaluate(mech, designs[0], options, resolution=8).to_dict()
        json.dumps(report, allow_nan=False)  # strict JSON


@pytest.mark.parametrize("name", available())
def test_ik_of_a_pose_at_the_bound_has_no_branch(name):
    """A pose at the bound on the first task axis: no bogus branches (issue 11: --pose=1e308 gave four). Where
    the first axis is bounded by link lengths (x of 2pauu-ppap, planar-fivebar, pprs-rprs, the tool point) there
    is none; where it is not (z of rps-upu, reached by legs without stroke limits in IK; alpha of ups-sspr, an
    angle, so 1e12 rad is some angle in (-pi, pi]) the one branch is real: finite, its LCI in [0, 1]."""
    mech = get(name)
    design, options = mech.resolve_design({}), mech.resolve_options({})
    pose = [MAX_MAGNITUDE] + [0.0] * (len(mech.task_axes) - 1)
    sols = mech.inverse_kinematics(design, options, pose)
    if name in ("2pauu-ppap", "planar-fivebar", "pprs-rprs", "rps-upu-tool"):
        assert sols == []
    for sol in sols:
        assert np.isfinite(sol.values).all()
        assert 0.0 <= mech.lci(design, options, pose, sol.values) <= 1.0
    with pytest.raises(InvalidPose, match="beyond"):
        mech.check_vector("--pose", [1e13] + [0.0] * (len(mech.task_axes) - 1), len(mech.task_axes))


@pytest.mark.parametrize(("changes", "field"), [
    ({"design": {**SMALL["design"], "l1": 1e300}}, "design.l1: 1e+300 is beyond"),
    ({"bounds": {**SMALL["bounds"], "l1": [0.5, 1e308]}}, "bounds.l1: 1e+308 is beyond"),
    ({"bounds": {**SMALL["bounds"], "c": [0.1, 1.1e12]}}, "bounds.c: 1.1e+12 is beyond"),
    ({"grid": {"resolution": 12, "region": {"x": [-1e308, 1e308]}}}, "grid.region.x: -1e+308 is beyond"),
    ({"options": {"e": 1e200}}, "options.e: 1e+200 is beyond"),
    ({"options": {"stroke_limits": [-1e300, 1e300]}}, "options.stroke_limits[0]: -1e+300 is beyond"),
    ({"references": {"r": {"l2": 1e155}}}, "references.r: design.l2: 1e+155 is beyond"),
])
def test_overflowing_inputs_are_refused_naming_the_field(changes, field):
    with pytest.raises(ConfigError) as err:
        config_from_dict({**SMALL, **changes})
    assert field in str(err.value)


def test_other_mechanisms_overflowing_inputs():
    fivebar = {"name": "f", "mechanism": "planar-fivebar", "design": {"l1": 1e155}}
    with pytest.raises(ConfigError, match=r"design\.l1: 1e\+155 is beyond"):
        config_from_dict(fivebar)
    rps = {"name": "r", "mechanism": "rps-upu", "options": {"z_range": [-1e308, 1e308]}}
    with pytest.raises(ConfigError, match=r"options\.z_range\[0\]: -1e\+308 is beyond"):
        config_from_dict(rps)


def test_a_value_at_the_bound_is_accepted():
    cfg = config_from_dict({**SMALL, "bounds": {**SMALL["bounds"], "l1": [0.5, MAX_MAGNITUDE]}})
    assert cfg.bounds["l1"] == (0.5, MAX_MAGNITUDE)
