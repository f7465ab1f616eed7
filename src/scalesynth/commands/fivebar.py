"""`scalesynth plot-task CONFIG`: LCI map over the task box of a planar mechanism, with the task path.

Written for the seed-004 packing robot (configs/fivebar_packing.yaml) but works for any planar mechanism
whose config has a ``task`` section. The numbers come from the mechanism's point kernel on a cell-centred grid
over the box (the nodes ``task_coverage`` / ``task_gci`` use); unreachable cells are left blank.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Annotated

import numpy as np
import typer

from scalesynth.cliapp import DesignOpt, ForceOpt, SetOpt, _print_json, app, handles_errors
from scalesynth.errors import ConfigError
from scalesynth.names import hint


@dataclass(frozen=True)
class TaskMap:
    """LCI on the task box: ``lci[i, j]`` at (xs[i], ys[j]), -1 where unreachable within the limits."""

    xs: np.ndarray
    ys: np.ndarray
    lci: np.ndarray
    path: np.ndarray | None  # (n, 2) vertices of the task path, or None
    field: str = "lci"  # the field drawn (a name of mech.fields), its values (-1 unreachable) and colour-bar label
    values: np.ndarray | None = None
    label: str = "LCI"

    @property
    def coverage(self) -> float:
        return float(np.mean(self.lci >= 0))

    @property
    def gci(self) -> float:
        v = self.lci[self.lci >= 0]
        return float(v.mean()) if v.size else 0.0

    @property
    def fci(self) -> float:
        v = self.lci[self.lci >= 0]
        return float(v.std()) if v.size else 0.0


def task_map(cfg, resolution: int | None = None, field: str = "lci") -> TaskMap:
    """Sample the config design's point kernel on the task box (``resolution`` cells per axis; default the
    task's, else the grid's), and the field ``field`` of the mechanism's field kernel (e.g. 'deflection', a
    stiffness map). Raises ConfigError for a non-planar mechanism, a config without a task or an unknown field."""
    from scalesynth.kernels.grid import sample_grid

    mech = cfg.mech
    res = check_task_map(cfg, resolution, field)
    lo, step = np.zeros(3), np.ones(3)
    for a, name in enumerate(mech.task_axes):  # config validation guarantees both axes are in the box
        lo[a], hi = cfg.task.box[name]
        step[a] = (hi - lo[a]) / res
    shape = np.array([res, res, 1], dtype=np.int64)
    packed = mech.pack(cfg.resolved_design(), cfg.resolved_options())
    lci = sample_grid(mech.point_kernel, packed, lo, step, shape)[:, :, 0]
    xs = lo[0] + (np.arange(res) + 0.5) * step[0]
    ys = lo[1] + (np.arange(res) + 0.5) * step[1]
    path = None if cfg.task.path is None else np.asarray(cfg.task.path, dtype=float)
    if field == "lci":
        return TaskMap(xs=xs, ys=ys, lci=lci, path=path)
    from scalesynth.kernels.grid import sample_fields

    slot = mech.field_names.index(field)
    spec = mech.fields[slot]
    vals = sample_fields(mech.field_kernel, mech.n_fields, packed, lo, step, shape)[:, :, 0, slot]
    vals = np.where(lci >= 0, vals, -1.0)
    label = f"{field} ({spec.unit.replace('{length}', cfg.units.length)})"
    return TaskMap(xs=xs, ys=ys, lci=lci, path=path, field=field, values=vals, label=label)


def check_task_map(cfg, resolution: int | None = None, field: str = "lci") -> int:
    """:func:`task_map`'s checks, before any sampling: a planar mechanism, a task section, at least 2 cells per
    axis within the memory limit, a known field (ConfigError naming each); returns the cells per axis."""
    mech = cfg.mech
    if not mech.planar:
        raise ConfigError(f"mechanism: plot-task needs a planar mechanism, {mech.name} has {len(mech.task_axes)} axes")
    if cfg.task is None:
        raise ConfigError("task: plot-task needs a task section (task.box, optional task.path)")
    res = resolution or cfg.task.resolution or cfg.grid.resolution
    if res < 2:
        raise ConfigError(f"--resolution: need at least 2 cells per axis, got {res}")
    from scalesynth import memory

    memory.check(memory.task_map_estimate(res, "--resolution" if resolution else "task.resolution"))
    if field != "lci" and field not in mech.field_names:
        raise ConfigError(f"--field: unknown field {field!r} of {mech.name} " + hint(field, mech.field_names, "fields"))
    return res


def task_figure(tm: TaskMap, axes: tuple[str, str], unit: str, title: str):
    """LCI map (viridis, colour bar, unreachable cells blank) and the task path with its vertices numbered."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    dx = tm.xs[1] - tm.xs[0]
    dy = tm.ys[1] - tm.ys[0]
    extent = (tm.xs[0] - dx / 2, tm.xs[-1] + dx / 2, tm.ys[0] - dy / 2, tm.ys[-1] + dy / 2)
    width, height = extent[1] - extent[0], extent[3] - extent[2]
    fig, ax = plt.subplots(figsize=(9.0, float(np.clip(7.0 * height / width + 2.0, 3.5, 9.0))))
    shown = tm.lci if tm.values is None else tm.values
    masked = np.ma.masked_where(tm.lci.T < 0.0, shown.T)
    img = ax.imshow(masked, origin="lower", extent=extent, cmap="viridis", aspect="equal", interpolation="nearest")
    # colour bar as tall as the (equal-aspect) map
    fig.colorbar(img, ax=ax, label=tm.label, fraction=0.046 * min(height / width, 1.0), pad=0.02)
    if tm.path is not None:
        ax.plot(tm.path[:, 0], tm.path[:, 1], "-", c="C3", lw=1.5, marker="o", ms=5, zorder=4, label="task path")
        visits: dict[tuple[float, float], list[str]] = {}  # a pick-and-place path revisits its vertices
        for k, (px, py) in enumerate(tm.path):
            visits.setdefault((float(px), float(py)), []).append(str(k))
        for (px, py), ks in visits.items():
            ax.annotate(",".join(ks), (px, py), textcoords="offset points", xytext=(4, 4), fontsize=7, color="C3")
        ax.legend(loc="upper left", bbox_to_anchor=(0.0, -0.18), fontsize=8, frameon=False)
    # a margin so that a path along the edges of the box stays visible
    ax.set_xlim(extent[0] - 0.04 * width, extent[1] + 0.04 * width)
    ax.set_ylim(extent[2] - 0.04 * height, extent[3] + 0.04 * height)
    ax.set_xlabel(f"{axes[0]} [{unit}]")
    ax.set_ylabel(f"{axes[1]} [{unit}]")
    ax.set_title(title, fontsize=10)
    fig.tight_layout()
    return fig


@app.command("plot-task")
@handles_errors
def plot_task_cmd(
    config: Annotated[Path, typer.Argument(help="run config (YAML) of a planar mechanism with a task section, or a "
                                           "results directory with --design")],
    design_choice: DesignOpt = None,
    out: Annotated[Path | None, typer.Option("--out", help="directory to write task_<field>.<format> into (default "
                                              "RUN_DIR/plots, or OUTDIR/plots of a config); a name with a "
                                              ".png/.svg/.pdf suffix is the file")] = None,
    fmt: Annotated[str, typer.Option("--format", help="png | svg | pdf")] = "png",
    sets: SetOpt = None,
    resolution: Annotated[int | None, typer.Option(help="cells per axis (default task/grid resolution)")] = None,
    field: Annotated[str, typer.Option("--field", help="field to map: lci or any of the mechanism's fields, e.g. "
                                       "deflection or stiffness_min (see `scalesynth metrics MECH`)")] = "lci",
    as_json: Annotated[bool, typer.Option("--json", help="print one JSON object on stdout")] = False,
    force: ForceOpt = False,
) -> None:
    """LCI (or another field, e.g. the deflection under the load) over the task box (unreachable cells blank) with
    the task path, as a PNG."""
    from scalesynth import plot_output
    from scalesynth.selection import load_design

    if fmt not in ("png", "svg", "pdf"):
        raise ConfigError(f"--format: must be one of png, svg, pdf, got {fmt!r}")
    chosen = load_design(config, design_choice, sets)
    cfg = chosen.cfg
    res = check_task_map(cfg, resolution, field)
    if out is not None and out.suffix.lower() in (".png", ".svg", ".pdf"):
        target = plot_output.check_file(out, "plot-task", force)  # before the map: nothing computed for nothing
        _draw(cfg, resolution, field, target)
    else:
        default = (chosen.result.out_dir if chosen.result is not None else cfg.output_dir()) / "plots"
        name = f"task_{field}.{fmt}"
        with plot_output.figures(out or default, "plot-task", force, str(config)) as figs:
            _draw(cfg, resolution, field, figs.dir / name)
        target = figs.final(figs.dir.relative_to(figs.root) / name)
    shown = task_metrics_at(cfg, res)
    if as_json:
        _print_json({"out": str(target), **shown})
    else:
        typer.echo(f"wrote {target} (" + ", ".join(f"{k} {v:.4f}" for k, v in shown.items()) + ")")


def _draw(cfg, resolution: int | None, field: str, target: Path) -> None:
    """The task map and its figure, written atomically to ``target`` (format from its suffix), marked as
    plot-task's (``plot_output.metadata``)."""
    from scalesynth import io as rio
    from scalesynth import plot_output

    tm = task_map(cfg, resolution, field)
    unit = cfg.units.length
    design = ", ".join(f"{k}={v:g}" for k, v in cfg.resolved_design().items())
    cells = f"{tm.lci.shape[0]}x{tm.lci.shape[1]} cells"
    title = (
        f"{cfg.mech.name} ({design} {unit}), mode {cfg.resolved_options().get('mode', '-')}\n"
        f"task coverage {tm.coverage:.4f}, GCI {tm.gci:.4f}, FCI {tm.fci:.4f} ({cells})"
    )
    if tm.values is not None:
        v = tm.values[tm.lci >= 0]
        title += f"\n{tm.label}: {v.min():.4g} ... {v.max():.4g}" if v.size else ""
    import matplotlib.pyplot as plt  # after the map: the evaluation does not wait for matplotlib's import

    fig = task_figure(tm, cfg.mech.task_axes[:2], unit, title)
    try:
        rio.ensure_dir(target.parent)  # the file form's new directories: made once the map is drawn
        rio.save_figure(fig, target, metadata=plot_output.metadata(target, "plot-task"))
    finally:
        plt.close(fig)


def task_metrics_at(cfg, resolution: int) -> dict[str, float]:
    """The catalogue's task-box metrics of the config's design with ``resolution`` cells per axis (the map's)."""
    from scalesynth.evaluate import evaluate_config
    from scalesynth.metrics import catalogue

    at = cfg.model_copy(update={"task": cfg.task.model_copy(update={"resolution": resolution})})
    rep = evaluate_config(at)
    task = [m.column for m in catalogue(cfg.mech, cfg.units.length).values() if m.family == "task"]
    return {k: rep.metrics[k] for k in task if k in rep.metrics}
