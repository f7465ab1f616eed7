"""``scalesynth example``: list the example configs shipped with the package, or write one to a file."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer

from scalesynth.cliapp import app, handles_errors
from scalesynth.errors import ConfigError


@app.command("example")
@handles_errors
def example_cmd(
    name: Annotated[str | None, typer.Argument(help="example name (see --list)")] = None,
    out: Annotated[
        str | None, typer.Option("--out", "-o", help="file to write (default NAME.yaml here; '-' for stdout)")
    ] = None,
    force: Annotated[bool, typer.Option("--force", help="overwrite an existing file")] = False,
    list_: Annotated[bool, typer.Option("--list", help="list the examples with a one-line description")] = False,
) -> None:
    """Write an example config (e.g. `scalesynth example quick --out q.yaml`), or list them with --list."""
    from scalesynth import examples
    from scalesynth import io as rio

    if list_:
        width = max(len(n) for n in examples.names())
        for n in examples.names():
            typer.echo(f"{n:<{width}}  {examples.description(n)}")
        return
    if name is None:
        raise ConfigError("example: give an example name (see `scalesynth example --list`)")
    content = examples.text(name)
    if out == "-":
        sys.stdout.write(content)
        return
    path = Path(out) if out else Path(f"{name}.yaml")
    if path.exists() and not force:
        raise ConfigError(f"--out: {path} exists (use --force to overwrite it)")
    if path.is_dir():
        raise ConfigError(f"--out: {path} is a directory")
    rio.write_text(path, content)
    typer.echo(f"wrote {path} (example {name!r}); run it with: scalesynth optimize {path}", err=True)
