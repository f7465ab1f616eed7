"""`scalesynth compare RUN_DIR...`: runs side by side (also of different mechanisms for one task) on the metrics they
share, with each run's selected designs: one table (compare.csv, printed) and one figure (compare.<fmt>).

A metric is shared when every run's pareto.csv has it, matched by its catalogue name (``link_length_sum``), not by
its column (``link_length_sum_mm`` in a run in mm, ``link_length_sum_m`` in one in m): values in another length
unit are converted to the first run's unit, whose column names the table and the figure use, and the conversion
is reported (``units``, ``converted``). A metric whose units differ by more than the length unit (e.g. an area in
mm² and a measure in mm²·rad) is not shared. Selected designs: the knee, and every design `scalesynth select`
wrote into the run directory (selected_<method>.yaml, its pareto.csv row).
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
from scalesynth.names import hint

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


def metric_names(cfg, columns: Sequence[str]) -> dict[str, tuple[str, str]]:
    """{column: (catalogue key, unit)} of a run's metric columns: the catalogue name (``band<k>_share``,
    ``band<k>_volume`` for band metrics), or the column itself with no unit for a column outside the catalogue."""
    from scalesynth.metrics import catalogue

    n_bands = len(cfg.dexterity.band_edges) - 1
    known = {}
    for m in catalogue(cfg.mech, cfg.units.length).values():
        if "band" in m.needs:
            base = m.name.removeprefix("band_")
            known.update({m.column_for(b): (f"band{b}_{base}", m.unit) for b in range(n_bands)})
        else:
            known[m.column] = (m.name, m.unit)
    return {c: known.get(c, (c, "")) for c in columns}


def load_runs(run_dirs: Sequence[Path]) -> list[dict[str, Any]]:
    from scalesynth.results import load

    if len(run_dirs) < 2:
        raise ConfigError("RUN_DIR: compare needs at least two results directories")
    runs = []
    for d in run_dirs:
        result = load(Path(d))
        problem, pareto = result.problem, result.pareto
        metrics = [c for c in pareto.columns if c not in problem.var_names and c not in NOT_METRICS]
        derived = set(result.cfg.mech.derived_columns(problem.base_design))
        names = {c: v for c, v in metric_names(result.cfg, metrics).items() if c not in derived}
        runs.append({"dir": Path(d), "cfg": result.cfg, "problem": problem, "pareto": pareto,
                     "history": result.history, "metrics": metrics, "selected": _selected(result),
                     "columns": {key: (col, unit) for col, (key, unit) in names.items()}})
    return runs


# length units a metric's unit may contain, in metres (config.LENGTH_UNITS)
_LENGTHS = {"m": 1.0, "dm": 0.1, "cm": 0.01, "mm": 0.001}
_TOKEN = re.compile(r"([A-Za-z]+?)\^?(\d*)")


def unit_scale(unit: str) -> tuple[str, float] | None:
    """(the unit with its lengths written as 'L', the factor to SI) of a unit text such as 'mm3', 'N/mm', 'mm/s^2' or
    'mm_rad2'; None when it cannot be read (e.g. 'rad/s or mm/s', whose value may be in either)."""
    if " or " in unit:
        return None
    parts = unit.split("/")
    if len(parts) > 2:
        return None
    skeleton, scale = [], 1.0
    for sign, part in zip((1, -1), parts, strict=False):
        words = []
        for token in re.split(r"[ _*·]+", part):
            m = _TOKEN.fullmatch(token)
            if m is None:
                words.append(token)
                continue
            name, power = m.group(1), int(m.group(2) or 1)
            if name in _LENGTHS:
                scale *= _LENGTHS[name] ** (sign * power)
                words.append(f"L{power}")
            else:
                words.append(token)
        skeleton.append(" ".join(words))
    return "/".join(skeleton), scale


def conversion(unit: str, to: str) -> float | None:
    """Factor taking a value in ``unit`` to ``to`` (1.0 when equal), or None when they differ by more than their
    length units."""
    if unit == to:
        return 1.0
    a, b = unit_scale(unit), unit_scale(to)
    if a is None or b is None or a[0] != b[0]:
        return None
    return a[1] / b[1]


def shared_metrics(runs: Sequence[dict]) -> list[str]:
    """Metrics every run has (by catalogue name, in the first run's order, units convertible), as the first run's
    column names. Sets each run's ``own`` ({first run's column: the run's column}) and ``factors`` ({first run's
    column: factor to the first run's unit})."""
    first = runs[0]["columns"]
    shared = []
    for key, (col0, unit0) in first.items():
        if not all(key in r["columns"] for r in runs):
            continue
        factors = [conversion(r["columns"][key][1], unit0) for r in runs]
        if any(f is None for f in factors):
            continue
        shared.append(col0)
        for r, f in zip(runs, factors, strict=True):
            r.setdefault("factors", {})[col0] = f
            r.setdefault("own", {})[col0] = r["columns"][key][0]
    return shared


def values(run: dict, column0: str):
    """The run's values (a pandas Series over its front) of the metric the first run names ``column0``, in the
    first run's unit."""
    column = run["pareto"][run["own"][column0]].astype(float)
    factor = run["factors"][column0]
    return column if factor == 1.0 else column * factor


def _key_of(run: dict, column: str) -> str | None:
    return next((k for k, (c, _) in run["columns"].items() if c == column), None)


def figure_axes(runs: Sequence[dict], shared: Sequence[str]) -> tuple[str, str]:
    first = runs[0]
    objective_sets = [{_key_of(r, c) for c in r["problem"].objective_keys} for r in runs]
    objectives = [c for c in first["problem"].objective_keys
                  if c in shared and all(_key_of(first, c) in keys for keys in objective_sets)]
    from scalesynth.metrics import catalogue

    cfg = first["cfg"]
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


def axis_column(runs: Sequence[dict], shared: Sequence[str], option: str, given: str) -> str:
    """The first run's column of ``--x``/``--y``: a catalogue name (``link_length_sum``) or any run's column name
    of a shared metric (``link_length_sum_m``)."""
    by_key = {_key_of(runs[0], c): c for c in shared}
    if given in by_key:
        return by_key[given]
    for r in runs:
        key = next((k for k, (c, _) in r["columns"].items() if c == given), None)
        if key in by_key:
            return by_key[key]
    raise ConfigError(f"{option}: {given[:60]!r} is not a metric all runs share " + hint(given, list(by_key), "shared"))


def run_label(run: dict) -> str:
    cfg = run["cfg"]
    return f"{cfg.name} ({cfg.mechanism}, seed {cfg.algorithm.seed})"


def conversions(runs: Sequence[dict], shared: Sequence[str]) -> list[dict[str, Any]]:
    """Every value converted to the first run's unit: metric, column, run, from, to, factor."""
    out = []
    for col0 in shared:
        key, unit0 = _key_of(runs[0], col0), runs[0]["columns"][_key_of(runs[0], col0)][1]
        for r in runs[1:]:
            if r["factors"][col0] != 1.0:
                out.append({"metric": key, "column": col0, "run": r["cfg"].name, "from": r["columns"][key][1],
                            "to": unit0, "factor": r["factors"][col0]})
    return out


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
    if x is not None:
        xk = axis_column(runs, shared, "--x", x)
    if y is not None:
        yk = axis_column(runs, shared, "--y", y)
    rows = []
    for r in runs:
        hv = float(r["history"]["hypervolume"].iloc[-1]) if len(r["history"]) else 0.0
        converted = {k: values(r, k) for k in shared}
        for sel, i in r["selected"]:
            row = {"run": r["cfg"].name, "directory": str(r["dir"]), "mechanism": r["cfg"].mechanism,
                   "seed": r["cfg"].algorithm.seed, "pareto_size": len(r["pareto"]), "hypervolume": hv,
                   "design": sel, "pareto_row": int(i)}
            row.update({k: float(converted[k].iloc[i]) for k in shared})
            row["design_values"] = "; ".join(f"{k}={float(r['pareto'][k].iloc[i]):.6g}" for k in r["problem"].var_names)
            rows.append(row)
    table = pd.DataFrame(rows)
    files = ["compare.csv", f"compare.{fmt}", MANIFEST]
    with rundir.staged(target, OUTPUT, force) as staged:
        _write(staged.work, runs, table, xk, yk, fmt)
        rio.write_json(staged.work / MANIFEST, {"runs": [str(r["dir"]) for r in runs], "shared_metrics": shared,
                                                "axes": [xk, yk], "files": files})
    return {"shared_metrics": shared, "axes": [xk, yk], "table": table, "out": str(target), "files": files[:2],
            "converted": conversions(runs, shared)}


def _write(target: Path, runs: list[dict], table: pd.DataFrame, xk: str, yk: str, fmt: str) -> None:
    from scalesynth import plotting

    rio.write_csv(target / "compare.csv", table)
    series = []
    for r in runs:
        xs, ys = values(r, xk), values(r, yk)
        series.append({"label": run_label(r), "x": xs.to_numpy(), "y": ys.to_numpy(),
                       "selected": [(s, float(xs.iloc[i]), float(ys.iloc[i])) for s, i in r["selected"]]})
    label = lab.labeller(runs[0]["cfg"])  # every run's values are in the first run's units (its column names)
    fig = plotting.compare_figure(series, label(xk), label(yk),
                                  f"{len(runs)} runs on their shared metrics")
    rio.save_figure(fig, target / f"compare.{fmt}")
    plotting.close(fig)
