"""A/B of the adaptive evaluator with the field kernel against the LCI kernel (Mechanism.lci_kernel) at its Gauss
points: what a search whose workspace metrics are the LCI's saves per design.

    NUMBA_NUM_THREADS=1 python benchmarks/lci_kernel_ab.py [MECH ...] [--designs N] [--rounds R]

Per mechanism (``benchmarks/adaptive.py``'s config, ``random_designs(cfg, N, seed=0)``, the mechanism's plan, the
config's tolerance): both kernels alternately in one process, R rounds, min wall time per design; also checks that
the count, LCI sum, levels and kernel calls are byte-identical (the refinement reads slot 0 alone).
"""

from __future__ import annotations

import argparse
import os
import time

from adaptive import design_set

from scalesynth.evaluate import adaptive_population_stats


def ab(name: str, n_designs: int, rounds: int) -> dict:
    s = design_set(name, n_designs)
    cfg, mech, options, tol, edges, designs, packed = s.cfg, s.mech, s.options, s.tol, s.edges, s.designs, s.packed

    def run(lci_only: bool):
        t0 = time.perf_counter()
        r = adaptive_population_stats(mech, designs, options, packed, tol, edges, cfg.grid.region, lci_only=lci_only)
        return time.perf_counter() - t0, r

    full, lci = run(False)[1], run(True)[1]  # compiled or loaded
    same = (full.stats[:, :2].tobytes() == lci.stats[:, :2].tobytes()
            and full.levels.tobytes() == lci.levels.tobytes()
            and full.evaluations.tobytes() == lci.evaluations.tobytes())
    tf, tl = [], []
    for _ in range(rounds):
        tf.append(run(False)[0])
        tl.append(run(True)[0])
    return {"mechanism": name, "full_ms": 1e3 * min(tf) / n_designs, "lci_ms": 1e3 * min(tl) / n_designs,
            "ratio": min(tl) / min(tf), "identical": same}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mechanisms", nargs="*", default=["ups-sspr", "rps-upu", "rps-upu-tool", "pprs-rprs"])
    ap.add_argument("--designs", type=int, default=20)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f}; NUMBA_NUM_THREADS={os.environ.get('NUMBA_NUM_THREADS', 'default')}")
    print("| mechanism | field kernel ms/design | LCI kernel ms/design | ratio | count, LCI sum, levels, calls identical |")
    print("|---|---|---|---|---|")
    for name in args.mechanisms:
        r = ab(name, args.designs, args.rounds)
        print(f"| {name} | {r['full_ms']:.2f} | {r['lci_ms']:.2f} | {r['ratio']:.2f} | {'yes' if r['identical'] else 'NO'} |",
              flush=True)
    print(f"load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
