"""Stiffness maps in the section plots (issue 12): a run whose mechanism has per-voxel stiffness fields gets its report
sections coloured by deflection and stiffness_min, with units, whose cells are the reference solver's values; a
mechanism without them gets none; `show --field` colours by them too."""

import json

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from scalesynth.cli import app
from scalesynth.config import config_from_dict, load_config
from scalesynth.optimize import run
from scalesynth.report import STIFFNESS_MAP_FIELDS, field_sections, section_panels
from scalesynth.results import REPORT
from scalesynth.stiffness.solve import solve
from scalesynth.workspace_view import default_section_point

from conftest import ROOT, SMALL


def _cell_centres(panel, n):
    x0, x1, y0, y1 = panel["extent"]
    return x0 + (np.arange(n[0]) + 0.5) * (x1 - x0) / n[0], y0 + (np.arange(n[1]) + 0.5) * (y1 - y0) / n[1]


@pytest.mark.parametrize("field", STIFFNESS_MAP_FIELDS)
def test_fivebar_section_map_cells_are_the_reference_solver(field):
    cfg = load_config(ROOT / "configs" / "fivebar_stiffness.yaml", ["grid.resolution=16"])
    design, opt = cfg.resolved_design(), cfg.resolved_options()
    (panel,) = section_panels(cfg, design, field)
    values = np.asarray(panel["values"])
    lci = np.asarray(section_panels(cfg, design)[0]["values"])
    assert np.array_equal(np.isfinite(values), lci >= 0)  # unreachable cells blank
    xs, ys = _cell_centres(panel, values.shape)
    rng = np.random.default_rng(4)
    reach = np.argwhere(np.isfinite(values))
    for i, j in reach[rng.choice(len(reach), 25, replace=False)]:
        res = solve(cfg.mech.stiffness_model(design, opt, (xs[i], ys[j])))
        want = res.deflection_norm if field == "deflection" else res.stiffness_min
        assert values[i, j] == pytest.approx(want, rel=1e-8)


def test_ups_sspr_section_maps_are_the_reference_solver():
    """3-D: the two centroid sections of each stiffness field; reachable cells equal the reference solver."""
    cfg = load_config(ROOT / "configs" / "ups_sspr.yaml")
    design, opt = cfg.resolved_design(), cfg.resolved_options()
    lci_panels = section_panels(cfg, design)
    point = default_section_point(cfg, design)  # the planes' positions, as section_panels places them
    for field in STIFFNESS_MAP_FIELDS:
        panels = section_panels(cfg, design, field)
        for normal, panel, lp in zip((1, 2), panels, lci_panels, strict=True):
            values = np.asarray(panel["values"])
            assert panel["title"] == lp["title"] and np.array_equal(np.isfinite(values), np.asarray(lp["values"]) >= 0)
            a, b = [x for x in range(3) if x != normal]
            at = round(float(point[normal]), 10) + 0.0
            xs, ys = _cell_centres(panel, values.shape)
            reach = np.argwhere(np.isfinite(values))
            for i, j in reach[:: max(1, len(reach) // 6)][:6]:
                pose = np.zeros(3)
                pose[a], pose[b], pose[normal] = xs[i], ys[j], at
                res = solve(cfg.mech.stiffness_model(design, opt, pose))
                want = res.deflection_norm if field == "deflection" else res.stiffness_min
                assert values[i, j] == pytest.approx(want, rel=1e-9)


def test_run_report_has_stiffness_maps_with_units(tmp_path):
    """A five-bar synthesis with stiffness fields: plots/sections_deflection_<design> and
    sections_stiffness_min_<design> for every featured design, linked from report.md; the colour bars carry the units
    (drawn as SVG text)."""
    data = yaml.safe_load((ROOT / "configs" / "fivebar_stiffness.yaml").read_text())
    data["constraints"] = []  # a non-empty front from a tiny run
    cfg = config_from_dict(data, ["algorithm.pop_size=8", "algorithm.n_gen=2", "grid.resolution=16",
                                  "task.resolution=8"])
    out = tmp_path / "out"
    run(cfg, out)
    report = (out / REPORT).read_text()
    featured = [line.split("|")[1].strip() for line in report.split("## Featured designs")[1].splitlines()
                if line.startswith("| ") and not line.startswith("| design")]
    assert featured
    for name in featured:
        for field in STIFFNESS_MAP_FIELDS:
            path = out / "plots" / f"sections_{field}_{name.replace(' ', '_')}.png"
            assert path.stat().st_size > 0 and f"plots/{path.name}" in report
    html = (out / "report.html").read_text(encoding="utf-8")
    assert html.count("deflection [mm]") >= len(featured)  # report.html: a deflection heatmap per featured design
    design = cfg.resolved_design()
    for field, unit in (("deflection", "[mm]"), ("stiffness_min", "[N/mm]")):
        svg = field_sections(cfg, design, field, "t", tmp_path, "x", "svg")
        assert svg.name == f"sections_{field}_x.svg" and unit in svg.read_text()


def test_no_stiffness_maps_without_stiffness_fields(tmp_path):
    """seed 000 (2pauu-ppap) without options.stiffness_metrics (its default, so that the paper run keeps the fast
    path and its results): the report has LCI sections and no stiffness maps."""
    out = tmp_path / "small"
    run(config_from_dict(SMALL), out)
    plots = [p.name for p in (out / "plots").glob("sections_*")]
    assert plots and not [p for p in plots if any(f in p for f in STIFFNESS_MAP_FIELDS)]
    assert "deflection" not in (out / "report.html").read_text(encoding="utf-8")


def test_show_colours_by_deflection(tmp_path):
    """`show --field deflection` on ups-sspr: sections and 3-D view coloured by the field, unit in the summary."""
    out = CliRunner().invoke(app, ["show", str(ROOT / "configs" / "ups_sspr.yaml"), "--field", "deflection",
                                   "--resolution", "12", "--out", str(tmp_path / "v"), "--json"])
    assert out.exit_code == 0, out.output
    data = json.loads(out.output)
    assert data["field"] == "deflection"
    assert (tmp_path / "v" / "sections.png").stat().st_size > 0
