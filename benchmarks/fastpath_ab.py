"""2pauu-ppap's uniform fast path (population_stats_fast) of this tree against a git ref's, per design, at chosen N.

    python benchmarks/fastpath_ab.py [REF] [N ...]       # default: 3d9b530 (libm acos/cos), N = 56 72

Alternating subprocesses (``ROUNDS`` each), one Numba thread, on the benchmark's 40 random designs of
paper_2pauu_ppap.yaml (benchmarks/adaptive.py design_set, seed 0); each process reports its best of 9 calls in
*thread CPU time*, which waiting for a core on a shared machine does not inflate (wall time does), and the sum of
the count and LCI columns so that the two trees can be seen to compute the same thing.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ROUNDS = 3
SNIPPET = """
import json, sys, time
import numpy as np
sys.path.insert(0, sys.argv[1])
from adaptive import design_set
from scalesynth.evaluate import make_grid
import scalesynth.mechanisms.pauu_ppap as P
out = {}
s = design_set("2pauu-ppap", 40, 0)
for n in map(int, sys.argv[2:]):
    grids = [make_grid(s.mech, d, s.options, n, s.region) for d in s.designs]
    lo, step = np.stack([g.lo for g in grids]), np.stack([g.step for g in grids])
    P.population_stats_fast(s.packed[:1], lo[:1], step[:1], grids[0].shape, s.edges)  # compiled or loaded
    best = 1e9
    for _ in range(9):
        t = time.thread_time()
        rows = P.population_stats_fast(s.packed, lo, step, grids[0].shape, s.edges)
        best = min(best, time.thread_time() - t)
    out[n] = {"ms_per_design": best / len(s.designs) * 1e3, "checksum": float(rows[:, :3].sum())}
print(json.dumps(out))
"""


def main(argv: list[str]) -> None:
    ref = argv[0] if argv else "3d9b530"
    sizes = argv[1:] or ["56", "72"]
    with tempfile.TemporaryDirectory() as tmp:
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", ref, "src"], capture_output=True, check=True)
        subprocess.run(["tar", "-x", "-C", tmp], input=archive.stdout, check=True)
        trees = {ref: (Path(tmp) / "src", Path(tmp) / "cache-ref"), "this tree": (ROOT / "src", Path(tmp) / "cache")}
        best: dict[str, dict[str, dict]] = {k: {} for k in trees}
        for _ in range(ROUNDS):
            for label, (src, cache) in trees.items():
                env = dict(os.environ, NUMBA_NUM_THREADS="1", NUMBA_CACHE_DIR=str(cache), PYTHONPATH=str(src))
                proc = subprocess.run([sys.executable, "-c", SNIPPET, str(ROOT / "benchmarks"), *sizes], env=env,
                                      capture_output=True, text=True, check=True)
                for n, row in json.loads(proc.stdout).items():
                    old = best[label].get(n)
                    if old is None or row["ms_per_design"] < old["ms_per_design"]:
                        best[label][n] = row
    print(f"load average {os.getloadavg()[0]:.1f}; ms/design (thread CPU, best of {ROUNDS} processes x 9 calls)")
    for n in sizes:
        a, b = best[ref][n], best["this tree"][n]
        print(f"N = {n}: {ref} {a['ms_per_design']:.3f}, this tree {b['ms_per_design']:.3f} "
              f"({a['ms_per_design'] / b['ms_per_design']:.2f}x); checksums {a['checksum']!r} {b['checksum']!r}")


if __name__ == "__main__":
    main(sys.argv[1:])
