"""Plots, per-band Pareto sets, report.md and report.html of a run, from its RunResult in memory
(scalesynth.results); draws via plotting.py (matplotlib) and interactive.py (plotly).

``optimize.run`` passes the result it just built, so report.md, report.html, the plots and manifest.json show the
same figures; the ``plot-*`` commands pass ``results.load(run_dir)``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from scalesynth import hv_norm
from scalesynth import io as rio
from scalesynth import labels as lab
from scalesynth.config import RunConfig
from scalesynth.errors import ConfigError
from scalesynth.evaluate import evaluate_config, evaluator_description
from scalesynth.problem import SynthesisProblem
from scalesynth.results import PLOTS, REPORT, Front, RunResult, infeasibility_lines, load, read_front
from scalesynth.selection import choose, extremes
from scalesynth.workspace_view import (  # SECTION_RESOLUTION, section_panels: also report's (memory, tests)
    SECTION_RESOLUTION,  # noqa: F401
    STIFFNESS_MAP_FIELDS,  # noqa: F401
    band_labels,
    map_range,
    section_panels,
    stiffness_map_fields,
)


def _axes(problem: SynthesisProblem, cfg: RunConfig) -> tuple[str, str]:
    keys = problem.objective_keys
    if len(keys) >= 2:
        return keys[0], keys[1]
    return cfg.mech.measure_key(cfg.units.length), keys[0]


def reference_points(cfg: RunConfig) -> list[dict[str, Any]]:
    """The config's reference designs re-evaluated with the run's model and grid."""
    out = []
    for label, ref in cfg.references.items():
        design = cfg.mech.resolve_design({**cfg.design, **ref})
        metrics = evaluate_config(cfg, design).metrics
        out.append({"label": label, "design": design, "metrics": metrics})
    return out


def dominated_by_front(F_front: np.ndarray, f: np.ndarray) -> bool:
    """True if some front point is no worse in every objective and better in one (minimisation form)."""
    return bool(np.any(np.all(F_front <= f, axis=1) & np.any(F_front < f, axis=1)))


def _plots_dir(result: RunResult, out: Path | None, fmt: str) -> Path:
    _check_format(fmt)
    return rio.ensure_dir(Path(out) if out is not None else result.out_dir / PLOTS)


def _rel(run_dir: Path, path: Path) -> str:
    """A written file's name relative to the run directory (absolute when --out put it elsewhere)."""
    try:
        return str(path.resolve().relative_to(Path(run_dir).resolve()))
    except ValueError:
        return str(path)


def plot_front(result: RunResult, out: Path | None = None, fmt: str = "png") -> dict[str, Any]:
    """plots/front.<fmt> (front, final population, reference designs, knee) and plots/hypervolume.<fmt>."""
    plots = _plots_dir(result, out, fmt)
    cfg, pareto, history, population, problem = (result.cfg, result.pareto, result.history, result.population,
                                                 result.problem)
    label = lab.labeller(cfg)
    xk, yk = _axes(problem, cfg)
    refs = reference_points(cfg)
    highlight = []
    if len(pareto):
        F = result.objective_matrix()
        k = choose(F, "knee")
        highlight.append(("knee", float(pareto[xk].iloc[k]), float(pareto[yk].iloc[k])))
        for r in refs:
            fr = problem.minimisation_form(np.array([[r["metrics"][key] for key in problem.objective_keys]]))[0]
            r["dominated_by_front"] = dominated_by_front(F, fr)
    pop_xy = None
    if population is not None and len(population):
        pop_xy = (population[xk].to_numpy(), population[yk].to_numpy())
    from scalesynth import plotting  # matplotlib: imported where the drawing starts, after the evaluations

    fig = plotting.front_figure(
        pareto[xk].to_numpy(),
        pareto[yk].to_numpy(),
        label(xk),
        label(yk),
        f"{cfg.name}: Pareto front ({cfg.mechanism}, seed {cfg.algorithm.seed})",
        references=[(r["label"], r["metrics"][xk], r["metrics"][yk]) for r in refs],
        highlight=highlight,
        population=pop_xy,
    )
    rio.save_figure(fig, plots / f"front.{fmt}")
    plotting.close(fig)
    hv, hv_label = hv_norm.of_result(result)
    fig = plotting.hypervolume_figure(history["generation"].to_numpy(), hv, f"{cfg.name}: hypervolume per generation",
                                      hv_label)
    rio.save_figure(fig, plots / f"hypervolume.{fmt}")
    plotting.close(fig)
    files = [_rel(result.out_dir, plots / f"front.{fmt}"), _rel(result.out_dir, plots / f"hypervolume.{fmt}")]
    return {"references": refs, "files": files}


def featured_designs(F: np.ndarray, objective_keys: list[str]) -> list[tuple[str, int]]:
    """The knee and the best design of each objective of a front ``F`` (n_front, n_obj; minimisation form), as
    (label, row index), without repeats."""
    out = [("knee", choose(F, "knee"))]
    for obj_idx, row in enumerate(extremes(F)):
        label = f"best {objective_keys[obj_idx] if obj_idx < len(objective_keys) else obj_idx}"
        if row not in [r for _, r in out]:
            out.append((label, row))
    return out


@dataclass
class BandSections:
    """plot-bands' evaluations, made before anything is drawn: the featured designs of a front (label, row index,
    full design) and per design its section panels, field -> panels (``"lci"`` and each stiffness map field).
    ``X``, ``F``: the front they were computed from (design variables, objectives in minimisation form)."""

    featured: list[tuple[str, int, dict[str, float]]]
    panels: list[dict[str, list[dict[str, Any]]]]
    X: np.ndarray
    F: np.ndarray

    def of(self, X: np.ndarray, F: np.ndarray) -> bool:
        """True if computed from this front (the same numbers, bit for bit)."""
        return np.array_equal(self.X, X) and np.array_equal(self.F, F)


def band_sections(front: Front) -> BandSections:
    """The section panels of the featured designs of a front (``results.Front``): every workspace evaluation of
    plot-bands (the per-band Pareto sets and the band plots only read the tables)."""
    cfg, problem = front.cfg, front.problem
    featured, panels = [], []
    for name, i in featured_designs(front.F, problem.objective_keys) if len(front.F) else []:
        design = front.design(i)
        featured.append((name, i, design))
        panels.append({field: section_panels(cfg, design, field) for field in ("lci", *stiffness_map_fields(cfg))})
    return BandSections(featured, panels, front.X, front.F)


def plot_front_run(run_dir: Path, out: Path | None = None, fmt: str = "png", force: bool = False) -> list[Path]:
    """``plot-front``: :func:`plot_front` of a results directory into ``out`` (default RUN_DIR/plots), staged and
    swapped in whole (``scalesynth.plot_output``; ``--out`` claimed before anything is evaluated); returns the
    files written, where they are after the swap."""
    from scalesynth.plot_output import figures

    _check_format(fmt)
    result = load(run_dir, require_finished=False)
    with figures(_figures_dir(run_dir, out), "plot-front", force, str(run_dir)) as fig:
        info = plot_front(replace(result, out_dir=fig.root), fig.dir, fmt)
    return [fig.final(f) for f in info["files"]]


def plot_bands_run(run_dir: Path, out: Path | None = None, fmt: str = "png",
                   force: bool = False) -> dict[str, Any]:
    """``plot-bands``: :func:`plot_bands` of a results directory, staged and swapped in like
    :func:`plot_front_run`, its sections evaluated first, from config.yaml and pareto.csv read without pandas
    (issue 15: a fresh process reaches its first evaluation before the pandas and matplotlib imports and the
    drawing). Where that read fails, or --format is invalid, results.load reports what is wrong, as before.
    ``files`` and ``band_files`` are where the files are after the swap."""
    from scalesynth.plot_output import figures

    front = read_front(run_dir) if fmt in rio.FIGURE_FORMATS else None
    if front is None:
        load(run_dir, require_finished=False)  # says what is wrong with the directory
        _check_format(fmt)
    with figures(_figures_dir(run_dir, out), "plot-bands", force, str(run_dir)) as fig:
        sections = None if front is None else band_sections(front)
        result = replace(load(run_dir, require_finished=False), out_dir=fig.root)
        info = plot_bands(result, None if fig.into_run else fig.dir, fmt, sections)
    return {**info, "files": [fig.final(f) for f in info["files"]],
            "band_files": [fig.final(f) for f in info["band_files"]]}


def _figures_dir(run_dir: Path, out: Path | None) -> Path:
    return Path(out) if out is not None else Path(run_dir) / PLOTS


def _check_format(fmt: str) -> None:
    if fmt not in rio.FIGURE_FORMATS:
        raise ConfigError(f"--format: must be one of {', '.join(rio.FIGURE_FORMATS)}, got {fmt!r}")


def plot_bands(result: RunResult, out: Path | None = None, fmt: str = "png",
               sections: BandSections | None = None) -> dict[str, Any]:
    """plots/bands_front, plots/band_shares and plots/sections_<design> (paper Figs. 7-10, Table 5), and the
    per-band Pareto sets bands/pareto_band<k>.csv with their plots. ``sections``: the front's band_sections,
    computed earlier (used only if computed from this result's front; otherwise computed here)."""
    plots = _plots_dir(result, out, fmt)
    cfg, pareto, problem = result.cfg, result.pareto, result.problem
    if len(pareto):
        front = result.front()
        if sections is None or not sections.of(front.X, front.F):
            sections = band_sections(front)
    from scalesynth import plotting  # matplotlib: imported where the drawing starts, after the evaluations
    from scalesynth.band_fronts import write_band_fronts

    label = lab.labeller(cfg)
    edges = cfg.dexterity.band_edges
    labels = band_labels(edges)
    nb = len(edges) - 1
    files = []
    bands_out = None if out is None else plots / "bands"
    band_info = write_band_fronts(result.out_dir, cfg, problem, result.population, fmt, bands_out)
    band_rel = [_rel(result.out_dir, Path(p)) for p in band_info["paths"]]
    if not len(pareto):
        return {"files": files, "featured": [], "band_files": band_rel, "band_sizes": band_info["sizes"]}
    xk, yk = _axes(problem, cfg)
    shares = [pareto[f"band{b}_share"].to_numpy() for b in range(nb)]
    fig = plotting.band_front_figure(pareto[xk].to_numpy(), pareto[yk].to_numpy(), shares, labels, label(xk),
                                     label(yk))
    rio.save_figure(fig, plots / f"bands_front.{fmt}")
    plotting.close(fig)
    files.append(_rel(result.out_dir, plots / f"bands_front.{fmt}"))
    featured = [(name, i) for name, i, _ in sections.featured]
    bar = np.array([[pareto[f"band{b}_share"].iloc[i] for b in range(nb)] for _, i in featured])
    fig = plotting.band_shares_figure([name for name, _ in featured], bar, labels)
    rio.save_figure(fig, plots / f"band_shares.{fmt}")
    plotting.close(fig)
    files.append(_rel(result.out_dir, plots / f"band_shares.{fmt}"))
    for (name, _, design), panels in zip(sections.featured, sections.panels, strict=True):
        title = f"{name}: " + ", ".join(f"{k}={v:.4g}" for k, v in design.items())
        fig = plotting.sections_figure(panels["lci"], edges, title)
        fname = "sections_" + name.replace(" ", "_") + f".{fmt}"
        rio.save_figure(fig, plots / fname)
        plotting.close(fig)
        files.append(_rel(result.out_dir, plots / fname))
        for field in stiffness_map_fields(cfg):
            files.append(_rel(result.out_dir, field_sections(cfg, design, field, title, plots, name, fmt,
                                                             panels[field])))
    return {"files": files, "featured": [(name, int(i)) for name, i in featured], "band_files": band_rel,
            "band_sizes": band_info["sizes"]}


def field_sections(cfg: RunConfig, design: dict[str, float], field: str, title: str, plots: Path, name: str,
                   fmt: str, panels: list[dict[str, Any]] | None = None) -> Path:
    """plots/sections_<field>_<design>: the report's sections coloured by a per-voxel field (a stiffness map:
    deflection or stiffness_min), the colour bar labelled with its unit and the range of the shown cells in the
    title. ``panels``: section_panels(cfg, design, field), if already computed. Returns the file written."""
    from scalesynth import plotting

    if panels is None:
        panels = section_panels(cfg, design, field)
    vmin, vmax = map_range(panels)
    label = lab.field_label(cfg.mech, field, cfg.units.length)
    v = np.concatenate([np.asarray(p["values"], dtype=float).ravel() for p in panels])
    v = v[np.isfinite(v)]
    shown = f" ({v.min():.4g} to {v.max():.4g} in these sections)" if v.size else " (no reachable cell)"
    fig = plotting.sections_figure(panels, None, f"{title}\n{label}{shown}", field_label=label, vmin=vmin,
                                   vmax=vmax)
    target = plots / (f"sections_{field}_" + name.replace(" ", "_") + f".{fmt}")
    rio.save_figure(fig, target)
    plotting.close(fig)
    return target


def report_text(result: RunResult, front_info: dict[str, Any], bands_info: dict[str, Any],
                sheet: tuple[str, Any] | None = None) -> str:
    """report.md: key numbers of the run (from the RunResult and its manifest) and links to its plots; ``sheet``
    (label, datasheet or why not) of a featured design where the run has motors (``cycle.datasheet.of_featured``)."""
    cfg, pareto, history, manifest, problem = (result.cfg, result.pareto, result.history, result.manifest,
                                               result.problem)
    mkey = cfg.mech.measure_key(cfg.units.length)
    bands = ", ".join(band_labels(cfg.dexterity.band_edges))
    objectives = ", ".join(f"{o.sense} {k}" for o, k in zip(cfg.objectives, problem.objective_keys, strict=True))
    lines = [
        f"# {cfg.name}: scale synthesis of `{cfg.mechanism}`",
        "",
        f"- NSGA-II: population {cfg.algorithm.pop_size}, {int(history['generation'].iloc[-1])} generations, "
        f"{int(history['evaluations'].iloc[-1])} evaluations, seed {cfg.algorithm.seed}",
        f"- workspace: {evaluator_description(cfg)}; dexterity bands {bands}",
        f"- objectives: {objectives}",
    ]
    if cfg.constraints:
        lines.append("- constraints: " + ", ".join(
            f"{k} {'>= ' + repr(float(c.min)) if c.min is not None else ''}"
            f"{' and ' if c.min is not None and c.max is not None else ''}"
            f"{'<= ' + repr(float(c.max)) if c.max is not None else ''}"
            for c, k in zip(cfg.constraints, problem.constraint_keys, strict=True)))
    lines += [
        f"- final hypervolume: {history['hypervolume'].iloc[-1]:.6g}{hv_norm.share_text(result)}",
        f"- Pareto front: {len(pareto)} designs",
    ]
    if manifest.get("wall_seconds") is not None:
        cores = manifest.get("machine", {}).get("cores")
        lines.append(f"- wall time: {manifest['wall_seconds']:.1f} s on {cores} cores")
    if "m_minus_n" in pareto.columns:
        lines.append("- note: the model depends on m and n only through m - n (spec §1.1); see column m_minus_n")
    diagnostics = infeasibility_lines(manifest)
    if diagnostics:
        lines += ["", "## No feasible design", "",
                  "The final population has no design that meets every constraint. Best value seen of each "
                  "constraint over the run:", ""]
        lines += [f"- {line}" for line in diagnostics]
    lines += ["", "## Featured designs", ""]
    cols = [*problem.var_names, *problem.objective_keys, *problem.constraint_keys, mkey, "gci", "fci", "min_lci"]
    cols += [c for c in pareto.columns if c.endswith("_share")]
    cols = [c for c in dict.fromkeys(cols) if c in pareto.columns]
    lines.append("| design | " + " | ".join(cols) + " |")
    lines.append("|---" * (len(cols) + 1) + "|")
    for label, i in bands_info.get("featured", []):
        row = pareto.iloc[i]
        lines.append(f"| {label} | " + " | ".join(f"{row[c]:.4g}" for c in cols) + " |")
    if sheet is not None:
        from scalesynth.cycle.datasheet import markdown_table

        label, body = sheet
        lines += ["", f"## Datasheet of the {label} design", "",
                  markdown_table(body) if isinstance(body, dict) else f"Its cycle cannot be followed: {body}"]
    refs = front_info.get("references", [])
    if refs:
        lines += ["", "## Reference designs re-evaluated under the same model", ""]
        lines.append(f"| label | {mkey} | gci | dominated by the front |")
        lines.append("|---|---|---|---|")
        for r in refs:
            dom = r.get("dominated_by_front")
            lines.append(f"| {r['label']} | {r['metrics'][mkey]:.4g} | {r['metrics']['gci']:.4g} | "
                         f"{'yes' if dom else 'no' if dom is not None else '-'} |")
    sizes = bands_info.get("band_sizes") or []
    if sizes:
        lines += ["", "## Per-band Pareto sets", "",
                  "Designs of the final population non-dominated in band k's measure and the run's other objectives.",
                  ""]
        for k, n in enumerate(sizes):
            lines.append(f"- LCI {band_labels(cfg.dexterity.band_edges)[k]}: {n} designs, "
                         f"[bands/pareto_band{k}.csv](bands/pareto_band{k}.csv)")
    lines += ["", "## Plots", "", "Interactive version: [report.html](report.html) (self-contained, works offline).",
              ""]
    images = [f for f in bands_info.get("band_files", []) if not f.endswith(".csv")]
    for f in front_info.get("files", []) + bands_info.get("files", []) + images:
        lines.append(f"![{Path(f).stem}]({f})")
    return "\n".join(lines) + "\n"


def write_report(result: RunResult, front_info: dict[str, Any], bands_info: dict[str, Any],
                 sheet: tuple[str, Any] | None = None) -> None:
    rio.write_text(result.out_dir / REPORT, report_text(result, front_info, bands_info, sheet))


def write_plots_and_report(result: RunResult) -> None:
    """Every plot, the per-band Pareto sets, report.md and report.html of a run, from the RunResult (no files
    re-read, no second problem)."""
    from scalesynth.cycle.datasheet import of_featured
    from scalesynth.report_html import write_report_html

    front = plot_front(result)
    bands = plot_bands(result)
    sheet = of_featured(result, bands.get("featured") or [])
    write_report(result, front, bands, sheet)
    xk, yk = _axes(result.problem, result.cfg)
    write_report_html(result, bands.get("featured") or [], (xk, yk), bands.get("band_sizes"), sheet)
