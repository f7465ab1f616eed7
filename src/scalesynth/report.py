"""Plots and report.md of a run, from its RunResult in memory (scalesynth.results); draws via plotting.py.

``optimize.run`` passes the result it just built, so report.md, the plots and manifest.json show the same
figures; the ``plot-*`` commands pass ``results.load(run_dir)``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from scalesynth import io as rio
from scalesynth import plotting
from scalesynth.config import RunConfig
from scalesynth.evaluate import evaluate_config
from scalesynth.problem import SynthesisProblem
from scalesynth.results import PLOTS, REPORT, RunResult, infeasibility_lines
from scalesynth.selection import choose, extremes


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


def plot_front(result: RunResult) -> dict[str, Any]:
    """plots/front.png (front, final population, reference designs, knee) and plots/hypervolume.png."""
    cfg, pareto, history, population, problem = (result.cfg, result.pareto, result.history, result.population,
                                                 result.problem)
    plots = rio.ensure_dir(result.out_dir / PLOTS)
    xk, yk = _axes(problem, cfg)
    refs = reference_points(cfg)
    highlight = []
    if len(pareto):
        F = result.objective_matrix()
        k = choose(F, "knee")
        highlight.append(("knee", float(pareto[xk].iloc[k]), float(pareto[yk].iloc[k])))
        for r in refs:
            fr = np.array([r["metrics"][key] for key in problem.objective_keys]) * problem.signs
            r["dominated_by_front"] = dominated_by_front(F, fr)
    pop_xy = None
    if population is not None and len(population):
        pop_xy = (population[xk].to_numpy(), population[yk].to_numpy())
    fig = plotting.front_figure(
        pareto[xk].to_numpy(),
        pareto[yk].to_numpy(),
        xk,
        yk,
        f"{cfg.name}: Pareto front ({cfg.mechanism}, seed {cfg.algorithm.seed})",
        references=[(r["label"], r["metrics"][xk], r["metrics"][yk]) for r in refs],
        highlight=highlight,
        population=pop_xy,
    )
    rio.save_figure(fig, plots / "front.png")
    plotting.close(fig)
    fig = plotting.hypervolume_figure(
        history["generation"].to_numpy(), history["hypervolume"].to_numpy(), f"{cfg.name}: hypervolume per generation"
    )
    rio.save_figure(fig, plots / "hypervolume.png")
    plotting.close(fig)
    return {"references": refs, "files": ["plots/front.png", "plots/hypervolume.png"]}


def band_labels(edges) -> list[str]:
    return [f"{'[' if b == 0 else '('}{edges[b]:g}, {edges[b + 1]:g}]" for b in range(len(edges) - 1)]


def featured_designs(result: RunResult) -> list[tuple[str, int]]:
    """The knee and the best design of each objective on the front, as (label, row index), without repeats."""
    problem = result.problem
    F = result.objective_matrix()
    out = [("knee", choose(F, "knee"))]
    for obj_idx, row in enumerate(extremes(F)):
        label = f"best {problem.objective_keys[obj_idx] if obj_idx < len(problem.objective_keys) else obj_idx}"
        if row not in [r for _, r in out]:
            out.append((label, row))
    return out


SECTION_RESOLUTION = 128  # plots want finer cells than the optimisation grid; one design costs ~0.1 s


def section_panels(cfg: RunConfig, design: dict[str, float]) -> list[dict[str, Any]]:
    """Mid-plane sections of the LCI grid: (axis0, axis2) at the middle of axis1 and (axis0, axis1) at the middle
    of axis2 (for seed 000: xz at y = 0 and xy at the centre height); one map for planar mechanisms."""
    res = max(cfg.grid.resolution, SECTION_RESOLUTION)
    cfg = cfg.model_copy(update={"grid": cfg.grid.model_copy(update={"resolution": res + res % 2 + 1})})
    rep = evaluate_config(cfg, design, keep_grid=True)
    g, lci = rep.grid, rep.field("lci")
    names = cfg.mech.task_axes
    ext = [(g.lo[a], g.lo[a] + g.shape[a] * g.step[a]) for a in range(3)]
    if len(names) == 2:
        return [{"lci": lci[:, :, 0], "extent": (*ext[0], *ext[1]), "xlabel": names[0], "ylabel": names[1],
                 "title": f"{names[0]}{names[1]} workspace"}]
    j = int(g.shape[1]) // 2
    k = int(g.shape[2]) // 2
    yj = g.lo[1] + (j + 0.5) * g.step[1]
    zk = g.lo[2] + (k + 0.5) * g.step[2]
    return [
        {"lci": lci[:, j, :], "extent": (*ext[0], *ext[2]), "xlabel": names[0], "ylabel": names[2],
         "title": f"{names[0]}{names[2]} section at {names[1]} = {yj:.4g}"},
        {"lci": lci[:, :, k], "extent": (*ext[0], *ext[1]), "xlabel": names[0], "ylabel": names[1],
         "title": f"{names[0]}{names[1]} section at {names[2]} = {zk:.4g}"},
    ]


def plot_bands(result: RunResult) -> dict[str, Any]:
    """plots/bands_front.png, plots/band_shares.png and plots/sections_<design>.png (paper Figs. 7-10, Table 5)."""
    cfg, pareto, problem = result.cfg, result.pareto, result.problem
    plots = rio.ensure_dir(result.out_dir / PLOTS)
    edges = cfg.dexterity.band_edges
    labels = band_labels(edges)
    nb = len(edges) - 1
    files = []
    if not len(pareto):
        return {"files": files, "featured": []}
    xk, yk = _axes(problem, cfg)
    shares = [pareto[f"band{b}_share"].to_numpy() for b in range(nb)]
    fig = plotting.band_front_figure(pareto[xk].to_numpy(), pareto[yk].to_numpy(), shares, labels, xk, yk)
    rio.save_figure(fig, plots / "bands_front.png")
    plotting.close(fig)
    files.append("plots/bands_front.png")
    featured = featured_designs(result)
    bar = np.array([[pareto[f"band{b}_share"].iloc[i] for b in range(nb)] for _, i in featured])
    fig = plotting.band_shares_figure([label for label, _ in featured], bar, labels)
    rio.save_figure(fig, plots / "band_shares.png")
    plotting.close(fig)
    files.append("plots/band_shares.png")
    for label, i in featured:
        design = result.design_of(pareto.iloc[i])
        panels = section_panels(cfg, design)
        title = f"{label}: " + ", ".join(f"{k}={v:.4g}" for k, v in design.items())
        fig = plotting.sections_figure(panels, edges, title)
        name = "sections_" + label.replace(" ", "_") + ".png"
        rio.save_figure(fig, plots / name)
        plotting.close(fig)
        files.append(f"plots/{name}")
    return {"files": files, "featured": [(label, int(i)) for label, i in featured]}


def report_text(result: RunResult, front_info: dict[str, Any], bands_info: dict[str, Any]) -> str:
    """report.md: key numbers of the run (from the RunResult and its manifest) and links to its plots."""
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
        f"- grid: {cfg.grid.resolution} cells per axis; dexterity bands {bands}",
        f"- objectives: {objectives}",
    ]
    if cfg.constraints:
        lines.append("- constraints: " + ", ".join(
            f"{k} {'>= ' + repr(float(c.min)) if c.min is not None else ''}"
            f"{' and ' if c.min is not None and c.max is not None else ''}"
            f"{'<= ' + repr(float(c.max)) if c.max is not None else ''}"
            for c, k in zip(cfg.constraints, problem.constraint_keys, strict=True)))
    lines += [
        f"- final hypervolume: {history['hypervolume'].iloc[-1]:.6g}",
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
    refs = front_info.get("references", [])
    if refs:
        lines += ["", "## Reference designs re-evaluated under the same model", ""]
        lines.append(f"| label | {mkey} | gci | dominated by the front |")
        lines.append("|---|---|---|---|")
        for r in refs:
            dom = r.get("dominated_by_front")
            lines.append(f"| {r['label']} | {r['metrics'][mkey]:.4g} | {r['metrics']['gci']:.4g} | "
                         f"{'yes' if dom else 'no' if dom is not None else '-'} |")
    lines += ["", "## Plots", ""]
    for f in front_info.get("files", []) + bands_info.get("files", []):
        lines.append(f"![{Path(f).stem}]({f})")
    return "\n".join(lines) + "\n"


def write_report(result: RunResult, front_info: dict[str, Any], bands_info: dict[str, Any]) -> None:
    rio.write_text(result.out_dir / REPORT, report_text(result, front_info, bands_info))


def write_plots_and_report(result: RunResult) -> None:
    """Every plot and report.md of a run, from the RunResult (no files re-read, no second problem)."""
    front = plot_front(result)
    bands = plot_bands(result)
    write_report(result, front, bands)
