"""Views of results: report.html (opened in headless Chromium), per-band Pareto sets, `show`, `compare`, plot fixes."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from scalesynth.band_fronts import band_objectives
from scalesynth.cli import app
from scalesynth.config import config_from_dict, load_config
from scalesynth.optimize import run
from scalesynth.report_html import has_remote_scripts
from scalesynth.workspace_view import connected_regions, sample_fields, sample_plane

from conftest import ROOT, SMALL, TABLE4
from headless import need_chromium, open_page

runner = CliRunner()
CONFIGS = sorted((ROOT / "configs").glob("*.yaml"))


def nondominated(F):
    """True where no other row is <= everywhere and < somewhere (minimisation), by brute force."""
    return np.array([not (np.all(F <= f, axis=1) & np.any(F < f, axis=1)).any() for f in F], dtype=bool)


@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("views") / "small"
    run(config_from_dict(SMALL), out, plots=True)
    return out


@pytest.fixture(scope="module")
def other_mechanism_run(tmp_path_factory):
    """A tiny pprs-rprs synthesis: another mechanism beside SMALL's seed 000."""
    cfg = load_config(ROOT / "configs" / "pprs_rprs.yaml",
                      ["grid.resolution=8", "algorithm.pop_size=8", "algorithm.n_gen=2"])
    out = tmp_path_factory.mktemp("views") / "pprs"
    run(cfg, out, plots=False)
    return out


# ----- report.html --------------------------------------------------------------------------------------------------
def test_report_html_is_self_contained_with_every_column_on_hover(small_run):
    text = (small_run / "report.html").read_text(encoding="utf-8")
    assert not has_remote_scripts(text)
    assert "Plotly.newPlot" in text and len(text) > 1_000_000  # plotly.js itself is embedded (~4 MB)
    pareto = pd.read_csv(small_run / "pareto.csv")
    for col in pareto.columns:
        if col != "rank":
            assert f"({col}) = %{{customdata" in text, col  # the front's hover lists every variable and metric
    assert '"type":"parcoords"' in text and '"type":"scatter3d"' in text
    assert "report.html" in (small_run / "report.md").read_text()


def test_validator_checks_report_html_and_band_sets(small_run, tmp_path):
    import shutil

    from scalesynth.validate_results import check_results

    assert check_results(small_run) == []
    bad = tmp_path / "bad"
    shutil.copytree(small_run, bad)
    band = pd.read_csv(bad / "bands" / "pareto_band2.csv")
    worse = band.iloc[[0]].copy()
    worse["band2_volume_m3"] *= 0.5
    worse["gci"] *= 0.5
    pd.concat([band, worse]).to_csv(bad / "bands" / "pareto_band2.csv", index=False)
    html = (bad / "report.html").read_text(encoding="utf-8")
    (bad / "report.html").write_text(html.replace("<head>", '<head><script src="https://cdn.plot.ly/x.js"></script>'),
                                     encoding="utf-8")
    assert check_results(bad) == ["report.html: loads a script from the network",
                                  "bands/pareto_band2.csv: a row is dominated"]


def test_remote_script_check_can_fail():
    assert has_remote_scripts('<script src="https://cdn.plot.ly/plotly-2.35.2.min.js"></script>')
    assert has_remote_scripts("<script type='text/javascript' src='//cdn.example/x.js'></script>")
    assert not has_remote_scripts('<script type="text/javascript">var u = "https://plot.ly";</script>')


def _not_blank(pixels) -> None:
    assert pixels is not None, "no screenshot"
    grey = pixels.astype(float).mean(axis=2)
    assert grey.std() > 10  # a blank (white) page has std 0
    assert np.mean(grey < 250) > 0.03  # at least 3 % of the viewport is drawn on


def test_headless_harness_sees_script_errors(tmp_path):
    """Check the checker: a page whose script fails reports the error, and a white page is blank."""
    need_chromium()
    bad = tmp_path / "bad.html"
    bad.write_text("<!DOCTYPE html><html><head><meta charset='utf-8'></head><body><p>x</p>"
                   "<script>console.error('boom'); undefinedFunction();</script></body></html>")
    r = open_page(bad, tmp_path / "bad.png", budget_ms=2000)
    assert r["loaded"]
    assert any("boom" in e for e in r["errors"]) and any("undefinedFunction" in e for e in r["errors"])
    with pytest.raises(AssertionError):
        _not_blank(r["pixels"])


def test_report_html_renders_in_headless_chromium(small_run, tmp_path):
    need_chromium()
    r = open_page(small_run / "report.html", tmp_path / "report.png")
    assert r["loaded"] and r["errors"] == []
    assert r["dom"].count('class="main-svg"') >= 4  # plotly drew its figures (front, parcoords, HV, 3-D views)
    _not_blank(r["pixels"])


def test_show_html_renders_in_headless_chromium(small_run, tmp_path):
    need_chromium()
    res = runner.invoke(app, ["show", str(small_run), "--format", "html", "--resolution", "16",
                              "--out", str(tmp_path / "h")])
    assert res.exit_code == 0, res.output
    r = open_page(tmp_path / "h" / "show.html", tmp_path / "show.png")
    assert r["loaded"] and r["errors"] == []
    assert r["dom"].count('class="main-svg"') >= 5  # 3-D workspace, three bands, sections, robot
    _not_blank(r["pixels"])


# ----- per-band Pareto sets -----------------------------------------------------------------------------------------
def test_band_pareto_csvs_are_the_brute_force_nondominated_sets(small_run):
    pop = pd.read_csv(small_run / "population.csv")
    feas = pop[pop["feasible"]]
    for k in range(3):
        got = pd.read_csv(small_run / "bands" / f"pareto_band{k}.csv")
        assert (small_run / "bands" / f"pareto_band{k}.png").is_file()
        F = -feas[[f"band{k}_volume_m3", "gci"]].to_numpy()  # SMALL maximises volume and GCI
        expect = feas[nondominated(F)].drop_duplicates(subset=[f"band{k}_volume_m3", "gci"])
        key = ["m", "n", "l1", "l2", "c"]
        assert sorted(map(tuple, got[key].round(9).to_numpy())) == sorted(map(tuple, expect[key].round(9).to_numpy()))
        G = -got[[f"band{k}_volume_m3", "gci"]].to_numpy()
        assert nondominated(G).all() and len(got) >= 1
        assert (got[f"band{k}_volume_m3"].diff().dropna() <= 0).all()


def test_band_objectives_replace_the_measure_or_add_it():
    from scalesynth.problem import SynthesisProblem

    seed0 = SynthesisProblem(config_from_dict(SMALL))
    cols, signs = band_objectives(seed0, 1)
    assert cols == ["band1_volume_m3", "gci"] and list(signs) == [-1.0, -1.0]
    fivebar = SynthesisProblem(load_config(ROOT / "configs" / "fivebar_packing.yaml"))
    cols, signs = band_objectives(fivebar, 2)  # task GCI (max) and task FCI (min): the band's area is added
    assert cols == ["band2_area_mm2", "task_gci", "task_fci"] and list(signs) == [-1.0, -1.0, 1.0]


# ----- connected regions --------------------------------------------------------------------------------------------
def flood_fill_count(mask, full):
    """Number of connected components by breadth-first search (independent of scipy)."""
    from collections import deque
    from itertools import product

    nd = mask.ndim
    steps = [d for d in product((-1, 0, 1), repeat=nd) if any(d) and (full or sum(map(abs, d)) == 1)]
    seen = np.zeros_like(mask, dtype=bool)
    count = 0
    for start in zip(*np.nonzero(mask), strict=True):
        if seen[start]:
            continue
        count += 1
        seen[start] = True
        queue = deque([start])
        while queue:
            cur = queue.popleft()
            for d in steps:
                nb = tuple(c + e for c, e in zip(cur, d, strict=True))
                if all(0 <= c < s for c, s in zip(nb, mask.shape, strict=True)) and mask[nb] and not seen[nb]:
                    seen[nb] = True
                    queue.append(nb)
    return count


def test_connected_regions_match_a_flood_fill():
    rng = np.random.default_rng(5)
    for shape in ((9, 8, 7), (15, 11)):
        for p in (0.2, 0.35, 0.5):
            mask = rng.random(shape) < p
            for full in (True, False):
                assert connected_regions(mask, full)[1] == flood_fill_count(mask, full)
    corner = np.zeros((3, 3, 3), dtype=bool)
    corner[0, 0, 0] = corner[1, 1, 1] = True  # touching at a corner only
    assert connected_regions(corner, True)[1] == 1 and connected_regions(corner, False)[1] == 2


# ----- show ---------------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("config", CONFIGS, ids=lambda p: p.stem)
def test_show_works_for_every_config(config, tmp_path):
    res = runner.invoke(app, ["show", str(config), "--resolution", "12", "--out", str(tmp_path)])
    assert res.exit_code == 0, res.output
    info = json.loads((tmp_path / "show.json").read_text())
    cfg = load_config(config)
    assert info["mechanism"] == cfg.mechanism and len(info["bands"]) == len(cfg.dexterity.band_edges) - 1
    assert sum(b["cells"] for b in info["bands"]) == info["reachable_cells"] > 0
    for b in info["bands"]:
        assert b["regions"] <= b["regions_face_connected"] and (b["regions"] == 0) == (b["cells"] == 0)
    assert all(s["cells"] > 0 for s in info["sections"])  # default sections are never empty
    for f in info["files"]:
        assert (tmp_path / f).stat().st_size > 1000
    assert "sections.png" in info["files"]


def test_show_band_cells_match_the_evaluator():
    """show's band cells (sample_grid + its own banding) equal evaluate's band volumes (the seed-000 fast kernel)."""
    from scalesynth.evaluate import evaluate_config
    from scalesynth.workspace_view import band_regions

    cfg = load_config(ROOT / "configs" / "paper_2pauu_ppap.yaml", ["grid.resolution=24"])
    for group in (1, 4):
        fg = sample_fields(cfg, TABLE4[group], 24)
        rep = evaluate_config(cfg, TABLE4[group])
        for b in band_regions(fg, cfg.dexterity.band_edges, 3):
            assert b["cells"] == round(rep.metrics[f"band{b['band']}_volume_m3"] / fg.grid.cell_measure)


def test_show_of_a_run_dir_designs_formats_and_errors(small_run, tmp_path):
    res = runner.invoke(app, ["show", str(small_run), "--resolution", "12", "--json"])
    assert res.exit_code == 0, res.output
    info = json.loads(res.stdout)
    assert info["design_choice"] == "knee" and Path(info["out"]) == small_run / "show" / "knee"
    pareto = pd.read_csv(small_run / "pareto.csv")
    res = runner.invoke(app, ["show", str(small_run), "--design", "best-gci", "--resolution", "12", "--json",
                              "--out", str(tmp_path / "g"), "--at", "z=0.5"])
    info = json.loads(res.stdout)
    assert info["pareto_row"] == int(pareto["gci"].idxmax())
    z = [s for s in info["sections"] if s["normal"] == "z"][0]
    assert z["source"] == "--at" and abs(z["value"] - 0.5) <= 0.5 * 3.5 / 12 + 1e-9  # nearest cell centre
    res = runner.invoke(app, ["show", str(small_run), "--design", "2", "--format", "html", "--resolution", "12",
                              "--out", str(tmp_path / "h")])
    assert res.exit_code == 0, res.output
    html = (tmp_path / "h" / "show.html").read_text()
    assert "Plotly.newPlot" in html and not has_remote_scripts(html)
    for args, message in (
        (["--design", "bogus"], "--design: expected knee, best-<metric> or a row number"),
        (["--design", "99"], "--design: row 99 is not in pareto.csv"),
        (["--design", "best-nothing"], "--design: unknown metric 'nothing'"),
        (["--field", "stiffness"], "--field: unknown per-voxel field 'stiffness'"),
        (["--at", "q=1"], "--at q=1: expected axis=value with axis one of x, y, z"),
        (["--format", "gif"], "--format: must be one of png, svg, pdf, html"),
    ):
        res = runner.invoke(app, ["show", str(small_run), "--resolution", "8", "--out", str(tmp_path / "e"), *args])
        assert res.exit_code == 2 and message in res.stderr and len(res.stderr.strip().splitlines()) == 1, res.output
    res = runner.invoke(app, ["show", str(ROOT / "configs" / "quick.yaml"), "--design", "knee"])
    assert res.exit_code == 2 and "a config uses its own design" in res.stderr


def test_show_colours_by_any_field_of_the_kernel(tmp_path):
    """--field sigma_min: the field kernel's slot, NaN-free where reachable, with its unit in the colour bar."""
    from scalesynth.show import colour_range

    cfg = load_config(ROOT / "configs" / "rps_upu.yaml")
    fg = sample_fields(cfg, cfg.resolved_design(), 12)
    v = fg.fields["sigma_min"]
    assert np.isfinite(v[fg.reachable]).all() and np.isnan(v[~fg.reachable]).all()
    lo, hi = colour_range(fg, "sigma_min")
    assert lo == pytest.approx(np.percentile(v[fg.reachable], 2)) and hi > lo
    res = runner.invoke(app, ["show", str(ROOT / "configs" / "rps_upu.yaml"), "--field", "sigma_min",
                              "--resolution", "12", "--out", str(tmp_path), "--format", "svg"])
    assert res.exit_code == 0, res.output
    assert "σ_min" in (tmp_path / "sections.svg").read_text()
    assert json.loads((tmp_path / "show.json").read_text())["field"] == "sigma_min"


def test_show_draws_the_robot_from_its_link_geometry(tmp_path):
    """Five-bar at a chosen pose: the drawn arms and forearms have the design's lengths and meet at the pose; the
    pose must be reachable. ups-sspr: its SR link is c long, the platform legs b, and the drawn actuators have the
    IK's lengths (l1 from M to B0 = (2/3) B1 on the link)."""
    cfg = load_config(ROOT / "configs" / "fivebar_packing.yaml")
    d = cfg.resolved_design()
    res = runner.invoke(app, ["show", str(ROOT / "configs" / "fivebar_packing.yaml"), "--resolution", "16",
                              "--pose=0,-700", "--out", str(tmp_path), "--json"])
    assert res.exit_code == 0, res.output
    robot = json.loads(res.stdout)["robot"]
    seg = {s["name"]: (np.array(s["a"]), np.array(s["b"])) for s in robot["segments"]}
    for arm, fore in (("arm1", "forearm1"), ("arm2", "forearm2")):
        assert np.linalg.norm(seg[arm][1] - seg[arm][0]) == pytest.approx(d["l1"], rel=1e-12)
        assert np.linalg.norm(seg[fore][1] - seg[fore][0]) == pytest.approx(d["l2"], rel=1e-12)
        np.testing.assert_allclose(seg[fore][1], [0.0, -700.0, 0.0], atol=1e-9)
    assert robot["branch"] == cfg.resolved_options()["mode"] and (tmp_path / "robot.png").is_file()
    res = runner.invoke(app, ["show", str(ROOT / "configs" / "fivebar_packing.yaml"), "--resolution", "8",
                              "--pose=0,-5000", "--out", str(tmp_path / "far"), "--json"])
    assert res.exit_code == 0 and json.loads(res.stdout)["robot"]["missing"] == "the pose is out of reach"
    res = runner.invoke(app, ["show", str(ROOT / "configs" / "fivebar_packing.yaml"), "--pose=1,2,3"])
    assert res.exit_code == 2 and "--pose: expected 2 finite numbers (x, y)" in res.stderr
    ups = load_config(ROOT / "configs" / "ups_sspr.yaml")
    d = ups.resolved_design()
    res = runner.invoke(app, ["show", str(ROOT / "configs" / "ups_sspr.yaml"), "--resolution", "8",
                              "--pose=0.2,-0.1,10", "--out", str(tmp_path / "u"), "--json"])
    assert res.exit_code == 0, res.output
    robot = json.loads(res.stdout)["robot"]
    seg = {s["name"]: (np.array(s["a"]), np.array(s["b"])) for s in robot["segments"]}
    (ik,) = ups.mech.inverse_kinematics(d, ups.resolved_options(), (0.2, -0.1, 10.0))
    for i, name in enumerate(("leg1", "leg2", "leg3")):
        assert np.linalg.norm(seg[name][1] - seg[name][0]) == pytest.approx(ik.values[i], rel=1e-12)
    assert np.linalg.norm(seg["link"][1] - seg["link"][0]) == pytest.approx(d["c"], rel=1e-12)
    np.testing.assert_allclose(seg["leg1"][1], 2 / 3 * seg["link"][1], atol=1e-12)
    np.testing.assert_allclose(seg["link"][1][1], 10.0)  # B1's y is the task coordinate Y
    for side in ("platform12", "platform31"):
        assert np.linalg.norm(seg[side][1] - seg[side][0]) == pytest.approx(d["b"], rel=1e-12)
    assert robot["branch"] == "Z+" and (tmp_path / "u" / "robot.png").is_file()


def test_plane_sampling_equals_the_full_grid_slice():
    cfg = load_config(ROOT / "configs" / "paper_2pauu_ppap.yaml")
    design = TABLE4[1]
    fg = sample_fields(cfg, design, 16)
    for normal, index in ((1, 5), (2, 9)):
        value = fg.grid.axis(normal)[index]
        plane, ext = sample_plane(cfg, design, normal, value, 16)
        np.testing.assert_array_equal(plane, np.take(fg.lci, index, axis=normal))


@pytest.mark.parametrize("name", ["pprs_rprs", "rps_upu", "ups_sspr", "paper_2pauu_ppap"])
def test_default_sections_go_through_the_centroid_and_keep_units(name):
    """Report sections (sampled plane by plane) pass through the workspace centroid, within one cell of the coarse
    locating grid of the mean of the reachable cells of a finer grid, and are not empty. rps-upu and ups-sspr mix
    mm and rad: their sections are not drawn to equal scale, and the labels carry units."""
    from scalesynth.report import section_panels
    from scalesynth.workspace_view import CENTROID_RESOLUTION

    cfg = load_config(ROOT / "configs" / f"{name}.yaml")
    design = cfg.resolved_design()
    fine = sample_fields(cfg, design, 48)
    idx = np.nonzero(fine.reachable)
    mean = [fine.grid.axis(a)[idx[a]].mean() for a in range(3)]
    panels = section_panels(cfg, design)
    mech = cfg.mech
    for panel, normal in zip(panels, (1, 2), strict=True):
        assert (np.asarray(panel["values"]) >= 0).sum() > 100
        value = float(panel["title"].split(" = ")[1].split(" ")[0])
        coarse_cell = fine.grid.step[normal] * 48 / CENTROID_RESOLUTION
        assert abs(value - mean[normal]) <= coarse_cell
        a, b = [x for x in range(3) if x != normal]
        assert panel["equal"] == (mech.task_units[a] == mech.task_units[b])
        assert panel["xlabel"].endswith("]") and panel["ylabel"].endswith("]")
    if name == "rps_upu":
        assert [(p["xlabel"], p["ylabel"], p["equal"]) for p in panels] == [
            ("z [mm]", "ψ [rad]", False), ("z [mm]", "θ [rad]", False)]


# ----- compare ------------------------------------------------------------------------------------------------------
def test_compare_two_runs_of_different_mechanisms(small_run, other_mechanism_run, tmp_path):
    res = runner.invoke(app, ["compare", str(small_run), str(other_mechanism_run), "--out", str(tmp_path)])
    assert res.exit_code == 0, res.output
    table = pd.read_csv(tmp_path / "compare.csv")
    assert set(table["mechanism"]) == {"2pauu-ppap", "pprs-rprs"}
    assert (tmp_path / "compare.png").stat().st_size > 1000
    # matched by catalogue name: pprs-rprs's volume in mm3 is converted to the first run's m3 (1 mm3 = 1e-9 m3)
    assert "gci" in table.columns and "volume_m3" in table.columns and "volume_mm3" not in table.columns
    other = pd.read_csv(other_mechanism_run / "pareto.csv")
    row = table[table["mechanism"] == "pprs-rprs"].iloc[0]
    assert row["volume_m3"] == pytest.approx(other["volume_mm3"].iloc[int(row["pareto_row"])] * 1e-9, rel=1e-12)
    small_pareto = pd.read_csv(small_run / "pareto.csv")
    knee = table[(table["run"] == "small") & (table["design"] == "knee")].iloc[0]
    assert knee["gci"] == pytest.approx(small_pareto["gci"].iloc[int(knee["pareto_row"])], rel=1e-12)
    assert "small" in res.stdout and "pprs_rprs" in res.stdout
    res = runner.invoke(app, ["compare", str(small_run)])
    assert res.exit_code == 2 and "at least two results directories" in res.stderr


# ----- plot fixes ---------------------------------------------------------------------------------------------------
def test_plot_commands_take_out_and_format(small_run, tmp_path):
    res = runner.invoke(app, ["plot-front", str(small_run), "--out", str(tmp_path), "--format", "svg"])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "front.svg").read_text().lstrip().startswith("<?xml")
    res = runner.invoke(app, ["plot-bands", str(small_run), "--out", str(tmp_path / "b"), "--format", "pdf"])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "b" / "bands_front.pdf").read_bytes()[:4] == b"%PDF"
    assert (tmp_path / "b" / "bands" / "pareto_band0.pdf").is_file()
    res = runner.invoke(app, ["plot-front", str(small_run), "--format", "gif"])
    assert res.exit_code == 2 and "--format: must be one of png, svg, pdf" in res.stderr


def test_plot_bands_evaluates_its_sections_once_from_the_files(small_run, tmp_path, monkeypatch):
    """plot-bands evaluates its sections from config.yaml and pareto.csv read without pandas (results.read_front,
    before pandas and matplotlib load): the same front, bit for bit, as results.load reads, so plot_bands draws
    those sections (band_sections runs once) and writes the same bytes as plot_bands of the loaded run alone."""
    from scalesynth import report
    from scalesynth.results import load, read_front

    early, loaded = read_front(small_run), load(small_run).front()
    assert len(early.F) >= 2
    np.testing.assert_array_equal(early.X, loaded.X)
    np.testing.assert_array_equal(early.F, loaded.F)
    calls = []
    band_sections = report.band_sections
    monkeypatch.setattr(report, "band_sections", lambda front: calls.append(front) or band_sections(front))
    res = runner.invoke(app, ["plot-bands", str(small_run), "--out", str(tmp_path / "cli")])
    assert res.exit_code == 0, res.output
    assert len(calls) == 1
    info = report.plot_bands(load(small_run, require_finished=False), tmp_path / "alone")  # evaluates in plot_bands
    assert len(calls) == 2
    names = sorted(str(p.relative_to(tmp_path / "alone")) for p in (tmp_path / "alone").rglob("*") if p.is_file())
    assert len(names) == len(info["files"]) + len(info["band_files"])
    for name in names:
        assert (tmp_path / "cli" / name).read_bytes() == (tmp_path / "alone" / name).read_bytes(), name


def test_reference_labels_do_not_overlap():
    from matplotlib.text import Text

    from scalesynth import plotting

    x = np.linspace(60, 67, 12)
    y = 0.40 - 0.01 * (x - 60)
    refs = [(f"T4-{k}", 61.0 + 0.02 * k, 0.344 + 0.0002 * k) for k in range(6)]  # six nearly coincident designs
    fig = plotting.front_figure(x, y, "V [m³]", "GCI", "t", references=refs)
    renderer = fig.canvas.get_renderer()
    ax = fig.axes[0]
    boxes = []
    for t in ax.texts:
        if t.get_text().startswith("T4-"):  # measure a plain text at the label's place (no leader line)
            probe = Text(*t.xyann, t.get_text(), fontsize=t.get_fontsize(), va=t.get_va(), ha=t.get_ha(),
                         transform=ax.transData, figure=fig)
            boxes.append(probe.get_window_extent(renderer))
    assert len(boxes) == 6 and min(b.height for b in boxes) > 5
    for i in range(6):
        for j in range(i + 1, 6):
            assert not boxes[i].overlaps(boxes[j])
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any(t.startswith("reference designs") for t in legend)
    plotting.close(fig)


def test_spread_keeps_order_and_gap():
    from scalesynth.plotting import spread

    v = np.array([3.0, 1.0, 1.1, 1.05, 10.0])
    p = spread(v, 1.0)
    order = np.argsort(v, kind="mergesort")
    assert np.all(np.diff(p[order]) >= 1.0 - 1e-12) and np.all(np.argsort(p, kind="mergesort") == order)
    assert spread([0.0, 5.0], 1.0).tolist() == [0.0, 5.0]  # far-apart labels stay put
    assert spread([2.0, 2.0], 1.0).tolist() == [1.5, 2.5]  # least squares: centred on the pair


def test_metric_and_axis_labels_carry_units():
    from scalesynth import labels
    from scalesynth.mechanisms import get

    assert labels.metric_label("volume_m3") == "V [m³]"
    assert labels.metric_label("volume_mm_rad2") == "V [mm·rad²]"
    assert labels.metric_label("band2_area_mm2") == "A of band 2 [mm²]"
    assert labels.metric_label("gci") == "GCI"
    assert labels.axis_label(get("rps-upu"), 1, "mm") == "θ [rad]"
    assert labels.axis_label(get("ups-sspr"), 2, "mm") == "Y [mm]"
