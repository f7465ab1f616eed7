"""The results directory (``results/<name>/``): its files, writing them, loading them, the manifest, "finished".

The one module that knows the layout. ``optimize.run`` builds a :class:`RunResult` in memory and writes it here
(tables first, then the caller's plots/report from the same object, the manifest last: its presence marks a
finished run); ``select``, the ``plot-*`` commands, ``reproduce``, ``batch`` and the validator load it here.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from scalesynth import io as rio
from scalesynth.config import RunConfig, dump_config, load_config
from scalesynth.errors import ConfigError
from scalesynth.problem import SynthesisProblem

if TYPE_CHECKING:  # pandas is imported where a table is read (io.read_csv) or built (optimize)
    import pandas as pd

PARETO, POPULATION, HISTORY, MANIFEST, CONFIG, REPORT = (
    "pareto.csv", "population.csv", "history.csv", "manifest.json", "config.yaml", "report.md",
)
TABLES = (PARETO, POPULATION, HISTORY, CONFIG)
FILES = (PARETO, POPULATION, HISTORY, MANIFEST, CONFIG, REPORT)
CHECKPOINT = rio.CHECKPOINT
PLOTS = "plots"


@dataclass
class RunResult:
    """A run's results in memory. ``problem`` is the run's SynthesisProblem (columns, objective keys and signs),
    built once: by the run itself, or from the config when loaded."""

    out_dir: Path
    cfg: RunConfig
    pareto: pd.DataFrame
    history: pd.DataFrame
    manifest: dict[str, Any]
    population: pd.DataFrame | None = None
    problem: SynthesisProblem | None = field(default=None, repr=False)

    def __post_init__(self):
        self.out_dir = Path(self.out_dir)
        if self.problem is None:
            self.problem = SynthesisProblem(self.cfg)

    def objective_matrix(self, frame: pd.DataFrame | None = None) -> np.ndarray:
        """Objectives of the rows (default: the front) in minimisation form."""
        frame = self.pareto if frame is None else frame
        return self.problem.minimisation_form(frame[self.problem.objective_keys].to_numpy(dtype=float))

    def front(self) -> Front:
        """The front's design variables and objectives (as read_front gives them without pandas)."""
        X = self.pareto[self.problem.var_names].to_numpy(dtype=float)
        return Front(self.cfg, self.problem, X, self.objective_matrix())

    def design_of(self, row: pd.Series) -> dict[str, float]:
        """The full design of a results row (design variables over the config's fixed parameters)."""
        d = dict(self.problem.base_design)
        d.update({k: float(row[k]) for k in self.problem.design_names})
        return d

    def config_of(self, row: pd.Series) -> RunConfig:
        """The run's config with a results row's searched gear ratio (bounds.gear_ratio) as motors.gear_ratio."""
        return self.problem.config_of({k: float(row[k]) for k in self.problem.var_names})


def expected_pareto_columns(problem: SynthesisProblem) -> list[str]:
    """pareto.csv's columns: design variables, derived columns, every catalogue metric column, rank."""
    cfg = problem.cfg
    return [*problem.var_names, *cfg.mech.derived_columns(problem.base_design), *problem.metric_columns, "rank"]


def write_tables(result: RunResult) -> None:
    """pareto.csv, population.csv, history.csv and config.yaml (each atomically)."""
    out = rio.ensure_dir(result.out_dir)
    rio.write_csv(out / PARETO, result.pareto)
    if result.population is not None:
        rio.write_csv(out / POPULATION, result.population)
    rio.write_csv(out / HISTORY, result.history)
    rio.write_text(out / CONFIG, dump_config(result.cfg))


def write_manifest(result: RunResult) -> None:
    """manifest.json, written last: its presence (status 'finished') marks a finished run."""
    rio.write_json(result.out_dir / MANIFEST, result.manifest)


def read_manifest(out_dir: Path) -> dict[str, Any] | None:
    """The manifest of a results directory, or None if it has none (or an unreadable one)."""
    path = Path(out_dir) / MANIFEST
    if not path.is_file():
        return None
    try:
        return json.loads(path.read_text())
    except (OSError, json.JSONDecodeError, UnicodeDecodeError):
        return None


def finished(out_dir: Path, digest: str | None = None) -> bool:
    """True if ``out_dir`` holds a finished run (of the config with this digest, when given)."""
    manifest = read_manifest(out_dir)
    if manifest is None or manifest.get("status") != "finished":
        return False
    return digest is None or manifest.get("config_digest") == digest


def load(out_dir: Path, *, require_finished: bool = True) -> RunResult:
    """Read a results directory into a RunResult; ConfigError (exit 2) naming the missing or damaged file (and
    column), never a pandas or JSON traceback.

    ``require_finished``: the manifest must exist (a finished run); otherwise the tables and config suffice
    (plots of a directory whose manifest was lost)."""
    out = Path(out_dir)
    manifest = rio.read_manifest(out / MANIFEST) if (out / MANIFEST).is_file() else None
    if require_finished and manifest is None:
        raise ConfigError(f"{out}: not a finished scalesynth run (no {MANIFEST})")
    for name in (CONFIG, PARETO, HISTORY):
        if not (out / name).is_file():
            raise ConfigError(f"{out}: not a scalesynth results directory (missing {name})")
    cfg = load_config(out / CONFIG)
    problem = SynthesisProblem(cfg)
    needed, nullable = _pareto_columns(problem)
    pareto = rio.read_results_csv(out / PARETO, needed, nullable)
    history = rio.read_results_csv(out / HISTORY, HISTORY_COLUMNS)
    if not len(history):
        raise ConfigError(f"{out / HISTORY}: no generations")
    population = (rio.read_results_csv(out / POPULATION, problem.objective_keys, nullable)
                  if (out / POPULATION).is_file() else None)
    return RunResult(out_dir=out, cfg=cfg, pareto=pareto, history=history, manifest=manifest or {},
                     population=population, problem=problem)


HISTORY_COLUMNS = ("generation", "evaluations", "hypervolume")


def _pareto_columns(problem: SynthesisProblem) -> tuple[list[str], set[str]]:
    """(the columns pareto.csv must have, those of them that may be null) for :func:`load`."""
    from scalesynth.metrics import nullable_columns

    cfg = problem.cfg
    nb = len(cfg.dexterity.band_edges) - 1
    needed = [*problem.var_names, *problem.objective_keys, cfg.mech.measure_key(cfg.units.length),
              *(f"band{b}_share" for b in range(nb))]
    return list(dict.fromkeys(needed)), nullable_columns(cfg.mech, cfg.units.length, nb)


def _loads(out: Path, problem: SynthesisProblem) -> bool:
    """Whether :func:`load` (``require_finished=False``) would read ``out`` past its config, checked without
    pandas: a readable manifest if there is one, pareto.csv's columns, history.csv with a generation,
    population.csv's objectives if it is there. False where unsure (load then says what is wrong)."""
    from scalesynth.errors import ScalesynthError

    if (out / MANIFEST).is_file():
        try:
            rio.read_manifest(out / MANIFEST)
        except ScalesynthError:
            return False
    needed, nullable = _pareto_columns(problem)
    return (rio.csv_rows_conform(out / PARETO, needed, nullable) is not None
            and bool(rio.csv_rows_conform(out / HISTORY, HISTORY_COLUMNS))
            and (not (out / POPULATION).is_file()
                 or rio.csv_rows_conform(out / POPULATION, problem.objective_keys, nullable) is not None))


@dataclass
class Front:
    """A run's front read without pandas: its config and problem, pareto.csv's design variables ``X``
    (n_front, n_var) and objectives ``F`` (n_front, n_obj) in minimisation form, as RunResult.objective_matrix."""

    cfg: RunConfig
    problem: SynthesisProblem
    X: np.ndarray
    F: np.ndarray

    def design(self, i: int) -> dict[str, float]:
        """The full design of front row i, as RunResult.design_of."""
        return self.problem.designs(self.X[i])[0]


def read_front(out_dir: Path) -> Front | None:
    """config.yaml and pareto.csv's design variables and objectives, read without pandas (a command can evaluate
    before importing it); None where the directory is not one :func:`load` reads (a table missing or damaged, not
    only these two): :func:`load` then says what is wrong, before the command evaluates anything."""
    from scalesynth.errors import ScalesynthError

    out = Path(out_dir)
    if not (out / CONFIG).is_file():
        return None
    try:
        cfg = load_config(out / CONFIG)
        problem = SynthesisProblem(cfg)
    except ScalesynthError:
        return None
    cols = rio.read_csv_columns(out / PARETO, list(dict.fromkeys([*problem.var_names, *problem.objective_keys])))
    if cols is None or not _loads(out, problem):
        return None
    X = np.column_stack([cols[k] for k in problem.var_names])
    F = problem.minimisation_form(np.column_stack([cols[k] for k in problem.objective_keys]))
    return Front(cfg, problem, X, F)


def infeasibility_lines(manifest: dict[str, Any]) -> list[str]:
    """'no feasible design: task_coverage best 0.0002, needs >= 1.0', one per constraint (none when feasible)."""
    return [f"no feasible design: {d['constraint']} best {d['best']:.4g}, needs {d['needs']}"
            for d in manifest.get("no_feasible_design", [])]
