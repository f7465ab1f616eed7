"""`scalesynth batch`: many configs x seeds on dask.distributed (see scalesynth.batch)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from scalesynth.cliapp import ForceOpt, SetOpt, _print_json, app, handles_errors


@app.command("batch")
@handles_errors
def batch_cmd(
    configs: Annotated[list[Path], typer.Argument(help="run configs (YAML); each needs its own name")],
    seeds: Annotated[int, typer.Option("--seeds", help="seeds per config: seed, seed+1, ... from the config")] = 1,
    scheduler: Annotated[
        str | None,
        typer.Option("--scheduler", help="address of a running dask scheduler, e.g. tcp://host:8786 (default: a "
                     "local cluster sized to this machine)"),
    ] = None,
    scheduler_file: Annotated[
        Path | None,
        typer.Option("--scheduler-file", help="JSON file with the scheduler's address, as written by `dask scheduler "
                     "--scheduler-file` or dask-mpi"),
    ] = None,
    out: Annotated[Path, typer.Option("--out", help="batch directory on this machine (the client)")] = Path(
        "results/batch"),
    sets: SetOpt = None,
    as_json: Annotated[
        bool, typer.Option("--json", help="print the summary (batch.json) instead of the table")
    ] = False,
    force: ForceOpt = False,
) -> None:
    """Run every (config, seed) pair as one dask task into OUT/<name>/seed<k>/ (finished tasks are skipped,
    unfinished ones resumed); write OUT/batch.json and, per config, the combined front and a hypervolume plot.
    The client writes every file: workers need no access to OUT. A task directory that is neither new, empty nor
    a run's is refused before any task runs (exit 2) unless --force. Exit code 1 if any task failed."""
    from scalesynth.batch import format_table, run_batch
    from scalesynth.cluster import address_from_file, check_address, check_protocol
    from scalesynth.config import load_config
    from scalesynth.errors import ConfigError

    if scheduler and scheduler_file:
        raise ConfigError("--scheduler, --scheduler-file: give one of them")
    scheduler = address_from_file(scheduler_file) if scheduler_file else check_address(scheduler) if scheduler else None
    if scheduler:
        check_protocol(scheduler)  # one this installation cannot speak: refused before anything is loaded
    loaded = [(str(path), load_config(path, sets)) for path in configs]  # all validated before any task starts
    summary = run_batch(loaded, out, seeds=seeds, scheduler=scheduler, echo=lambda line: typer.echo(line, err=True),
                        force=force)
    if as_json:
        _print_json(summary.to_dict())
    else:
        typer.echo(format_table(summary.tasks))
        for name, info in summary.combined.items():
            if info.get("error"):
                typer.echo(f"{name}: no combined front ({info['error']})")
            elif info["seeds"]:
                typer.echo(f"{name}: combined front of seeds {', '.join(map(str, info['seeds']))}: "
                           f"{info['pareto_size']} designs, HV {info['hypervolume']:.6g}")
        typer.echo(f"summary: {out / 'batch.json'}")
    if summary.n_failed:
        typer.echo(f"error: {summary.n_failed} of {len(summary.tasks)} tasks failed", err=True)
        raise typer.Exit(1)
