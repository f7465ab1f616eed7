"""A description's calibrated evaluation plans (the ``evaluation`` block, docs/describing.md): the rotary Delta's
plan meets its tolerance against a finer uniform grid, the plan is chosen by tolerance (tighter ones run the
per-design ladder of scalesynth.calibration), and a wrong block is one line naming the field, exit 2."""

import numpy as np
import pytest
from typer.testing import CliRunner

from scalesynth import calibration
from scalesynth.cli import app
from scalesynth.config import load_config
from scalesynth.errors import ConfigError
from scalesynth.evaluate import Tolerance, config_tolerance, evaluate_population
from scalesynth.evaluation.plans import calibrated_plan
from scalesynth.mechanisms import get
from scalesynth.mechanisms.describe import BUILTIN_DIR, load_description, parse_description
from test_calibration import _designs  # random designs within a config's bounds

from conftest import ROOT

PAPER = ["grid.tolerance.volume=0.002", "grid.tolerance.gci=0.0005"]
DELTA_TEXT = (BUILTIN_DIR / "delta.yaml").read_text().replace("\nname: delta\n", "\nname: my-delta\n")


def test_the_delta_plan_meets_its_tolerance_against_a_3x_finer_uniform_grid():
    """The plan of src/scalesynth/mechanisms/delta.yaml at volume 0.2 %, GCI 5e-4 (the paper-scale tolerance), on 3
    random designs within configs/delta.yaml's bounds (seed 11, not one of the plan search's seeds 0-3): within the
    tolerance of the uniform N = 192 grid (LCI kernel at 7 077 888 cell centres, no column intervals, no
    refinement; the search's reference, 3x finer than N = 64), itself within 0.12 % and 2.1e-4 of N = 96 on such
    designs (benchmarks/RESULTS.md, issue 28). The description's sector plan (evaluation.sector) runs first for the
    Delta's rotationally symmetric legs, so this checks the sector evaluator; the adaptive plan is still its
    fallback (a design without the symmetry)."""
    cfg = load_config(ROOT / "configs" / "delta.yaml", PAPER)
    mech, options, region, tol = cfg.mech, cfg.resolved_options(), cfg.grid.region, config_tolerance(cfg)
    assert calibrated_plan(mech, tol).plan.columns == 12
    designs = _designs(cfg, 3, seed=11)
    got = evaluate_population(mech, designs, options, region=region, tolerance=tol, fields=["lci"])
    ref = evaluate_population(mech, designs, options, region=region, resolution=192, fields=["lci"])
    assert np.all(ref["volume_m3"] > 0.05)  # no sliver among them (m^3; the default design's is about 1.5)
    rel = np.abs(got["volume_m3"] - ref["volume_m3"]) / ref["volume_m3"]
    assert np.all(rel <= tol.volume), rel
    assert np.all(np.abs(got["gci"] - ref["gci"]) <= tol.gci), got["gci"] - ref["gci"]


def test_a_plan_serves_its_tolerance_and_looser_ones_and_tighter_ones_run_the_ladder():
    mech = get("delta")
    (only,) = mech.calibrated_plans
    assert calibrated_plan(mech, Tolerance(0.002, 0.0005)) == only
    assert calibrated_plan(mech, Tolerance(0.01, 0.002)) == only  # run at its own, tighter tolerance
    assert calibrated_plan(mech, Tolerance(0.001, 0.0005)) is None
    assert calibrated_plan(mech, Tolerance(0.002, 0.0002)) is None
    assert not calibration.has_plan(mech)  # no hand plan: what no calibrated plan serves climbs the ladder
    assert get("hexapod").calibrated_plans == ()


def test_the_ladder_still_runs_for_a_tighter_tolerance_and_the_plan_for_the_paper_one():
    """The same design under the paper tolerance (the plan: one level of refinement record, no rungs) and under a
    tighter one than any plan (the ladder: at least the third rung, levels = the rung)."""
    cfg = load_config(ROOT / "configs" / "delta.yaml", PAPER)
    mech, options, region = cfg.mech, cfg.resolved_options(), cfg.grid.region
    design = _designs(cfg, 1, seed=12)
    plan = evaluate_population(mech, design, options, region=region, tolerance=Tolerance(0.002, 0.0005),
                               fields=["lci"])
    ladder = evaluate_population(mech, design, options, region=region, tolerance=Tolerance(0.002, 0.0004),
                                 fields=["lci"])
    assert plan["volume_m3"][0] > 0.0
    assert plan["volume_m3"][0] != ladder["volume_m3"][0]  # two different evaluators
    assert abs(plan["volume_m3"][0] / ladder["volume_m3"][0] - 1.0) <= 0.002 + 0.002
    assert abs(plan["gci"][0] - ladder["gci"][0]) <= 0.0005 + 0.0004


def test_the_builtin_delta_block_loads_and_the_plan_is_the_files():
    desc = load_description(BUILTIN_DIR / "delta.yaml")
    (spec,) = desc.evaluation.plans
    (cp,) = get("delta").calibrated_plans
    assert (cp.tolerance.volume, cp.tolerance.gci) == (spec.tolerance["volume"], spec.tolerance["gci"])
    assert (cp.plan.columns, cp.plan.cells, cp.plan.levels, cp.plan.beta) == (spec.columns, spec.cells, spec.levels,
                                                                              spec.beta)


def _project(tmp_path, text):
    import yaml

    folder = tmp_path / "project"
    folder.mkdir()
    (folder / "my_robot.yaml").write_text(text)
    config = yaml.safe_load((ROOT / "configs" / "delta.yaml").read_text())
    cfg = folder / "robot.yaml"
    cfg.write_text(yaml.safe_dump({**config, "name": "robot", "mechanism": {"description": "my_robot.yaml"}},
                                  sort_keys=False))
    return cfg


HEAD = "error: mechanism.description (my_robot.yaml): "


@pytest.mark.parametrize(("edit", "message"), [
    (("      columns: 12\n", "      columns: 1\n"),
     "evaluation.plans[0].columns: Input should be greater than or equal to 2"),
    (("      beta: 0.35\n", "      beta: -1\n"), "evaluation.plans[0].beta: Input should be greater than 0"),
    (("      faces: true\n", "      faces: true\n      colour: red\n"), "evaluation.plans[0].colour: unknown key"),
    (("{volume: 0.002, gci: 0.0005}", "{volume: 0.002}"),
     "evaluation.plans[0].tolerance: needs volume and gci (missing gci)"),
    (("{volume: 0.002, gci: 0.0005}", "{volume: 2.0, gci: 0.0005}"),
     "evaluation.plans[0].tolerance.volume: expected a number in (0, 1), got 2.0"),
    (("{volume: 0.002, gci: 0.0005}", "{volume: 0.002, gci: .nan}"),
     "evaluation.plans[0].tolerance.gci: expected a number in (0, 1), got nan"),
    (("      levels: 2\n", "      levels: 2\n      field_levels: 3\n"),
     "evaluation.plans[0].field_levels: 3 is deeper than levels 2"),
    (("  plans:\n", "  plans: []\n  old:\n"), "evaluation.plans: List should have at least 1 item after validation, "
                                            "not 0"),
])
def test_a_wrong_evaluation_block_is_one_line_exit_2(tmp_path, edit, message):
    old, new = edit
    assert old in DELTA_TEXT
    text = DELTA_TEXT.replace(old, new, 1)
    res = CliRunner().invoke(app, ["evaluate", str(_project(tmp_path, text))])
    assert res.exit_code == 2, res.output
    assert res.output.strip().splitlines() == [HEAD + message]
    assert len(message) <= 200


def test_an_evaluation_block_is_refused_on_a_motion_that_does_not_read_it():
    import yaml

    data = yaml.safe_load((BUILTIN_DIR / "hexapod.yaml").read_text())
    data["evaluation"] = {"plans": [{"tolerance": {"volume": 0.01, "gci": 0.002}, "columns": 8, "cells": 8,
                                     "levels": 2}]}
    with pytest.raises(ConfigError, match=r"^description: evaluation: calibrated plans are read for motion 3T only"):
        parse_description(data)


def test_an_evaluation_block_of_sector_plans_alone_parses_and_an_empty_one_is_one_line():
    """The built-in linear Delta's block holds sector plans only (no column plans: a design without the symmetry
    climbs the ladder); a block with neither is refused."""
    import yaml

    lin = get("linear-delta")
    assert lin.calibrated_plans == () and len(lin.sector_plans) == 2
    data = yaml.safe_load((BUILTIN_DIR / "linear-delta.yaml").read_text())
    data["evaluation"] = {}
    with pytest.raises(ConfigError, match=r"^description: evaluation: needs plans \(column plans\) or sector"):
        parse_description(data)


def test_a_description_symmetric_only_at_its_defaults_gets_no_half_box():
    """The Delta as three single legs, then with a parameter 'offset' (default 0) moving leg 2's base along its arm
    axis: mirrored at the defaults, not for offset != 0, so no mirror axis is declared (the check shifts every
    parameter); the built-in Delta is symmetric in y (tests/test_mirror.py checks the fields)."""
    import yaml

    from scalesynth.mechanisms.describe import from_description

    assert get("delta").mirror_axes(get("delta").resolve_options({})) == (1,)
    data = yaml.safe_load((BUILTIN_DIR / "delta.yaml").read_text())
    data["name"] = "offset-delta"
    data["parameters"]["offset"] = {"default": 0.0, "doc": "leg 2's base shift along its arm axis",
                                    "positive": False}
    (arm,) = data["legs"]
    single = {k: v for k, v in arm.items() if k != "pattern"}
    data["legs"] = [{**single, "name": f"arm{i + 1}", "angle_deg": 120.0 * i} for i in range(3)]
    mech = from_description(parse_description(data))
    assert mech.mirror_axes(mech.resolve_options({})) == (1,)  # three single legs at 0, 120, 240 deg: symmetric
    data["legs"][1]["base"] = ["base_radius", "offset", 0]
    data["name"] = "offset-delta-2"
    mech = from_description(parse_description(data))
    assert mech.mirror_axes(mech.resolve_options({})) == ()
