"""Interactive, self-contained HTML (plotly): report.html of a run and the HTML view of `scalesynth show`.

One page embeds plotly.js once (``include_plotlyjs=True`` on the first figure), so it works offline with no CDN;
div ids are fixed, so the same run gives the same bytes. Drawing only: the numbers come in through the arguments.
"""

from __future__ import annotations

import html as _html
from collections.abc import Sequence

import numpy as np
import pandas as pd

from scalesynth import labels as lab

PALETTE = ("#0072B2", "#E69F00", "#009E73", "#D55E00", "#56B4E9", "#CC79A7", "#F0E442")  # Okabe-Ito
MAX_POINTS_3D = 15_000  # per 3-D view in a report (keeps report.html small and fast in a browser)

_CSS = """body{font-family:system-ui,sans-serif;margin:1.5em auto;max-width:1200px;color:#222}
h1{font-size:1.5em}h2{font-size:1.2em;margin-top:1.6em}table{border-collapse:collapse;font-size:.85em}
td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}th{background:#f3f3f3}.note{color:#555;font-size:.9em}"""


def page(title: str, blocks: Sequence[str]) -> str:
    """A whole HTML document from body blocks (figures and text)."""
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{_html.escape(title)}</title><style>{_CSS}</style></head><body>\n"
            + "\n".join(blocks) + "\n</body></html>\n")


class Figures:
    """Collects figures as HTML fragments; plotly.js goes into the first one only."""

    def __init__(self) -> None:
        self.count = 0

    def html(self, fig, height: int = 520) -> str:
        top = fig.layout.margin.t if fig.layout.margin.t is not None else 60
        fig.update_layout(height=height, template="plotly_white", margin={"l": 60, "r": 30, "t": top, "b": 50})
        self.count += 1
        return fig.to_html(full_html=False, include_plotlyjs=self.count == 1, div_id=f"fig{self.count}",
                           config={"displaylogo": False, "responsive": True})


def _hover(frame: pd.DataFrame, columns: Sequence[str], label=lab.metric_label) -> tuple[np.ndarray, str]:
    """customdata and a hovertemplate listing every column with its label."""
    data = frame[list(columns)].to_numpy(dtype=float)
    lines = [f"{_html.escape(label(c))} ({c}) = %{{customdata[{i}]:.6g}}" for i, c in enumerate(columns)]
    return data, "<br>".join(lines) + "<extra></extra>"


def front_figure(pareto: pd.DataFrame, population: pd.DataFrame | None, xk: str, yk: str, hover_cols: Sequence[str],
                 featured: Sequence[tuple[str, int]], title: str, label=lab.metric_label):
    import plotly.graph_objects as go

    fig = go.Figure()
    if population is not None and len(population):
        cols = [c for c in hover_cols if c in population.columns]
        data, tmpl = _hover(population, cols, label)
        fig.add_trace(go.Scatter(x=population[xk], y=population[yk], mode="markers", name="final population",
                                 marker={"color": "rgba(0,0,0,0)", "line": {"color": "#8c8c8c", "width": 1}, "size": 6},
                                 customdata=data, hovertemplate=tmpl))
    data, tmpl = _hover(pareto, hover_cols, label)
    order = np.argsort(pareto[xk].to_numpy())
    fig.add_trace(go.Scatter(x=pareto[xk].to_numpy()[order], y=pareto[yk].to_numpy()[order], mode="lines+markers",
                             name=f"Pareto front ({len(pareto)})", marker={"color": PALETTE[0], "size": 7},
                             line={"color": PALETTE[0], "width": 1}, customdata=data[order], hovertemplate=tmpl))
    if featured:
        rows = [i for _, i in featured]
        fig.add_trace(go.Scatter(x=pareto[xk].iloc[rows], y=pareto[yk].iloc[rows], mode="markers+text",
                                 text=[name for name, _ in featured], textposition="top right", name="featured",
                                 marker={"symbol": "star", "size": 15, "color": "#F0E442",
                                         "line": {"color": "black", "width": 1}},
                                 customdata=data[rows], hovertemplate=tmpl))
    fig.update_layout(title=title, xaxis_title=label(xk), yaxis_title=label(yk))
    return fig


def parallel_figure(pareto: pd.DataFrame, columns: Sequence[str], colour: str, title: str, label=lab.metric_label):
    import plotly.graph_objects as go

    dims = [{"label": label(c), "values": pareto[c].to_numpy(dtype=float)} for c in columns]
    line = {"color": pareto[colour].to_numpy(dtype=float), "colorscale": "Viridis", "showscale": True,
            "colorbar": {"title": {"text": label(colour)}}}
    fig = go.Figure(go.Parcoords(dimensions=dims, line=line))
    fig.update_layout(title=title)
    fig.update_layout(margin={"t": 110})  # room for the dimension labels above the axes
    return fig


def hypervolume_figure(generations, values, title: str, ylabel: str):
    """The hypervolume per generation (``values``: normalised by hv_norm, ``ylabel`` saying so)."""
    import plotly.graph_objects as go

    fig = go.Figure(go.Scatter(x=np.asarray(generations), y=np.asarray(values, dtype=float), mode="lines",
                               line={"color": PALETTE[0]}, name="hypervolume"))
    fig.update_layout(title=title, xaxis_title="generation [-]", yaxis_title=ylabel)
    return fig


def workspace_figure(points: np.ndarray, values: np.ndarray, axis_labels: Sequence[str], field_label: str,
                     title: str, equal: bool, box: np.ndarray | None = None, path: np.ndarray | None = None,
                     vmin: float = 0.0, vmax: float = 1.0):
    """3-D scatter of a workspace's boundary cells coloured by a field (viridis), task box and path on top."""
    import plotly.graph_objects as go

    fig = go.Figure(go.Scatter3d(
        x=points[:, 0], y=points[:, 1], z=points[:, 2], mode="markers", name=field_label,
        marker={"size": 2, "color": values, "colorscale": "Viridis", "cmin": vmin, "cmax": vmax, "showscale": True,
                "colorbar": {"title": {"text": field_label}}},
        hovertemplate=f"{axis_labels[0]} %{{x:.4g}}<br>{axis_labels[1]} %{{y:.4g}}<br>{axis_labels[2]} %{{z:.4g}}"
                      f"<br>{field_label} %{{marker.color:.3f}}<extra></extra>"))
    _box_path(fig, box, path)
    scene = {"xaxis_title": axis_labels[0], "yaxis_title": axis_labels[1], "zaxis_title": axis_labels[2],
             "aspectmode": "data" if equal else "cube"}
    fig.update_layout(title=title, scene=scene, showlegend=False)
    return fig


def _box_path(fig, box, path) -> None:
    import plotly.graph_objects as go

    if box is not None:
        lo, hi = np.asarray(box, dtype=float)
        xs, ys, zs = [], [], []
        for a in range(3):
            b, c = [i for i in range(3) if i != a]
            for vb in (lo[b], hi[b]):
                for vc in (lo[c], hi[c]):
                    seg = np.zeros((2, 3))
                    seg[:, a] = lo[a], hi[a]
                    seg[:, b], seg[:, c] = vb, vc
                    xs += [*seg[:, 0], None]
                    ys += [*seg[:, 1], None]
                    zs += [*seg[:, 2], None]
        fig.add_trace(go.Scatter3d(x=xs, y=ys, z=zs, mode="lines", name="task box",
                                   line={"color": PALETTE[3], "width": 4, "dash": "dash"}))
    if path is not None:
        p = np.asarray(path, dtype=float)
        fig.add_trace(go.Scatter3d(x=p[:, 0], y=p[:, 1], z=p[:, 2], mode="lines+markers", name="task path",
                                   line={"color": PALETTE[5], "width": 5}, marker={"size": 3}))


def heatmap_figure(panel: dict, field_label: str, title: str | None = None, vmin: float = 0.0, vmax: float = 1.0):
    """A section (or a planar workspace) as a heatmap, unreachable cells blank."""
    import plotly.graph_objects as go

    values = np.asarray(panel["values"], dtype=float)
    x0, x1, y0, y1 = panel["extent"]
    nx, ny = values.shape
    xs = x0 + (np.arange(nx) + 0.5) * (x1 - x0) / nx
    ys = y0 + (np.arange(ny) + 0.5) * (y1 - y0) / ny
    z = np.where(np.isfinite(values) & (values >= 0), values, np.nan).T
    fig = go.Figure(go.Heatmap(x=xs, y=ys, z=z.tolist(), colorscale="Viridis", zmin=vmin, zmax=vmax,
                               colorbar={"title": {"text": field_label}}))
    if panel.get("box") is not None:
        bx0, bx1, by0, by1 = panel["box"]
        fig.add_shape(type="rect", x0=bx0, x1=bx1, y0=by0, y1=by1, line={"color": PALETTE[3], "dash": "dash"})
    if panel.get("path") is not None:
        p = np.asarray(panel["path"])
        fig.add_trace(go.Scatter(x=p[:, 0], y=p[:, 1], mode="lines+markers",
                                 name=panel.get("path_label", "task path"), line={"color": PALETTE[5]}))
    # the legend below the axes (the colour bar holds the right side): it never covers the map
    fig.update_layout(title=title or panel["title"], xaxis_title=panel["xlabel"], yaxis_title=panel["ylabel"],
                      showlegend=panel.get("path") is not None,
                      legend={"orientation": "h", "x": 0.0, "y": -0.18, "xanchor": "left", "yanchor": "top"})
    if panel.get("equal", False):
        fig.update_yaxes(scaleanchor="x", scaleratio=1)
    return fig


def table(frame: pd.DataFrame, columns: Sequence[str], index_name: str, index: Sequence[str],
          label=lab.metric_label) -> str:
    head = "".join(f"<th>{_html.escape(label(c))}</th>" for c in columns)
    rows = []
    for name, (_, row) in zip(index, frame.iterrows(), strict=True):
        cells = "".join(f"<td>{row[c]:.5g}</td>" for c in columns)
        rows.append(f"<tr><th>{_html.escape(str(name))}</th>{cells}</tr>")
    return f"<table><tr><th>{_html.escape(index_name)}</th>{head}</tr>{''.join(rows)}</table>"


def robot_figure(segments: Sequence[dict], unit: str, title: str):
    """The robot's capsules as thick 3-D lines, one colour per body, equal scale (mechanism frame)."""
    import plotly.graph_objects as go

    fig = go.Figure()
    bodies = list(dict.fromkeys(s["body"] for s in segments))
    for k, body in enumerate(bodies):
        xs, ys, zs = [], [], []
        for s in segments:
            if s["body"] == body:
                xs += [s["a"][0], s["b"][0], None]
                ys += [s["a"][1], s["b"][1], None]
                zs += [s["a"][2], s["b"][2], None]
        fig.add_trace(go.Scatter3d(x=xs, y=ys, z=zs, mode="lines+markers", name=body,
                                   line={"color": PALETTE[k % len(PALETTE)], "width": 8}, marker={"size": 3}))
    fig.update_layout(title=title, scene={"xaxis_title": f"x [{unit}]", "yaxis_title": f"y [{unit}]",
                                          "zaxis_title": f"z [{unit}]", "aspectmode": "data"})
    return fig


def show_page(cfg, fg, field, bands, panels, axis_labels, equal, title, box, path, field_label: str,
              vmin: float = 0.0, vmax: float = 1.0, robot: dict | None = None) -> str:
    """The HTML of `scalesynth show --format html`: 3-D view, one 3-D view per band (regions coloured), sections."""
    import plotly.graph_objects as go

    from scalesynth import workspace_view as wv

    figs = Figures()
    blocks = [f"<h1>{_html.escape(title)}</h1>"]
    rows = "".join(f"<tr><th>{_html.escape(b['label'])}</th><td>{100 * b['share']:.2f} %</td><td>{b['regions']}</td>"
                   f"<td>{b['regions_face_connected']}</td><td>{b['regions_over_1pct']}</td></tr>" for b in bands)
    blocks.append("<table><tr><th>LCI band</th><th>share</th><th>regions (26-conn.)</th><th>regions (6-conn.)</th>"
                  f"<th>regions &ge; 1 % of the band</th></tr>{rows}</table>")
    if not cfg.mech.planar:
        pts, flat = wv.boundary_points(fg.reachable, fg.axes(), MAX_POINTS_3D)
        blocks.append(figs.html(workspace_figure(pts, fg.fields[field].ravel()[flat], axis_labels, field_label,
                                                 "workspace boundary", equal, box, path, vmin, vmax), 650))
        for b in bands:
            bpts, bflat = wv.boundary_points(b["_labels"] > 0, fg.axes(), MAX_POINTS_3D)
            region = b["_labels"].ravel()[bflat] - 1
            fig = go.Figure(go.Scatter3d(x=bpts[:, 0], y=bpts[:, 1], z=bpts[:, 2], mode="markers",
                                         marker={"size": 2, "color": [PALETTE[r % len(PALETTE)] for r in region]},
                                         text=[f"region {r + 1}" for r in region], name=b["label"]))
            _box_path(fig, box, path)
            fig.update_layout(title=f"LCI {b['label']}: {b['regions']} regions (26-connected)", showlegend=False,
                              scene={"xaxis_title": axis_labels[0], "yaxis_title": axis_labels[1],
                                     "zaxis_title": axis_labels[2], "aspectmode": "data" if equal else "cube"})
            blocks.append(figs.html(fig, 560))
    for panel in panels:
        blocks.append(figs.html(heatmap_figure(panel, field_label, vmin=vmin, vmax=vmax), 480))
    if robot and "segments" in robot:
        blocks.append(figs.html(robot_figure(robot["segments"], cfg.units.length, wv.robot_caption(cfg, robot)),
                                560))
    elif robot:
        blocks.append(f"<p class=\"note\">Robot not drawn: {_html.escape(robot['missing'])}</p>")
    return page(title, blocks)
