"""`scalesynth compare RUN_DIR...`: runs side by side (also of different mechanisms for one task) on the metrics they
share, with each run's selected designs: one table (compare.csv, printed) and one figure (compare.<fmt>).

A metric is shared when every run's pareto.csv has its column (units are in the names, so a volume in m³ and one
in mm³ are not mixed). Selected designs: the knee, and every design `scalesynth select` wrote into the run
directory (selected_<method>.yaml, its pareto.csv row).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pandas as pd

from scalesynth import io as rio
from scalesynth import labels as lab
from scalesynth import rundir
from scalesynth.errors import ConfigError

NOT_METRICS = {"rank", "feasible", "voxels"}
# preferred axes of the figure when the runs share no two objectives: by catalogue family, task metrics first
FAMILY_PREFERENCE = ("task", "workspace", "design", "cycle", "path")
_ROW = re.compile(r"\(row (\d+) of pareto\.csv\)")
MANIFEST = "compare.json"
_FILES = ("compare.csv", MANIFEST, *(f"compare.{fmt}" for fmt in rio.FIGURE_FORMATS))
# a compare directory is recognised by its compare.json (scalesynth.rundir), which lists the files beside it
OUTPUT = rundir.Output("compare", MANIFEST, ("runs", "shared_metrics", "files"), owned=lambda name: name in _FILES)


def _selected(result) -> list[tuple[str, int]]:
    from scalesynth.selection import choose

    run_dir, pareto = result.out_dir, result.pareto
    out = [("knee", choose(result.objective_matrix(), "knee"))] if len(pareto) else []
    for path in sorted(run_dir.glob("selected_*.yaml")):
        m = _ROW.search(path.read_text(encoding="utf-8", errors="replace").split("\n", 1)[0])
        if m and int(m.group(1)) < len(pareto):
            method = path.stem[len("selected_"):]
            if (method, int(m.group(1))) not in out:
                out.append((method, int(m.group(1))))
    return out


def load_runs(run_dirs: Sequence[Path]) -> list[dict[str, Any]]:
    from scalesynth.results import load

    if len(run_dirs) < 2:
        raise ConfigError("RUN_DIR: compare needs at least two results directories")
    runs = []
    for d in run_dirs:
        result = load(Path(d))
        problem, pareto = result.problem, result.pareto
        metrics = [c for c in pareto.columns if c not in problem.var_names and c not in NOT_METRICS]
        runs.append({"dir": Path(d), "cfg": result.cfg, "problem": problem, "pareto": pareto,
                     "history": result.history, "metrics": metrics, "selected": _selected(result)})
    return runs


def shared_metrics(runs: Sequence[dict]) -> list[str]:
    """Metric columns every run has, in the first run's order (design-variable columns excluded)."""
    common = set.intersection(*(set(r["metrics"]) for r in runs))
    derived = set()
    for r in runs:
        derived |= set(r["cfg"].mech.derived_columns(r["problem"].base_design))
    return [c for c in runs[0]["metrics"] if c in common and c not in derived]


def figure_axes(runs: Sequence[dict], shared: Sequence[str]) -> tuple[str, str]:
    objectives = [k for k in runs[0]["problem"].objective_keys
                  if all(k in r["problem"].objective_keys for r in runs) and k in shared]
    from scalesynth.metrics import catalogue

    cfg = runs[0]["cfg"]
    family = {}
    for m in catalogue(cfg.mech, cfg.units.length).values():
        for col in m.columns(len(cfg.dexterity.band_edges) - 1):
            family[col] = m.family
    rank = {f: i for i, f in enumerate(FAMILY_PREFERENCE)}
    by_family = sorted(shared, key=lambda c: rank.get(family.get(c, ""), len(rank)))  # stable: keeps column order
    ordered = list(dict.fromkeys([*objectives, *by_family]))
    if len(ordered) < 2:
        raise ConfigError("RUN_DIR: the runs share fewer than two metrics, nothing to compare "
                          f"(shared: {', '.join(shared) or 'none'})")
    return ordered[0], ordered[1]


def run_label(run: dict) -> str:
    cfg = run["cfg"]
    return f"{cfg.name} ({cfg.mechanism}, seed {cfg.algorithm.seed})"


def compare_runs(run_dirs: Sequence[Path], out: Path | None = None, fmt: str = "png",
                 x: str | None = None, y: str | None = None, force: bool = False) -> dict[str, Any]:
    """Write compare.csv, compare.<fmt> and compare.json into ``out`` (default ./compare), staged and swapped in
    whole (``scalesynth.rundir``; new, empty or a compare directory unless ``force``); return the table and file
    names."""
    if fmt not in rio.FIGURE_FORMATS:
        raise ConfigError(f"--format: must be one of {', '.join(rio.FIGURE_FORMATS)}, got {fmt!r}")
    target = Path(out) if out is not None else Path("compare")
    rundir.check(target, OUTPUT, force)  # before reading the runs; claimed when the table is ready
    runs = load_runs(run_dirs)
    shared = shared_metrics(runs)
    xk, yk = figure_axes(runs, shared)
    for name, given in (("--x", x), ("--y", y)):
        if given is not None and given not in shared:
            raise ConfigError(f"{name}: {given!r} is not a metric all runs share (shared: {', '.join(shared)})")
    xk, yk = x or xk, y or yk
    rows = []
    for r in runs:
        hv = float(r["history"]["hypervolume"].iloc[-1]) if len(r["history"]) else 0.0
        for sel, i in r["selected"]:
            row = {"run": r["cfg"].name, "directory": str(r["dir"]), "mechanism": r["cfg"].mechanism,
                   "seed": r["cfg"].algorithm.seed, "pareto_size": len(r["pareto"]), "hypervolume": hv,
                   "design": sel, "pareto_row": int(i)}
            row.update({k: float(r["pareto"][k].iloc[i]) for k in shared})
            row["design_values"] = "; ".join(f"{k}={float(r['pareto'][k].iloc[i]):.6g}" for k in r["problem"].var_names)
            rows.append(row)
    table = pd.DataFrame(rows)
    files = ["compare.csv", f"compare.{fmt}", MANIFEST]
    with rundir.staged(target, OUTPUT, force) as staged:
        _write(staged.work, runs, table, xk, yk, fmt)
        rio.write_json(staged.work / MANIFEST, {"runs": [str(r["dir"]) for r in runs], "shared_metrics": shared,
                                                "axes": [xk, yk], "files": files})
    return {"shared_metrics": shared, "axes": [xk, yk], "table": table, "out": str(target), "files": files[:2]}


def _write(target: Path, runs: list[dict], table: pd.DataFrame, xk: str, yk: str, fmt: str) -> None:
    from scalesynth import plotting

    rio.write_csv(target / "compare.csv", table)
    series = [{"label": run_label(r), "x": r["pareto"][xk].to_numpy(), "y": r["pareto"][yk].to_numpy(),
               "selected": [(s, float(r["pareto"][xk].iloc[i]), float(r["pareto"][yk].iloc[i]))
                            for s, i in r["selected"]]} for r in runs]
    label = lab.labeller(runs[0]["cfg"])  # shared columns have the same name and unit in every run
    fig = plotting.compare_figure(series, label(xk), label(yk),
                                  f"{len(runs)} runs on their shared metrics")
    rio.save_figure(fig, target / f"compare.{fmt}")
    plotting.close(fig)
