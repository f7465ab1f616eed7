"""Plots and report.md for a finished results directory (reads its CSVs and config; draws via plotting.py)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from scalesynth import io as rio
from scalesynth import plotting
from scalesynth.config import RunConfig, load_config
from scalesynth.errors import ConfigError
from scalesynth.evaluate import evaluate_config, make_grid
from scalesynth.kernels.grid import sample_grid
from scalesynth.problem import SynthesisProblem
from scalesynth.selection import choose, extremes


def load_run(run_dir: Path) -> tuple[RunConfig, pd.DataFrame, pd.DataFrame, pd.DataFrame | None]:
    run_dir = Path(run_dir)
    for name in ("config.yaml", "pareto.csv", "history.csv"):
        if not (run_dir / name).is_file():
            raise ConfigError(f"{run_dir}: not a scalesynth results directory (missing {name})")
    cfg = load_config(run_dir / "config.yaml")
    # damaged files give one line naming the file and column (issue 11), never a pandas traceback
    problem = SynthesisProblem(cfg)
    nb = len(cfg.dexterity.band_edges) - 1
    needed = [*problem.var_names, *problem.objective_keys, cfg.mech.measure_key(cfg.units.length),
              *(f"band{b}_share" for b in range(nb))]
    pareto = rio.read_results_csv(run_dir / "pareto.csv", list(dict.fromkeys(needed)))
    history = rio.read_results_csv(run_dir / "history.csv", ("generation", "evaluations", "hypervolume"))
    if not len(history):
        raise ConfigError(f"{run_dir / 'history.csv'}: no generations")
    pop_path = run_dir / "population.csv"
    population = rio.read_results_csv(pop_path, problem.objective_keys) if pop_path.is_file() else None
    return cfg, pareto, history, population


def objective_matrix(problem: SynthesisProblem, frame: pd.DataFrame) -> np.ndarray:
    """Objectives of the rows in minimisation form."""
    return frame[problem.objective_keys].to_numpy(dtype=float) * problem.signs


def _axes(problem: SynthesisProblem, cfg: RunConfig) -> tuple[str, str]:
    keys = problem.objective_keys
    if len(keys) >= 2:
        return keys[0], keys[1]
    return cfg.mech.measure_key(cfg.units.length), keys[0]


def design_of(problem: SynthesisProblem, row: pd.Series) -> dict[str, float]:
    d = dict(problem.base_design)
    d.update({k: float(row[k]) for k in problem.var_names})
    return d


def reference_points(cfg: RunConfig, problem: SynthesisProblem) -> list[dict[str, Any]]:
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


def plot_front(run_dir: Path) -> dict[str, Any]:
    """plots/front.png (front, final population, reference designs, knee) and plots/hypervolume.png."""
    run_dir = Path(run_dir)
    cfg, pareto, history, population = load_run(run_dir)
    problem = SynthesisProblem(cfg)
    plots = rio.ensure_dir(run_dir / "plots")
    xk, yk = _axes(problem, cfg)
    refs = reference_points(cfg, problem)
    highlight = []
    if len(pareto):
        F = objective_matrix(problem, pareto)
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


def featured_designs(problem: SynthesisProblem, pareto: pd.DataFrame) -> list[tuple[str, int]]:
    """The knee and the best design of each objective, as (label, row index), without repeats."""
    F = objective_matrix(problem, pareto)
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
    res = res + res % 2 + 1
    mech, options = cfg.mech, cfg.resolved_options()
    design = mech.resolve_design(design)
    g = make_grid(mech, design, options, res, cfg.grid.region)
    packed = mech.pack(design, options)

    def plane(axis: int, index: int) -> np.ndarray:
        """LCI on the grid's plane ``index`` of ``axis`` only (never the whole res^3 grid: issue 11)."""
        lo, shape = g.lo.copy(), g.shape.copy()
        lo[axis] += index * g.step[axis]
        shape[axis] = 1
        return sample_grid(mech.point_kernel, packed, lo, g.step, shape)

    names = mech.task_axes
    ext = [(g.lo[a], g.lo[a] + g.shape[a] * g.step[a]) for a in range(3)]
    if len(names) == 2:
        return [{"lci": plane(2, 0)[:, :, 0], "extent": (*ext[0], *ext[1]), "xlabel": names[0],
                 "ylabel": names[1], "title": f"{names[0]}{names[1]} workspace"}]
    j = int(g.shape[1]) // 2
    k = int(g.shape[2]) // 2
    yj = g.lo[1] + (j + 0.5) * g.step[1]
    zk = g.lo[2] + (k + 0.5) * g.step[2]
    return [
        {"lci": plane(1, j)[:, 0, :], "extent": (*ext[0], *ext[2]), "xlabel": names[0], "ylabel": names[2],
         "title": f"{names[0]}{names[2]} section at {names[1]} = {yj:.4g}"},
        {"lci": plane(2, k)[:, :, 0], "extent": (*ext[0], *ext[1]), "xlabel": names[0], "ylabel": names[1],
         "title": f"{names[0]}{names[1]} section at {names[2]} = {zk:.4g}"},
    ]


def plot_bands(run_dir: Path) -> dict[str, Any]:
    """plots/bands_front.png, plots/band_shares.png and plots/sections_<design>.png (paper Figs. 7-10, Table 5)."""
    run_dir = Path(run_dir)
    cfg, pareto, _, _ = load_run(run_dir)
    problem = SynthesisProblem(cfg)
    plots = rio.ensure_dir(run_dir / "plots")
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
    featured = featured_designs(problem, pareto)
    bar = np.array([[pareto[f"band{b}_share"].iloc[i] for b in range(nb)] for _, i in featured])
    fig = plotting.band_shares_figure([label for label, _ in featured], bar, labels)
    rio.save_figure(fig, plots / "band_shares.png")
    plotting.close(fig)
    files.append("plots/band_shares.png")
    for label, i in featured:
        design = design_of(problem, pareto.iloc[i])
        panels = section_panels(cfg, design)
        title = f"{label}: " + ", ".join(f"{k}={v:.4g}" for k, v in design.items())
        fig = plotting.sections_figure(panels, edges, title)
        name = "sections_" + label.replace(" ", "_") + ".png"
        rio.save_figure(fig, plots / name)
        plotting.close(fig)
        files.append(f"plots/{name}")
    return {"files": files, "featured": [(label, int(i)) for label, i in featured]}


def write_report(run_dir: Path, front_info: dict[str, Any], bands_info: dict[str, Any]) -> None:
    """report.md: key numbers of the run and links to its plots."""
    import json

    run_dir = Path(run_dir)
    cfg, pareto, history, _ = load_run(run_dir)
    problem = SynthesisProblem(cfg)
    manifest_path = run_dir / "manifest.json"
    manifest = json.loads(manifest_path.read_text()) if manifest_path.exists() else {}
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
        f"- final hypervolume: {history['hypervolume'].iloc[-1]:.6g}",
        f"- Pareto front: {len(pareto)} designs",
    ]
    if manifest.get("wall_seconds") is not None:
        cores = manifest.get("machine", {}).get("cores")
        lines.append(f"- wall time: {manifest['wall_seconds']:.1f} s on {cores} cores")
    if "m_minus_n" in pareto.columns:
        lines.append("- note: the model depends on m and n only through m - n (spec §1.1); see column m_minus_n")
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
    rio.write_text(run_dir / "report.md", "\n".join(lines) + "\n")


def write_plots_and_report(run_dir: Path) -> None:
    front = plot_front(run_dir)
    bands = plot_bands(run_dir)
    write_report(run_dir, front, bands)
