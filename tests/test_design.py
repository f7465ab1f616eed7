"""`scalesynth design` (spec sheet -> comparison, recommendation, datasheet, exports), `datasheet` and `export`."""

import json
import re
from pathlib import Path

import numpy as np
import pytest
import yaml

from cli_main import run_main
from scalesynth.design import export, sizing
from scalesynth.design.spec import SpecError, load_spec, spec_from_dict

from headless import need_chromium, open_page

ROOT = Path(__file__).resolve().parents[1]
PLANAR = {"name": "packer2d", "envelope": {"box": {"x": 1000, "y": 250}, "depth": 600},
          "cycle": {"picks_per_minute": 60}, "mechanisms": ["planar-fivebar"],
          "search": {"population": 4, "generations": 1, "task_resolution": 6, "cycle_samples": 16}}


# ----- spec --------------------------------------------------------------------------------------------------
def test_case_packer_example_is_packaged_and_valid():
    packaged = ROOT / "src/scalesynth/examples/specs/case_packer.yaml"
    assert (ROOT / "examples/case_packer.yaml").read_bytes() == packaged.read_bytes()
    spec = load_spec(packaged)
    assert (spec.envelope.box.x, spec.envelope.box.y, spec.envelope.box.z) == (400, 300, 80)
    assert spec.cycle.picks_per_minute == 120 and spec.rated_payload == 1.0
    assert spec.stiffness.max_deflection == 0.1 and spec.stiffness.force == 150
    assert spec.links.tube == [60, 4] and spec.links.youngs_modulus == 135 and spec.links.density == 1600


@pytest.mark.parametrize("change, field", [
    ({"envelope": {"box": {"x": -4, "y": 3}, "depth": 1}}, "envelope.box.x"),
    ({"envelope": {"box": {"x": 4, "y": 3}}}, "envelope.depth"),
    ({"envelope": {"box": {"x": 4, "y": 3}, "cylinder": {"diameter": 1, "height": 1}, "depth": 1}}, "envelope"),
    ({"envelope": {"task": {"box": {"x": [1, 0], "y": [0, 1]}}}}, "envelope.task.box"),
    ({"payloads": [0]}, "payloads.0"),
    ({"cycle": {"picks_per_minute": -1}}, "cycle.picks_per_minute"),
    ({"cycle": {"picks_per_minute": 60, "law": "jerky"}}, "cycle.law"),
    ({"stiffness": {"max_deflection": 0.1}}, "stiffness.force"),
    ({"mechanisms": ["detla"]}, "mechanisms.0"),
    ({"search": {"population": 1}}, "search.population"),
    ({"colour": "red"}, "colour"),
    ({"links": {"tube": [40, 25]}}, "links.tube"),
    ({"links": {"tube": [40]}}, "links.tube"),
    ({"links": {"youngs_modulus": -70}}, "links.youngs_modulus"),
    ({"links": {"density": 1e6}}, "links.density"),
    ({"links": {"colour": "black"}}, "links.colour"),
])
def test_bad_spec_is_one_line_naming_the_field(change, field, tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump({**PLANAR, **change}))
    code, out, err = run_main(["design", bad, "--out", tmp_path / "out"], capsys)
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {field}") and len(lines[0]) <= 200, err
    assert not (tmp_path / "out").exists()


def test_spec_file_missing_or_not_a_mapping(tmp_path):
    with pytest.raises(SpecError, match="no such spec file"):
        load_spec(tmp_path / "none.yaml")
    with pytest.raises(SpecError, match="top level must be a mapping"):
        spec_from_dict([1, 2])


# ----- sizing ------------------------------------------------------------------------------------------------
def test_candidates_follow_the_zone_and_the_motion():
    three_d = spec_from_dict({**PLANAR, "envelope": {"cylinder": {"diameter": 400, "height": 80}, "depth": 300},
                              "mechanisms": None})
    run, skipped = sizing.candidates(three_d)
    assert {"delta", "linear-delta", "2pauu-ppap"} <= set(run)
    assert "planar-fivebar" not in run and "2T" in skipped["planar-fivebar"]
    run2, skipped2 = sizing.candidates(spec_from_dict({**PLANAR, "mechanisms": None}))
    assert run2 == ["planar-fivebar"]  # not also its description twin, planar-fivebar-described
    assert skipped2["planar-fivebar-described"].startswith("the same robot as planar-fivebar")


def test_fivebar_rule_reproduces_the_packing_examples_bounds():
    """The five-bar rule is the packaged example's ranges (fivebar_pnp_cycle.yaml: r [50, 400], l1 [250, 800],
    l2 [500, 1400] for a 1000 x 250 mm rectangle 600-850 mm below the base) written as multiples of the zone."""
    cand = sizing.build("planar-fivebar", spec_from_dict(PLANAR))
    example = yaml.safe_load((ROOT / "src/scalesynth/examples/fivebar_pnp_cycle.yaml").read_text())
    assert cand.bounds == {k: tuple(v) for k, v in example["bounds"].items()}
    assert cand.config["task"]["box"] == example["task"]["box"]


def test_zone_in_metres_below_a_delta_and_above_a_2pauu():
    spec = spec_from_dict({**PLANAR, "envelope": {"box": {"x": 400, "y": 300, "z": 80}, "depth": 300},
                           "mechanisms": None})
    z = sizing.zone_in(__import__("scalesynth.mechanisms", fromlist=["get"]).get("delta"), spec, "m")
    assert z.box == {"x": (-0.2, 0.2), "y": (-0.15, 0.15), "z": (-0.38, -0.3)}
    assert z.a == pytest.approx(0.25)  # half the 500 mm diagonal
    up = sizing.build("2pauu-ppap", spec)
    assert up.config["task"]["box"]["z"] == [0.3, 0.38]


def test_the_specs_links_reach_each_candidates_stiffness_and_mass_models():
    """links: the tube (spec unit mm) in each candidate's own unit (the Delta's m: 60 x 4 mm -> 0.06 x 0.004 m),
    the modulus in its stiffness options, the density in its cycle's mass model; without links, the defaults."""
    zone = {"envelope": {"box": {"x": 400, "y": 300, "z": 80}, "depth": 300}, "mechanisms": ["delta"],
            "stiffness": {"max_deflection": 0.1, "force": 150}}
    spec = spec_from_dict({**PLANAR, **zone, "links": {"tube": [60, 4], "youngs_modulus": 135, "density": 1600}})
    cfg = sizing.build("delta", spec).config
    assert cfg["options"]["tube"] == pytest.approx([0.06, 0.004], rel=1e-12)
    assert cfg["options"]["youngs_modulus"] == 135 and cfg["dynamics"] == {"density": 1600.0}
    plain = sizing.build("delta", spec_from_dict({**PLANAR, **zone})).config
    assert "tube" not in plain["options"] and "youngs_modulus" not in plain["options"] and "dynamics" not in plain


# ----- export ------------------------------------------------------------------------------------------------
def test_description_round_trip(tmp_path):
    """The exported description loads back through `mechanism: {description: FILE}` with the design as defaults."""
    from scalesynth.config import config_from_dict
    from scalesynth.mechanisms import get

    chosen = {"base_radius": 0.31, "platform_radius": 0.05, "upper_arm": 0.42, "forearm": 0.77}
    name, text = export.description_yaml(get("delta"), chosen)
    (tmp_path / f"{name}.yaml").write_text(text)
    cfg = config_from_dict({"name": "rt", "mechanism": {"description": f"{name}.yaml"}}, base_dir=tmp_path)
    assert cfg.mechanism == "delta-design"
    assert cfg.resolved_design() == chosen
    assert [p.name for p in cfg.mech.parameters] == [p.name for p in get("delta").parameters]
    assert export.description_yaml(get("planar-fivebar"), {"r": 1.0}) is None  # written in Python


def test_mesh_loads_and_its_bounds_are_the_capsules(tmp_path):
    """The STL of the five-bar at a pose has the bounding box of its capsules: min/max over segment ends -/+ the
    radius (a capsule's exact box), within the faceting of the spheres and cylinders (2 % of the radius)."""
    import trimesh

    from scalesynth.mechanisms import get

    mech = get("planar-fivebar")
    design = {"r": 200.0, "l1": 475.0, "l2": 875.0}
    options = mech.resolve_options({"link_radius": 20.0})
    geometry = export.geometry_at(mech, design, options, [0.0, -700.0])
    path = tmp_path / "robot.stl"
    export.write_mesh(export.capsule_mesh(geometry), path)
    mesh = trimesh.load(path)
    a, b, _ = geometry.as_arrays()
    r = export.display_radii(geometry)
    lo = np.minimum(a - r[:, None], b - r[:, None]).min(axis=0)
    hi = np.maximum(a + r[:, None], b + r[:, None]).max(axis=0)
    assert np.allclose(mesh.bounds[0], lo, atol=0.02 * r.max())
    assert np.allclose(mesh.bounds[1], hi, atol=0.02 * r.max())
    assert len(mesh.faces) > 100
    glb = tmp_path / "robot.glb"
    export.write_mesh(export.capsule_mesh(geometry), glb)
    assert np.allclose(trimesh.load(glb, force="mesh").bounds, mesh.bounds)


# ----- the command end to end ----------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def planar_design(tmp_path_factory):
    from scalesynth.cli import main

    tmp = tmp_path_factory.mktemp("design")
    spec = tmp / "spec.yaml"
    spec.write_text(yaml.safe_dump(PLANAR))
    with pytest.raises(SystemExit) as exc:
        main(["design", str(spec), "--out", str(tmp / "out")])
    assert exc.value.code in (0, None)
    return tmp / "out"


def test_design_writes_comparison_configs_runs_and_the_chosen_design(planar_design):
    out = planar_design
    for f in ("design.json", "comparison.json", "comparison.md", "comparison.html", "configs/planar-fivebar.yaml"):
        assert (out / f).is_file(), f
    comparison = json.loads((out / "comparison.json").read_text())
    (entry,) = comparison["mechanisms"]
    assert entry["bounds"] == {"r": [50.0, 400.0], "l1": [250.0, 800.0], "l2": [500.0, 1400.0]}
    assert entry["requirements"]["rate"]["status"] == "not evaluated"  # the spec names no motors
    assert "planar-fivebar" in (out / "comparison.md").read_text()
    rec = comparison["recommendation"]
    if rec["mechanism"] is not None:  # a feasible design at this tiny budget: datasheet and exports written
        assert (out / "chosen/datasheet.html").is_file() and (out / "chosen/robot.stl").is_file()
    else:
        assert entry["why_not"] and "cannot do the task" in " ".join(rec["reasons"])
    # the candidate's config is the schema users write: it loads as a run config
    from scalesynth.config import load_config

    assert load_config(out / "configs/planar-fivebar.yaml").mechanism == "planar-fivebar"


def test_design_refuses_a_foreign_directory(tmp_path, capsys):
    spec = tmp_path / "spec.yaml"
    spec.write_text(yaml.safe_dump(PLANAR))
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("keep")
    code, _, err = run_main(["design", spec, "--out", tmp_path / "mine"], capsys)
    assert code == 2 and "not empty" in err
    assert (tmp_path / "mine" / "notes.txt").read_text() == "keep"


def test_unmeetable_spec_finishes_and_names_the_failed_requirement(tmp_path, capsys):
    """A deflection no five-bar meets (1e-9 mm under 150 N): exit 0, the comparison says which requirement
    failed with the best value seen."""
    spec = tmp_path / "spec.yaml"
    spec.write_text(yaml.safe_dump({**PLANAR, "stiffness": {"max_deflection": 1e-9, "force": 150}}))
    code, out, err = run_main(["design", spec, "--out", tmp_path / "out"], capsys)
    assert code == 0, err
    assert "recommendation: none" in out
    entry = json.loads((tmp_path / "out/comparison.json").read_text())["mechanisms"][0]
    defl = entry["requirements"]["deflection"]
    assert defl["status"] == "failed" and defl["best"] > 1e-9
    assert not entry["can_do"] and "deflection" in entry["why_not"]


def test_datasheet_and_export_of_a_run(planar_design, tmp_path, capsys):
    run = planar_design / "runs" / "packer2d-planar-fivebar" / "seed1"
    front = (run / "pareto.csv").read_text().strip().splitlines()
    if len(front) < 2:
        pytest.skip("no feasible design at this budget")
    page = tmp_path / "ds.html"
    code, _, err = run_main(["datasheet", run, "--design", "knee", "--out", page], capsys)
    assert code == 0, err
    text = page.read_text()
    assert 'class="zone"' in text and 'class="link"' in text and "<svg" in text
    assert "not evaluated" in text  # motors: the run names none
    code, _, err = run_main(["datasheet", run, "--out", page], capsys)
    assert code == 2 and "exists" in err  # a file it did not write is never replaced without --force
    code, _, err = run_main(["export", run, "--mesh", tmp_path / "r.glb"], capsys)
    assert code == 0, err
    code, _, err = run_main(["export", run, "--description", tmp_path / "d.yaml"], capsys)
    assert code == 2 and "written in Python" in err
    need_chromium()
    r = open_page(page, tmp_path / "ds.png")
    assert r["loaded"] and r["errors"] == []
    assert r["dom"].count("<svg") >= 1 and "Picks per minute against payload" in r["dom"]
    grey = r["pixels"].astype(float).mean(axis=2)
    assert grey.std() > 10 and np.mean(grey < 250) > 0.03


# ----- the datasheet's print (headless Chromium; scalesynth.html_print) ----------------------------------------
A4_PT = (595.28, 841.89)  # ISO 216 A4, 210 x 297 mm, in PDF points (1/72 inch)


def _front_run(planar_design) -> Path:
    run = planar_design / "runs" / "packer2d-planar-fivebar" / "seed1"
    if len((run / "pareto.csv").read_text().strip().splitlines()) < 2:
        pytest.skip("no feasible design at this budget")
    return run


def test_datasheet_without_a_browser(planar_design, tmp_path, capsys, no_browser):
    """Asked for, a print without a browser is one line naming the flag, exit 2, nothing written; by default the
    HTML is written and a note says how to get the print."""
    run = _front_run(planar_design)
    code, _, err = run_main(["datasheet", run, "--out", tmp_path / "a.html", "--print", "pdf"], capsys)
    assert code == 2 and err.startswith("error: --print pdf: no Chromium found") and err.count("\n") == 1, err
    assert not (tmp_path / "a.html").exists()
    code, out, err = run_main(["datasheet", run, "--out", tmp_path / "b.html"], capsys)
    assert code == 0, err
    assert (tmp_path / "b.html").is_file() and not (tmp_path / "b.pdf").exists()
    assert "no Chromium found" in err and "apt-get install chromium" in err and "print:" not in out
    code, _, err = run_main(["datasheet", run, "--out", tmp_path / "c.html", "--print", "tiff"], capsys)
    assert code == 2 and "--print: expected one of pdf, png, none, got 'tiff'" in err
    code, _, err = run_main(["datasheet", run, "--out", tmp_path / "d.html", "--print", "none"], capsys)
    assert code == 0 and err == "" and (tmp_path / "d.html").is_file()


def test_design_refuses_an_asked_for_print_without_a_browser_before_any_work(tmp_path, capsys, no_browser):
    spec = tmp_path / "spec.yaml"
    spec.write_text(yaml.safe_dump(PLANAR))
    code, _, err = run_main(["design", spec, "--out", tmp_path / "out", "--print", "png"], capsys)
    assert code == 2 and err.startswith("error: --print png: no Chromium found") and err.count("\n") == 1, err
    assert not (tmp_path / "out").exists()


def test_datasheet_prints_an_a4_vector_pdf_and_a_png(planar_design, tmp_path, capsys):
    from scalesynth.html_print import PNG_SCALE, PNG_WIDTH_PX, pdf_pages, png_size

    run = _front_run(planar_design)
    need_chromium()
    code, out, err = run_main(["datasheet", run, "--out", tmp_path / "ds.html", "--print", "pdf"], capsys)
    assert code == 0, err
    assert f"print: {tmp_path / 'ds.pdf'}" in out
    data = (tmp_path / "ds.pdf").read_bytes()
    assert data.startswith(b"%PDF-") and pdf_pages(data) >= 1
    boxes = re.findall(rb"/MediaBox\s*\[\s*0\s+0\s+([\d.]+)\s+([\d.]+)\s*\]", data)
    assert boxes and all(abs(float(w) - A4_PT[0]) < 1 and abs(float(h) - A4_PT[1]) < 1 for w, h in boxes), boxes
    assert b"/Subtype /Image" not in data  # the drawings are SVG: printed as vector paths, no raster image
    # a print file the user has is not replaced without --force (and then nothing is written)
    (tmp_path / "mine.pdf").write_bytes(b"the user's")
    code, _, err = run_main(["datasheet", run, "--out", tmp_path / "mine.html", "--print", "pdf"], capsys)
    assert code == 2 and "mine.pdf exists" in err
    assert (tmp_path / "mine.pdf").read_bytes() == b"the user's" and not (tmp_path / "mine.html").exists()
    code, _, err = run_main(["datasheet", run, "--out", tmp_path / "same.pdf", "--print", "pdf"], capsys)
    assert code == 2 and "give a .html name" in err
    code, out, err = run_main(["datasheet", run, "--out", tmp_path / "p.html", "--print", "png"], capsys)
    assert code == 0, err
    size = png_size((tmp_path / "p.png").read_bytes())
    import matplotlib.image as mpimg

    pixels = mpimg.imread(tmp_path / "p.png")
    assert size is not None and pixels.shape[:2] == (size[1], size[0]) and size[0] == PNG_WIDTH_PX * PNG_SCALE
    grey = pixels[..., :3].mean(axis=2)
    assert grey.std() > 0.04 and np.mean(grey < 0.98) > 0.03  # drawn on, not a blank page


def test_design_writes_the_datasheets_print(planar_design):
    from scalesynth.html_print import pdf_pages

    need_chromium()  # the fixture ran with a browser: the default print is a PDF
    rec = json.loads((planar_design / "comparison.json").read_text())["recommendation"]
    if rec["mechanism"] is None:
        pytest.skip("no feasible design at this budget")
    assert pdf_pages((planar_design / "chosen/datasheet.pdf").read_bytes()) >= 1
    assert "chosen/datasheet.pdf" in rec["files"]
    assert "chosen/datasheet.pdf" in json.loads((planar_design / "design.json").read_text())["files"]


def test_datasheet_when_the_browser_fails(planar_design, tmp_path, capsys, monkeypatch):
    """A browser that writes nothing: an asked-for print is exit 1 and nothing written; the default print is a
    warning and the HTML is written."""
    from scalesynth import html_print

    run = _front_run(planar_design)
    broken = tmp_path / "broken-chromium"
    broken.write_text("#!/bin/sh\nexit 0\n")
    broken.chmod(0o755)
    monkeypatch.setenv(html_print.BROWSER_ENV, str(broken))
    code, _, err = run_main(["datasheet", run, "--out", tmp_path / "a.html", "--print", "pdf"], capsys)
    assert code == 1 and err.startswith("error: --print pdf: the browser wrote no PDF") and err.count("\n") == 1
    assert not (tmp_path / "a.html").exists() and not (tmp_path / "a.pdf").exists()
    code, out, err = run_main(["datasheet", run, "--out", tmp_path / "b.html"], capsys)
    assert code == 0 and "warning: no print of the datasheet: --print pdf: the browser wrote no PDF" in err
    assert (tmp_path / "b.html").is_file() and not (tmp_path / "b.pdf").exists() and "print:" not in out


def test_design_keeps_its_results_when_an_asked_for_print_fails(tmp_path, capsys, monkeypatch):
    """`design --print pdf` with a browser that writes nothing: the synthesis, comparison and datasheet are kept
    (swapped in whole), then one line says the print failed, exit 1."""
    from scalesynth import html_print

    broken = tmp_path / "broken-chromium"
    broken.write_text("#!/bin/sh\nexit 0\n")
    broken.chmod(0o755)
    monkeypatch.setenv(html_print.BROWSER_ENV, str(broken))
    spec = tmp_path / "spec.yaml"
    spec.write_text(yaml.safe_dump(PLANAR))
    code, out, err = run_main(["design", spec, "--out", tmp_path / "out", "--print", "pdf"], capsys)
    comparison = json.loads((tmp_path / "out/comparison.json").read_text())
    if comparison["recommendation"]["mechanism"] is None:
        pytest.skip("no feasible design at this budget (no datasheet to print)")
    assert code == 1 and out == ""
    last = err.strip().splitlines()[-1]
    assert last.startswith("error: --print pdf: the browser wrote no PDF") and "everything else is written" in last
    assert (tmp_path / "out/chosen/datasheet.html").is_file() and not (tmp_path / "out/chosen/datasheet.pdf").exists()
    assert json.loads((tmp_path / "out/design.json").read_text())["status"] == "finished"
