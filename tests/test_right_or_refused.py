"""Issue 27, "Right or refused": no silently wrong numbers.

- A length unit other than the mechanism's own is refused (nothing converts lengths, so it would only relabel).
- A statistic over an empty set is null (NaN in memory, null in JSON, an empty CSV cell) and the worst value where
  it is an objective or constraint, never 0 read as best.
- Actuator peaks never mix revolute (rad/s, N m) and prismatic (length/s, N) actuators.
- pprs-rprs' grid box follows from its parameters: no hidden +-300 x +-300 x 0-500 mm clipping box.
"""

import json
import math
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

from scalesynth import io as rio
from scalesynth.api import evaluate
from scalesynth.config import config_from_dict, dump_config, load_config
from scalesynth.errors import ConfigError, ScalesynthError
from scalesynth.evaluate import evaluate_config
from scalesynth.mechanisms import get
from scalesynth.metrics import catalogue
from scalesynth.problem import SynthesisProblem

from conftest import ROOT

QUICK = ROOT / "configs" / "quick.yaml"  # 2pauu-ppap, lengths in m
STIFF = ROOT / "configs" / "fivebar_stiffness.yaml"  # planar-fivebar, lengths in mm, deflection field


# ----- length units ------------------------------------------------------------------------------------------------
def test_a_length_unit_that_is_not_the_mechanisms_is_refused_in_config_api_and_cli():
    """Old code took `units.length: mm` on 2pauu-ppap (lengths in m) and wrote volume_mm3 for a volume in m^3."""
    with pytest.raises(ConfigError, match=r"^units\.length: 2pauu-ppap computes in m, not 'mm'"):
        load_config(QUICK, ["units.length=mm"])
    with pytest.raises(ScalesynthError, match=r"^length_unit: planar-fivebar computes in mm, not 'm'"):
        evaluate("planar-fivebar", {}, length_unit="m", resolution=4)
    r = subprocess.run([sys.executable, "-m", "scalesynth", "evaluate", str(QUICK), "--set", "units.length=cm"],
                       capture_output=True, text=True, timeout=300, stdin=subprocess.DEVNULL)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1 and "units.length" in lines[0] and len(lines[0]) <= 200, r.stderr


def test_a_config_without_units_names_the_mechanisms_own_unit():
    """Old code defaulted units.length to m, so a five-bar config without `units` (lengths in mm) wrote area_m2."""
    cfg = config_from_dict({"name": "t", "mechanism": "planar-fivebar"})
    assert cfg.units.length == "mm"
    assert cfg.mech.measure_key(cfg.units.length) == "area_mm2"
    assert "units:\n  length: mm" in dump_config(cfg)


# ----- statistics over an empty set --------------------------------------------------------------------------------
def _unreachable_task(extra: list[str] | None = None):
    """fivebar_stiffness with its task box moved far out of reach (reach l1 + l2 - r = 1150 mm < 5000 mm), on
    coarse uniform grids."""
    return load_config(STIFF, ["grid={resolution: 8}", "task.box={x: [5000, 5100], y: [5000, 5100]}",
                               "task.resolution=4", "task.path=null", "constraints=[]", *(extra or [])])


def test_task_statistics_over_an_unreachable_box_are_null_in_json_and_empty_in_csv(tmp_path):
    cfg = _unreachable_task()
    rep = evaluate_config(cfg)
    m = rep.metrics
    assert m["task_coverage"] == 0.0  # nothing of the box is reachable
    stats = [c for c in m if c.startswith("task_") and c not in ("task_coverage", "task_gci")]  # every statistic
    assert "task_max_deflection_mm" in stats and "task_fci" in stats and "task_min_lci" in stats
    for col in stats:
        assert math.isnan(m[col]), col  # old code: 0.0, the best value of a minimised deflection
    assert m["task_gci"] == 0.0  # the GCI of an empty set: 0 by convention (the worst LCI)
    out = json.loads(json.dumps(rep.to_dict(), allow_nan=False))  # valid JSON: null, never NaN
    assert out["task_max_deflection_mm"] is None and out["task_coverage"] == 0.0
    path = tmp_path / "t.csv"
    rio.write_csv(path, pd.DataFrame({"task_coverage": [0.0], "task_max_deflection_mm": [m["task_max_deflection_mm"]]}))
    assert path.read_text().splitlines()[1] == "0,"  # the empty cell
    back = rio.read_results_csv(path, ["task_max_deflection_mm"], {"task_max_deflection_mm"})
    assert math.isnan(back["task_max_deflection_mm"][0])
    with pytest.raises(ConfigError, match="not a finite number"):  # an empty cell in a column that has no null
        rio.read_results_csv(path, ["task_max_deflection_mm"])


def test_an_empty_workspace_gives_null_statistics_but_gci_0():
    """l1 + l2 < r: an empty lens. fci (the LCI's standard deviation, better low) was 0, the best value."""
    rep = evaluate("planar-fivebar", {"r": 500.0, "l1": 100.0, "l2": 100.0}, resolution=8)
    m = rep.metrics
    assert m["area_mm2"] == 0.0 and m["voxels"] == 0 and m["gci"] == 0.0
    for col in ("fci", "min_lci", "max_lci", "band0_share", "min_sigma_max_mm_per_rad"):
        assert math.isnan(m[col]), col


def test_a_statistic_over_an_empty_set_is_the_worst_objective_and_violates_every_constraint():
    """The search of issue 27 minimised task_max_deflection and drifted to designs that cover nothing; now an
    empty task set gets the objective's hypervolume reference (its worst value) and violates the constraint."""
    cfg = _unreachable_task(["objectives=[{metric: task_max_deflection, sense: min}, {metric: task_coverage}]",
                             "constraints=[{metric: task_max_deflection, max: 0.5}, {metric: task_min_lci, min: 0}]",
                             "bounds={r: [50, 400], l1: [250, 800], l2: [500, 1400]}"])
    problem = SynthesisProblem(cfg)
    X = np.array([[200.0, 475.0, 875.0]])
    out = {}
    problem._evaluate(X, out)
    worst = problem.hv_reference()
    entry = catalogue(cfg.mech, "mm")["task_max_deflection"]
    assert worst[0] == entry.worst and math.isfinite(entry.worst)  # the catalogue's worst deflection
    np.testing.assert_array_equal(out["F"][0], [entry.worst, 0.0])  # old code: F = [0, 0], the best deflection
    assert np.all(out["G"][0] >= 1.0)  # old code: 0 <= 0.5 and 0 >= 0 were both satisfied
    assert math.isnan(out["M"][0, problem.metric_columns.index("task_max_deflection_mm")])  # results: null


# ----- actuator peaks per kind -------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["pprs-rprs", "2pauu-ppap"])
def test_mixed_actuator_peaks_are_per_kind_with_one_unit_each(name):
    mech = get(name)
    cat = catalogue(mech)
    lu = mech.default_length_unit
    for peak, (rev, pri) in {"speed": ("rad/s", f"{lu}/s"), "accel": ("rad/s^2", f"{lu}/s^2"),
                             "force": ("N m", "N")}.items():
        plain = f"cycle_max_actuator_{peak}"
        assert plain not in cat  # old code: one entry, the maximum over rad/s and length/s together
        assert cat[f"{plain}_revolute"].unit == rev and cat[f"{plain}_prismatic"].unit == pri


def test_the_old_mixed_name_is_refused_with_did_you_mean():
    with pytest.raises(ConfigError) as err:
        load_config(ROOT / "configs" / "pprs_rprs.yaml",
                    ["objectives=[{metric: cycle_max_actuator_force, sense: min}]"])
    msg = str(err.value)
    assert msg.startswith("objectives[0].metric: cycle_max_actuator_force mixes units on pprs-rprs")
    assert "did you mean cycle_max_actuator_force_revolute or cycle_max_actuator_force_prismatic" in msg
    assert len(msg) <= 200


def test_a_single_kind_mechanism_keeps_the_plain_names():
    cat = catalogue(get("planar-fivebar"))  # two revolute actuators
    assert cat["cycle_max_actuator_speed"].unit == "rad/s" and "cycle_max_actuator_speed_revolute" not in cat


def test_peaks_are_taken_over_the_actuators_of_their_kind_only():
    """2pauu-ppap: theta1, theta2 revolute, d prismatic; a prismatic speed of 300 m/s must not be the revolute
    peak (old code: one maximum, 300)."""
    from scalesynth.cycle import analysis

    qd = np.array([[[1.0, -2.0, 300.0], [0.5, 1.5, -20.0]]])
    qdd = np.array([[[7.0, 0.0, 1.0], [0.0, -3.0, 2.0]]])
    force = np.array([[[4.0, 5.0, -900.0], [6.0, 0.0, 10.0]]])
    got = analysis.actuator_peaks(get("2pauu-ppap").joint_units, qd, qdd, force)
    assert got == {"cycle_max_actuator_speed_revolute": [2.0], "cycle_max_actuator_speed_prismatic": [300.0],
                   "cycle_max_actuator_accel_revolute": [7.0], "cycle_max_actuator_accel_prismatic": [2.0],
                   "cycle_max_actuator_force_revolute": [6.0], "cycle_max_actuator_force_prismatic": [900.0]}


# ----- no hidden clipping box ---------------------------------------------------------------------------------------
def test_pprs_rprs_box_holds_a_workspace_beyond_the_old_spec_box():
    """Sliders raised by 500 mm put the whole workspace above z = 500 mm, where the old hidden box cut it to
    nothing (volume 0). The box must come from the parameters and hold every reachable cell of a wider grid."""
    mech = get("pprs-rprs")
    options = {"s_limits": [537.5, 637.5]}
    design, opts = mech.resolve_design({}), mech.resolve_options(options)
    lo, hi = mech.bounding_box(design, opts)
    assert lo[2] >= 537.5 > 500.0 and np.all(hi > lo)
    rep = evaluate(mech, {}, options, resolution=8)
    assert rep.measure > 0.0  # old code: 0
    pad = 0.25 * (hi - lo)
    region = {a: [float(lo[i] - pad[i]), float(hi[i] + pad[i])] for i, a in enumerate(mech.task_axes)}
    wide = evaluate(mech, {}, options, resolution=12, region=region, keep_grid=True)
    reach = wide.lci_grid >= 0
    assert reach.any()
    for i in range(3):
        centres = wide.grid.axis(i)
        idx = np.nonzero(reach.any(axis=tuple(j for j in range(3) if j != i)))[0]
        assert centres[idx].min() >= lo[i] and centres[idx].max() <= hi[i], mech.task_axes[i]
