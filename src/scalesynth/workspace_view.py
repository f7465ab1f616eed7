"""One design's workspace as data for views: per-voxel fields on a grid, dexterity-band regions and their
connected components, the centroid and sections (planes sampled on their own, never through a full grid). A design
of a results directory is chosen by ``scalesynth.selection.choose_row``.

Connectivity of regions: two cells of a band belong to one region when they share a face, an edge or a corner
(26-connectivity in 3-D, 8 in 2-D, ``scipy.ndimage.label``); the face-only count (6 / 4) is reported beside it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from scalesynth import labels as lab
from scalesynth.errors import ConfigError, InvalidParameter
from scalesynth.evaluate import Grid, make_grid
from scalesynth.kernels import grid as _grid
from scalesynth.names import hint

CENTROID_RESOLUTION = 24  # coarse grid locating a section's default position (24^3 = 14k points)
MAX_POINTS = 20_000  # boundary voxels drawn per 3-D panel (deterministic thinning beyond; drawing dominates show)


def available_fields(mech) -> tuple[str, ...]:
    """Per-voxel fields a mechanism's field kernel writes (lci, sigma_min, sigma_max and its own)."""
    return tuple(mech.field_names)


def check_field(mech, name: str) -> str:
    known = available_fields(mech)
    if name not in known:
        raise ConfigError(f"--field: unknown per-voxel field {name!r} of {mech.name} " + hint(name, known))
    return name


@dataclass(frozen=True)
class FieldGrid:
    """A design's fields on a cell-centred grid: ``lci[i, j, k]`` (-1 = unreachable) at grid.axis(a) nodes."""

    grid: Grid
    lci: np.ndarray
    fields: dict[str, np.ndarray]  # name -> (nx, ny, nz), NaN where unreachable

    @property
    def reachable(self) -> np.ndarray:
        return self.lci >= 0

    def axes(self) -> list[np.ndarray]:
        return [self.grid.axis(a) for a in range(3)]


def _packed(cfg, design: Mapping[str, float]) -> np.ndarray:
    return cfg.mech.pack(cfg.mech.resolve_design(design), cfg.resolved_options())


def sample_fields(cfg, design: Mapping[str, float], resolution: int) -> FieldGrid:
    """Every field of ``design`` on the config's grid box at ``resolution`` cells per task axis."""
    mech = cfg.mech
    g = make_grid(mech, mech.resolve_design(design), cfg.resolved_options(), resolution, cfg.grid.region)
    values = _grid.sample_fields(mech.field_kernel, mech.n_fields, _packed(cfg, design), g.lo, g.step, g.shape)
    lci = values[..., 0]
    unreachable = lci < 0
    fields = {}
    for f, name in enumerate(mech.field_names):
        v = values[..., f].copy()
        v[unreachable] = np.nan
        fields[name] = v
    return FieldGrid(grid=g, lci=np.ascontiguousarray(lci), fields=fields)


def sample_plane(cfg, design: Mapping[str, float], normal: int, value: float, resolution: int, field: str = "lci"):
    """A per-voxel field (default LCI) on the plane ``task axis normal = value`` only (the other axes at
    ``resolution`` cells over the grid box): returns (2-D array indexed by the two remaining axes in order, their
    extent (a0, a1, b0, b1)). Unreachable cells: LCI -1, any other field NaN."""
    mech = cfg.mech
    slot = mech.field_names.index(check_field(mech, field))
    g = make_grid(mech, mech.resolve_design(design), cfg.resolved_options(), resolution, cfg.grid.region)
    lo, step, shape = g.lo.copy(), g.step.copy(), g.shape.copy()
    lo[normal] = value - 0.5 * step[normal]
    shape[normal] = 1
    cells = _grid.sample_fields(mech.field_kernel, mech.n_fields, _packed(cfg, design), lo, step, shape)
    plane = cells[..., 0] if slot == 0 else np.where(cells[..., 0] >= 0, cells[..., slot], np.nan)
    others = [a for a in range(3) if a != normal]
    values = np.take(plane, 0, axis=normal)
    ext = []
    for a in others:
        ext += [g.lo[a], g.lo[a] + g.shape[a] * g.step[a]]
    return values, tuple(float(e) for e in ext)


def centroid(fg: FieldGrid) -> np.ndarray:
    """Mean position of the reachable cells (3 entries; the grid centre for an empty workspace)."""
    reach = fg.reachable
    axes = fg.axes()
    if not reach.any():
        return np.array([ax.mean() for ax in axes])
    idx = np.nonzero(reach)
    return np.array([axes[a][idx[a]].mean() for a in range(3)])


def nearest_nonempty(fg: FieldGrid, normal: int, value: float) -> tuple[int, bool]:
    """Index of the grid plane normal to ``normal`` nearest to ``value`` that holds a reachable cell, and
    whether it had to move away from the nearest plane (an empty workspace keeps the nearest one)."""
    ax = fg.grid.axis(normal)
    i0 = int(np.argmin(np.abs(ax - value)))
    counts = fg.reachable.sum(axis=tuple(a for a in range(3) if a != normal))
    if counts[i0] > 0 or not counts.any():
        return i0, False
    filled = np.nonzero(counts)[0]
    return int(filled[np.argmin(np.abs(filled - i0))]), True


def default_section_point(cfg, design: Mapping[str, float]) -> np.ndarray:
    """Where sections go by default: the workspace centroid, from a coarse grid, moved per axis onto a plane that
    cuts the workspace."""
    fg = sample_fields(cfg, design, CENTROID_RESOLUTION)
    c = centroid(fg)
    out = c.copy()
    for a in range(len(cfg.mech.task_axes)):
        i, moved = nearest_nonempty(fg, a, c[a])
        if moved:
            out[a] = fg.grid.axis(a)[i]
    return out


def band_of(lci: np.ndarray, edges: Sequence[float]) -> np.ndarray:
    """Band index of each LCI value, as the kernels count it: band k holds (e_k, e_k+1], band 0 also e_0."""
    return np.searchsorted(np.asarray(edges, dtype=float)[1:-1], lci, side="left")


def band_labels(edges: Sequence[float]) -> list[str]:
    return [f"{'[' if b == 0 else '('}{edges[b]:g}, {edges[b + 1]:g}]" for b in range(len(edges) - 1)]


def _structures(ndim: int):
    from scipy import ndimage

    return ndimage.generate_binary_structure(ndim, ndim), ndimage.generate_binary_structure(ndim, 1)


def connected_regions(mask: np.ndarray, full: bool = True) -> tuple[np.ndarray, int]:
    """Connected components of a boolean mask (2-D or 3-D): (labels, count); ``full`` = 26 (8) connectivity, else
    face connectivity 6 (4)."""
    from scipy import ndimage

    dense, faces = _structures(mask.ndim)
    labels, n = ndimage.label(mask, structure=dense if full else faces)
    return labels, int(n)


def band_regions(fg: FieldGrid, edges: Sequence[float], ndim: int) -> list[dict[str, Any]]:
    """Per dexterity band: cells, share of the workspace, measure, number of connected regions (26- and
    6-connected in 3-D; 8 and 4 in 2-D), and the sizes of the largest regions (cells)."""
    lci = fg.lci if ndim == 3 else fg.lci[:, :, 0]
    reach = lci >= 0
    band = band_of(lci, edges)
    total = int(reach.sum())
    cell = fg.grid.cell_measure
    out = []
    for k, label in enumerate(band_labels(edges)):
        mask = reach & (band == k)
        labels, n_full = connected_regions(mask, full=True)
        _, n_faces = connected_regions(mask, full=False)
        sizes = np.sort(np.bincount(labels.ravel())[1:])[::-1] if n_full else np.zeros(0, dtype=int)
        cells = int(mask.sum())
        out.append({
            "band": k,
            "label": label,
            "cells": cells,
            "share": cells / total if total else 0.0,
            "measure": cells * cell,
            "regions": n_full,
            "regions_face_connected": n_faces,
            # regions of at least 1 % of the band's cells: isolated cells at band edges are grid noise
            "regions_over_1pct": int(np.sum(sizes >= 0.01 * cells)) if cells else 0,
            "largest_regions_cells": [int(s) for s in sizes[:12]],
            "_labels": labels,
        })
    return out


def boundary_points(mask: np.ndarray, axes: Sequence[np.ndarray], max_points: int = MAX_POINTS):
    """Cell centres of the boundary of a 3-D mask (cells with a face neighbour outside it), thinned
    deterministically to at most ``max_points``: (points (n, 3), their flat indices into the mask)."""
    from scipy import ndimage

    inner = ndimage.binary_erosion(mask, structure=ndimage.generate_binary_structure(3, 1), border_value=0)
    flat = np.flatnonzero(mask & ~inner)
    if len(flat) > max_points:
        flat = flat[np.linspace(0, len(flat) - 1, max_points).astype(np.int64)]
    i, j, k = np.unravel_index(flat, mask.shape)
    pts = np.column_stack([axes[0][i], axes[1][j], axes[2][k]])
    return pts, flat


def task_geometry(cfg):
    """The task box as a (2, 3) array (lo, hi; planar: third axis 0) and the task path (n, 3), each or None."""
    task = cfg.task
    if task is None:
        return None, None
    box = np.zeros((2, 3))
    for a, name in enumerate(cfg.mech.task_axes):
        box[:, a] = task.box[name]
    path = None
    if task.path is not None:
        p = np.asarray(task.path, dtype=float)
        path = np.pad(p, ((0, 0), (0, 3 - p.shape[1])))[:, :3]
    return box, path


# ----- where sections go with a task ---------------------------------------------------------------------------------
def task_section_point(cfg) -> tuple[np.ndarray, list[str]] | None:
    """Where sections go when the config has a task: per task axis, the task path's own coordinate where the path
    is level along that axis (all its points share it: a path at one height gets its xy section at that height),
    otherwise the task box centre. Returns (point (3,), per task axis the source: 'task path' or 'task box
    centre'), or None without a task."""
    box, path = task_geometry(cfg)
    if box is None:
        return None
    point = 0.5 * (box[0] + box[1])
    sources = []
    for a in range(len(cfg.mech.task_axes)):
        if path is not None and np.ptp(path[:, a]) <= 1e-9 * max(1.0, float(np.abs(path[:, a]).max())):
            point[a] = float(path[0, a])
            sources.append("task path")
        else:
            sources.append("task box centre")
    return point, sources


def path_label(cfg, path: np.ndarray, normal: int | None, kind: str = "task path") -> str:
    """Legend text of a path drawn on a section normal to task axis ``normal``: where the path lies along that
    axis ('task path at z = 0.4 m', or 'task path, z 0.3 to 0.5 m (projected)'); planar maps: ``kind`` alone."""
    if normal is None:
        return kind
    name = lab.axis_name(cfg.mech.task_axes[normal])
    unit = lab.axis_unit(cfg.mech, normal, cfg.units.length)
    lo, hi = float(np.min(path[:, normal])), float(np.max(path[:, normal]))
    if hi - lo <= 1e-9 * max(1.0, abs(lo), abs(hi)):
        return f"{kind} at {name} = {lo:.4g} {unit}"
    return f"{kind}, {name} {lo:.4g} to {hi:.4g} {unit} (projected)"


def _packed_cells(cfg, design: Mapping[str, float], lo, step, shape) -> np.ndarray:
    mech = cfg.mech
    return _grid.sample_fields(mech.field_kernel, mech.n_fields, _packed(cfg, design), np.asarray(lo, dtype=float),
                               np.asarray(step, dtype=float), np.asarray(shape, dtype=np.int64))


def reachable_points(cfg, design: Mapping[str, float], points: np.ndarray) -> np.ndarray:
    """True where the field kernel reaches a task point (rows of ``points``, task coordinates padded to 3): the
    same test as the workspace's cells (LCI >= 0), each point evaluated on its own."""
    ndim = len(cfg.mech.task_axes)
    out = np.zeros(len(points), dtype=bool)
    step = np.ones(3)
    for k, p in enumerate(np.asarray(points, dtype=float)):
        lo = np.zeros(3)
        lo[:ndim] = p[:ndim] - 0.5
        out[k] = _packed_cells(cfg, design, lo, step, (1, 1, 1))[0, 0, 0, 0] >= 0
    return out


TASK_POSE_CELLS = 8  # cells per axis of the task box searched for a reachable pose when its centre is not


def task_pose(cfg, design: Mapping[str, float]) -> tuple[np.ndarray, str] | None:
    """A reachable point of the config's task to draw the robot at: the first reachable vertex of the task path,
    else the task box centre, else the reachable cell of a TASK_POSE_CELLS grid over the task box nearest its
    centre (distance in box widths). Returns (pose (ndim,), what it is), or None when no such point is reachable
    (or there is no task)."""
    box, path = task_geometry(cfg)
    if box is None:
        return None
    ndim = len(cfg.mech.task_axes)
    centre = 0.5 * (box[0] + box[1])
    named = [(p, f"task path point {k + 1}") for k, p in enumerate(path)] if path is not None else []
    named.append((centre, "task box centre"))
    ok = reachable_points(cfg, design, np.array([p for p, _ in named]))
    for (p, what), hit in zip(named, ok, strict=True):
        if hit:
            return p[:ndim].copy(), what
    shape = np.array([TASK_POSE_CELLS] * ndim + [1] * (3 - ndim), dtype=np.int64)
    lo, step = np.zeros(3), np.ones(3)
    lo[:ndim] = box[0, :ndim]
    step[:ndim] = (box[1, :ndim] - box[0, :ndim]) / TASK_POSE_CELLS
    lci = _packed_cells(cfg, design, lo, step, shape)[..., 0]
    idx = np.argwhere(lci >= 0)
    if not len(idx):
        return None
    centres = lo + (idx + 0.5) * step
    k = int(np.argmin((((centres - centre) / step)[:, :ndim] ** 2).sum(axis=1)))
    return centres[k, :ndim], "reachable task cell nearest the task box centre"


def parse_at(items: Sequence[str] | None, mech) -> dict[int, float]:
    """``--at axis=value`` items -> {axis index: value}; the axis by its task-axis name."""
    out: dict[int, float] = {}
    for item in items or []:
        name, sep, raw = item.partition("=")
        if not sep or name.strip() not in mech.task_axes:
            raise InvalidParameter(
                f"--at {item}: expected axis=value with axis one of {', '.join(mech.task_axes)}")
        try:
            value = float(raw)
        except ValueError:
            raise InvalidParameter(f"--at {item}: {raw!r} is not a number") from None
        if not np.isfinite(value):
            raise InvalidParameter(f"--at {item}: must be finite")
        out[mech.task_axes.index(name.strip())] = value
    return out


# ----- the robot and the cycle path ------------------------------------------------------------------------------
def cycle_path(cfg) -> np.ndarray | None:
    """The config's pick-and-place cycle as a closed polyline (n, 3) in task units, or None without a cycle."""
    if getattr(cfg, "cycle", None) is None:
        return None
    from scalesynth.cycle.config import vertices

    v = np.asarray(vertices(cfg.cycle, cfg.mech, cfg.units.length), dtype=float)
    v = np.vstack([v, v[:1]])
    return np.pad(v, ((0, 0), (0, 3 - v.shape[1])))[:, :3]


def default_pose(fg: FieldGrid, ndim: int, near: np.ndarray | None = None) -> np.ndarray | None:
    """The reachable grid node nearest to ``near`` (default: the workspace centroid), in task coordinates
    (``ndim`` entries); None for an empty workspace (no pose is reachable)."""
    c = centroid(fg) if near is None else np.pad(np.asarray(near, dtype=float)[:3], (0, 3 - min(len(near), 3)))
    idx = np.argwhere(fg.reachable)
    if not len(idx):
        return None
    axes = fg.axes()
    pts = np.column_stack([axes[a][idx[:, a]] for a in range(3)])
    span = np.where(fg.grid.step > 0, fg.grid.step, 1.0)  # distance in cells: axes of different units
    k = int(np.argmin((((pts - c) / span) ** 2).sum(axis=1)))
    return pts[k, :ndim]


def robot_pose(cfg, design: Mapping[str, float], fg: FieldGrid) -> tuple[np.ndarray | None, str]:
    """Where ``show`` draws the robot by default, and what that pose is: a reachable point of the task when the
    config has one (task_pose), else the reachable grid node nearest the task box centre (no point of the task is
    reachable) or, without a task, nearest the workspace centroid; never an unreachable pose (None: the
    workspace is empty)."""
    ndim = len(cfg.mech.task_axes)
    box, _ = task_geometry(cfg)
    if box is not None:
        found = task_pose(cfg, design)
        if found is not None:
            return found
        pose = default_pose(fg, ndim, 0.5 * (box[0] + box[1]))
        return pose, "no point of the task is reachable: the reachable grid node nearest the task box centre"
    return default_pose(fg, ndim), "the reachable grid node nearest the workspace centroid"


def robot(cfg, design, pose) -> dict[str, Any]:
    """Link geometry at ``pose`` in the kernel's working mode: {"pose", "branch", "segments": [{"name", "body",
    "a", "b", "radius"}]} or {"pose", "missing": reason} when the mechanism has no link geometry or the pose is out
    of reach."""
    from scalesynth.errors import ScalesynthError

    mech = cfg.mech
    options = cfg.resolved_options()
    design = mech.resolve_design(design)
    pose = [float(v) for v in pose]
    sols = mech.inverse_kinematics(design, options, pose)
    if not sols:
        return {"pose": pose, "missing": "the pose is out of reach"}
    branch = mech.kernel_branch(options)
    sol = next((s for s in sols if s.label == branch), sols[0])
    try:
        geo = mech.link_geometry(design, options, pose, sol.values)
    except ScalesynthError as err:
        return {"pose": pose, "missing": str(err)}
    segs = [{"name": s.name, "body": s.body, "a": [float(v) for v in s.a], "b": [float(v) for v in s.b],
             "radius": float(s.radius)} for s in geo.segments]
    return {"pose": pose, "branch": sol.label, "segments": segs}


def robot_caption(cfg, robot: dict) -> str:
    """'robot at x=0.1, y=0, z=0.4 (task path point 1), branch ++': the pose, where it comes from, the branch."""
    pose = ", ".join(f"{lab.axis_name(a)}={v:.4g}" for a, v in zip(cfg.mech.task_axes, robot["pose"], strict=True))
    source = robot.get("pose_source")
    return f"robot at {pose}{f' ({source})' if source else ''}, branch {robot['branch']}"


# ----- report sections (report.md and report.html) ------------------------------------------------------------------
# per-voxel fields drawn as their own section maps in a run's report, when the mechanism has them
STIFFNESS_MAP_FIELDS = ("deflection", "stiffness_min")
SECTION_RESOLUTION = 128  # plots want finer cells than the optimisation grid; a plane costs 128^2 points


def stiffness_map_fields(cfg) -> tuple[str, ...]:
    """The STIFFNESS_MAP_FIELDS a config's report draws: those its mechanism has and whose needs_options are set
    (seed 000's stiffness fields need options.stiffness_metrics, as their metrics do)."""
    mech, options = cfg.mech, cfg.resolved_options()
    return tuple(name for name in STIFFNESS_MAP_FIELDS if name in mech.field_names
                 and mech.fields[mech.field_names.index(name)].enabled(options))


def section_panels(cfg, design: dict[str, float], field: str = "lci") -> list[dict[str, Any]]:
    """Workspace sections coloured by a per-voxel field (default LCI), each sampled on its plane only (never a full
    grid): for a 3-D mechanism the planes normal to its second and third task axes, for seed 000 the xz and xy
    sections; one map for planar mechanisms. With a task the planes go through it (task_section_point: the task
    path's own height, else the task box centre) and the task path is drawn in its true coordinates, its legend
    saying where it lies along the plane's normal; without one through the workspace centroid (from a coarse grid;
    an empty plane moves to the nearest one that cuts the workspace). Each panel records its ``normal`` (task
    axis), ``position`` and ``source``. Axis labels carry units; axes of different units are not drawn to equal
    scale."""
    mech = cfg.mech
    unit = cfg.units.length
    res = max(cfg.grid.resolution, SECTION_RESOLUTION)
    box, path = task_geometry(cfg)
    if mech.planar:
        values, ext = sample_plane(cfg, design, 2, 0.0, res, field)
        return [{"values": values, "extent": ext, "xlabel": lab.axis_label(mech, 0, unit),
                 "ylabel": lab.axis_label(mech, 1, unit), "title": "workspace", "equal": lab.same_units(mech, (0, 1)),
                 "box": None if box is None else (box[0, 0], box[1, 0], box[0, 1], box[1, 1]),
                 "path": None if path is None else path[:, :2], "normal": None}]
    at_task = task_section_point(cfg)
    if at_task is None:
        point, sources = default_section_point(cfg, design), ["centroid"] * 3
    else:
        point, sources = at_task
    panels = []
    for normal in (1, 2):
        a, b = [x for x in range(3) if x != normal]
        point[normal] = round(float(point[normal]), 10) + 0.0  # no '-7e-17' in titles for a symmetric workspace
        values, ext = sample_plane(cfg, design, normal, float(point[normal]), res, field)
        name = lab.axis_name(mech.task_axes[normal])
        panel = {"values": values, "extent": ext, "xlabel": lab.axis_label(mech, a, unit),
                 "ylabel": lab.axis_label(mech, b, unit), "equal": lab.same_units(mech, (a, b)),
                 "title": f"{lab.axis_name(mech.task_axes[a])}{lab.axis_name(mech.task_axes[b])} section at "
                          f"{name} = {point[normal]:.4g} ({sources[normal]})",
                 "normal": normal, "position": float(point[normal]), "source": sources[normal]}
        if box is not None and box[0, normal] <= point[normal] <= box[1, normal]:
            panel["box"] = (box[0, a], box[1, a], box[0, b], box[1, b])
        if path is not None:
            panel["path"] = path[:, [a, b]]
            panel["path_label"] = path_label(cfg, path, normal)
        panels.append(panel)
    return panels


def map_range(panels: list[dict[str, Any]]) -> tuple[float, float]:
    """Colour scale of a field's section maps: the 2nd to 98th percentile of its reachable values over the panels
    (a few near-singular cells, e.g. the capped deflection, would otherwise squash the scale); (0, 1) if none."""
    v = np.concatenate([np.asarray(p["values"], dtype=float).ravel() for p in panels])
    v = v[np.isfinite(v)]
    if not v.size:
        return 0.0, 1.0
    lo, hi = (float(x) for x in np.percentile(v, [2, 98]))
    return (lo, hi) if hi > lo else (lo, lo + max(abs(lo), 1.0))
