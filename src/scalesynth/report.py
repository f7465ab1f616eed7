"""Plots and report.md for a finished results directory (reads its CSVs and config; draws via plotting.py)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from scalesynth import io as rio
from scalesynth import labels as lab
from scalesynth import plotting
from scalesynth.config import RunConfig, load_config
from scalesynth.errors import ConfigError
from scalesynth.evaluate import evaluate_config
from scalesynth.problem import SynthesisProblem
from scalesynth.selection import choose, extremes


def load_run(run_dir: Path) -> tuple[RunConfig, pd.DataFrame, pd.DataFrame, pd.DataFrame | None]:
    run_dir = Path(run_dir)
    for name in ("config.yaml", "pareto.csv", "history.csv"):
        if not (run_dir / name).is_file():
            raise ConfigError(f"{run_dir}: not a scalesynth results directory (missing {name})")
    cfg = load_config(run_dir / "config.yaml")
    pareto = pd.read_csv(run_dir / "pareto.csv")
    history = pd.read_csv(run_dir / "history.csv")
    pop_path = run_dir / "population.csv"
    population = pd.read_csv(pop_path) if pop_path.is_file() else None
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


def _plots_dir(run_dir: Path, out: Path | None, fmt: str) -> Path:
    if fmt not in rio.FIGURE_FORMATS:
        raise ConfigError(f"--format: must be one of {', '.join(rio.FIGURE_FORMATS)}, got {fmt!r}")
    return rio.ensure_dir(Path(out) if out is not None else run_dir / "plots")


def _rel(run_dir: Path, path: Path) -> str:
    try:
        return str(path.resolve().relative_to(run_dir.resolve()))
    except ValueError:
        return str(path)


def plot_front(run_dir: Path, out: Path | None = None, fmt: str = "png") -> dict[str, Any]:
    """plots/front.<fmt> (front, final population, reference designs, knee) and plots/hypervolume.<fmt>."""
    run_dir = Path(run_dir)
    plots = _plots_dir(run_dir, out, fmt)
    cfg, pareto, history, population = load_run(run_dir)
    problem = SynthesisProblem(cfg)
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
        lab.labeller(cfg)(xk),
        lab.labeller(cfg)(yk),
        f"{cfg.name}: Pareto front ({cfg.mechanism}, seed {cfg.algorithm.seed})",
        references=[(r["label"], r["metrics"][xk], r["metrics"][yk]) for r in refs],
        highlight=highlight,
        population=pop_xy,
    )
    rio.save_figure(fig, plots / f"front.{fmt}")
    plotting.close(fig)
    fig = plotting.hypervolume_figure(
        history["generation"].to_numpy(), history["hypervolume"].to_numpy(), f"{cfg.name}: hypervolume per generation"
    )
    rio.save_figure(fig, plots / f"hypervolume.{fmt}")
    plotting.close(fig)
    files = [_rel(run_dir, plots / f"front.{fmt}"), _rel(run_dir, plots / f"hypervolume.{fmt}")]
    return {"references": refs, "files": files}


from scalesynth.workspace_view import band_labels  # noqa: E402  (re-exported: report.band_labels)


def featured_designs(problem: SynthesisProblem, pareto: pd.DataFrame) -> list[tuple[str, int]]:
    """The knee and the best design of each objective, as (label, row index), without repeats."""
    F = objective_matrix(problem, pareto)
    out = [("knee", choose(F, "knee"))]
    for obj_idx, row in enumerate(extremes(F)):
        label = f"best {problem.objective_keys[obj_idx] if obj_idx < len(problem.objective_keys) else obj_idx}"
        if row not in [r for _, r in out]:
            out.append((label, row))
    return out


SECTION_RESOLUTION = 128  # plots want finer cells than the optimisation grid; a plane costs 128^2 points


def section_panels(cfg: RunConfig, design: dict[str, float]) -> list[dict[str, Any]]:
    """Workspace sections coloured by LCI, each sampled on its plane only (never a full grid): for a 3-D mechanism
    the planes normal to its second and third task axes through the workspace centroid (from a coarse grid; an
    empty plane moves to the nearest one that cuts the workspace), for seed 000 the xz and xy sections; one map
    for planar mechanisms. Axis labels carry units; axes of different units are not drawn to equal scale."""
    from scalesynth.show import _task_geometry
    from scalesynth.workspace_view import default_section_point, sample_plane

    mech = cfg.mech
    unit = cfg.units.length
    res = max(cfg.grid.resolution, SECTION_RESOLUTION)
    box, path = _task_geometry(cfg)
    if mech.planar:
        values, ext = sample_plane(cfg, design, 2, 0.0, res)
        return [{"values": values, "extent": ext, "xlabel": lab.axis_label(mech, 0, unit),
                 "ylabel": lab.axis_label(mech, 1, unit), "title": "workspace", "equal": lab.same_units(mech, (0, 1)),
                 "box": None if box is None else (box[0, 0], box[1, 0], box[0, 1], box[1, 1]),
                 "path": None if path is None else path[:, :2]}]
    point = default_section_point(cfg, design)
    panels = []
    for normal in (1, 2):
        a, b = [x for x in range(3) if x != normal]
        point[normal] = round(float(point[normal]), 10) + 0.0  # no '-7e-17' in titles for a symmetric workspace
        values, ext = sample_plane(cfg, design, normal, float(point[normal]), res)
        name = lab.axis_name(mech.task_axes[normal])
        panel = {"values": values, "extent": ext, "xlabel": lab.axis_label(mech, a, unit),
                 "ylabel": lab.axis_label(mech, b, unit), "equal": lab.same_units(mech, (a, b)),
                 "title": f"{lab.axis_name(mech.task_axes[a])}{lab.axis_name(mech.task_axes[b])} section at "
                          f"{name} = {point[normal]:.4g} (centroid)"}
        if box is not None and box[0, normal] <= point[normal] <= box[1, normal]:
            panel["box"] = (box[0, a], box[1, a], box[0, b], box[1, b])
        panels.append(panel)
    return panels


def plot_bands(run_dir: Path, out: Path | None = None, fmt: str = "png") -> dict[str, Any]:
    """plots/bands_front, plots/band_shares and plots/sections_<design> (paper Figs. 7-10, Table 5), and the
    per-band Pareto sets bands/pareto_band<k>.csv with their plots."""
    from scalesynth.band_fronts import write_band_fronts

    run_dir = Path(run_dir)
    plots = _plots_dir(run_dir, out, fmt)
    cfg, pareto, _, population = load_run(run_dir)
    problem = SynthesisProblem(cfg)
    edges = cfg.dexterity.band_edges
    labels = band_labels(edges)
    nb = len(edges) - 1
    files = []
    bands_out = None if out is None else plots / "bands"
    band_info = write_band_fronts(run_dir, cfg, problem, population, fmt, bands_out)
    if not len(pareto):
        return {"files": files, "featured": [], "band_files": band_info["files"], "band_sizes": band_info["sizes"]}
    xk, yk = _axes(problem, cfg)
    shares = [pareto[f"band{b}_share"].to_numpy() for b in range(nb)]
    fig = plotting.band_front_figure(pareto[xk].to_numpy(), pareto[yk].to_numpy(), shares, labels,
                                     lab.labeller(cfg)(xk), lab.labeller(cfg)(yk))
    rio.save_figure(fig, plots / f"bands_front.{fmt}")
    plotting.close(fig)
    files.append(_rel(run_dir, plots / f"bands_front.{fmt}"))
    featured = featured_designs(problem, pareto)
    bar = np.array([[pareto[f"band{b}_share"].iloc[i] for b in range(nb)] for _, i in featured])
    fig = plotting.band_shares_figure([label for label, _ in featured], bar, labels)
    rio.save_figure(fig, plots / f"band_shares.{fmt}")
    plotting.close(fig)
    files.append(_rel(run_dir, plots / f"band_shares.{fmt}"))
    for label, i in featured:
        design = design_of(problem, pareto.iloc[i])
        panels = section_panels(cfg, design)
        title = f"{label}: " + ", ".join(f"{k}={v:.4g}" for k, v in design.items())
        fig = plotting.sections_figure(panels, edges, title)
        name = "sections_" + label.replace(" ", "_") + f".{fmt}"
        rio.save_figure(fig, plots / name)
        plotting.close(fig)
        files.append(_rel(run_dir, plots / name))
    return {"files": files, "featured": [(label, int(i)) for label, i in featured],
            "band_files": band_info["files"], "band_sizes": band_info["sizes"]}


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
    for f in front_info.get("files", []) + bands_info.get("files", []) + bands_info.get("band_files", [])[1::2]:
        lines.append(f"![{Path(f).stem}]({f})")
    rio.write_text(run_dir / "report.md", "\n".join(lines) + "\n")


def write_plots_and_report(run_dir: Path) -> None:
    """Plots, per-band Pareto sets, report.md and the self-contained interactive report.html."""
    from scalesynth.report_html import write_report_html

    front = plot_front(run_dir)
    bands = plot_bands(run_dir)
    write_report(run_dir, front, bands)
    write_report_html(run_dir, bands.get("featured"), bands.get("band_sizes"))
