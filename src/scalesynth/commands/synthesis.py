"""Commands of the synthesis workflow: optimize, plot-front, plot-bands, select."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from scalesynth.cliapp import ForceOpt, SetOpt, app, handles_errors


@app.command("optimize")
@handles_errors
def optimize_cmd(
    config: Annotated[Path, typer.Argument(help="run config (YAML)")],
    out: Annotated[Path | None, typer.Option("--out", help="results directory (default results/<name>)")] = None,
    seed: Annotated[
        int | None, typer.Option("--seed", min=0, max=2**32 - 1, help="random seed (overrides algorithm.seed)")
    ] = None,
    resume: Annotated[bool, typer.Option("--resume", help="continue from the directory's checkpoint")] = False,
    sets: SetOpt = None,
    no_plots: Annotated[bool, typer.Option("--no-plots", help="skip plots and report.md")] = False,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="no progress output")] = False,
    force: ForceOpt = False,
) -> None:
    """Run the NSGA-II synthesis and write pareto.csv, history.csv, manifest.json, config.yaml, plots, report.md."""
    from scalesynth.config import load_config
    from scalesynth.optimize import run
    from scalesynth.progress import make_progress
    from scalesynth.results import infeasibility_lines

    cfg = load_config(config, sets)
    progress = make_progress(cfg.algorithm.n_gen, quiet)
    try:
        result = run(cfg, out, seed=seed, resume=resume, progress=progress, plots=not no_plots, force=force)
    finally:
        if progress is not None:
            progress.close()
    m = result.manifest
    for line in infeasibility_lines(m):
        typer.echo(line, err=True)
    typer.echo(
        f"{m['name']}: {m['pareto_size']} Pareto designs, HV {m['hypervolume']:.6g}, "
        f"{m['evaluations']} evaluations in {m['wall_seconds']:.1f} s -> {result.out_dir}",
        err=True,
    )
    typer.echo(str(result.out_dir))


PlotOut = Annotated[Path | None, typer.Option("--out", help="directory for the figures (default RUN_DIR/plots)")]
PlotFormat = Annotated[str, typer.Option("--format", help="png | svg | pdf")]


def _echo_files(files) -> None:
    for f in files:
        typer.echo(str(f))


@app.command("plot-front")
@handles_errors
def plot_front_cmd(run_dir: Annotated[Path, typer.Argument(help="results directory of a finished run")],
                   out: PlotOut = None, fmt: PlotFormat = "png", force: ForceOpt = False) -> None:
    """Pareto front with the config's reference designs re-evaluated, and hypervolume per generation."""
    from scalesynth.report import plot_front_run

    _echo_files(plot_front_run(run_dir, out, fmt, force))


@app.command("plot-bands")
@handles_errors
def plot_bands_cmd(run_dir: Annotated[Path, typer.Argument(help="results directory of a finished run")],
                   out: PlotOut = None, fmt: PlotFormat = "png", force: ForceOpt = False) -> None:
    """Front coloured by each dexterity band's share; band shares and LCI sections of knee and extreme designs;
    per-band Pareto sets (bands/pareto_band<k>.csv and their plots)."""
    from scalesynth.report import plot_bands_run

    info = plot_bands_run(run_dir, out, fmt, force)
    _echo_files(info["files"] + info["band_files"])


@app.command("select")
@handles_errors
def select_cmd(
    run_dir: Annotated[Path, typer.Argument(help="results directory of a finished run")],
    method: Annotated[str, typer.Option("--method", help="knee | balanced | weights")] = "knee",
    weights: Annotated[str | None, typer.Option("--weights", help="comma-separated, one per objective")] = None,
    out: Annotated[
        Path | None, typer.Option("--out", help="config to write (default RUN_DIR/selected_<method>.yaml)")
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="print one JSON object on stdout")] = False,
    force: Annotated[bool, typer.Option("--force", help="replace an existing --out file that select did not write")
                     ] = False,
) -> None:
    """Choose one design from the front; print it and write it as a config that `scalesynth evaluate` accepts."""
    from scalesynth.errors import InvalidParameter
    from scalesynth.selection import select_design

    w = None
    if weights is not None:
        try:
            w = [float(v) for v in weights.split(",")]
        except ValueError:
            raise InvalidParameter(f"--weights: expected comma-separated numbers, got {weights!r}") from None
    chosen = select_design(run_dir, method, w, out, force=force)
    if as_json:
        from scalesynth.cliapp import _print_json

        _print_json(chosen)
        return
    typer.echo(f"{method} design: " + ", ".join(f"{k}={v:.6g}" for k, v in chosen["design"].items()))
    typer.echo("  " + ", ".join(f"{k}={v:.6g}" for k, v in chosen["metrics"].items()))
    typer.echo(f"  config written to {chosen['config']}")


@app.command("reproduce")
@handles_errors
def reproduce_cmd(
    run_dir: Annotated[Path, typer.Argument(help="results directory of a finished run")],
    out: Annotated[Path | None, typer.Option("--out", help="where to re-run (default: a temporary directory)")] = None,
    force: ForceOpt = False,
) -> None:
    """Re-run a finished run from its manifest (config and seed) and check pareto.csv is byte-identical."""
    import tempfile

    from scalesynth.optimize import reproduce

    def warn_versions(differences: list[str]) -> None:
        if differences:  # said before the re-run, which may take long
            typer.echo(f"warning: dependency versions differ from the recorded run ({'; '.join(differences)}): "
                       "byte-identical results are expected only with the same versions and machine type", err=True)

    with tempfile.TemporaryDirectory() as tmp:
        info = reproduce(run_dir, out if out is not None else Path(tmp) / "rerun", on_versions=warn_versions,
                         force=force)
    verdict = "identical" if info["identical"] else "DIFFERENT"
    typer.echo(f"pareto.csv {verdict}: HV {info['hypervolume']:.6g} (original {info['original_hypervolume']:.6g}), "
               f"re-run took {info['wall_seconds']:.1f} s")
    if not info["identical"]:
        raise typer.Exit(1)
