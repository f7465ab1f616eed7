"""The per-voxel clearance field of described 3T and 6-DOF mechanisms (kernel.py / kernel6.py over the capsules
packed by bodies.capsules / capsules6, opt-in with options.clearance_metrics) against its slow, obviously correct
twin: the clearance the cycle computes, cycle.clearance.clearance (NumPy segment distances) of the mechanism's
link_geometry at the same pose, with the joint values of NumPy's inverse kinematics in the kernel's branch. Both
take the same capsules and pairs, so they agree to rounding (1e-9 of the link lengths stated here). Then the flag
and interference_free, and `evaluate` on configs/delta.yaml."""

import json

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from scalesynth.cli import app
from scalesynth.cycle.clearance import clearance
from scalesynth.mechanisms import get
from scalesynth.mechanisms.describe import bodies

from conftest import ROOT

DELTA, LINEAR, HEXA, HEXAPOD = get("delta"), get("linear-delta"), get("hexa"), get("hexapod")
SLOT = 5  # the clearance's field slot (checked in test_flags_and_interference_free)


def _case(mech, rng):
    """A random design near the defaults (x U(0.8, 1.25); 6-DOF x U(0.95, 1.05) and a random orientation within
    0.1 rad) and random capsule radii per group, large enough that some poses interfere."""
    sixdof = mech.motion == "6DOF"
    spread = (0.95, 1.05) if sixdof else (0.8, 1.25)
    d = {k: v * rng.uniform(*spread) for k, v in mech.default_design().items()}
    groups = set(map(bodies.group_of, bodies.body_names(mech._codes())))
    opts = {"clearance_metrics": True, "link_radius": {g: float(rng.uniform(0.005, 0.08)) for g in sorted(groups)}}
    if mech is DELTA:
        opts["theta_limits"] = [-0.5, 1.8]
    if sixdof:
        opts["orientation"] = list(rng.uniform(-0.1, 0.1, 3))
    return d, mech.resolve_options(opts)


def _reachable(mech, d, opts, rng, n):
    """n random platform centres of the bounding box that the field kernel finds reachable."""
    lo, hi = mech.bounding_box(d, opts)
    packed, out, pts = mech.pack(d, opts), np.zeros(mech.n_fields), []
    for _ in range(100000):
        p = rng.uniform(lo, hi)
        mech.field_kernel(packed, *p, out)
        if out[0] >= 0.0:
            pts.append(p)
            if len(pts) == n:
                return pts
    raise AssertionError("too few reachable points")


def _twin(mech, d, opts, pose):
    (q,) = [s.values for s in mech.inverse_kinematics(d, opts, pose) if s.label == mech.kernel_branch(opts)]
    return clearance(mech.link_geometry(d, opts, pose, q)).value


@pytest.mark.parametrize("mech, seed", [(DELTA, 1), (DELTA, 2), (LINEAR, 3), (HEXA, 4), (HEXAPOD, 5), (HEXAPOD, 6)])
def test_the_field_equals_the_cycle_clearance(mech, seed):
    rng = np.random.default_rng(seed)
    d, opts = _case(mech, rng)
    packed, out = mech.pack(d, opts), np.zeros(mech.n_fields)
    scale = max(d.values())
    values = []
    for pose in _reachable(mech, d, opts, rng, 8):
        mech.field_kernel(packed, *pose, out)
        ref = _twin(mech, d, opts, pose)
        assert np.isfinite(ref)
        assert out[SLOT] == pytest.approx(ref, rel=1e-9, abs=1e-9 * scale), pose
        values.append(ref)
    assert max(values) > min(values)  # the poses differ: a constant would not pass


def test_flags_and_interference_free():
    for mech in (DELTA, HEXAPOD):
        assert mech.field_names[SLOT] == "clearance"
        f = mech.fields[SLOT]
        assert f.unit == "{length}" and f.needs_options == ("clearance_metrics",)
    d = DELTA.default_design()
    pose = (0.1, -0.05, -1.0)
    on, off = np.zeros(6), np.zeros(6)
    DELTA.field_kernel(DELTA.pack(d, DELTA.resolve_options({"clearance_metrics": True})), *pose, on)
    DELTA.field_kernel(DELTA.pack(d, DELTA.resolve_options({})), *pose, off)
    assert off[SLOT] == 0.0 and np.array_equal(on[:SLOT], off[:SLOT]) and on[SLOT] > 0.0
    # the cycle reads the kernel's slot only where it is computed (else link_geometry per sample)
    assert DELTA.kernel_clearance(DELTA.resolve_options({"clearance_metrics": True}))
    assert not DELTA.kernel_clearance(DELTA.resolve_options({}))
    assert HEXAPOD.kernel_clearance(HEXAPOD.resolve_options({"interference_free": True}))
    # a fat platform capsule (it meets the upper arms and the base in about half the poses): interference_free keeps
    # exactly the reachable poses whose clearance is >= 0, in the field, LCI and reach kernels alike, and the column
    # intervals hand every column to nodes and bisection
    fat = DELTA.resolve_options({"theta_limits": [0.0, 1.6], "clearance_metrics": True,
                                 "link_radius": {"platform": 0.86}})
    free = DELTA.pack(d, DELTA.resolve_options({**fat, "interference_free": True}))
    plain, kept, rng = DELTA.pack(d, fat), [], np.random.default_rng(7)
    for pose in _reachable(DELTA, d, fat, rng, 40):
        out = np.zeros(6)
        DELTA.field_kernel(plain, *pose, out)
        gap = _twin(DELTA, d, fat, pose)
        assert out[SLOT] == pytest.approx(gap, abs=1e-12)
        for kernel in (DELTA.field_kernel, DELTA.lci_kernel, DELTA.reach_kernel):
            kernel(free, *pose, out)
            assert (out[0] >= 0.0) == (gap >= 0.0)
        kept.append(gap >= 0.0)
    assert 0 < sum(kept) < len(kept)  # both kinds of pose were met
    assert DELTA.interval_kernel(free, 0.0, 0.0, -2.0, -0.3, np.zeros((8, 2))) == -1
    # symmetry: alike legs keep the Delta's 60 degree sector and its y mirror; one thicker arm breaks both
    alike = DELTA.pack(d, DELTA.resolve_options({"clearance_metrics": True}))
    odd_opts = DELTA.resolve_options({"clearance_metrics": True, "link_radius": {"upper_arm2": 0.05}})
    odd = DELTA.pack(d, odd_opts)
    assert DELTA.sector_angle(alike[None, :]) == pytest.approx(np.pi / 3)
    assert DELTA.sector_angle(odd[None, :]) is None and DELTA.sector_angle(free[None, :]) is None
    assert DELTA.mirror_axes(DELTA.resolve_options({"clearance_metrics": True})) == (1,)
    assert DELTA.mirror_axes(odd_opts) == ()


def test_evaluate_reports_the_clearance_of_the_delta(tmp_path):
    """configs/delta.yaml with the clearance metric asked: the task box's worst clearance equals the twin's minimum
    over the same task points (the task grid's cell centres, all reachable)."""
    cfg = yaml.safe_load((ROOT / "configs" / "delta.yaml").read_text())
    cfg["options"]["clearance_metrics"] = True
    cfg["grid"] = {"region": {"z": [-2.5, -0.3]}, "resolution": 10}
    cfg["task"] = {"box": {"x": [-0.2, 0.2], "y": [-0.15, 0.15], "z": [-1.1, -0.9]}, "resolution": 3}
    cfg["constraints"] = [{"metric": "task_min_clearance", "min": 0.0}]
    cfg.pop("cycle")
    path = tmp_path / "c.yaml"
    path.write_text(yaml.safe_dump(cfg))
    out = CliRunner().invoke(app, ["evaluate", str(path), "--json"])
    assert out.exit_code == 0, out.output
    data = json.loads(out.output)
    metrics = data.get("metrics", data)
    d = {**DELTA.default_design(), **cfg["design"]}
    opts = DELTA.resolve_options(cfg["options"])
    # the task grid's cell centres (evaluation.grid.task_grid)
    axes = [lo + (np.arange(3) + 0.5) * (hi - lo) / 3 for lo, hi in (cfg["task"]["box"][a] for a in "xyz")]
    twin = min(_twin(DELTA, d, opts, np.array(p)) for p in np.stack(np.meshgrid(*axes), -1).reshape(-1, 3))
    assert metrics["task_min_clearance_m"] == pytest.approx(twin, rel=1e-9)
    # and a closed form: in this box the closest capsules are two legs' neighbouring forearm bars at their platform
    # ends, Q_1 + h n_1 = (r, h, .) and its neighbour Q_2 - h n_2 = Rz(120 deg) (r, -h) (r = platform_radius 0.2 m,
    # h = half the 0.1 m width; the bars spread apart towards the elbows), minus two forearm radii (0.01 m default):
    # 0.2964 - 0.02 = 0.2764 m at every pose of the box (the platform translates)
    r, h, c, s = 0.2, 0.05, np.cos(2 * np.pi / 3), np.sin(2 * np.pi / 3)
    closed = np.hypot(r - (r * c + h * s), h - (r * s - h * c)) - 2 * 0.01
    assert metrics["task_min_clearance_m"] == pytest.approx(closed, rel=1e-12)
    assert metrics["task_max_clearance_m"] == pytest.approx(closed, rel=1e-12)
    assert metrics["min_clearance_m"] <= metrics["task_min_clearance_m"]
    # without the flag the metric is refused in one line
    cfg["options"].pop("clearance_metrics")
    path.write_text(yaml.safe_dump(cfg))
    out = CliRunner().invoke(app, ["evaluate", str(path)])
    lines = out.output.strip().splitlines()
    assert out.exit_code == 2 and len(lines) == 1, out.output
    assert "task_min_clearance" in lines[0] and "options.clearance_metrics" in lines[0]
