"""`scalesynth compare RUN_DIR...`: one table and one figure comparing runs on the metrics they share."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from scalesynth.cliapp import ForceOpt, _print_json, app, handles_errors


@app.command("compare")
@handles_errors
def compare_cmd(
    run_dirs: Annotated[list[Path], typer.Argument(help="results directories of finished runs (two or more)")],
    out: Annotated[Path | None, typer.Option("--out", help="directory for compare.csv and the figure")] = None,
    fmt: Annotated[str, typer.Option("--format", help="png | svg | pdf")] = "png",
    x: Annotated[str | None, typer.Option("--x", help="shared metric on the figure's x axis (catalogue name, e.g. "
                                          "link_length_sum, or column)")] = None,
    y: Annotated[str | None, typer.Option("--y", help="shared metric on the figure's y axis")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="print the table as one JSON object")] = False,
    force: ForceOpt = False,
) -> None:
    """Compare runs (also of different mechanisms) on their shared metrics, with each run's selected designs;
    metrics are matched by catalogue name, values in another length unit converted to the first run's."""
    from scalesynth.compare import compare_runs

    info = compare_runs(run_dirs, out, fmt, x, y, force)
    table = info["table"]
    _say_conversions(info)
    if as_json:
        _print_json({"shared_metrics": info["shared_metrics"], "axes": info["axes"], "out": info["out"],
                     "converted": info["converted"], "rows": table.to_dict(orient="records")})
        return
    cols = ["run", "mechanism", "design", *info["shared_metrics"]]
    typer.echo(table[cols].to_string(index=False, float_format=lambda v: f"{v:.5g}"))
    for f in info["files"]:
        typer.echo(str(Path(info["out"]) / f))


def _say_conversions(info: dict) -> None:
    """One line on stderr per run whose values were converted to the first run's units: the figure's axes first."""
    from scalesynth.names import short_list

    by_run: dict[str, list[dict]] = {}
    for c in info["converted"]:
        by_run.setdefault(c["run"], []).append(c)
    axes = info["axes"]
    for run, items in by_run.items():
        items.sort(key=lambda c: axes.index(c["column"]) if c["column"] in axes else len(axes))
        text = short_list([f"{c['metric']} {c['from']} -> {c['to']}" for c in items], 100)
        typer.echo(f"note: {run}: converted to the first run's units: {text}", err=True)
