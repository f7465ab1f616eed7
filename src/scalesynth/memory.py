"""Memory estimates made before allocating, and the limit they are checked against.

Every large allocation of a run is predicted from the config alone (the sizes below are the arrays the code
allocates, counted in bytes), and a config whose estimate exceeds the limit is refused with exit code 2 before
anything is computed or written, instead of ending in a MemoryError traceback hours later.

The limit is half of the memory available when the check runs (``MemAvailable`` of /proc/meminfo, else the
free physical pages), or the environment variable ``SCALESYNTH_MEMORY_LIMIT``: bytes, or a number with a unit
(``512M``, ``8GiB``, ``1.5T``; powers of 1024).
"""

from __future__ import annotations

import os
import re

from scalesynth.errors import ScalesynthError

ENV_VAR = "SCALESYNTH_MEMORY_LIMIT"
F8 = 8  # bytes per float64 / int64

# plot-task: the LCI map, its mask, matplotlib's RGBA float image and resampling buffers, per cell
TASK_MAP_BYTES_PER_CELL = 8 * F8
# pymoo's DefaultDuplicateElimination: cdist of the offspring with itself (n x n float64), the n(n+1)/2 pairs of
# np.triu_indices (two int64 arrays), isnan/<= masks and scipy's temporaries: 24.6 bytes per pair of individuals
# measured with tracemalloc at n = 1200 (tests/test_memory.py), rounded up
DUPLICATE_BYTES_PER_PAIR = 26


class MemoryLimitError(ScalesynthError):
    """A config whose estimated memory exceeds the limit (exit code 2: change the config or the limit)."""


def available_bytes() -> int:
    """Memory the system can give this process now (bytes)."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (OSError, ValueError, AttributeError):
        return 4 * 1024**3  # unknown system: assume a small machine


_UNITS = {"": 1, "K": 1024, "M": 1024**2, "G": 1024**3, "T": 1024**4}


def parse_size(text: str) -> int:
    """'8GiB', '512M', '1.5T', '1000000' -> bytes; ValueError for anything else."""
    m = re.fullmatch(r"\s*([0-9]+(?:\.[0-9]*)?(?:[eE][0-9]+)?)\s*([KMGT]?)(?:i?B)?\s*", text, flags=re.IGNORECASE)
    if not m:
        raise ValueError(text)
    value = float(m.group(1)) * _UNITS[m.group(2).upper()]
    if not value >= 1 or value > 2**63:
        raise ValueError(text)
    return int(value)


def limit_bytes() -> tuple[int, str]:
    """(limit in bytes, where it comes from)."""
    raw = os.environ.get(ENV_VAR)
    if raw is not None and raw.strip():
        try:
            return parse_size(raw), f"{ENV_VAR}={raw.strip()}"
        except ValueError:
            shown = raw if len(raw) <= 40 else raw[:40] + "..."
            raise MemoryLimitError(f"{ENV_VAR}: expected a size such as 8GiB or 512M, got {shown!r}") from None
    return available_bytes() // 2, f"half the available memory; set {ENV_VAR} to change it"


def human(n: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if abs(n) < 1024 or unit == "PiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n:.1f} PiB"  # pragma: no cover


def check(items: list[tuple[str, str, float]]) -> int:
    """Refuse (MemoryLimitError naming the field, the estimate and the limit) if the largest of the estimates
    ``(field, what, bytes)`` (allocations that are not alive at the same time) exceeds the limit; returns it."""
    if not items:
        return 0
    field, what, need = max(items, key=lambda item: item[2])
    limit, source = limit_bytes()
    if need > limit:
        raise MemoryLimitError(f"{field}: {what} needs about {human(need)}, above the memory limit "
                               f"{human(limit)} ({source})")
    return int(need)


# ----- estimates ------------------------------------------------------------------------------------------------

def _ncols(cfg) -> int:
    return 5 + len(cfg.dexterity.band_edges) - 1  # kernels.grid row layout: N_FIXED + one count per band


def grid_stats_bytes(n_designs: int, resolution: int, ncols: int) -> float:
    """kernels.grid.population_stats (and the seed-000 kernel): one partial-sum row per (design, x-slab)."""
    return float(n_designs) * resolution * ncols * F8


def run_estimates(cfg, plots: bool = True) -> list[tuple[str, str, float]]:
    """What an NSGA-II run of ``cfg`` allocates at its peak, per cause."""
    pop = cfg.algorithm.pop_size
    res = cfg.grid.resolution
    n_var = max(len(cfg.bounds), 1)
    n_cols = 6 + 2 * (len(cfg.dexterity.band_edges) - 1) + 7  # metric columns incl. task and path metrics
    items = [
        ("grid.resolution", f"the evaluation of {pop} designs on a {res}-cell grid",
         grid_stats_bytes(pop, res, _ncols(cfg))),
        ("algorithm.pop_size", f"pymoo's duplicate-elimination distance matrix ({pop}^2 pairs)",
         DUPLICATE_BYTES_PER_PAIR * float(pop) ** 2),
        ("algorithm.pop_size", "the population matrices and result tables",
         2.0 * pop * (n_var + len(cfg.objectives) + 2 * len(cfg.constraints) + n_cols) * F8 * 4),
    ]
    if cfg.task is not None:
        tres = cfg.task.resolution or res
        items.append(("task.resolution", f"the task-box evaluation of {pop} designs ({tres} cells per axis)",
                      grid_stats_bytes(pop, tres, _ncols(cfg))))
        if cfg.task.path is not None:
            items.append(("task.path_samples", "the path LCI of the population",
                          float(pop) * cfg.task.path_samples * F8 * 2))
    if plots:
        items.extend(section_estimates(cfg))
    return items


def section_estimates(cfg) -> list[tuple[str, str, float]]:
    """report.section_panels: two mid-plane sections (not the whole grid) of max(res, 128) + 1 or 2 cells."""
    from scalesynth.workspace_view import SECTION_RESOLUTION  # not via report: that imports matplotlib

    n = max(cfg.grid.resolution, SECTION_RESOLUTION) + 2
    planes = 1 if len(cfg.mech.task_axes) == 2 else 2
    return [("grid.resolution", f"the section plots ({planes} planes of {n}^2 cells)",
             planes * float(n) ** 2 * F8 * 6)]


def evaluate_estimates(cfg) -> list[tuple[str, str, float]]:
    items = [("grid.resolution", f"a {cfg.grid.resolution}-cell grid evaluation",
              grid_stats_bytes(1, cfg.grid.resolution, _ncols(cfg)))]
    if cfg.task is not None:
        items.append(("task.resolution", "the task-box evaluation",
                      grid_stats_bytes(1, cfg.task.resolution or cfg.grid.resolution, _ncols(cfg))))
    return items


def task_map_estimate(resolution: int, field: str = "--resolution") -> list[tuple[str, str, float]]:
    return [(field, f"a {resolution} x {resolution} LCI map", TASK_MAP_BYTES_PER_CELL * float(resolution) ** 2)]


# show: per cell, the sampled fields and their NaN-masked copies (2 x 8 bytes per field), the LCI and band index
# arrays (8 + 8), one int32 region-label array per band kept for the figures, one more for the face count, and
# boolean masks (about 8)
SHOW_FIXED_BYTES_PER_CELL = 8 + 8 + 4 + 8


def show_estimate(cfg, resolution: int, field: str) -> list[tuple[str, str, float]]:
    """What ``scalesynth show`` allocates: every per-voxel array of a ``resolution``-cell grid over the task axes."""
    mech = cfg.mech
    cells = float(resolution) ** len(mech.task_axes)
    n_bands = len(cfg.dexterity.band_edges) - 1
    per_cell = 2 * mech.n_fields * F8 + 4 * n_bands + SHOW_FIXED_BYTES_PER_CELL
    return [(field, f"the fields of a {resolution}-cell grid ({cells:.3g} cells)", cells * per_cell)]
