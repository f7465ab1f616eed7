"""`scalesynth show`: one design's workspace in 3-D coloured by a per-voxel field, each dexterity band's region with
its number of connected regions, and sections (default through the workspace centroid), written to a directory
with ``show.json``.

The source is a config (its ``design``) or a finished results directory (its knee, best-<metric> or a row of
pareto.csv). PNG, SVG and PDF come from matplotlib; HTML (interactive, self-contained) from plotly.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from scalesynth import io as rio
from scalesynth import labels as lab
from scalesynth import rundir
from scalesynth import workspace_view as wv
from scalesynth.errors import ConfigError

FORMATS = ("png", "svg", "pdf", "html")
_VIEWS = ("show.json", "show.html", *(f"{view}.{fmt}" for view in ("workspace_3d", "bands_3d", "sections", "robot")
                                       for fmt in FORMATS[:3]))
# a show directory is recognised by its show.json (scalesynth.rundir); its "files" list the views beside it
OUTPUT = rundir.Output("show", "show.json", ("design_choice", "sections", "files"), owned=lambda name: name in _VIEWS)
CONNECTIVITY = "26-connected: cells sharing a face, an edge or a corner (8 in 2-D); face-only count beside it"


def load_source(source: Path, sets: Sequence[str] | None = None, design: str | None = None):
    """The selection.DesignSource of ``show SOURCE [--design ...] [--set ...]`` (a config or a results directory)."""
    from scalesynth.selection import load_design

    return load_design(source, design, sets)


def sections(cfg, fg: wv.FieldGrid, field: str, at: dict[int, float],
             design: dict[str, float] | None = None) -> tuple[list[dict], list[dict]]:
    """Sections normal to each task axis of a 3-D mechanism (the whole map of a planar one). Each plane goes where
    ``--at`` puts it (the nearest grid plane), else through the task (wv.task_section_point: the task path's own
    coordinate, else the task box centre; sampled exactly there, from ``design``), else through the workspace
    centroid (an empty centroid plane moves to the nearest plane that cuts the workspace). The task or cycle path
    is drawn in its true coordinates, its legend saying where it lies along the plane's normal. Returns (figure
    panels, their descriptions for show.json)."""
    mech = cfg.mech
    unit = cfg.units.length
    values = fg.fields[field]
    axes = fg.axes()
    g = fg.grid
    ext = [(float(g.lo[a]), float(g.lo[a] + g.shape[a] * g.step[a])) for a in range(3)]
    box, path = wv.task_geometry(cfg)
    kind = "task path"
    if path is None:
        path, kind = wv.cycle_path(cfg), "cycle path"
    if mech.planar:
        panel = {"values": values[:, :, 0], "extent": (*ext[0], *ext[1]), "xlabel": lab.axis_label(mech, 0, unit),
                 "ylabel": lab.axis_label(mech, 1, unit), "title": "workspace", "equal": lab.same_units(mech, (0, 1)),
                 "box": None if box is None else (box[0, 0], box[1, 0], box[0, 1], box[1, 1]),
                 "path": None if path is None else path[:, :2], "path_label": kind}
        return [panel], [{"normal": None, "cells": int(fg.reachable.sum())}]
    c = wv.centroid(fg)
    at_task = wv.task_section_point(cfg) if design is not None else None
    panels, info = [], []
    for normal in range(3):
        requested = at.get(normal)
        if requested is not None:  # the user's plane stays where it was asked for, even if empty
            i = int(np.argmin(np.abs(axes[normal] - requested)))
            plane, pos, source = np.take(values, i, axis=normal), float(axes[normal][i]), "--at"
        elif at_task is not None:  # the task's plane, sampled exactly there, even where it misses the workspace
            pos, source = round(float(at_task[0][normal]), 10) + 0.0, at_task[1][normal]
            plane, _ = wv.sample_plane(cfg, design, normal, pos, g.shape[0], field)
            if field == "lci":
                plane = np.where(plane >= 0, plane, np.nan)
        else:
            i, moved = wv.nearest_nonempty(fg, normal, c[normal])
            plane, pos = np.take(values, i, axis=normal), float(axes[normal][i])
            source = "centroid, moved to the nearest non-empty plane" if moved else "centroid"
        a, b = [x for x in range(3) if x != normal]
        cells = int(np.isfinite(plane).sum())
        name = lab.axis_name(mech.task_axes[normal])
        title = f"{lab.axis_name(mech.task_axes[a])}{lab.axis_name(mech.task_axes[b])} section at {name} = {pos:.4g}"
        if source != "--at":
            title += f" ({source.split(',')[0]})"
        if not cells:
            title += ": no reachable cell"
        panel = {"values": plane, "extent": (*ext[a], *ext[b]), "xlabel": lab.axis_label(mech, a, unit),
                 "ylabel": lab.axis_label(mech, b, unit), "title": title, "equal": lab.same_units(mech, (a, b)),
                 "normal": normal, "position": pos, "source": source}
        if box is not None and box[0, normal] <= pos <= box[1, normal]:
            panel["box"] = (box[0, a], box[1, a], box[0, b], box[1, b])
        if path is not None:
            panel["path"] = path[:, [a, b]]
            panel["path_label"] = wv.path_label(cfg, path, normal, kind)
        panels.append(panel)
        info.append({"normal": mech.task_axes[normal], "value": pos, "cells": cells, "source": source,
                     **({"path": panel["path_label"]} if path is not None else {})})
    return panels, info


def show_design(
    source: Path,
    design: str | None = None,
    field: str = "lci",
    at: Sequence[str] | None = None,
    out: Path | None = None,
    fmt: str = "png",
    resolution: int | None = None,
    sets: Sequence[str] | None = None,
    pose: str | None = None,
    force: bool = False,
) -> dict[str, Any]:
    """Write the views of one design into ``out`` (default <run or results/<name>>/show/<design label>/) and
    return what show.json holds. The directory is staged and swapped in whole (``scalesynth.rundir``); it must be
    new, empty or a show directory unless ``force``."""
    t0 = time.perf_counter()
    if fmt not in FORMATS:
        raise ConfigError(f"--format: must be one of {', '.join(FORMATS)}, got {fmt!r}")
    chosen_source = load_source(source, sets, design)
    cfg, result = chosen_source.cfg, chosen_source.result
    run_dir = None if result is None else result.out_dir
    mech = cfg.mech
    wv.check_field(mech, field)
    at_axes = wv.parse_at(at, mech)
    res = resolution or cfg.grid.resolution
    if not 4 <= res <= 512:
        raise ConfigError(f"--resolution: must be between 4 and 512 cells per axis, got {res}")
    from scalesynth import memory

    memory.check(memory.show_estimate(cfg, res, "--resolution" if resolution else "grid.resolution"))
    chosen, label, row = chosen_source.design, chosen_source.label, chosen_source.row
    target = Path(out) if out is not None else (run_dir or cfg.output_dir()) / "show" / label
    with rundir.staged(target, OUTPUT, force) as staged:  # --out checked and locked before the sampling
        summary = _show(cfg, source, label, row, chosen, field, at_axes, res, fmt, pose, staged.work, t0)
    summary["out"] = str(staged.target)
    return summary


def _show(cfg, source, label, row, chosen, field, at_axes, res, fmt, pose, target: Path, t0: float) -> dict:
    """Sample the design's fields, write its views and show.json into ``target``; return show.json's content."""
    mech = cfg.mech
    t1 = time.perf_counter()
    fg = wv.sample_fields(cfg, chosen, res)
    t_sample = time.perf_counter() - t1
    ndim = len(mech.task_axes)
    edges = cfg.dexterity.band_edges
    bands = wv.band_regions(fg, edges, ndim)
    panels, section_info = sections(cfg, fg, field, at_axes, chosen)
    unit = cfg.units.length
    axis_labels = [lab.axis_label(mech, a, unit) for a in range(ndim)]
    equal = lab.same_units(mech, range(ndim))
    c = wv.centroid(fg)
    reach = fg.reachable
    measure_key = mech.measure_key(unit)
    summary = {
        "source": str(source),
        "mechanism": mech.name,
        "design_choice": label,
        "pareto_row": row,
        "design": chosen,
        "field": field,
        "resolution": res,
        "grid": {name: {"lo": float(fg.grid.lo[a]), "hi": float(fg.grid.lo[a] + fg.grid.shape[a] * fg.grid.step[a]),
                        "cells": int(fg.grid.shape[a])} for a, name in enumerate(mech.task_axes)},
        "reachable_cells": int(reach.sum()),
        measure_key: float(reach.sum() * fg.grid.cell_measure),
        "gci": float(fg.lci[reach].mean()) if reach.any() else 0.0,
        "centroid": {name: float(c[a]) for a, name in enumerate(mech.task_axes)},
        "connectivity": CONNECTIVITY,
        "bands": [{k: v for k, v in b.items() if not k.startswith("_")} for b in bands],
        "sections": section_info,
        "task": None if cfg.task is None else {"box": {k: list(v) for k, v in cfg.task.box.items()},
                                               "path_points": None if cfg.task.path is None else len(cfg.task.path)},
        "cycle_path_points": None if wv.cycle_path(cfg) is None else int(len(wv.cycle_path(cfg)) - 1),
        "files": [],
    }
    if pose is None:
        pose_values, pose_source = wv.robot_pose(cfg, chosen, fg)
    else:
        pose_values, pose_source = _parse_pose(pose, mech), "--pose"
    if pose_values is None:
        summary["robot"] = {"pose": None, "pose_source": pose_source, "missing": "no reachable pose: the workspace "
                            "is empty at this resolution"}
    else:
        summary["robot"] = {**wv.robot(cfg, chosen, pose_values), "pose_source": pose_source}
    title = f"{mech.name} {label}: " + ", ".join(f"{k}={v:.4g}" for k, v in chosen.items())
    files = _write_views(cfg, fg, field, bands, panels, axis_labels, equal, title, target, fmt, summary["robot"])
    summary["files"] = files
    summary["seconds"] = {"sample": round(t_sample, 3), "total": round(time.perf_counter() - t0, 3)}
    rio.write_json(target / "show.json", summary)
    return summary


def colour_range(fg: wv.FieldGrid, field: str) -> tuple[float, float]:
    """Colour scale of a field: [0, 1] for LCI, else the 2nd to 98th percentile of its reachable values (a few
    near-singular cells would otherwise squash the scale)."""
    if field == "lci":
        return 0.0, 1.0
    v = fg.fields[field][np.isfinite(fg.fields[field])]
    if not v.size:
        return 0.0, 1.0
    lo, hi = (float(x) for x in np.percentile(v, [2, 98]))
    return (lo, hi) if hi > lo else (lo, lo + 1.0)


def _parse_pose(text: str, mech) -> np.ndarray:
    from scalesynth.errors import InvalidPose

    try:
        values = np.array([float(t) for t in text.split(",")])
    except ValueError:
        raise InvalidPose(f"--pose: expected {len(mech.task_axes)} comma-separated numbers, got {text!r}") from None
    if values.shape != (len(mech.task_axes),) or not np.all(np.isfinite(values)):
        raise InvalidPose(f"--pose: expected {len(mech.task_axes)} finite numbers "
                          f"({', '.join(mech.task_axes)}), got {text!r}")
    return values


def _robot_view(cfg, robot: dict, target: Path, fmt: str, title: str) -> list[str]:
    """robot.<fmt>: the links at the chosen pose, with the task or cycle path when the task axes are x, y(, z)."""
    from scalesynth import plotting

    if "segments" not in robot:
        return []
    mech = cfg.mech
    cartesian = tuple(mech.task_axes) in (("x", "y"), ("x", "y", "z"))
    box, path = wv.task_geometry(cfg)
    label = "task path"
    if path is None:
        path, label = wv.cycle_path(cfg), "cycle path"
    fig = plotting.robot_figure(robot["segments"], cfg.units.length, f"{title}\n{wv.robot_caption(cfg, robot)}",
                                mech.planar, path if cartesian else None, label)
    rio.save_figure(fig, target / f"robot.{fmt}")
    plotting.close(fig)
    return [f"robot.{fmt}"]


def _write_views(cfg, fg, field, bands, panels, axis_labels, equal, title, target: Path, fmt: str,
                 robot: dict | None = None) -> list[str]:
    mech = cfg.mech
    edges = cfg.dexterity.band_edges
    field_label = lab.field_label(mech, field, cfg.units.length)
    vmin, vmax = colour_range(fg, field)
    box, path = wv.task_geometry(cfg)
    if path is None:
        path = wv.cycle_path(cfg)
    files = []
    if fmt == "html":
        from scalesynth import interactive

        html = interactive.show_page(cfg, fg, field, bands, panels, axis_labels, equal, title, box, path,
                                     field_label, vmin, vmax, robot)
        rio.write_text(target / "show.html", html)
        return ["show.html"]
    from scalesynth import plotting

    if not mech.planar:
        mask = fg.reachable
        pts, flat = wv.boundary_points(mask, fg.axes())
        fig = plotting.surface_scatter_figure(pts, fg.fields[field].ravel()[flat], axis_labels,
                                              f"{title}\nworkspace boundary coloured by {field_label}", field_label,
                                              vmin, vmax, box=box, path=path, equal=equal)
        rio.save_figure(fig, target / f"workspace_3d.{fmt}")
        plotting.close(fig)
        files.append(f"workspace_3d.{fmt}")
        regions = []
        for b in bands:
            bmask = b["_labels"] > 0
            bpts, bflat = wv.boundary_points(bmask, fg.axes())
            regions.append({"label": b["label"], "points": bpts, "region": b["_labels"].ravel()[bflat] - 1,
                            "regions": b["regions"]})
        fig = plotting.band_regions_figure(regions, axis_labels, f"{title}\ndexterity bands (26-connected regions)",
                                           box=box, path=path, equal=equal)
        rio.save_figure(fig, target / f"bands_3d.{fmt}")
        plotting.close(fig)
        files.append(f"bands_3d.{fmt}")
    fig = plotting.sections_figure(panels, edges if field == "lci" else None, title, field_label=field_label,
                                   vmin=vmin, vmax=vmax)
    rio.save_figure(fig, target / f"sections.{fmt}")
    plotting.close(fig)
    files.append(f"sections.{fmt}")
    files += _robot_view(cfg, robot or {}, target, fmt, title)
    return files
