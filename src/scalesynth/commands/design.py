"""`scalesynth design` (spec sheet -> compared mechanisms, a recommended robot, its datasheet and exports),
`scalesynth datasheet` (the datasheet of any run's design) and `scalesynth export` (description and mesh)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from scalesynth.cliapp import DesignOpt, ForceOpt, app, handles_errors

OutFile = Annotated[Path, typer.Option("--out", help="output file (an existing one only with --force)")]
PrintOpt = Annotated[str | None, typer.Option(
    "--print", help="a print of the datasheet beside it, through headless Chromium: pdf (A4), png or none "
    "(default: pdf when Chromium is found, else none with a note)")]


def _check_new_file(out: Path, force: bool) -> Path:
    from scalesynth import outpath
    from scalesynth.errors import ConfigError

    real, exists = outpath.check_file(out)
    if exists and not force:
        raise ConfigError(f"--out: {outpath.shown(out)} exists; give a new file name, or --force to replace it")
    real.parent.mkdir(parents=True, exist_ok=True)
    return real


@app.command("design")
@handles_errors
def design_cmd(
    spec: Annotated[Path, typer.Argument(help="spec sheet (YAML): working zone, payloads, cycle and rate, "
                                         "stiffness, motors, mechanisms, search budget (docs/design.md)")],
    out: Annotated[Path | None, typer.Option("--out", help="output directory (default results/design-<name>)")]
    = None,
    scheduler: Annotated[str | None, typer.Option(
        "--scheduler", help="address of a running dask scheduler (default: a local cluster sized to this machine)")]
    = None,
    print_as: PrintOpt = None,
    force: ForceOpt = False,
) -> None:
    """Size every candidate mechanism for the spec, run their syntheses, compare them, recommend one with its
    reasons and write its datasheet, description and mesh. A spec no design meets still finishes (exit 0) and
    says which requirement failed for each mechanism."""
    from scalesynth.cluster import check_address, check_protocol
    from scalesynth.design.run import design
    from scalesynth.design.spec import load_spec

    if scheduler:
        scheduler = check_address(scheduler)
        check_protocol(scheduler)
    s = load_spec(spec)
    target = out if out is not None else Path("results") / f"design-{s.name}"
    comparison = design(s, target, scheduler=scheduler, force=force, print_as=print_as,
                        echo=lambda line: typer.echo(line, err=True))
    rec = comparison["recommendation"]
    typer.echo(f"recommendation: {rec['mechanism'] or 'none'}")
    for reason in rec["reasons"]:
        typer.echo(f"  - {reason}")
    typer.echo(f"comparison: {target / 'comparison.md'}")
    if rec["mechanism"]:
        typer.echo(f"datasheet: {target / 'chosen' / 'datasheet.html'}")
        for kind in ("pdf", "png"):
            if f"chosen/datasheet.{kind}" in rec.get("files", []):
                typer.echo(f"print: {target / 'chosen' / f'datasheet.{kind}'}")


@app.command("datasheet")
@handles_errors
def datasheet_cmd(
    run: Annotated[Path, typer.Argument(help="results directory")],
    out: OutFile,
    design: DesignOpt = None,
    print_as: PrintOpt = None,
    force: ForceOpt = False,
) -> None:
    """Write the datasheet (self-contained HTML) of a design of a run's front, and its print (PDF or PNG, same
    name) beside it."""
    from scalesynth import html_print
    from scalesynth import io as rio
    from scalesynth.cliapp import _warn
    from scalesynth.design import datasheet
    from scalesynth.errors import ConfigError, RunError
    from scalesynth.selection import load_design

    printing = html_print.plan(print_as)
    shown = html_print.print_target(out, printing.kind) if printing.kind else None
    if shown is not None and shown.name == Path(out).name:
        raise ConfigError(f"--out: {Path(out).name[:60]}: the datasheet is HTML; give a .html name (its print goes "
                          f"beside it as .{printing.kind})")
    chosen = load_design(run, design or "knee")
    target = _check_new_file(out, force)
    print_file = _check_new_file(shown, force) if shown is not None else None
    page = datasheet.build(chosen.result, chosen.row, label=chosen.label)
    if printing.note:
        _warn(printing.note)
    if print_file is not None:  # printed first: an asked-for print that fails leaves nothing written
        try:
            html_print.print_html(page, print_file, printing.kind, printing.browser)
        except RunError as err:
            if printing.explicit:
                raise
            _warn(f"no print of the datasheet: {err}")
            shown = None
    rio.write_text(target, page)
    typer.echo(f"datasheet: {out}")
    if shown is not None:
        typer.echo(f"print: {shown}")


@app.command("export")
@handles_errors
def export_cmd(
    run: Annotated[Path, typer.Argument(help="results directory")],
    design: DesignOpt = None,
    description: Annotated[Path | None, typer.Option(
        "--description", help="write the mechanism description with the design's numbers (YAML)")] = None,
    mesh: Annotated[Path | None, typer.Option("--mesh", help="write a mesh of the robot (.stl or .glb)")] = None,
    pose: Annotated[str | None, typer.Option("--pose", help="pose of the mesh, comma-separated task coordinates "
                                             "(default: the task box's centre)")] = None,
    force: ForceOpt = False,
) -> None:
    """Export a design of a run's front: its mechanism description with the numbers filled in (described
    mechanisms) and/or a mesh of the robot at a pose."""
    from scalesynth import io as rio
    from scalesynth.cliapp import _parse_vector
    from scalesynth.design import export
    from scalesynth.errors import ConfigError, InvalidParameter
    from scalesynth.selection import load_design

    if description is None and mesh is None:
        raise ConfigError("export: give --description FILE, --mesh FILE or both")
    chosen = load_design(run, design or "knee")
    mech = chosen.mech
    if mesh is not None and Path(mesh).suffix.lower() not in (".stl", ".glb"):
        raise ConfigError(f"--mesh: {Path(mesh).name[:60]}: expected a .stl or .glb file")
    targets = {k: _check_new_file(p, force) for k, p in (("description", description), ("mesh", mesh)) if p}
    if description is not None:
        made = export.description_yaml(mech, chosen.design, Path(description).stem)
        if made is None:
            raise InvalidParameter(f"--description: {mech.name} is written in Python, not described (no "
                                   "description to fill in)")
        rio.write_text(targets["description"], made[1])
        typer.echo(f"description: {description}")
    if mesh is not None:
        at = _parse_vector("--pose", pose, len(mech.task_axes)) if pose else export.default_pose(chosen.cfg)
        geometry = export.geometry_at(mech, chosen.design, chosen.options, at)
        if geometry is None:
            raise InvalidParameter(f"--mesh: {mech.name} has no link geometry yet (nothing to mesh)")
        export.write_mesh(export.capsule_mesh(geometry), targets["mesh"])
        typer.echo(f"mesh: {mesh}")
