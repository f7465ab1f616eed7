"""report.html of a finished run: self-contained (plotly.js embedded, no network), the Pareto front with every design
variable and metric on hover, parallel coordinates of design variables and objectives, the hypervolume history,
the featured designs' workspaces in 3-D coloured by LCI, and the per-band Pareto set sizes."""

from __future__ import annotations

import html as _html
from pathlib import Path
from typing import Any

from scalesynth import hv_norm
from scalesynth import interactive as ia
from scalesynth import io as rio
from scalesynth import labels as lab
from scalesynth import workspace_view as wv
from scalesynth.evaluate import evaluator_description

VIEW_RESOLUTION = 40  # cells per axis of the featured designs' 3-D views (40^3 = 64k cells, ~0.05 s each)


def write_report_html(result, featured: list[tuple[str, int]], axes: tuple[str, str],
                      band_sizes: list[int] | None = None, sheet: tuple[str, Any] | None = None) -> Path:
    """Write report.html for a results.RunResult; ``featured`` (label, pareto row) and the front's ``axes`` as the
    report and plots use them; ``sheet`` (label, datasheet or why not) as report.md's."""
    cfg, pareto, history, population, problem = (result.cfg, result.pareto, result.history, result.population,
                                                 result.problem)
    run_dir = result.out_dir
    mech = cfg.mech
    manifest: dict[str, Any] = result.manifest or {}
    xk, yk = axes
    derived = [c for c in pareto.columns if c not in problem.var_names and c not in problem.metric_columns
               and c not in ("rank", "feasible")]
    hover = [c for c in [*problem.var_names, *derived, *problem.metric_columns] if c in pareto.columns]
    label = lab.labeller(cfg, explicit=True)  # every axis with a unit, '[-]' where there is none
    figs = ia.Figures()
    title = f"{cfg.name}: scale synthesis of {mech.name}"
    blocks = [f"<h1>{_html.escape(title)}</h1>", _summary(cfg, problem, pareto, history, manifest, label, result)]
    blocks.append("<h2>Pareto front</h2><p class=\"note\">Hover a point for every design variable and metric.</p>")
    if len(pareto):
        blocks.append(figs.html(ia.front_figure(pareto, population, xk, yk, hover, featured,
                                                f"Pareto front ({len(pareto)} designs) and final population", label)))
        obj = list(dict.fromkeys(problem.objective_keys))
        blocks.append("<h2>Design variables and objectives</h2>")
        blocks.append(figs.html(ia.parallel_figure(pareto, [*problem.var_names, *obj], obj[0],
                                                   "parallel coordinates of the Pareto front", label), 480))
    else:
        blocks.append("<p>The front is empty: no feasible design.</p>")
    blocks.append("<h2>Hypervolume</h2>")
    hv, hv_label = hv_norm.of_result(result)
    blocks.append(figs.html(ia.hypervolume_figure(history["generation"], hv, "hypervolume per generation", hv_label),
                            380))
    if featured:
        blocks.append("<h2>Featured designs</h2>")
        cols = [c for c in [*problem.var_names, *problem.objective_keys, "gci"] if c in pareto.columns]
        cols = list(dict.fromkeys(cols))
        rows = pareto.iloc[[i for _, i in featured]]
        blocks.append(ia.table(rows, cols, "design", [name for name, _ in featured], label))
        unit = cfg.units.length
        ndim = len(mech.task_axes)
        axis_labels = [lab.axis_label(mech, a, unit) for a in range(ndim)]
        equal = lab.same_units(mech, range(ndim))
        box, path = wv.task_geometry(cfg)
        lci_label = lab.field_label(mech, "lci", unit, explicit=True)
        for name, i in featured:
            design = result.design_of(pareto.iloc[i])
            fg = wv.sample_fields(cfg, design, VIEW_RESOLUTION if ndim == 3 else max(cfg.grid.resolution, 96))
            caption = f"{name}: " + ", ".join(f"{k}={v:.4g}" for k, v in design.items())
            if ndim == 3:
                pts, flat = wv.boundary_points(fg.reachable, fg.axes(), ia.MAX_POINTS_3D)
                fig = ia.workspace_figure(pts, fg.lci.ravel()[flat], axis_labels, lci_label,
                                          f"{caption} (workspace boundary, {VIEW_RESOLUTION}³ grid)", equal, box, path)
                blocks.append(figs.html(fig, 600))
            else:
                g = fg.grid
                ext = (g.lo[0], g.lo[0] + g.shape[0] * g.step[0], g.lo[1], g.lo[1] + g.shape[1] * g.step[1])
                panel = {"values": fg.fields["lci"][:, :, 0], "extent": ext, "xlabel": axis_labels[0],
                         "ylabel": axis_labels[1], "title": caption, "equal": equal,
                         "box": None if box is None else (box[0, 0], box[1, 0], box[0, 1], box[1, 1]),
                         "path": None if path is None else path[:, :2]}
                blocks.append(figs.html(ia.heatmap_figure(panel, lci_label), 520))
            if "deflection" in wv.stiffness_map_fields(cfg):  # the stiffness map: the sections coloured by deflection
                panels = wv.section_panels(cfg, design, "deflection")
                vmin, vmax = wv.map_range(panels)
                flabel = lab.field_label(mech, "deflection", unit, explicit=True)
                for panel in panels:
                    blocks.append(figs.html(ia.heatmap_figure(panel, flabel, f"{caption}: {flabel}, {panel['title']}",
                                                              vmin, vmax), 520))
    if sheet is not None:
        from scalesynth.cycle.datasheet import html_table

        name, body = sheet
        blocks.append(f"<h2>Datasheet of the {_html.escape(name)} design</h2>")
        blocks.append(html_table(body) if isinstance(body, dict)
                      else f"<p>Its cycle cannot be followed: {_html.escape(body)}</p>")
    if band_sizes:
        edges = cfg.dexterity.band_edges
        items = "".join(f"<li>LCI {wv.band_labels(edges)[k]}: {n} designs in <code>bands/pareto_band{k}.csv</code>"
                        "</li>" for k, n in enumerate(band_sizes))
        blocks.append(f"<h2>Per-band Pareto sets</h2><ul>{items}</ul>")
    target = run_dir / "report.html"
    rio.write_text(target, ia.page(title, blocks))
    return target


def _summary(cfg, problem, pareto, history, manifest, label, result) -> str:
    objectives = ", ".join(f"{o.sense} {label(k)}"
                           for o, k in zip(cfg.objectives, problem.objective_keys, strict=True))
    items = [
        f"mechanism {cfg.mechanism}; NSGA-II population {cfg.algorithm.pop_size}, "
        f"{int(history['generation'].iloc[-1]) if len(history) else 0} generations, seed {cfg.algorithm.seed}",
        f"workspace: {evaluator_description(cfg)}; dexterity bands "
        + ", ".join(wv.band_labels(cfg.dexterity.band_edges)),
        f"objectives: {objectives}",
        f"final hypervolume {float(history['hypervolume'].iloc[-1]) if len(history) else 0.0:.6g}"
        f"{hv_norm.share_text(result) if len(history) else ''}; "
        f"Pareto front {len(pareto)} designs",
    ]
    if manifest.get("wall_seconds") is not None:
        items.append(f"wall time {manifest['wall_seconds']:.1f} s on {manifest.get('machine', {}).get('cores')} cores")
    return "<ul>" + "".join(f"<li>{_html.escape(t)}</li>" for t in items) + "</ul>"


def has_remote_scripts(text: str) -> bool:
    """True if an HTML text loads a script from the network (a CDN link)."""
    import re

    return re.search(r"<script[^>]*\bsrc\s*=\s*[\"']?\s*(https?:)?//", text, re.IGNORECASE) is not None

