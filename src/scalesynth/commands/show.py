"""`scalesynth show CONFIG|RUN_DIR`: one design's workspace in 3-D, its dexterity-band regions and sections."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from scalesynth.cliapp import ForceOpt, SetOpt, _print_json, app, handles_errors


@app.command("show")
@handles_errors
def show_cmd(
    source: Annotated[Path, typer.Argument(help="run config (YAML) or results directory of a finished run")],
    design: Annotated[str | None, typer.Option(
        "--design", help="of a results directory: knee (default), best-<metric> (e.g. best-gci) or a pareto.csv row")
    ] = None,
    field: Annotated[str, typer.Option("--field", help="per-voxel field colouring the views")] = "lci",
    at: Annotated[list[str] | None, typer.Option(
        "--at", help="section position axis=value (repeatable; default: through the workspace centroid)")] = None,
    out: Annotated[Path | None, typer.Option(
        "--out", help="directory to write (default RUN_DIR/show/<design> or results/<name>/show/config)")] = None,
    fmt: Annotated[str, typer.Option("--format", help="png | svg | pdf | html")] = "png",
    resolution: Annotated[int | None, typer.Option(help="cells per axis (default grid.resolution)")] = None,
    pose: Annotated[str | None, typer.Option(
        "--pose", help="task coordinates of the robot drawing, comma-separated (default: near the centroid)")] = None,
    sets: SetOpt = None,
    as_json: Annotated[bool, typer.Option("--json", help="print show.json's content on stdout")] = False,
    force: ForceOpt = False,
) -> None:
    """3-D workspace coloured by a field, each dexterity band's connected regions (counted, 26-connectivity),
    sections with the task box and path; writes the figures and show.json."""
    from scalesynth.show import show_design

    info = show_design(source, design, field, at, out, fmt, resolution, sets, pose, force)
    if as_json:
        _print_json(info)
        return
    typer.echo(f"{info['mechanism']} {info['design_choice']}: "
               + ", ".join(f"{k}={v:.6g}" for k, v in info["design"].items()))
    for b in info["bands"]:
        typer.echo(f"  LCI {b['label']:<11} {100 * b['share']:6.2f} %  {b['regions']} connected regions "
                   f"(26-connected; {b['regions_face_connected']} face-connected, {b['regions_over_1pct']} of >= 1 %)")
    for s in info["sections"]:
        if s.get("normal") is not None:
            typer.echo(f"  section {s['normal']} = {s['value']:.6g} ({s['source']}): {s['cells']} reachable cells")
    robot = info["robot"]
    if "missing" in robot:
        typer.echo(f"  robot not drawn: {robot['missing']}")
    for f in info["files"] + ["show.json"]:
        typer.echo(str(Path(info["out"]) / f))
