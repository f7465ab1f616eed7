"""Matplotlib figures (PNG, SVG or PDF; Agg). Drawing only: every number comes in through the arguments.

Colours: the Okabe-Ito palette (distinguishable with the common colour-vision deficiencies) for categories and
viridis (perceptually uniform, colour-blind safe) for continuous fields.
"""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import BoundaryNorm  # noqa: E402

# Okabe & Ito (2008), "Color Universal Design": black omitted
OKABE_ITO = ("#0072B2", "#E69F00", "#009E73", "#D55E00", "#56B4E9", "#CC79A7", "#F0E442")
FRONT, REFERENCE, POPULATION = "#0072B2", "#D55E00", "#8c8c8c"
# dexterity bands, low to high: vermillion, orange, bluish green, then blue, sky blue, purple, yellow
BAND_COLOURS = ("#D55E00", "#E69F00", "#009E73", "#0072B2", "#56B4E9", "#CC79A7", "#F0E442")


def _isotonic(values: np.ndarray) -> np.ndarray:
    """Least-squares non-decreasing fit of a sequence (pool adjacent violators)."""
    blocks: list[list[float]] = []  # [sum, count]
    for v in values:
        blocks.append([float(v), 1.0])
        while len(blocks) > 1 and blocks[-2][0] / blocks[-2][1] > blocks[-1][0] / blocks[-1][1]:
            s, c = blocks.pop()
            blocks[-1][0] += s
            blocks[-1][1] += c
    return np.concatenate([np.full(int(c), s / c) for s, c in blocks])


def spread(values: Sequence[float], gap: float, lo: float = -np.inf, hi: float = np.inf) -> np.ndarray:
    """Positions closest (least squares) to ``values`` with sorted neighbours at least ``gap`` apart, order kept.

    Places labels so that they do not overlap: with p_i = gap * i + q_i the constraint becomes q non-decreasing,
    an isotonic regression of v_i - gap * i. The block is then shifted inside [lo, hi] where it fits."""
    v = np.asarray(values, dtype=float)
    if v.size == 0:
        return v
    order = np.argsort(v, kind="mergesort")
    steps = gap * np.arange(len(v))
    pos = _isotonic(v[order] - steps) + steps
    if pos[-1] > hi:
        pos -= pos[-1] - hi
    if pos[0] < lo:
        pos += lo - pos[0]
    out = np.empty_like(pos)
    out[order] = pos
    return out


def label_points(ax, points: Sequence[tuple[str, float, float]], colour: str, fontsize: float = 8) -> list:
    """Annotate points with labels stacked beside them so that no two labels overlap (leader lines join them).

    Points in the left half of the axes get labels to their right, the others to their left; on each side the
    vertical positions are spread in display space by ``spread`` with a gap of one text line."""
    if not points:
        return []
    fig = ax.figure
    fig.canvas.draw()  # display transforms are final only after a draw
    trans = ax.transData
    inv = trans.inverted()
    disp = np.array([trans.transform((x, y)) for _, x, y in points])
    line = fontsize * fig.dpi / 72 * 1.4
    bbox = ax.get_window_extent()
    right = disp[:, 0] < 0.5 * (bbox.x0 + bbox.x1)
    texts = []
    for side in (True, False):
        idx = np.nonzero(right == side)[0]
        if not len(idx):
            continue
        ys = spread(disp[idx, 1], line, bbox.y0 + line / 2, bbox.y1 - line / 2)
        for i, yt in zip(idx, ys, strict=True):
            label, x, y = points[i]
            xt = disp[i, 0] + (24 if side else -24)
            tx, ty = inv.transform((xt, yt))
            texts.append(ax.annotate(label, (x, y), xytext=(tx, ty), textcoords="data", fontsize=fontsize,
                                     color=colour, va="center", ha="left" if side else "right",
                                     arrowprops={"arrowstyle": "-", "color": colour, "lw": 0.6}))
    return texts


def front_figure(
    x: np.ndarray,
    y: np.ndarray,
    xlabel: str,
    ylabel: str,
    title: str,
    references: Sequence[tuple[str, float, float]] = (),
    highlight: Sequence[tuple[str, float, float]] = (),
    population: tuple[np.ndarray, np.ndarray] | None = None,
):
    """Pareto front (line + points), optional final population (grey), reference designs and highlights.

    Reference labels are spread so that they never overlap, with leader lines to their points."""
    fig, ax = plt.subplots(figsize=(7.5, 5.2))
    if population is not None:
        ax.scatter(*population, s=12, facecolors="none", edgecolors=POPULATION, linewidths=0.8,
                   label=f"final population ({len(population[0])})", zorder=1)
    order = np.argsort(x)
    ax.plot(x[order], y[order], "-", c=FRONT, lw=1, zorder=2)
    ax.scatter(x, y, s=22, c=FRONT, label=f"Pareto front ({len(x)} designs)", zorder=3)
    if references:
        ax.scatter([r[1] for r in references], [r[2] for r in references], marker="s", s=40, c=REFERENCE, zorder=4,
                   label="reference designs (re-evaluated)")
    for label, hx, hy in highlight:
        ax.scatter([hx], [hy], marker="*", s=160, c="#F0E442", edgecolors="k", zorder=5)
        ax.annotate(label, (hx, hy), textcoords="offset points", xytext=(6, -12), fontsize=9)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    label_points(ax, list(references), REFERENCE)
    return fig


def hypervolume_figure(generations: np.ndarray, hv: np.ndarray, title: str, ylabel: str = "hypervolume"):
    fig, ax = plt.subplots(figsize=(6.5, 4))
    ax.plot(generations, hv, c=FRONT)
    ax.set_xlabel("generation")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def band_front_figure(x, y, shares: Sequence[np.ndarray], band_labels: Sequence[str], xlabel: str, ylabel: str):
    """One panel per dexterity band: the front coloured by that band's share of the workspace."""
    n = len(shares)
    fig, axes = plt.subplots(1, n, figsize=(4.6 * n, 4.2), squeeze=False)
    for ax, share, label in zip(axes[0], shares, band_labels, strict=True):
        sc = ax.scatter(x, y, c=100 * np.asarray(share), cmap="viridis", s=18)
        cb = fig.colorbar(sc, ax=ax)
        cb.set_label("share of workspace (%)")
        ax.set_title(f"LCI band {label}")
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def band_shares_figure(designs: Sequence[str], shares: np.ndarray, band_labels: Sequence[str]):
    """Grouped bars: share of each dexterity band (%) for a few designs."""
    shares = np.asarray(shares)
    n_d, n_b = shares.shape
    fig, ax = plt.subplots(figsize=(1.8 + 1.6 * n_d, 4.2))
    width = 0.8 / n_b
    xs = np.arange(n_d)
    for b in range(n_b):
        bars = ax.bar(xs + (b - (n_b - 1) / 2) * width, 100 * shares[:, b], width, label=f"LCI {band_labels[b]}",
                      color=BAND_COLOURS[b % len(BAND_COLOURS)])
        ax.bar_label(bars, fmt="%.1f", fontsize=7)
    ax.set_xticks(xs, designs, fontsize=8)
    ax.set_ylabel("share of workspace (%)")
    ax.set_title("dexterity bands")
    ax.legend(fontsize=8)
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    return fig


def sections_figure(panels: Sequence[dict], band_edges: Sequence[float] | None, title: str, field_label: str = "LCI",
                    vmin: float = 0.0, vmax: float = 1.0):
    """Workspace sections coloured by a per-voxel field (unreachable cells blank); for LCI the band edges are
    drawn as contour lines and colour-bar ticks.

    Each panel: {"values": 2-D array (negative or NaN = unreachable) indexed [i, j], "extent": (x0, x1, y0, y1),
    "xlabel", "ylabel", "title"} and optionally "equal" (draw to equal scale: only when both axes have one unit),
    "box" (x0, x1, y0, y1) of the task and "path" (n, 2) points of the task path, drawn on top.
    """
    n = len(panels)
    fig, axes = plt.subplots(1, n, figsize=(5.2 * n, 4.6), squeeze=False)
    edges = None if band_edges is None else np.asarray(band_edges)
    cmap = plt.get_cmap("viridis")
    for ax, panel in zip(axes[0], panels, strict=True):
        raw = np.asarray(panel["values"] if "values" in panel else panel["lci"], dtype=float).T
        data = np.ma.masked_where(~np.isfinite(raw) | (raw < 0), raw)
        im = ax.imshow(data, origin="lower", extent=panel["extent"], cmap=cmap, vmin=vmin, vmax=vmax,
                       aspect="equal" if panel.get("equal", True) else "auto", interpolation="nearest")
        if edges is not None and data.count() > 0:
            x0, x1, y0, y1 = panel["extent"]
            ny, nx = data.shape
            xs = x0 + (np.arange(nx) + 0.5) * (x1 - x0) / nx
            ys = y0 + (np.arange(ny) + 0.5) * (y1 - y0) / ny
            inner = list(edges[1:-1])
            if inner:
                ax.contour(xs, ys, data.filled(-1), levels=inner, colors="w", linewidths=0.8)
        if panel.get("box") is not None:
            bx0, bx1, by0, by1 = panel["box"]
            ax.add_patch(plt.Rectangle((bx0, by0), bx1 - bx0, by1 - by0, fill=False, ec="#D55E00", lw=1.5,
                                       ls="--", label="task box"))
        if panel.get("path") is not None:
            pth = np.asarray(panel["path"])
            ax.plot(pth[:, 0], pth[:, 1], "-o", c="#CC79A7", lw=1.2, ms=3, label=panel.get("path_label", "task path"))
        n_items = (panel.get("box") is not None) + (panel.get("path") is not None)
        if n_items:  # above the axes, under the title: a legend inside would cover the map
            ax.legend(fontsize=7, loc="lower center", bbox_to_anchor=(0.5, 1.0), frameon=False, borderaxespad=0.3)
        cb = fig.colorbar(im, ax=ax, ticks=edges if edges is not None else None)
        cb.set_label(field_label + (" (band edges marked)" if edges is not None else ""))
        ax.set_xlabel(panel["xlabel"])
        ax.set_ylabel(panel["ylabel"])
        ax.set_title(panel["title"], fontsize=9, pad=8 + 12 * n_items)  # points: room for the legend
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig


def surface_scatter_figure(points: np.ndarray, values: np.ndarray, labels: Sequence[str], title: str,
                           field_label: str, vmin: float = 0.0, vmax: float = 1.0,
                           box: np.ndarray | None = None, path: np.ndarray | None = None, equal: bool = False):
    """3-D view of a workspace: its boundary voxels (points (n, 3)) coloured by a field, with the task box
    (lo, hi as a (2, 3) array) as a wire frame and the task path. Axes of different units keep their own scale."""
    fig = plt.figure(figsize=(7.5, 6.2))
    ax = fig.add_subplot(projection="3d")
    sc = ax.scatter(points[:, 0], points[:, 1], points[:, 2], c=values, cmap="viridis", vmin=vmin, vmax=vmax, s=2,
                    depthshade=False, linewidths=0)
    _draw_box_path(ax, box, path)
    fig.colorbar(sc, ax=ax, shrink=0.7, label=field_label)
    _label_3d(ax, labels, points, equal)
    ax.set_title(title, fontsize=9)
    return fig


def band_regions_figure(regions: Sequence[dict], labels: Sequence[str], title: str, box=None, path=None,
                        equal: bool = False):
    """One 3-D panel per dexterity band: the band's voxels (boundary points), each connected region in its own
    colour, the count in the panel title. regions[k] = {"label", "points": (n, 3), "region": (n,) ids,
    "regions": count}."""
    n = len(regions)
    fig = plt.figure(figsize=(5.0 * n, 5.0))
    for k, reg in enumerate(regions):
        ax = fig.add_subplot(1, n, k + 1, projection="3d")
        pts = reg["points"]
        if len(pts):
            colours = np.array(OKABE_ITO)[np.asarray(reg["region"]) % len(OKABE_ITO)]
            ax.scatter(pts[:, 0], pts[:, 1], pts[:, 2], c=colours, s=2, depthshade=False, linewidths=0)
        _draw_box_path(ax, box, path)
        _label_3d(ax, labels, pts, equal)
        ax.set_title(f"LCI {reg['label']}: {reg['regions']} region{'s' if reg['regions'] != 1 else ''}", fontsize=9)
    fig.suptitle(title, fontsize=10)
    fig.subplots_adjust(left=0.02, right=0.96, bottom=0.04, top=0.86, wspace=0.12)  # tight_layout is slow in 3-D
    return fig


def robot_figure(segments: Sequence[dict], unit: str, title: str, planar: bool, path: np.ndarray | None = None,
                 path_label: str = "path"):
    """The robot: each capsule's segment a -> b as a thick line, one colour per body, joints as dots; drawn to
    equal scale in the mechanism frame (x, y, z in the length unit)."""
    bodies = list(dict.fromkeys(s["body"] for s in segments))
    colour = {b: OKABE_ITO[k % len(OKABE_ITO)] for k, b in enumerate(bodies)}
    fig = plt.figure(figsize=(7.0, 6.0))
    ax = fig.add_subplot() if planar else fig.add_subplot(projection="3d")
    seen = set()
    pts = []
    for s in segments:
        a, b = np.asarray(s["a"]), np.asarray(s["b"])
        pts += [a, b]
        lbl = s["body"] if s["body"] not in seen else None
        seen.add(s["body"])
        xyz = np.stack([a, b])
        lw = 4 if s["radius"] > 0 else 2
        if planar:
            ax.plot(xyz[:, 0], xyz[:, 1], "-o", c=colour[s["body"]], lw=lw, ms=4, label=lbl)
        else:
            ax.plot(xyz[:, 0], xyz[:, 1], xyz[:, 2], "-o", c=colour[s["body"]], lw=lw, ms=3, label=lbl)
    if path is not None:
        p = np.asarray(path, dtype=float)
        if planar:
            ax.plot(p[:, 0], p[:, 1], "--", c="k", lw=1, label=path_label)
        else:
            ax.plot(p[:, 0], p[:, 1], p[:, 2], "--", c="k", lw=1, label=path_label)
    ax.set_xlabel(f"x [{unit}]")
    ax.set_ylabel(f"y [{unit}]")
    if planar:
        ax.set_aspect("equal")
    else:
        ax.set_zlabel(f"z [{unit}]")
        span = np.ptp(np.array(pts), axis=0) if pts else np.ones(3)
        ax.set_box_aspect(np.where(span > 0, span, max(span.max(), 1.0) * 0.05))
    # the legend right of the axes: inside, it covered links
    fig.subplots_adjust(left=0.08, right=0.74, top=0.88, bottom=0.08)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.04, 1.0), borderaxespad=0.0)
    ax.set_title(title, fontsize=9)
    return fig


def _draw_box_path(ax, box, path) -> None:
    if box is not None:
        lo, hi = np.asarray(box, dtype=float)
        for a in range(3):  # the 12 edges: 4 parallel to each axis
            b, c = [i for i in range(3) if i != a]
            for vb in (lo[b], hi[b]):
                for vc in (lo[c], hi[c]):
                    seg = np.zeros((2, 3))
                    seg[:, a] = lo[a], hi[a]
                    seg[:, b] = vb
                    seg[:, c] = vc
                    ax.plot(seg[:, 0], seg[:, 1], seg[:, 2], c="#D55E00", lw=1.2, ls="--")
    if path is not None:
        p = np.asarray(path, dtype=float)
        ax.plot(p[:, 0], p[:, 1], p[:, 2], "-o", c="#CC79A7", lw=1.5, ms=3)


def _label_3d(ax, labels, points, equal: bool) -> None:
    ax.set_xlabel(labels[0])
    ax.set_ylabel(labels[1])
    ax.set_zlabel(labels[2])
    if equal and len(points):
        span = np.ptp(points, axis=0)
        ax.set_box_aspect(np.where(span > 0, span, 1.0))


def band_pareto_figure(all_x, all_y, x, y, xlabel: str, ylabel: str, title: str):
    """A band's Pareto set (band-k volume against another objective) over the final population."""
    fig, ax = plt.subplots(figsize=(6.5, 4.6))
    ax.scatter(all_x, all_y, s=12, facecolors="none", edgecolors=POPULATION, linewidths=0.8,
               label=f"final population ({len(all_x)})")
    order = np.argsort(x)
    ax.plot(np.asarray(x)[order], np.asarray(y)[order], "-", c=FRONT, lw=1)
    ax.scatter(x, y, s=24, c=FRONT, label=f"non-dominated ({len(x)})", zorder=3)
    return _finish(fig, ax, xlabel, ylabel, title)


def _finish(fig, ax, xlabel: str, ylabel: str, title: str):
    """Labels, title, grid, legend and a tight layout: the common end of the scatter figures."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def compare_figure(series: Sequence[dict], xlabel: str, ylabel: str, title: str):
    """Runs side by side in the plane of two shared metrics: each run's front and its selected designs.

    series[k] = {"label", "x", "y", "selected": [(name, x, y), ...]}."""
    fig, ax = plt.subplots(figsize=(7.5, 5.2))
    markers = "osD^vP"
    for k, s in enumerate(series):
        colour = OKABE_ITO[k % len(OKABE_ITO)]
        order = np.argsort(s["x"])
        ax.plot(np.asarray(s["x"])[order], np.asarray(s["y"])[order], "-", c=colour, lw=1)
        ax.scatter(s["x"], s["y"], s=18, c=colour, marker=markers[k % len(markers)], label=s["label"])
        for name, sx, sy in s.get("selected", []):
            ax.scatter([sx], [sy], marker="*", s=170, c=colour, edgecolors="k", zorder=5)
            ax.annotate(f"{s['label']}: {name}", (sx, sy), textcoords="offset points", xytext=(6, 6), fontsize=7)
    return _finish(fig, ax, xlabel, ylabel, title)


def task_figure(lci: np.ndarray, extent, path: np.ndarray | None, band_edges, xlabel, ylabel, title):
    """LCI over a planar task box with the path drawn on top."""
    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    data = np.ma.masked_less(np.asarray(lci).T, 0.0)
    norm = BoundaryNorm(np.linspace(0, 1, 21), 256)
    im = ax.imshow(data, origin="lower", extent=extent, cmap="viridis", norm=norm, aspect="auto")
    if path is not None:
        ax.plot(path[:, 0], path[:, 1], "-o", c="k", lw=1.5, ms=4, label="path")
        ax.legend(fontsize=8)
    cb = fig.colorbar(im, ax=ax, ticks=band_edges)
    cb.set_label("LCI")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    fig.tight_layout()
    return fig


def _mark_segments(ax, vertex_times: np.ndarray) -> None:
    """Vertical lines at the cycle's vertex times, numbered (vertex k reached at vertex_times[k])."""
    for k, t in enumerate(vertex_times):
        ax.axvline(t, color="0.75", lw=0.8, zorder=0)
        ax.annotate(str(k % (len(vertex_times) - 1) + 1), (t, 1.0), xycoords=("data", "axes fraction"),
                    ha="center", va="bottom", fontsize=7, color="0.4")


def cycle_actuator_figure(t, series: Sequence[tuple[str, Sequence[tuple[str, np.ndarray]]]], vertex_times, title):
    """One row per quantity (e.g. 'q1 (rad)' ...), one column per actuator: ``series`` is a list of
    (actuator label, [(axis label with unit, values (n,)), ...]); vertex times marked and numbered."""
    n_act = len(series)
    n_rows = len(series[0][1])
    fig, axes = plt.subplots(n_rows, n_act, figsize=(3.2 * n_act + 1, 2.0 * n_rows + 1), sharex=True, squeeze=False)
    for j, (name, rows) in enumerate(series):
        for i, (label, values) in enumerate(rows):
            ax = axes[i, j]
            ax.plot(t, values, lw=1.2, c=f"C{i}")
            ax.set_ylabel(label, fontsize=8)
            ax.tick_params(labelsize=7)
            ax.grid(alpha=0.3)
            _mark_segments(ax, vertex_times)
        axes[0, j].set_title(name, fontsize=9, pad=12)
        axes[-1, j].set_xlabel("t (s)")
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def cycle_path_figure(lci, extent, path: np.ndarray, vertices: np.ndarray, band_edges, xlabel, ylabel, title,
                      equal: bool = True):
    """The cycle's path drawn on an LCI section of the workspace (unreachable cells blank), vertices numbered;
    ``equal`` False for axes of different units (mm against rad), which are then not drawn to equal scale."""
    fig, ax = plt.subplots(figsize=(7.0, 5.5))
    data = np.ma.masked_less(np.asarray(lci).T, 0.0)
    norm = BoundaryNorm(np.linspace(0, 1, 21), 256)
    im = ax.imshow(data, origin="lower", extent=extent, cmap="viridis", norm=norm, aspect="equal" if equal else "auto")
    ax.plot(path[:, 0], path[:, 1], "-", c="k", lw=1.5, label="cycle path")
    for k, (x, y) in enumerate(vertices[:-1]):
        ax.annotate(str(k + 1), (x, y), textcoords="offset points", xytext=(4, 4), fontsize=8, color="k")
    ax.plot(vertices[:, 0], vertices[:, 1], "o", c="w", mec="k", ms=4)
    cb = fig.colorbar(im, ax=ax, ticks=band_edges)
    cb.set_label("LCI")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    return fig


def cycle_quality_figure(t, lci, clearance, vertex_times, clearance_label, title, deflection=None,
                         deflection_label=""):
    """LCI and link clearance over the cycle (clearance 0 = capsules touching, drawn red), and the deflection when
    the mechanism has a stiffness model."""
    rows = 2 if deflection is None else 3
    fig, axes = plt.subplots(rows, 1, figsize=(8, 2.5 * rows), sharex=True)
    axes[0].plot(t, lci, c="C0")
    axes[0].set_ylabel("LCI")
    axes[1].plot(t, clearance, c="C2")
    axes[1].axhline(0.0, c="C3", lw=1)
    axes[1].set_ylabel(clearance_label)
    if deflection is not None:
        axes[2].plot(t, deflection, c="C1")
        axes[2].set_ylabel(deflection_label)
    axes[-1].set_xlabel("t (s)")
    for ax in axes:
        ax.grid(alpha=0.3)
        _mark_segments(ax, vertex_times)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def close(fig) -> None:
    plt.close(fig)
