"""Column intervals in closed form (Mechanism.interval_kernel) against nodes and bisection, A/B in one process.

    NUMBA_NUM_THREADS=1 python benchmarks/interval_ab.py [MECH] [N_DESIGNS]   # default rps-upu-tool, 20

Random designs of the mechanism's config (benchmarks/adaptive.py's random_designs, seed 0), the search's call
(adaptive_population_stats with lci_only=True) with intervals on (the interval plan, evaluate.INTERVAL_PLAN_OF) and
off (nodes and bisection with the node plan), alternately, best of 3: ms/design and
kernel calls/design; then both against the uniform grid N = 96 (volume relative, GCI absolute; worst design and
the errors as multiples of the config's tolerance).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

from adaptive import design_set, gci_of  # noqa: E402

from scalesynth.evaluate import adaptive_population_stats, make_grid  # noqa: E402

N_REF = 96


def main(name: str = "rps-upu-tool", n: int = 20) -> None:
    s = design_set(name, n)
    mech, options, tol, edges, region, designs, packed = s.mech, s.options, s.tol, s.edges, s.region, s.designs, s.packed

    def run(on: bool):
        t0 = time.perf_counter()
        r = adaptive_population_stats(mech, designs, options, packed, tol, edges, region, lci_only=True,
                                      intervals=on)
        return time.perf_counter() - t0, r

    for on in (True, False):
        adaptive_population_stats(mech, designs[:1], options, packed[:1], tol, edges, region, lci_only=True,
                                  intervals=on)  # compiled or loaded
    best = {True: np.inf, False: np.inf}
    res = {}
    for _ in range(3):
        for on in (True, False):
            sec, res[on] = run(on)
            best[on] = min(best[on], sec)
    grids = [make_grid(mech, d, options, N_REF, region) for d in designs]
    lo, step = np.stack([g.lo for g in grids]), np.stack([g.step for g in grids])
    s = mech.grid_stats(packed, lo, step, grids[0].shape, edges, lci_only=True)
    ref_v = s[:, 0] * np.array([g.cell_measure for g in grids])
    ref_g = gci_of(s)
    print(f"{name}: {n} designs, tolerance ({tol.volume:g}, {tol.gci:g}), reference uniform N = {N_REF}")
    for on in (True, False):
        r = res[on]
        v, g = r.stats[:, 0] * r.cell, gci_of(r.stats)
        ev = np.abs(v - ref_v) / np.where(ref_v > 0, ref_v, 1.0)
        eg = np.abs(g - ref_g)
        print(f"  intervals {'on ' if on else 'off'}: {1e3 * best[on] / n:7.2f} ms/design, "
              f"{r.evaluations.mean():9.0f} calls/design, levels {np.bincount(r.levels).tolist()}; "
              f"vs N = {N_REF}: volume {100 * ev.max():.3f} % (max), {100 * np.median(ev):.3f} % (median), "
              f"GCI {eg.max():.1e} (max); designs outside the tolerance "
              f"{int(((ev > tol.volume) | (eg > tol.gci)).sum())}")
    print(f"  speed-up {best[False] / best[True]:.2f}x, calls {res[False].evaluations.mean() / res[True].evaluations.mean():.2f}x fewer")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "rps-upu-tool", int(sys.argv[2]) if len(sys.argv) > 2 else 20)
