"""``scalesynth cycle CONFIG|RUN_DIR``: a design's pick-and-place cycle (``scalesynth.cycle``).

CONFIG is a run config with a ``cycle:`` section (its ``design`` is analysed); RUN_DIR is a results directory,
whose config must have one, with ``--design knee`` (default), ``best-<metric>`` (the front row with the best
value of a metric) or a row number of pareto.csv (``scalesynth.selection``); ``--set`` overrides either. Writes
cycle.csv, cycle.json, actuators.png, path.png, quality.png to ``--out`` (default: <results dir>/cycle for a config,
RUN_DIR/cycle-<design> for a run).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from scalesynth.cliapp import ForceOpt, JsonOpt, SetOpt, _print_json, app, handles_errors
from scalesynth.errors import ConfigError


def run_cycle(source: Path, sets: list[str] | None = None, design_choice: str | None = None, out: Path | None = None,
              force: bool = False, need_motors: bool = False):
    """Analyse the cycle and write its files; returns the summary dict (cycle.json's content plus file paths).

    The output directory is staged and swapped in whole (``scalesynth.rundir``): a failure or an interrupt leaves
    the previous one as it was. It must be new, empty or a cycle directory unless ``force``. ``need_motors``
    (``--datasheet``): a config without a motors section is refused before anything is written."""
    from scalesynth import rundir
    from scalesynth.cycle import analysis, output
    from scalesynth.selection import load_design

    source = Path(source)
    chosen = load_design(source, design_choice, sets)
    cfg, design = chosen.cfg, chosen.design
    if out is not None:
        out_dir = out
    elif chosen.result is not None:
        out_dir = source / f"cycle-{chosen.label}"
    else:
        out_dir = cfg.output_dir() / "cycle"
    if cfg.cycle is None:
        raise ConfigError("cycle: the config has no cycle section (cycle.path or cycle.preset)")
    if need_motors and getattr(cfg.cycle, "_motors", None) is None:
        raise ConfigError("--datasheet: the config has no motors section (the datasheet needs motors)")
    options = cfg.resolved_options()
    with rundir.staged(out_dir, output.OUTPUT, force) as staged:  # --out checked and locked before the analysis
        res = analysis.analyse(cfg.mech, design, options, cfg.cycle, cfg.units.length)
        metrics = analysis.result_metrics(res, cfg.cycle)
        info = output.write_all(staged.work, cfg, design, options, res, metrics)
    info["files"] = [str(staged.target / name) for name in info["files"]]
    return info


@app.command("cycle")
@handles_errors
def cycle_cmd(
    source: Annotated[Path, typer.Argument(help="run config (YAML) with a cycle section, or a results directory")],
    sets: SetOpt = None,
    design: Annotated[
        str | None, typer.Option("--design", help="of a results directory: knee (default), best-<metric> or a row")
    ] = None,
    out: Annotated[Path | None, typer.Option("--out", help="output directory")] = None,
    as_json: JsonOpt = False,
    force: ForceOpt = False,
    show_datasheet: Annotated[bool, typer.Option(
        "--datasheet", help="print the design's datasheet (needs motors): picks/min against payload, tool and "
        "motor peaks")] = False,
) -> None:
    """Pick-and-place cycle of a design: actuator curves and forces, LCI and link clearance (cycle.csv, plots)."""
    info = run_cycle(source, sets, design, out, force, need_motors=show_datasheet)
    if as_json:
        _print_json(info)
        return
    m = info["metrics"]
    typer.echo(f"cycle of {info['period_s']:.4g} s, {info['samples']} samples, {len(info['vertices']) - 1} segments")
    for key, value in m.items():
        typer.echo(f"  {key:<26} {value:.6g}")
    where = info["min_clearance_at"]
    typer.echo(f"  min clearance at t = {where['t_s']:.4g} s between {' and '.join(where['segments']) or '-'}")
    if "time_optimal_picks_per_minute" in info:
        typer.echo(f"  time-optimal (toppra, peak torque and speed): {info['time_optimal_picks_per_minute']:.4g} "
                   f"picks/min, {info['time_optimal_cycle_time_s']:.4g} s, binding "
                   f"{info['time_optimal_binding_limit']}")
    if show_datasheet:
        from scalesynth.cycle.datasheet import text_table

        typer.echo(text_table(info["datasheet"]))
    typer.echo("wrote " + ", ".join(info["files"]))
