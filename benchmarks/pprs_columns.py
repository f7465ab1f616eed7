"""pprs-rprs: the adaptive evaluator's interval plans against converged references, and its time against the uniform
grid.

    NUMBA_NUM_THREADS=1 python benchmarks/pprs_columns.py check SEED PLAN [PLAN ...]   # e.g. 24,1,5,3,4,0,1,0,0,1
    NUMBA_NUM_THREADS=1 python benchmarks/pprs_columns.py ab

``check``: the 20 random designs of ``benchmarks/adaptive.py`` (``random_designs(cfg, 20, SEED)``). Reference volume:
the exact reachable length of every column (``PprsRprs.interval_kernel``, closed form) summed over a 2400 x 2400
cross grid of the bounding box (its midpoint error, from the walls between columns, is below 0.02 % there).
Reference GCI: the adaptive evaluator itself with 324 x 324 columns of 4 z-cells, every column's fields evaluated
(2-point rule, no refinement): its column lengths are exact, so only the cross midpoint rule and the Gauss rule
along z remain; against 216 x 216 columns it moves by at most 0.07x the GCI tolerance without slivers on seeds 0-4,
where the uniform N = 192 is up to 0.35x off it (benchmarks/notes/pprs_rprs.md). Per plan (columns,cells,
bisections,levels,beta,zlevels,zconfirm,faces[,field_levels[,gauss_points]], as benchmarks/plan_search.py):
kernel calls per design, the worst volume and GCI errors as multiples of the config's tolerance (0.2 %, 5e-4;
slivers, reference volume below 1 % of the median, left out), the largest own estimate, and the three worst
designs. ``ab``: seed 0, alternating, best of 3, one process: the search's call (``adaptive_population_stats``,
lci_only) with the column intervals and the interval plan, with the interval plan before inherited fields
(PLAN_BEFORE), with nodes and bisection and the node plan, and the uniform N = 32 grid (the config's resolution
before the tolerance form); then the interval kernel alone, in us per column (48 x 48 columns per design).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

from adaptive import COLUMN_GCI_PLAN, N_CROSS, SLIVER, cross_volume, design_set  # noqa: E402
from adaptive import exact_volumes as adaptive_exact_volumes  # noqa: E402
from plan_search import Search, parse_plan  # noqa: E402

from scalesynth.evaluate import (  # noqa: E402
    ColumnPlan,
    Tolerance,
    adaptive_plan,
    adaptive_population_stats,
    column_axis,
    column_order,
    design_boxes,
)

# the interval plan before inherited fields and the midpoint rule (2026-12-02 morning), for ``ab``
PLAN_BEFORE = ColumnPlan(24, 2, 5, 3, beta=1.0, faces=True)


def exact_volumes(s) -> np.ndarray:
    """Volume (mm^3) of every design of a design set from its column intervals (N_CROSS^2 columns)."""
    return adaptive_exact_volumes(s.mech, s.designs, s.options, s.packed, s.region, N_CROSS)


def gci_of(stats: np.ndarray) -> np.ndarray:
    return np.where(stats[:, 0] > 0, stats[:, 1] / np.where(stats[:, 0] > 0, stats[:, 0], 1.0), 0.0)


def check(seed: int, plans: list[str]) -> None:
    s = design_set("pprs-rprs", seed=seed)
    t0 = time.perf_counter()
    ex = exact_volumes(s)
    rg = gci_of(adaptive_population_stats(s.mech, s.designs, s.options, s.packed, s.tol, s.edges, s.region,
                                          plan=COLUMN_GCI_PLAN, lci_only=True).stats)
    keep = ex >= SLIVER * np.median(ex)
    print(f"# seed {seed}: references in {time.perf_counter() - t0:.0f} s; slivers (left out): "
          f"{np.flatnonzero(~keep).tolist()}; exact volumes {np.round(ex).tolist()}", flush=True)
    tol: Tolerance = s.tol
    for text in plans:
        plan = parse_plan(text)
        r = adaptive_population_stats(s.mech, s.designs, s.options, s.packed, tol, s.edges, s.region, plan=plan,
                                      lci_only=True)
        vol = r.stats[:, 0] * r.cell
        gci = gci_of(r.stats)
        ev = np.where(keep, np.abs(vol - ex) / np.where(keep, ex, 1.0), 0.0) / tol.volume
        eg = np.where(keep, np.abs(gci - rg), 0.0) / tol.gci
        est = np.maximum(r.error_volume / tol.volume, r.error_gci / tol.gci)
        worst = np.argsort(-np.maximum(ev, eg))[:3]
        print(f"{text}: calls {r.evaluations.mean():.0f}, volume {ev.max():.2f}, GCI {eg.max():.2f}, own estimate "
              f"{est.max():.2f}; worst " + ", ".join(f"d{j} {ev[j]:.2f}, {eg[j]:.2f}" for j in worst), flush=True)


def ab() -> None:
    s = design_set("pprs-rprs")
    uni = Search("pprs-rprs", 32, None)

    def adaptive(intervals: bool, plan: ColumnPlan | None = None):
        plan = plan or adaptive_plan(s.mech, s.options if intervals else None)
        return lambda: adaptive_population_stats(s.mech, s.designs, s.options, s.packed, s.tol, s.edges, s.region,
                                                 plan=plan, lci_only=True, intervals=intervals)

    runs = {"column intervals, interval plan": adaptive(True),
            "column intervals, the interval plan before inherited fields": adaptive(True, PLAN_BEFORE),
            "nodes and bisection, node plan": adaptive(False), "uniform N = 32": lambda: uni.uniform(s.designs, 32)}
    for f in runs.values():
        f()  # compiled or loaded
    best = dict.fromkeys(runs, np.inf)
    for _ in range(3):
        for k, f in runs.items():
            t0 = time.perf_counter()
            f()
            best[k] = min(best[k], (time.perf_counter() - t0) / len(s.designs) * 1e3)
    for k, v in best.items():
        print(f"{k}: {v:.2f} ms/design ({v / best['uniform N = 32']:.2f}x uniform N = 32)")
    # the interval kernel alone, per column: 48 x 48 columns of each design's box (adaptive.cross_volume)
    kernel = s.mech.interval_kernel_for(s.options)
    order = column_order(3, column_axis(s.mech, s.options))
    lo, hi = design_boxes(s.mech, s.designs, s.options, s.region)
    cross_volume(kernel, s.packed[0], lo[0, order], hi[0, order], 8)  # compiled or loaded
    per_column = np.inf
    for _ in range(3):
        t0 = time.perf_counter()
        for i, p in enumerate(s.packed):
            cross_volume(kernel, p, lo[i, order], hi[i, order], 48)
        per_column = min(per_column, (time.perf_counter() - t0) / (len(s.designs) * 48 * 48))
    print(f"column_intervals: {1e6 * per_column:.3f} us per column")


if __name__ == "__main__":
    if sys.argv[1] == "check":
        check(int(sys.argv[2]), sys.argv[3:])
    else:
        ab()
