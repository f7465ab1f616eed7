"""Per-voxel stiffness fields of the described mechanisms (the stiffness stages of describe/kernel.py and
kernel6.py, opt-in with options.stiffness_metrics) against their slow, obviously correct twin: the per-pose stiffness
frame of the same description (describe/frame.py, frame6.py) solved by the NumPy reference solver
(stiffness/solve.py), itself checked against PyNite in test_delta_stiffness.py and test_sixdof_stiffness.py. Both are
the same idealisation (ideal joints), so they agree to rounding: 1e-6 relative is the bound stated here (measured:
about 1e-12, 2e-9 and 4e-9 for stiffness_min of the linear Delta and the hexapod on their axes, where two
eigenvalues are equal). Then: the flag off leaves the fields 0 and the LCI kernel bit for bit;
the catalogue refuses their metrics without the flag; `evaluate` and the design command use them."""

import json
import math

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from scalesynth.cli import app
from scalesynth.evaluate import make_grid
from scalesynth.kernels import grid as kgrid
from scalesynth.mechanisms import get
from scalesynth.stiffness.legs import DEFLECTION_CAP
from scalesynth.stiffness.solve import solve

from conftest import ROOT

RTOL = 1e-6  # the kernel and the reference solver condense the same frame: agreement to rounding
DELTA, LINEAR, HEXA, HEXAPOD = get("delta"), get("linear-delta"), get("hexa"), get("hexapod")


def _random_case(mech, rng):
    """A random design near the defaults (each parameter x U(0.8, 1.25); 6-DOF x U(0.95, 1.05) and a random
    orientation within 0.1 rad), random sections of the thinnest link group, actuator and load."""
    sixdof = mech.motion == "6DOF"
    spread = (0.95, 1.05) if sixdof else (0.8, 1.25)
    d = {k: v * rng.uniform(*spread) for k, v in mech.default_design().items()}
    group = {"delta": "forearm", "linear-delta": "forearm", "hexa": "rod", "hexapod": "leg"}[mech.name]
    opts = {"stiffness_metrics": True, "load": list(rng.normal(0.0, 60.0, 3)),
            "sections": {group: [0.03, float(rng.uniform(0.001, 0.004))]},
            "actuator_stiffness": mech.resolve_options({})["actuator_stiffness"] * rng.uniform(0.3, 3.0)}
    if mech is DELTA:
        opts["theta_limits"] = [-0.5, 1.8]
    if sixdof:
        opts["orientation"] = list(rng.uniform(-0.1, 0.1, 3))
    return d, mech.resolve_options(opts)


def _reachable_points(mech, d, opts, rng, n=4):
    g = make_grid(mech, d, opts, 9)
    f = kgrid.sample_fields(mech.field_kernel, mech.n_fields, mech.pack(d, opts), g.lo, g.step, g.shape)
    idx = np.argwhere(f[..., 0] > 1e-3)
    assert len(idx) >= n
    pick = idx[rng.choice(len(idx), n, replace=False)]
    return [tuple(g.lo + (i + 0.5) * g.step) for i in pick]  # the grid's nodes are cell centres


@pytest.mark.parametrize("mech, seed", [(DELTA, 1), (DELTA, 2), (DELTA, 3), (LINEAR, 4), (LINEAR, 5), (HEXA, 6),
                                        (HEXA, 7), (HEXAPOD, 8), (HEXAPOD, 9)])
def test_the_kernel_equals_the_frame_solved_per_pose(mech, seed):
    rng = np.random.default_rng(seed)
    d, opts = _random_case(mech, rng)
    p = mech.pack(d, opts)
    out = np.zeros(mech.n_fields)
    slots = mech.field_names.index("stiffness_min"), mech.field_names.index("deflection")
    for pose in _reachable_points(mech, d, opts, rng):
        mech.field_kernel(p, *pose, out)
        ref = solve(mech.stiffness_model(d, opts, pose))
        assert not ref.singular
        assert out[slots[0]] == pytest.approx(ref.stiffness_min, rel=RTOL), pose
        assert out[slots[1]] == pytest.approx(ref.deflection_norm, rel=RTOL), pose


def test_field_layout_and_the_flag():
    for mech in (DELTA, LINEAR, HEXA, HEXAPOD):
        assert mech.field_names == ("lci", "sigma_min", "sigma_max", "stiffness_min", "deflection", "clearance")
        f = {fd.name: fd for fd in mech.fields}
        assert f["stiffness_min"].unit == "N/{length}" and f["deflection"].unit == "{length}"
        assert f["deflection"].needs_options == ("stiffness_metrics",)
    d = DELTA.default_design()
    pose = (0.1, -0.05, -1.0)
    on, off, lci = np.zeros(6), np.zeros(6), np.full(6, 7.0)
    DELTA.field_kernel(DELTA.pack(d, DELTA.resolve_options({"stiffness_metrics": True})), *pose, on)
    DELTA.field_kernel(DELTA.pack(d, DELTA.resolve_options({})), *pose, off)
    DELTA.lci_kernel(DELTA.pack(d, DELTA.resolve_options({"stiffness_metrics": True})), *pose, lci)
    assert on[3] > 0.0 and 0.0 < on[4] < DEFLECTION_CAP
    assert off[3] == 0.0 and off[4] == 0.0 and np.array_equal(on[:3], off[:3])
    assert lci[0] == on[0] and lci[3] == 7.0  # the LCI kernel skips the stiffness stage
    d6 = HEXAPOD.default_design()
    on6, lci6 = np.zeros(6), np.full(6, 7.0)
    p6 = HEXAPOD.pack(d6, HEXAPOD.resolve_options({"stiffness_metrics": True}))
    HEXAPOD.field_kernel(p6, 0.05, 0.0, 0.75, on6)
    HEXAPOD.lci_kernel(p6, 0.05, 0.0, 0.75, lci6)
    assert on6[3] > 0.0 and lci6[0] == on6[0] > 0.0 and lci6[3] == 7.0


def test_no_load_no_deflection_and_the_load_is_linear():
    d = DELTA.default_design()
    pose = (0.2, 0.1, -0.9)
    vals = {}
    for key, load in (("zero", [0.0, 0.0, 0.0]), ("a", [10.0, 0.0, -150.0]), ("2a", [20.0, 0.0, -300.0])):
        out = np.zeros(6)
        DELTA.field_kernel(DELTA.pack(d, DELTA.resolve_options({"stiffness_metrics": True, "load": load})), *pose, out)
        vals[key] = out
    assert vals["zero"][4] == 0.0 and vals["zero"][3] == vals["a"][3]
    assert vals["2a"][4] == pytest.approx(2.0 * vals["a"][4], rel=1e-12)


def test_a_singular_platform_is_capped_never_nan():
    """platform_radius = base_radius + upper_arm cos 60 deg: with every arm at 60 deg each elbow lies straight above
    its platform joint, so the three forearms are vertical and parallel (a forward singularity: the platform
    translates sideways freely). The reference solver finds the frame singular; the kernel writes (0, cap)."""
    d0 = DELTA.default_design()
    d = {**d0, "platform_radius": d0["base_radius"] + d0["upper_arm"] * math.cos(math.pi / 3)}
    opts = DELTA.resolve_options({"stiffness_metrics": True})
    pose = (0.0, 0.0, -d0["upper_arm"] * math.sin(math.pi / 3) - d0["forearm"])
    out = np.zeros(6)
    DELTA.field_kernel(DELTA.pack(d, opts), *pose, out)
    assert solve(DELTA.stiffness_model(d, opts, pose)).singular
    assert out[0] == 0.0 and out[3] == 0.0 and out[4] == DEFLECTION_CAP


def _config(tmp_path, **options):
    cfg = yaml.safe_load((ROOT / "configs" / "delta.yaml").read_text())
    cfg["options"].update(options)
    cfg["grid"] = {"region": {"z": [-2.5, -0.3]}, "resolution": 12}
    cfg["task"] = {"box": {"x": [-0.2, 0.2], "y": [-0.15, 0.15], "z": [-1.1, -0.9]}, "resolution": 4}
    cfg["constraints"] = [{"metric": "task_max_deflection", "max": 0.01}]
    cfg.pop("cycle")
    path = tmp_path / "c.yaml"
    path.write_text(yaml.safe_dump(cfg))
    return path


def test_evaluate_reports_the_deflection_metrics(tmp_path):
    out = CliRunner().invoke(app, ["evaluate", str(_config(tmp_path, stiffness_metrics=True)), "--json"])
    assert out.exit_code == 0, out.output
    data = json.loads(out.output)
    metrics = data.get("metrics", data)
    # the task box lies on the central axis' side of the default Delta: its worst deflection under 150 N is a few
    # mm (the per-pose frame gives 4.05 mm at (0, 0, -1), test above), well below the cap
    assert 1e-3 < metrics["task_max_deflection_m"] < 0.01
    assert metrics["max_deflection_m"] >= metrics["task_max_deflection_m"]
    assert metrics["task_min_stiffness_min_N_per_m"] > 0.0


def test_a_deflection_metric_without_the_flag_is_one_line(tmp_path):
    out = CliRunner().invoke(app, ["evaluate", str(_config(tmp_path))])
    lines = out.output.strip().splitlines()
    assert out.exit_code == 2 and len(lines) == 1, out.output
    assert "task_max_deflection" in lines[0] and "options.stiffness_metrics" in lines[0]


def test_the_design_command_constrains_the_delta_deflection():
    """The case packer's spec states a deflection: the Delta's candidate config switches the stiffness fields on and
    constrains task_max_deflection (before, its comparison said the Delta had no per-voxel stiffness field)."""
    from scalesynth.design.sizing import build
    from scalesynth.design.spec import load_spec

    spec = load_spec(ROOT / "examples" / "case_packer.yaml")
    cand = build("delta", spec)
    assert cand.config["options"]["stiffness_metrics"] is True
    (con,) = [c for c in cand.config["constraints"] if c["metric"] == "task_max_deflection"]
    assert con["max"] == pytest.approx(spec.stiffness.max_deflection * 1e-3)  # spec in mm, the Delta in m
