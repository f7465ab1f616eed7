"""A/B of the adaptive evaluator on the half box of the mechanism's mirror symmetries (evaluate.HalfBox) against the
full box: time and kernel calls per design, and how far apart the results are.

    NUMBA_NUM_THREADS=1 python benchmarks/mirror_ab.py [MECH ...] [--designs N] [--rounds R] [--lci]

Per mechanism (``benchmarks/adaptive.py``'s config, ``random_designs(cfg, N, seed=0)``, the mechanism's plan, the
config's tolerance): both alternately in one process, R rounds, min wall time per design (``--lci``: the search's
LCI kernel at the Gauss points). The difference columns: the largest relative difference of the volume, the
largest absolute difference of the GCI, and whether the refinement levels are equal on every design.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
from adaptive import design_set

from scalesynth.evaluate import HalfBox, adaptive_plan, adaptive_population_stats, column_axis, design_boxes


def ab(name: str, n_designs: int, rounds: int, lci_only: bool) -> dict:
    s = design_set(name, n_designs)
    cfg, mech, options, tol, edges, designs, packed = s.cfg, s.mech, s.options, s.tol, s.edges, s.designs, s.packed
    lo, hi = design_boxes(mech, designs, options, cfg.grid.region)
    half = HalfBox.of(mech, options, lo, hi, adaptive_plan(mech, options), axis=column_axis(mech, options))

    def run(mirror: bool):
        t0 = time.perf_counter()
        r = adaptive_population_stats(mech, designs, options, packed, tol, edges, cfg.grid.region,
                                      lci_only=lci_only, mirror=mirror)
        return time.perf_counter() - t0, r

    full, mirrored = run(False)[1], run(True)[1]  # compiled or loaded
    vol_f, vol_m = full.stats[:, 0] * full.cell, mirrored.stats[:, 0] * mirrored.cell
    gci_f = full.stats[:, 1] / np.where(full.stats[:, 0] > 0, full.stats[:, 0], 1.0)
    gci_m = mirrored.stats[:, 1] / np.where(mirrored.stats[:, 0] > 0, mirrored.stats[:, 0], 1.0)
    tf, tm = [], []
    for _ in range(rounds):
        tf.append(run(False)[0])
        tm.append(run(True)[0])
    return {"mechanism": name, "factor": half.factor, "full_ms": 1e3 * min(tf) / n_designs,
            "half_ms": 1e3 * min(tm) / n_designs, "ratio": min(tm) / min(tf),
            "calls_full": float(full.evaluations.mean()), "calls_half": float(mirrored.evaluations.mean()),
            "volume_rel": float(np.max(np.abs(vol_m - vol_f) / np.where(vol_f > 0, vol_f, 1.0))),
            "gci_abs": float(np.max(np.abs(gci_m - gci_f))),
            "levels_equal": bool(np.array_equal(full.levels, mirrored.levels))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mechanisms", nargs="*", default=["ups-sspr", "rps-upu", "rps-upu-tool", "planar-fivebar"])
    ap.add_argument("--designs", type=int, default=20)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--lci", action="store_true", help="the LCI kernel at the Gauss points (what a search runs)")
    args = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f}; NUMBA_NUM_THREADS={os.environ.get('NUMBA_NUM_THREADS', 'default')}"
          f"; {'LCI' if args.lci else 'field'} kernel")
    print("| mechanism | halves | full box ms/design | half box ms/design | time ratio | calls full / half | "
          "max volume difference | max GCI difference | levels equal |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name in args.mechanisms:
        r = ab(name, args.designs, args.rounds, args.lci)
        print(f"| {name} | {r['factor']:.0f} | {r['full_ms']:.2f} | {r['half_ms']:.2f} | {r['ratio']:.2f} | "
              f"{r['calls_full']:.0f} / {r['calls_half']:.0f} | {r['volume_rel']:.1e} | {r['gci_abs']:.1e} | "
              f"{'yes' if r['levels_equal'] else 'NO'} |", flush=True)
    print(f"load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
