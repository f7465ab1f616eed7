"""``scalesynth cycle CONFIG|RUN_DIR``: a design's pick-and-place cycle (``scalesynth.cycle``).

CONFIG is a run config with a ``cycle:`` section (its ``design`` is analysed); RUN_DIR is a results directory,
whose config must have one, with ``--design knee`` (default), ``best-<metric>`` (the front row with the best
value of a metric) or a row number of pareto.csv. Writes cycle.csv, cycle.json, actuators.png, path.png, quality.png to
``--out`` (default: <results dir>/cycle for a config, RUN_DIR/cycle-<design> for a run).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from scalesynth.cliapp import ForceOpt, JsonOpt, SetOpt, _print_json, app, handles_errors
from scalesynth.errors import ConfigError


def pick_design(run_dir: Path, choice: str):
    """(config, design, label) of a results directory's front row chosen by ``choice``: knee, best-<metric> (a
    catalogue metric name or result column; the best value in the objective's sense, or the catalogue's better
    direction for a metric that is not an objective) or a row number of pareto.csv."""
    import numpy as np

    from scalesynth import results
    from scalesynth.metrics import catalogue
    from scalesynth.selection import choose

    result = results.load(run_dir, require_finished=False)
    cfg, pareto = result.cfg, result.pareto
    if not len(pareto):
        raise ConfigError(f"{run_dir}: the front is empty (no feasible design)")
    if choice == "knee":
        row = choose(result.objective_matrix(), "knee")
    elif choice.startswith("best-"):
        wanted = choice.removeprefix("best-")
        cat = catalogue(cfg.mech, cfg.units.length)
        entry = next((m for m in cat.values() if wanted in (m.name, m.column) and "band" not in m.needs), None)
        if entry is None or entry.column not in pareto.columns or entry.better is None:
            known = [m.name for m in cat.values() if m.column in pareto.columns and m.better is not None]
            raise ConfigError(f"--design: best-{wanted}: not a metric of the run's results (known: {', '.join(known)})")
        senses = {o.metric: o.sense for o in cfg.objectives}
        sense = senses.get(entry.name, entry.better)
        values = pareto[entry.column].to_numpy(dtype=float)
        if np.isnan(values).all():
            raise ConfigError(f"--design: best-{wanted}: null on every front row (a statistic over an empty set)")
        # a statistic over an empty set (NaN) is never the best row
        row = int(np.nanargmax(values) if sense == "max" else np.nanargmin(values))
    else:
        try:
            row = int(choice)
        except ValueError:
            raise ConfigError(f"--design: expected knee, best-<metric> or a row number, got {choice!r}") from None
        if not 0 <= row < len(pareto):
            raise ConfigError(f"--design: row {row} out of range (pareto.csv has {len(pareto)} rows)")
    label = choice if choice.startswith(("knee", "best-")) else f"row{row}"
    return cfg, result.design_of(pareto.iloc[row]), label


def run_cycle(source: Path, sets: list[str] | None = None, design_choice: str | None = None, out: Path | None = None,
              force: bool = False):
    """Analyse the cycle and write its files; returns the summary dict (cycle.json's content plus file paths).

    The output directory is staged and swapped in whole (``scalesynth.rundir``): a failure or an interrupt leaves
    the previous one as it was. It must be new, empty or a cycle directory unless ``force``."""
    from scalesynth import rundir
    from scalesynth.config import load_config
    from scalesynth.cycle import analysis, output

    source = Path(source)
    if source.is_dir():
        if sets:
            raise ConfigError("--set: applies to a config file, not to a results directory")
        cfg, design, label = pick_design(source, design_choice or "knee")
        out_dir = out if out is not None else source / f"cycle-{label}"
    else:
        if design_choice is not None:
            raise ConfigError("--design: applies to a results directory, not to a config file")
        cfg = load_config(source, sets)
        design = cfg.resolved_design()
        out_dir = out if out is not None else cfg.output_dir() / "cycle"
    if cfg.cycle is None:
        raise ConfigError("cycle: the config has no cycle section (cycle.path or cycle.preset)")
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
        str | None, typer.Option("--design", help="results directory only: knee (default), best-<metric> or a row")
    ] = None,
    out: Annotated[Path | None, typer.Option("--out", help="output directory")] = None,
    as_json: JsonOpt = False,
    force: ForceOpt = False,
) -> None:
    """Pick-and-place cycle of a design: actuator curves and forces, LCI and link clearance (cycle.csv, plots)."""
    info = run_cycle(source, sets, design, out, force)
    if as_json:
        _print_json(info)
        return
    m = info["metrics"]
    typer.echo(f"cycle of {info['period_s']:.4g} s, {info['samples']} samples, {len(info['vertices']) - 1} segments")
    for key, value in m.items():
        typer.echo(f"  {key:<26} {value:.6g}")
    where = info["min_clearance_at"]
    typer.echo(f"  min clearance at t = {where['t_s']:.4g} s between {' and '.join(where['segments']) or '-'}")
    typer.echo("wrote " + ", ".join(info["files"]))
