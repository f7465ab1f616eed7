"""``scalesynth metrics [MECH] [--json]``: the metric catalogue (scalesynth.metrics), per mechanism or for all."""

from __future__ import annotations

from typing import Annotated

import typer

from scalesynth.cliapp import JsonOpt, _print_json, app, handles_errors


@app.command("metrics")
@handles_errors
def metrics_cmd(
    mechanism: Annotated[
        str | None, typer.Argument(help="mechanism name (see `scalesynth mechanisms`); default: every mechanism")
    ] = None,
    as_json: JsonOpt = False,
) -> None:
    """Every metric usable as an objective or constraint: column, family, field, unit, range, better sense,
    worst value, what it needs, description."""
    from scalesynth.metrics import listing

    rows = listing(mechanism)
    if as_json:
        _print_json(rows)
        return
    for r in rows:
        rng = "[" + ", ".join("inf" if v is None else f"{v:g}" for v in r["range"]) + "]"
        needs = f"  needs {', '.join(r['needs'])}" if r["needs"] else ""
        typer.echo(f"{r['name']:<22} {r['column']:<32} {r['family']:<9} {r['unit']:<8} {rng:<10} "
                   f"better {r['better'] or '-'}{needs}")
        typer.echo(f"    {r['description']}")
        if mechanism is None:
            typer.echo(f"    mechanisms: {', '.join(r['mechanisms'])}")
