"""Command-line interface (typer). Thin: parse -> library call -> print / exit code.

Exit codes: 0 ok, 1 run failed, 2 bad input (one line on stderr naming what is wrong).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Annotated

# OpenBLAS (NumPy's and SciPy's copies) starts a thread pool per library when it loads, whose threads spin: about
# 0.1 s of wall and 0.25 s of CPU time at every CLI process's start on 2 cores (benchmarks/notes/first_evaluation.md).
# scalesynth's parallel work is Numba's; its BLAS calls are on matrices too small for OpenBLAS to thread. Set before
# anything imports NumPy; an explicit OPENBLAS_NUM_THREADS wins.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import typer  # noqa: E402

from scalesynth.cliapp import (  # noqa: F401 - re-exported: app and the shared helpers live in cliapp
    DesignOpt,
    JsonOpt,
    SetOpt,
    SourceArg,
    _design_inputs,
    _fail,
    _parse_vector,
    _print_json,
    _warn,
    app,
    error_line,
    handles_errors,
)
from scalesynth.errors import ConfigError  # noqa: E402


@app.command("mechanisms")
@handles_errors
def mechanisms_cmd(
    name: Annotated[str | None, typer.Argument(help="only this mechanism")] = None,
    description: Annotated[bool, typer.Option(
        "--description", help="print the mechanism's description (YAML) to start your own from")] = False,
    as_json: JsonOpt = False,
) -> None:
    """List registered mechanisms and their parameters; with NAME --description, print NAME's description."""
    from scalesynth.mechanisms import available, get

    if description:
        if name is None:
            raise ConfigError("--description: name the mechanism (scalesynth mechanisms NAME --description)")
        _print_description(get(name))
        return
    rows = []
    for key in ([get(name).name] if name is not None else available()):
        m = get(key)
        rows.append(
            {
                "name": m.name,
                "title": m.title,
                "seed": m.seed,
                "motion": m.motion,
                "task_axes": list(m.task_axes),
                "joints": list(m.joints),
                "parameters": {p.name: {"default": p.default, "doc": p.doc} for p in m.parameters},
                "options": {o.name: {"default": o.default, "doc": o.doc} for o in m.options},
            }
        )
    if as_json:
        _print_json(rows)
        return
    for r in rows:
        origin = f"seed {r['seed']}" if r["seed"] else "described"
        typer.echo(f"{r['name']:<16} {origin:<9}  {r['motion']:<5} {r['title']}")
        typer.echo("    parameters: " + ", ".join(f"{k}={v['default']:g}" for k, v in r["parameters"].items()))
        if r["options"]:
            typer.echo("    options:    " + ", ".join(f"{k}={v['default']!r}" for k, v in r["options"].items()))


def _print_description(mech) -> None:
    """The description file of a described built-in mechanism, as shipped (comments included)."""
    from scalesynth.mechanisms.describe import builtin_path

    path = builtin_path(mech.name)
    if getattr(mech, "description", None) is None or not path.is_file():
        raise ConfigError(f"--description: {mech.name} is a hand-written mechanism (seed {mech.seed}), not a "
                          "described one: start from a described one (scalesynth mechanisms lists them)")
    typer.echo(path.read_text(encoding="utf-8"), nl=False)


@app.command("evaluate")
@handles_errors
def evaluate_cmd(
    config: Annotated[Path, typer.Argument(help="run config (YAML), or a results directory with --design")],
    design_choice: DesignOpt = None,
    sets: SetOpt = None,
    resolution: Annotated[int | None, typer.Option(help="cells per axis; forces the uniform grid")] = None,
    as_json: JsonOpt = False,
) -> None:
    """Evaluate one design: workspace measure, GCI, FCI, band shares, voxels, seconds."""
    from scalesynth.evaluate import evaluate_config
    from scalesynth.selection import load_design

    overrides = list(sets or [])
    if resolution is not None:
        overrides.append(f"grid.resolution={resolution}")
    chosen = load_design(config, design_choice, overrides)
    cfg = chosen.cfg
    from scalesynth import memory

    memory.check(memory.evaluate_estimates(cfg))
    mech = cfg.mech
    design = chosen.design
    for key, (lo, hi) in cfg.bounds.items():
        if not lo <= design[key] <= hi:
            _warn(f"design.{key}={design[key]:g} is outside the optimisation bounds [{lo:g}, {hi:g}]")
    report = evaluate_config(cfg, design)
    out = report.to_dict()
    if as_json:
        _print_json(out)
        return
    typer.echo(f"{mech.name}  design " + ", ".join(f"{k}={v:g}" for k, v in design.items()))
    edges = report.band_edges
    for key, value in report.metrics.items():  # every catalogue metric of this config, in catalogue order
        if key == "voxels":
            continue
        label = key
        if key.startswith("band") and key.endswith("_share"):
            b = int(key[4:-6])
            label = f"{key} (band {b}: LCI in {'[' if b == 0 else '('}{edges[b]:g}, {edges[b + 1]:g}])"
        typer.echo(f"  {label:<34} {value:.6g}")
    if "error_volume" in out:  # grid.tolerance: error_volume / error_gci printed above
        from scalesynth.evaluate import config_tolerance, uniform_resolution

        n = uniform_resolution(mech, config_tolerance(cfg))
        if n is None:
            typer.echo(f"  adaptive grid: {out['grid_cells']} kernel calls, {out['seconds']:.3f} s")
        else:
            typer.echo(f"  calibrated uniform grid: resolution {n} (estimates against {2 * n}), "
                       f"{out['grid_cells']} cells, {out['seconds']:.3f} s")
    else:
        typer.echo(
            f"  voxels {out['voxels']} of {out['grid_cells']} (resolution {out['resolution']}), {out['seconds']:.3f} s"
        )


@app.command("ik")
@handles_errors
def ik_cmd(
    mechanism: SourceArg,
    pose: Annotated[str, typer.Option("--pose", help="task coordinates, comma-separated")],
    design_choice: DesignOpt = None,
    sets: SetOpt = None,
    as_json: JsonOpt = False,
) -> None:
    """All inverse-kinematics branches of a pose."""
    mech, design, options = _design_inputs(mechanism, design_choice, sets)
    p = _parse_vector("--pose", pose, len(mech.task_axes))
    sols = mech.inverse_kinematics(design, options, p)
    rows = []
    for s in sols:
        row = s.as_dict()
        row["singularity"] = mech.singularity(design, options, p, s.values)
        row["lci"] = mech.lci(design, options, p, s.values)
        rows.append(row)
    _print_solutions(mech.joints, rows, as_json, "pose out of reach: no IK solution")


@app.command("fk")
@handles_errors
def fk_cmd(
    mechanism: SourceArg,
    inputs: Annotated[str, typer.Option("--inputs", help="joint inputs, comma-separated")],
    design_choice: DesignOpt = None,
    sets: SetOpt = None,
    as_json: JsonOpt = False,
) -> None:
    """All forward-kinematics assembly modes of a joint-input vector."""
    mech, design, options = _design_inputs(mechanism, design_choice, sets)
    q = _parse_vector("--inputs", inputs, len(mech.joints))
    rows = [s.as_dict() for s in mech.forward_kinematics(design, options, q)]
    _print_solutions(mech.pose_axes, rows, as_json, "no isolated assembly: inputs out of reach or degenerate")


def _print_solutions(names, rows, as_json: bool, empty_msg: str) -> None:
    if as_json:
        _print_json({"names": list(names), "solutions": rows})
        return
    if not rows:
        typer.echo(empty_msg)
        return
    for r in rows:
        vals = ", ".join(f"{n}={v:.6f}" for n, v in zip(names, r["values"], strict=True))
        extra = ""
        if "singularity" in r:
            extra = f"  singularity={r['singularity']} lci={r['lci']:.6f}"
        typer.echo(f"{r['branch']:>6}: {vals}{extra}")


@app.callback()
def _root(
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="no notice when Numba compiles (any command)")] = False,
) -> None:
    """Multi-objective dimensional synthesis of parallel mechanisms."""
    if quiet:
        from scalesynth import compile_notice

        compile_notice.enable(quiet=True)


def _quiet(argv: list[str]) -> bool:
    """-q/--quiet anywhere before '--' (before the command, or a command's own, e.g. optimize -q)."""
    words = argv[: argv.index("--")] if "--" in argv else argv
    return any(w in ("-q", "--quiet") for w in words)


def _load_commands() -> None:
    """Register the commands defined in ``scalesynth.commands`` (one module per command group)."""
    import importlib
    import pkgutil

    import scalesynth.commands as pkg

    for info in pkgutil.iter_modules(pkg.__path__):
        importlib.import_module(f"{pkg.__name__}.{info.name}")


_load_commands()


def _usage_message(err) -> str:
    """click's message (it already says "did you mean" for a misspelt command or option) and where help is."""
    hint = f" (try `{err.ctx.command_path} --help`)" if err.ctx is not None else ""
    return f"{err.format_message()}{hint}"


def main(argv: list[str] | None = None) -> None:
    """The console entry point: usage errors (unknown option, bad value, missing argument) become one line on
    stderr with exit code 2, like every other bad input, instead of click's framed box. A process that compiles
    Numba kernels says so in one line on stderr, unless -q/--quiet (scalesynth.compile_notice)."""
    from scalesynth import compile_notice

    args = list(sys.argv[1:] if argv is None else argv)
    compile_notice.enable(quiet=_quiet([str(a) for a in args]))  # one line on stderr if this process compiles
    try:
        _run(args)
    finally:  # main() called in-process (tests, scripts): the notice does not outlive it
        compile_notice.enable(quiet=True)


def _run(args: list[str]) -> None:
    try:  # typer >= 0.22 vendors click
        from typer._click import exceptions as click_errors
    except ImportError:  # pragma: no cover - older typer on upstream click
        from click import exceptions as click_errors

    from scalesynth import environment
    from scalesynth.errors import ScalesynthError

    try:
        environment.check()  # NUMBA_* variables, before any command imports Numba
    except ScalesynthError as err:
        typer.echo(f"error: {err}", err=True)
        sys.exit(err.exit_code)
    try:
        rv = app(args=args, prog_name="scalesynth", standalone_mode=False)
    except click_errors.NoArgsIsHelpError as err:
        typer.echo(err.ctx.get_help() if err.ctx is not None else str(err), err=True)
        sys.exit(2)
    except click_errors.UsageError as err:
        typer.echo(error_line(_usage_message(err)), err=True)
        sys.exit(2)
    except typer.Abort:
        typer.echo(error_line("interrupted"), err=True)
        sys.exit(1)
    except Exception as err:  # a bug: still one line, never a traceback (SCALESYNTH_DEBUG=1 shows it)
        import os

        if os.environ.get("SCALESYNTH_DEBUG"):
            raise
        typer.echo(error_line(f"internal error ({err.__class__.__name__}: {err}); please report it"), err=True)
        sys.exit(1)
    sys.exit(rv if isinstance(rv, int) else 0)
