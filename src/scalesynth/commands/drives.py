"""``scalesynth drives``: seed 001's square cycle, an alias of ``scalesynth cycle`` kept for its old outputs.

The paper (§5, Figs. 6-7) moves O1 around a closed path at constant orientation and plots the six drive
displacements over time. ``drives CONFIG`` is ``cycle`` on the square E-F-G-H-E with the motion law
``constant`` (the loop at constant speed, period 1 s, so t is the fraction of the loop) for a pprs-rprs config:
the same analysis (``scalesynth.cycle.analysis``), written in the old format, each file atomically:
``drives.csv`` (t, x, y, z, w1, w2, beta, s1, s2, s3; mm, beta in rad) and ``drives.png`` (one subplot per
actuator), with ``drives.json`` (the summary ``--json`` prints, and the files) marking the directory as drives'
own. The directory (default RUN_DIR/drives, or OUTDIR/drives of a config) is staged and swapped in whole
(``scalesynth.rundir``): it must be new, empty or a drives directory, anything else is refused before the
analysis unless ``--force``. For velocities, accelerations, forces, clearance and rest-to-rest laws use
``scalesynth cycle`` with a ``cycle:`` section.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer

from scalesynth.cliapp import DesignOpt, ForceOpt, SetOpt, _print_json, app, handles_errors
from scalesynth.errors import ConfigError, InvalidPose
from scalesynth.io import save_figure, write_json, write_text
from scalesynth.rundir import Output

CSV_COLUMNS = ("t", "x", "y", "z", "w1", "w2", "beta", "s1", "s2", "s3")
FILES = ("drives.csv", "drives.png")
MANIFEST = "drives.json"
OUTPUT = Output("drives", MANIFEST, ("corners", "files"), owned=lambda name: name in (*FILES, MANIFEST))
# At z = 200 mm the cross-section of the primary workspace is a diagonal band: the largest axis-parallel square
# that fits is about 30.9 mm, centred near (-41, -25); a 20 mm square there keeps about 5 mm of margin.
DEFAULT_CENTER = "-40,-25"


def square_path(center: tuple[float, float], side: float, z: float) -> np.ndarray:
    """Corners E, F, G, H (counter-clockwise from the lower left) of an axis-parallel square at height z (mm)."""
    cx, cy = center
    a = 0.5 * side
    return np.array([[cx - a, cy - a, z], [cx + a, cy - a, z], [cx + a, cy + a, z], [cx - a, cy + a, z]])


def write_csv(path: Path, res) -> None:
    """drives.csv, atomically: CSV_COLUMNS, one row per sample, 12 significant digits."""
    table = np.column_stack([res.traj.t, res.traj.p, res.q])
    lines = [",".join(CSV_COLUMNS)] + [",".join(f"{v:.12g}" for v in row) for row in table]
    write_text(path, "\n".join(lines) + "\n")


def write_plot(path: Path, curves, corners: list[tuple[str, float]]) -> None:
    """drives.png, atomically: six subplots (w1, w2, beta in deg, s1, s2, s3) over t, the path's corners marked."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 8), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(3, 2, sharex=True)
    labels = ("w1 (mm)", "w2 (mm)", "beta (deg)", "s1 (mm)", "s2 (mm)", "s3 (mm)")
    for k, ax in enumerate(axes.T.ravel()):
        values = np.degrees(curves.q[:, k]) if k == 2 else curves.q[:, k]
        ax.plot(curves.traj.t, values, lw=1.5)
        ax.set_ylabel(labels[k])
        for name, t in corners:
            ax.axvline(t, color="0.8", lw=0.8, zorder=0)
            ax.annotate(name, (t, 1.0), xycoords=("data", "axes fraction"), ha="center", va="bottom", fontsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("t (fraction of the loop)")
    fig.suptitle("2PPRS-RPRS drive displacements along E-F-G-H-E")
    save_figure(fig, path, dpi=120)


def _parse_center(text: str) -> tuple[float, float]:
    try:
        x, y = (float(v) for v in text.split(","))
    except ValueError:
        raise InvalidPose(f"--center: expected x,y in mm, got {text!r}") from None
    if not (np.isfinite(x) and np.isfinite(y)):
        raise InvalidPose(f"--center: expected finite x,y, got {text!r}")
    return x, y


@app.command("drives")
@handles_errors
def drives_cmd(
    config: Annotated[Path, typer.Argument(help="run config (YAML) of a pprs-rprs design, or a results directory "
                                           "with --design")],
    design_choice: DesignOpt = None,
    sets: SetOpt = None,
    z: Annotated[float, typer.Option("--z", help="height of the square path (mm)")] = 200.0,
    side: Annotated[float, typer.Option("--side", help="side of the square (mm)")] = 20.0,
    center: Annotated[str, typer.Option("--center", help="centre x,y of the square (mm)")] = DEFAULT_CENTER,
    samples: Annotated[int, typer.Option("--samples", help="samples along the closed path (>= 9)")] = 400,
    out: Annotated[Path | None, typer.Option("--out", help="output directory (default: RUN_DIR/drives, or "
                                              "OUTDIR/drives of a config)")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="print one JSON object on stdout")] = False,
    force: ForceOpt = False,
) -> None:
    """Drive-displacement curves of a pprs-rprs design along a closed square E-F-G-H-E: drives.csv, drives.png."""
    from scalesynth import rundir
    from scalesynth.cycle import analysis
    from scalesynth.cycle.config import CycleConfig
    from scalesynth.mechanisms.pprs_rprs import MECHANISM
    from scalesynth.selection import load_design

    chosen = load_design(config, design_choice, sets)
    cfg = chosen.cfg
    if cfg.mechanism != MECHANISM.name:
        raise ConfigError(f"mechanism: drives needs {MECHANISM.name}, got {cfg.mechanism!r}")
    if not (np.isfinite(side) and side > 0):
        raise InvalidPose(f"--side: must be a positive length in mm, got {side:g}")
    if not np.isfinite(z):
        raise InvalidPose(f"--z: must be finite, got {z:g}")
    if not 9 <= samples <= 100_001:
        raise InvalidPose(f"--samples: need 9 to 100001 samples, got {samples}")
    corners = square_path(_parse_center(center), side, z)
    cycle = CycleConfig(path=corners.tolist(), law="constant", period=1.0, samples=samples - 1)
    if out is None:
        out = (chosen.result.out_dir if chosen.result is not None else cfg.output_dir()) / "drives"
    with rundir.staged(out, OUTPUT, force) as staged:  # --out checked and locked before the analysis
        curves = analysis.analyse(cfg.mech, cfg.resolved_design(), cfg.resolved_options(), cycle, cfg.units.length)
        write_csv(staged.work / FILES[0], curves)
        marks = [(name, k / 4) for k, name in enumerate("EFGHE")]
        write_plot(staged.work / FILES[1], curves, marks)
        summary = {
            "csv": str(staged.target / FILES[0]),
            "png": str(staged.target / FILES[1]),
            "corners": {name: [float(v) for v in c] for name, c in zip("EFGH", corners, strict=True)},
            "samples": int(curves.traj.t.size),
            "ranges": {
                name: [float(curves.q[:, k].min()), float(curves.q[:, k].max())]
                for k, name in enumerate(MECHANISM.joints)
            },
            "min_lci": float(curves.lci.min()),
        }
        write_json(staged.work / MANIFEST, {"source": str(config), "design": cfg.resolved_design(), **summary,
                                            "files": [*FILES, MANIFEST]})
    csv_path, png_path = summary["csv"], summary["png"]
    if as_json:
        _print_json(summary)
        return
    typer.echo(
        "square " + " -> ".join(f"{n}({c[0]:g}, {c[1]:g}, {c[2]:g})" for n, c in summary["corners"].items())
        + f" -> E, {summary['samples']} samples"
    )
    for name, (lo, hi) in summary["ranges"].items():
        unit = "rad" if name == "beta" else "mm"
        typer.echo(f"  {name:<5} {lo:10.4f} .. {hi:10.4f} {unit}")
    typer.echo(f"  min LCI on the path {summary['min_lci']:.4f}")
    typer.echo(f"wrote {csv_path} and {png_path}")
