"""Files of ``scalesynth cycle``: cycle.csv, cycle.json and three plots, each written atomically.

* ``cycle.csv``: the columns of :meth:`CycleResult.columns` (units in ``cycle.json`` and the README), 12
  significant digits;
* ``cycle.json``: design, cycle settings, units of every column, the catalogue metrics, where the minimum
  clearance occurs and the directory's files (it marks the directory as a cycle output, ``scalesynth.rundir``);
* ``actuators.png`` (q, qd, qdd, force of every actuator over t, the vertices marked), ``path.png`` (the path on
  an LCI section of the workspace), ``quality.png`` (LCI, clearance and, with a stiffness model, the deflection over t).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from scalesynth import io as rio
from scalesynth.cycle.analysis import CycleResult
from scalesynth.rundir import Output

PATH_SECTION_RESOLUTION = 160
FILES = ("cycle.csv", "cycle.json", "actuators.png", "path.png", "quality.png")
# a cycle directory is recognised by its cycle.json (scalesynth.rundir); "files" in it lists what it holds
OUTPUT = Output("cycle", "cycle.json", ("cycle", "metrics", "units"), owned=lambda name: name in FILES)


def write_csv(path: Path, res: CycleResult) -> None:
    cols = res.columns()
    table = np.column_stack(list(cols.values()))
    lines = [",".join(cols)] + [",".join(f"{v:.12g}" for v in row) for row in table]
    rio.write_text(path, "\n".join(lines) + "\n")


def summary(res: CycleResult, metrics: dict[str, float], design: dict[str, float], cyc) -> dict[str, Any]:
    k = int(np.argmin(res.clearance))
    return {**_motor_summary(res, cyc),
        "design": design,
        "cycle": cyc.model_dump(mode="json"),
        "period_s": res.traj.period,
        "samples": int(res.traj.t.size),
        "vertices": res.traj.vertices.tolist(),
        "vertex_times_s": res.traj.vertex_times.tolist(),
        "metrics": metrics,
        "min_clearance_at": {"t_s": float(res.traj.t[k]), "segments": list(res.min_clearance_pair or [])},
        "units": res.units(),
        "model": "forces: inverse dynamics by virtual work (docs/cycles.md): every link segment a thin uniform rod "
        "(dynamics.masses or tube sections), the payload a point mass at the tool point, gravity, no friction; "
        "A^T tau = [F_links + F_payload; 0]",
    }


def _motor_summary(res: CycleResult, cyc) -> dict[str, Any]:
    """picks_per_minute, cycle_time_s and the binding limit with motors (``dynamics.motors``), else {}."""
    from scalesynth.cycle.analysis import motor_metrics

    vals, binding = motor_metrics(res, cyc)
    if not vals:
        return {}
    return {"picks_per_minute": vals["picks_per_minute"], "cycle_time_s": vals["cycle_time_s"],
            "binding_limit": binding, "dwell_s": cyc.dwell_s}


def motor_extras(cfg, design, options, res: CycleResult) -> dict[str, Any]:
    """With motors: the time-optimal cycle at the cycle's payload (``dynamics.optimal``: toppra under peak torque
    and speed, ``time_optimal_*``) and the ``datasheet`` (``cycle.datasheet``); {} without."""
    from scalesynth.cycle.datasheet import datasheet

    sheet = datasheet(cfg.mech, design, options, cfg.cycle, cfg.units.length, res)
    if sheet is None:
        return {}
    row = next(r for r in sheet["rows"] if r["payload_kg"] == float(cfg.cycle.payload))
    keys = ("time_optimal_picks_per_minute", "time_optimal_cycle_time_s", "time_optimal_binding_limit",
            "time_optimal_rms_torque_ratio")
    return {**{k: row[k] for k in keys}, "datasheet": sheet}


def _section(cfg, design, options, res: CycleResult):
    """LCI on the workspace section through the path: (lci (n, n), extent, axes (i, j), label)."""
    from scalesynth.kernels.grid import sample_grid

    mech = cfg.mech
    k = len(mech.task_axes)
    lo, hi = (np.asarray(v, dtype=float) for v in mech.bounding_box(design, options))
    p = res.traj.p
    if k == 2:
        axes, normal = (0, 1), None
    else:
        # the axis along which the path spreads least, relative to the box (axes of different units compare)
        normal = int(np.argmin(np.ptp(p, axis=0) / np.maximum(hi - lo, 1e-300)))
        axes = tuple(a for a in range(3) if a != normal)[:2]
    n = PATH_SECTION_RESOLUTION
    glo, step = np.zeros(3), np.ones(3)
    shape = np.ones(3, dtype=np.int64)
    for a in axes:
        a_lo, a_hi = min(lo[a], p[:, a].min()), max(hi[a], p[:, a].max())
        glo[a], step[a], shape[a] = a_lo, (a_hi - a_lo) / n, n
    label = ""
    if normal is not None:
        value = float(np.mean(p[:, normal]))
        glo[normal] = value - 0.5
        unit = cfg.units.length if mech.task_units[normal] == "length" else "rad"
        label = f", section {mech.task_axes[normal]} = {value:.4g} {unit}"
    lci = sample_grid(mech.point_kernel, mech.pack(design, options), glo, step, shape)
    lci = lci.reshape(tuple(shape))
    lci2 = lci[:, :, 0] if normal in (None, 2) else (lci[:, 0, :] if normal == 1 else lci[0, :, :])
    extent = (glo[axes[0]], glo[axes[0]] + n * step[axes[0]], glo[axes[1]], glo[axes[1]] + n * step[axes[1]])
    return lci2, extent, axes, label


def write_plots(out_dir: Path, cfg, design, options, res: CycleResult) -> list[Path]:
    from scalesynth import plotting

    units = res.units()
    series = []
    for i, name in enumerate(res.joints, start=1):
        series.append((f"{i}: {name}", [
            (f"q{i} ({units[f'q{i}']})", res.q[:, i - 1]),
            (f"qd{i} ({units[f'qd{i}']})", res.qd[:, i - 1]),
            (f"qdd{i} ({units[f'qdd{i}']})", res.qdd[:, i - 1]),
            (f"force{i} ({units[f'force{i}']})", res.force[:, i - 1]),
        ]))
    law = res.traj.law[0] if len(set(res.traj.law)) == 1 else "per-segment laws"
    title = (f"{cfg.mech.name}: actuators over one cycle ({res.traj.period:.3g} s, {law}, payload "
             f"{res.payload:g} kg); numbers = path vertices")
    figs = [("actuators.png", plotting.cycle_actuator_figure(res.traj.t, series, res.traj.vertex_times, title))]
    lci, extent, axes, label = _section(cfg, design, options, res)
    names = [f"{cfg.mech.task_axes[a]} ({units['p_' + cfg.mech.task_axes[a]]})" for a in axes]
    figs.append(("path.png", plotting.cycle_path_figure(
        lci, extent, res.traj.p[:, list(axes)], res.traj.vertices[:, list(axes)], cfg.dexterity.band_edges,
        names[0], names[1], f"{cfg.mech.name}: cycle path on the workspace LCI{label}",
        equal=cfg.mech.task_units[axes[0]] == cfg.mech.task_units[axes[1]])))
    deflected = res.deflection is not None
    figs.append(("quality.png", plotting.cycle_quality_figure(
        res.traj.t, res.lci, res.clearance, res.traj.vertex_times, f"clearance ({res.length_unit})",
        f"{cfg.mech.name}: LCI, link clearance{' and deflection' if deflected else ''} along the cycle",
        res.deflection, f"deflection ({res.length_unit})")))
    paths = []
    for name, fig in figs:
        rio.save_figure(fig, out_dir / name, dpi=110)
        plotting.close(fig)
        paths.append(out_dir / name)
    return paths


def write_all(out_dir: Path, cfg, design, options, res: CycleResult, metrics: dict[str, float]) -> dict[str, Any]:
    """cycle.csv, the plots and, last, cycle.json (listing them) into ``out_dir``; returns cycle.json's content."""
    write_csv(out_dir / "cycle.csv", res)
    info = summary(res, metrics, design, cfg.cycle)
    info.update(motor_extras(cfg, design, options, res))
    plots = write_plots(out_dir, cfg, design, options, res)
    info["files"] = ["cycle.csv", "cycle.json", *(p.name for p in plots)]
    rio.write_json(out_dir / "cycle.json", info)
    return info
