"""Matplotlib figures (PNG, Agg). Drawing only: every number comes in through the arguments."""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import BoundaryNorm  # noqa: E402

BAND_COLOURS = ("#d62728", "#ff7f0e", "#2ca02c", "#1f77b4", "#9467bd", "#8c564b")


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
    """Pareto front (line + points), optional final population (grey), reference designs and highlights."""
    fig, ax = plt.subplots(figsize=(7.5, 5.2))
    if population is not None:
        ax.scatter(*population, s=10, c="0.8", label="final population", zorder=1)
    order = np.argsort(x)
    ax.plot(x[order], y[order], "-", c="C0", lw=1, zorder=2)
    ax.scatter(x, y, s=22, c="C0", label=f"Pareto front ({len(x)} designs)", zorder=3)
    for k, (label, rx, ry) in enumerate(references):
        label0 = "reference designs (re-evaluated)" if k == 0 else None
        ax.scatter([rx], [ry], marker="s", s=40, c="C3", zorder=4, label=label0)
        # staggered labels: reference designs often sit close together
        ax.annotate(label, (rx, ry), textcoords="offset points", xytext=(5, 4 + 9 * (k % 4)), fontsize=8, color="C3")
    for label, hx, hy in highlight:
        ax.scatter([hx], [hy], marker="*", s=160, c="gold", edgecolors="k", zorder=5)
        ax.annotate(label, (hx, hy), textcoords="offset points", xytext=(6, -12), fontsize=9)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    return fig


def hypervolume_figure(generations: np.ndarray, hv: np.ndarray, title: str):
    fig, ax = plt.subplots(figsize=(6.5, 4))
    ax.plot(generations, hv, c="C0")
    ax.set_xlabel("generation")
    ax.set_ylabel("hypervolume")
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


def sections_figure(panels: Sequence[dict], band_edges: Sequence[float], title: str):
    """Workspace sections coloured by LCI (unreachable cells blank), band edges as contour lines and colourbar ticks.

    Each panel: {"lci": 2-D array (-1 = unreachable) indexed [i, j], "extent": (x0, x1, y0, y1), "xlabel",
    "ylabel", "title"}.
    """
    n = len(panels)
    fig, axes = plt.subplots(1, n, figsize=(5.2 * n, 4.6), squeeze=False)
    edges = np.asarray(band_edges)
    cmap = plt.get_cmap("viridis")
    for ax, panel in zip(axes[0], panels, strict=True):
        data = np.ma.masked_less(np.asarray(panel["lci"]).T, 0.0)
        im = ax.imshow(data, origin="lower", extent=panel["extent"], cmap=cmap, vmin=0, vmax=1, aspect="equal",
                       interpolation="nearest")
        if data.count() > 0:
            x0, x1, y0, y1 = panel["extent"]
            ny, nx = data.shape
            xs = x0 + (np.arange(nx) + 0.5) * (x1 - x0) / nx
            ys = y0 + (np.arange(ny) + 0.5) * (y1 - y0) / ny
            inner = [e for e in edges[1:-1]]
            if inner:
                ax.contour(xs, ys, data.filled(-1), levels=inner, colors="w", linewidths=0.8)
        cb = fig.colorbar(im, ax=ax, ticks=edges)
        cb.set_label("LCI (band edges marked)")
        ax.set_xlabel(panel["xlabel"])
        ax.set_ylabel(panel["ylabel"])
        ax.set_title(panel["title"], fontsize=9)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


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


def cycle_path_figure(lci, extent, path: np.ndarray, vertices: np.ndarray, band_edges, xlabel, ylabel, title):
    """The cycle's path drawn on an LCI section of the workspace (unreachable cells blank), vertices numbered."""
    fig, ax = plt.subplots(figsize=(7.0, 5.5))
    data = np.ma.masked_less(np.asarray(lci).T, 0.0)
    norm = BoundaryNorm(np.linspace(0, 1, 21), 256)
    im = ax.imshow(data, origin="lower", extent=extent, cmap="viridis", norm=norm, aspect="equal")
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


def cycle_quality_figure(t, lci, clearance, vertex_times, clearance_label, title):
    """LCI and link clearance over the cycle (clearance 0 = capsules touching, drawn red)."""
    fig, axes = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
    axes[0].plot(t, lci, c="C0")
    axes[0].set_ylabel("LCI")
    axes[1].plot(t, clearance, c="C2")
    axes[1].axhline(0.0, c="C3", lw=1)
    axes[1].set_ylabel(clearance_label)
    axes[1].set_xlabel("t (s)")
    for ax in axes:
        ax.grid(alpha=0.3)
        _mark_segments(ax, vertex_times)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def close(fig) -> None:
    plt.close(fig)
