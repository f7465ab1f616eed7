"""The public Python API behind ``import scalesynth``: thin wrappers over the modules that do the work.

Each function here only turns convenient arguments (a mechanism name, a config path) into the objects the working
modules take, so the CLI and the Python API share one implementation. ``scalesynth/__init__.py`` imports this
module lazily, on first use of a public name.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from scalesynth import environment as _environment

_environment.check()  # NUMBA_* before anything imports Numba (one ConfigError line, not an import traceback)

from scalesynth.config import RunConfig, check_grid_arguments, config_from_dict, load_config  # noqa: E402
from scalesynth.errors import ConfigError  # noqa: E402
from scalesynth.evaluate import DEFAULT_BAND_EDGES, WorkspaceReport  # noqa: E402
from scalesynth.evaluate import evaluate as _evaluate  # noqa: E402
from scalesynth.evaluate import evaluate_config as _evaluate_config  # noqa: E402
from scalesynth.mechanisms import available as _available  # noqa: E402
from scalesynth.mechanisms import get as _get  # noqa: E402
from scalesynth.mechanisms.base import Mechanism  # noqa: E402
from scalesynth.optimize import ProgressFn  # noqa: E402
from scalesynth.optimize import run as _run  # noqa: E402
from scalesynth.results import RunResult  # noqa: E402
from scalesynth.results import load as _load_result  # noqa: E402

ConfigLike = RunConfig | str | Path | Mapping[str, Any]


def mechanisms() -> list[str]:
    """Names of the registered mechanisms, sorted (e.g. ``['2pauu-ppap', 'planar-fivebar', ...]``)."""
    return _available()


def get_mechanism(name: str) -> Mechanism:
    """The registered :class:`~scalesynth.mechanisms.base.Mechanism` called ``name``.

    Raises :class:`scalesynth.errors.UnknownMechanism` (a ``ScalesynthError``) naming the available ones.
    """
    return _get(name)


def as_config(config: ConfigLike, overrides: list[str] | None = None) -> RunConfig:
    """A validated :class:`RunConfig` from a config object, a YAML path or a plain mapping (as in a YAML file);
    ``overrides`` are ``--set``-style strings ``"key=value"``. Bad input raises ``ConfigError`` naming the field."""
    if isinstance(config, RunConfig):
        return config_from_dict(config.model_dump(mode="json"), overrides) if overrides else config
    if isinstance(config, str | Path):
        return load_config(config, overrides)
    return config_from_dict(dict(config), overrides)


def evaluate(
    mechanism: str | Mechanism,
    design: Mapping[str, float] | None = None,
    options: Mapping[str, Any] | None = None,
    *,
    resolution: int = 64,
    region: Mapping[str, Sequence[float]] | None = None,
    band_edges: Sequence[float] = DEFAULT_BAND_EDGES,
    length_unit: str | None = None,
    keep_grid: bool = False,
) -> WorkspaceReport:
    """Workspace and dexterity of one design on a voxel grid.

    Args:
        mechanism: a registered name (see :func:`mechanisms`) or a Mechanism object.
        design: parameter values in the mechanism's length unit (m for 2pauu-ppap, mm for the others; angles in
            rad); missing parameters take the mechanism's defaults (``get_mechanism(name).default_design()``).
        options: working mode, joint limits and the like (``default_options()``); missing ones take defaults.
        resolution: cells per task axis, 4 to 1024 as ``grid.resolution`` of a config; the grid spans the
            mechanism's bounding box of this design, or
            ``region`` ({axis name: [lo, hi]} in task units) for the axes it names.
        band_edges: dexterity band edges in LCI, increasing from 0 to 1; band k is (edges[k], edges[k+1]].
        length_unit: unit of the measure column name (e.g. ``"m"`` gives ``volume_m3``); default the mechanism's.
        keep_grid: also return the per-voxel arrays (``report.lci_grid`` and ``report.grid``, see
            :class:`WorkspaceReport`); costs one extra pass over the grid.

    Returns:
        A :class:`WorkspaceReport`; ``report.metrics`` holds the measure (volume or area), ``gci``, ``fci``,
        ``min_lci``, ``max_lci``, ``voxels`` and the band shares and measures. An empty workspace gives 0, never NaN.

        With ``keep_grid=True`` it also carries the per-voxel arrays:

        - ``report.lci_grid``: float64 array of shape ``report.grid.shape`` = (nx, ny, nz), nz = 1 for planar
          mechanisms: the LCI in [0, 1] at each cell centre; **-1 marks an unreachable cell** (no inverse solution
          in the selected working mode, or a joint or box limit violated); a reachable singular cell has LCI 0.
        - ``report.grid``: the :class:`Grid`; cell (i, j, k) has its centre at
          ``(grid.axis(0)[i], grid.axis(1)[j], grid.axis(2)[k])`` in the units of ``Mechanism.task_axes``, and
          ``grid.cell_measure`` is the measure of one cell, so ``(lci_grid >= 0).sum() * grid.cell_measure`` is the
          workspace measure and the mean of the reachable cells is the GCI.

    Raises:
        ConfigError (a ``ScalesynthError``), one line naming the argument, for what a config would refuse: a
        resolution outside 4..1024, a region that is not ``{task axis: [lo, hi]}`` with finite lo < hi, band edges
        that do not rise from 0 to 1, an unknown length unit, or ``keep_grid`` arrays above the memory limit;
        ``InvalidParameter`` for a bad design value or option.
    """
    if isinstance(mechanism, str):
        mech = _get(mechanism)
    elif isinstance(mechanism, Mechanism):
        mech = mechanism
    else:
        raise ConfigError(f"mechanism: expected a name or a Mechanism, got {type(mechanism).__name__}")
    check_grid_arguments(mech, resolution, region, band_edges, length_unit)
    if keep_grid:
        from scalesynth import memory

        cells = float(resolution) ** len(mech.task_axes)
        memory.check([("keep_grid", f"the per-voxel fields of a {resolution}-cell grid",
                       cells * mech.n_fields * memory.F8)])
    return _evaluate(
        mech,
        design or {},
        options,
        resolution=resolution,
        region=region,
        band_edges=band_edges,
        length_unit=length_unit,
        keep_grid=keep_grid,
    )


def evaluate_config(
    config: ConfigLike, design: Mapping[str, float] | None = None, *, keep_grid: bool = False
) -> WorkspaceReport:
    """Evaluate ``design`` (default: the config's ``design``) with everything else taken from the config
    (options, grid resolution and region, band edges, length unit, task). ``config`` is a RunConfig, a YAML path
    or a mapping. With a ``task`` section the report's metrics include task_coverage, task_gci, ...."""
    return _evaluate_config(as_config(config), design, keep_grid=keep_grid)


def optimize(
    config: ConfigLike,
    out_dir: str | Path | None = None,
    *,
    seed: int | None = None,
    resume: bool = False,
    plots: bool = True,
    progress: ProgressFn | None = None,
    overrides: list[str] | None = None,
    force: bool = False,
) -> RunResult:
    """Run the config's NSGA-II synthesis and write its results directory (``docs/results.md``).

    Args:
        config: a RunConfig, a YAML path or a mapping.
        out_dir: results directory; default ``output.dir`` of the config, else ``results/<name>`` under the
            current directory.
        seed: overrides ``algorithm.seed``.
        resume: continue from the directory's checkpoint (or return the finished run unchanged).
        plots: write ``plots/*.png`` and ``report.md`` as well.
        progress: called once per generation with a dict (generation, evaluations, hypervolume, ...).
        overrides: ``"key=value"`` strings as for ``--set``.
        force: write into a directory that is neither new, empty nor a run directory (ConfigError otherwise),
            replacing only files of the names a run writes.

    Returns:
        :class:`RunResult` with ``out_dir``, ``pareto`` (pandas DataFrame, one row per non-dominated design),
        ``history`` (DataFrame, one row per generation) and ``manifest`` (dict).
    """
    cfg = as_config(config, overrides)
    return _run(cfg, None if out_dir is None else Path(out_dir), seed=seed, resume=resume, plots=plots,
                progress=progress, force=force)


def load_result(run_dir: str | Path) -> RunResult:
    """Read a finished results directory into a :class:`RunResult` (pareto and history as pandas DataFrames,
    the manifest as a dict). A directory without ``manifest.json`` raises ``ConfigError``."""
    return _load_result(Path(run_dir))
