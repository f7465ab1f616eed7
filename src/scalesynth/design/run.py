"""``scalesynth design SPEC --out DIR``: size every candidate mechanism for a spec sheet, run their syntheses
through the batch machinery (a local dask cluster, or ``scheduler``), compare them and recommend one, then write
the recommended design's datasheet and exports.

OUT (staged beside it and swapped in whole, ``scalesynth.rundir``)::

    design.json                      manifest: spec, status, files
    comparison.json / .md / .html    the comparison and recommendation
    configs/<mechanism>.yaml         each candidate's run config (rerun it with `scalesynth optimize`)
    runs/<spec>-<mechanism>/seed<k>/ each candidate's results directory
    chosen/datasheet.html            the recommended design's datasheet
    chosen/<mechanism>-design.yaml   its mechanism description with the design's numbers (described mechanisms)
    chosen/robot.stl                 a mesh of it at the zone's centre (mechanisms with link geometry)
    chosen/datasheet.pdf (or .png)   the datasheet's print (headless Chromium; ``print_as``)
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from scalesynth import io as rio
from scalesynth import rundir
from scalesynth.design import comparison as cmp
from scalesynth.design import sizing
from scalesynth.design.spec import DesignSpec

MANIFEST = "design.json"
OWNED = ("comparison.json", "comparison.md", "comparison.html", "configs", "runs", "chosen")
DESIGN = rundir.Output("design", MANIFEST, ("spec", "status"), owned=lambda name: name in OWNED)


def _run_all(cands, configs, runs: Path, scheduler: str | None, echo) -> dict[str, Any]:
    """Run every candidate's synthesis; {mechanism: RunResult or an error line}. On the batch machinery (dask:
    a local cluster, or ``scheduler``); without dask installed and no scheduler, one after another here."""
    from scalesynth import results

    try:
        import distributed  # noqa: F401
        have_dask = True
    except ImportError:
        have_dask = False
    out: dict[str, Any] = {}
    if scheduler or have_dask:
        from scalesynth.batch import run_batch

        summary = run_batch([(f"configs/{c.mechanism}.yaml", cfg) for c, cfg in zip(cands, configs, strict=True)],
                            runs, seeds=1, scheduler=scheduler, echo=echo)
        by_name = {r.config: r for r in summary.tasks}
        for c, cfg in zip(cands, configs, strict=True):
            rec = by_name.get(cfg.name)
            if rec is None or rec.status == "failed":
                out[c.mechanism] = f"run failed: {rec.error if rec else 'no task'}"
            else:
                out[c.mechanism] = results.load(Path(rec.out_dir))
        return out
    from scalesynth.optimize import run

    for c, cfg in zip(cands, configs, strict=True):
        echo(f"{c.mechanism}: running (no dask installed: one candidate after another)")
        out[c.mechanism] = run(cfg, runs / cfg.name / f"seed{cfg.algorithm.seed}", plots=False)
    return out


def design(spec: DesignSpec, out: Path, *, scheduler: str | None = None, force: bool = False,
           print_as: str | None = None, echo: Callable[[str], None] = lambda line: None) -> dict[str, Any]:
    """Run the design study of ``spec`` into ``out``; returns the comparison (also in OUT/comparison.json).

    ``print_as``: the datasheet's print, as ``--print`` (html_print.plan): None prints a PDF when Chromium is
    found; 'pdf' or 'png' without a browser is refused (ConfigError) before any work. A print that fails after the
    runs leaves everything else written, then raises RunError when it was asked for."""
    from scalesynth.config import config_from_dict, dump_config
    from scalesynth.errors import RunError
    from scalesynth.html_print import plan

    printing = plan(print_as)
    names, skipped = sizing.candidates(spec)
    cands = [sizing.build(n, spec) for n in names]
    configs = [config_from_dict(c.config) for c in cands]  # every config valid before anything is written
    rundir.check(out, DESIGN, force)
    for c in cands:
        echo(f"{c.mechanism}: bounds ({c.length_unit}) " + ", ".join(
            f"{k} [{lo:.4g}, {hi:.4g}]" for k, (lo, hi) in c.bounds.items()) + f"; rule: {c.rule}")
        for note in c.notes:
            echo(f"{c.mechanism}: {note}")
    for name, why in skipped.items():
        echo(f"{name}: not a candidate: {why}")
    if printing.note:
        echo(printing.note)
    print_error = None
    with rundir.staged(out, DESIGN, force) as rd:
        work = rd.work
        files: list[str] = []
        for c, cfg in zip(cands, configs, strict=True):
            rio.write_text(rio.ensure_dir(work / "configs") / f"{c.mechanism}.yaml", dump_config(cfg))
        results = _run_all(cands, configs, work / "runs", scheduler, echo) if cands else {}
        entries = []
        for c in cands:
            res = results[c.mechanism]
            if isinstance(res, str):
                entries.append({"mechanism": c.mechanism, "error": res, "can_do": False,
                                "requirements": {}, "designs": []})
                echo(f"{c.mechanism}: {res}")
                continue
            entry = cmp.mechanism_entry(spec, c, res)
            entry["run"] = str(Path(res.out_dir).relative_to(work))
            entries.append(entry)
            echo(f"{c.mechanism}: {entry['feasible_designs']} designs meet every evaluated requirement"
                 if entry["can_do"] else f"{c.mechanism}: cannot do the task: {entry['why_not']}")
        comparison = {"spec": spec.name, "length_unit": spec.units.length,
                      "spec_data": spec.model_dump(mode="json"), "mechanisms": entries,
                      "skipped": skipped, "recommendation": cmp.recommend(entries, spec)}
        link = None
        rec = comparison["recommendation"]
        if rec["mechanism"] is not None:
            link, print_error = _chosen(work, spec, rec, results[rec["mechanism"]], comparison, printing, echo)
        files += cmp.write(work, comparison, link)
        rio.write_json(work / MANIFEST, {"spec": spec.model_dump(mode="json"), "status": "finished",
                                         "files": rundir.listing(work)})
    if print_error is not None and printing.explicit:
        raise RunError(f"{print_error}; everything else is written in {out}")
    return comparison


def _chosen(work: Path, spec, rec, result, comparison, printing, echo) -> tuple[str, str | None]:
    """Write the recommended design's datasheet, its print and exports into chosen/; (the datasheet's link
    (relative), why the print failed or None)."""
    from scalesynth.design import datasheet, export
    from scalesynth.errors import RunError
    from scalesynth.html_print import print_html

    chosen = rio.ensure_dir(work / "chosen")
    row = rec["design"]["row"]
    page = datasheet.build(result, row, spec=spec)
    rio.write_text(chosen / "datasheet.html", page)
    written = ["chosen/datasheet.html"]
    print_error = None
    if printing.kind is not None:
        try:
            print_html(page, chosen / f"datasheet.{printing.kind}", printing.kind, printing.browser)
            written.append(f"chosen/datasheet.{printing.kind}")
        except RunError as err:
            print_error = str(err)
            echo(f"no print of the datasheet: {err}")
    desc = export.description_yaml(result.cfg.mech, result.design_of(result.pareto.iloc[row]))
    if desc is not None:
        name, text = desc
        rio.write_text(chosen / f"{name}.yaml", text)
        written.append(f"chosen/{name}.yaml")
    mesh = export.robot_mesh(result.cfg, result.design_of(result.pareto.iloc[row]))
    if mesh is not None:
        export.write_mesh(mesh, chosen / "robot.stl")
        written.append("chosen/robot.stl")
    else:
        written.append("(no mesh: the mechanism has no link geometry yet)")
    echo("recommended design: " + ", ".join(written))
    comparison["recommendation"]["files"] = written
    return "chosen/datasheet.html", print_error
