"""Schema and invariant checks of a finished results directory (CI: `python -m scalesynth.validate_results DIR`).

Checks: every file present and parseable (scalesynth.results); pareto.csv has the design variables, derived and
every catalogue metric column; no NaN/inf; design variables within bounds; every metric within its catalogue
range; band shares sum to 1; every row non-dominated and no two rows equal in objective space; history
generations 1..n_gen, hypervolume finite and higher at the end than at the start; manifest status finished with
matching evaluations. With the report: report.html loads no script from the network, and every
bands/pareto_band<k>.csv exists and is non-dominated in its band objectives.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from scalesynth import metrics as _metrics
from scalesynth import results
from scalesynth.errors import ConfigError


def check_results(run_dir: Path, require_report: bool = True) -> list[str]:
    """Problems found (empty list: the directory is valid). ``require_report``: report.md must exist too."""
    run_dir = Path(run_dir)
    problems: list[str] = []
    names = [results.PARETO, results.POPULATION, results.HISTORY, results.MANIFEST, results.CONFIG]
    for name in names + ([results.REPORT] if require_report else []):
        if not (run_dir / name).is_file():
            problems.append(f"{name}: missing")
    if problems:
        return problems
    leftovers = [p.name for p in run_dir.iterdir() if p.name.endswith(".tmp") or p.name == results.CHECKPOINT]
    if leftovers:
        problems.append(f"leftover files: {', '.join(sorted(leftovers))}")
    try:
        result = results.load(run_dir)
    except ConfigError as err:
        return [str(err)]
    cfg, problem, manifest, pareto, history = result.cfg, result.problem, result.manifest, result.pareto, result.history
    expected = results.expected_pareto_columns(problem)
    missing = [c for c in expected if c not in pareto.columns]
    if missing:
        problems.append(f"pareto.csv: missing columns {missing}")
        return problems
    nb = len(cfg.dexterity.band_edges) - 1
    nullable = _metrics.nullable_columns(cfg.mech, cfg.units.length, nb)  # statistics over an empty set
    numeric = pareto.select_dtypes(include=[np.number])
    values = numeric.to_numpy(dtype=float)
    allowed = np.array([c in nullable for c in numeric.columns], dtype=bool)
    if not np.all(np.isfinite(values) | (np.isnan(values) & allowed[None, :])):
        problems.append("pareto.csv: NaN or inf values")
    for k in problem.var_names:
        lo, hi = cfg.bounds[k]
        if not pareto[k].between(lo, hi).all():
            problems.append(f"pareto.csv: {k} outside bounds [{lo}, {hi}]")
    for m in _metrics.catalogue(cfg.mech, cfg.units.length).values():
        lo, hi = m.range
        for col in m.columns(len(cfg.dexterity.band_edges) - 1):
            if col in pareto.columns and not (pareto[col].between(lo, hi) | pareto[col].isna()).all():
                problems.append(f"pareto.csv: {col} outside [{lo:g}, {hi:g}]")
    shares = [c for c in pareto.columns if c.startswith("band") and c.endswith("_share")]
    nonempty = pareto["voxels"] > 0
    if shares and not np.allclose(pareto.loc[nonempty, shares].sum(axis=1), 1.0, atol=1e-9):
        problems.append("pareto.csv: band shares do not sum to 1")
    F = problem.minimisation_form(pareto[problem.objective_keys].to_numpy(dtype=float))
    for i in range(len(F)):
        dominated = np.all(F <= F[i], axis=1) & np.any(F < F[i], axis=1)
        if dominated.any():
            problems.append(f"pareto.csv: row {i} is dominated by row {int(np.argmax(dominated))}")
            break
    if len(np.unique(F, axis=0)) != len(F):
        problems.append("pareto.csv: duplicate rows in objective space")
    if (pareto["rank"] != 0).any():
        problems.append("pareto.csv: rank must be 0 on the front")
    gens = list(history["generation"])
    if gens != list(range(1, cfg.algorithm.n_gen + 1)):
        problems.append(f"history.csv: generations {gens[:3]}... are not 1..{cfg.algorithm.n_gen}")
    hv = history["hypervolume"].to_numpy(dtype=float)
    # NSGA-II can lose a little hypervolume when a full front is truncated by crowding, so only the trend is checked
    if not np.all(np.isfinite(hv)) or (hv < 0).any() or hv[-1] < hv[0]:
        problems.append("history.csv: hypervolume not finite, negative, or lower at the end than at the start")
    if manifest.get("status") != "finished":
        problems.append("manifest.json: status is not finished")
    if manifest.get("evaluations") != int(history["evaluations"].iloc[-1]):
        problems.append("manifest.json: evaluations differ from history.csv")
    if require_report:
        problems += _check_views(run_dir, result)
    return problems


def _check_views(run_dir: Path, result) -> list[str]:
    """report.html self-contained; per-band Pareto sets present and non-dominated."""
    import pandas as pd

    from scalesynth.band_fronts import band_objectives
    from scalesynth.report_html import has_remote_scripts

    problems = []
    html = run_dir / "report.html"
    if not html.is_file():
        problems.append("report.html: missing")
    elif has_remote_scripts(html.read_text(encoding="utf-8", errors="replace")):
        problems.append("report.html: loads a script from the network")
    if result.population is None or not result.population["feasible"].any():
        return problems
    for k in range(len(result.cfg.dexterity.band_edges) - 1):
        path = run_dir / "bands" / f"pareto_band{k}.csv"
        if not path.is_file():
            problems.append(f"bands/pareto_band{k}.csv: missing")
            continue
        cols, signs = band_objectives(result.problem, k)
        F = pd.read_csv(path)[cols].to_numpy(dtype=float) * signs
        if any((np.all(F <= f, axis=1) & np.any(F < f, axis=1)).any() for f in F):
            problems.append(f"bands/pareto_band{k}.csv: a row is dominated")
    return problems


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print("usage: python -m scalesynth.validate_results RUN_DIR", file=sys.stderr)
        return 2
    problems = check_results(Path(argv[0]))
    for p in problems:
        print(f"FAIL {p}")
    print(f"{argv[0]}: {'ok' if not problems else f'{len(problems)} problem(s)'}")
    return 0 if not problems else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
