"""What pinning Numba's CPU target costs: the same kernels compiled for the host CPU, plain x86-64 and x86-64-v3.

Each target runs in its own process with its own Numba cache (compiled once, then timed warm), rounds alternating
so the machine's load falls on every target alike. Timed: 2pauu-ppap's uniform evaluator (8 designs, N = 72,
3 calls) and ups-sspr's adaptive evaluator (one design, 20 calls), CPU seconds, one Numba thread.

    python benchmarks/bench.py cpu_target [--before TREE]   (stored, and in RESULTS.md)
    python benchmarks/cpu_target.py [ROUNDS] [--before TREE]  (printed only)

``--before TREE`` adds another checkout's sources (e.g. a worktree of the commit before fast-math was turned off),
compiled for the host CPU, as one more variant of the same run.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile

PROBE = r"""
import json, time
import numpy as np
from scalesynth.evaluate import Tolerance, adaptive_population_stats, make_grid
from scalesynth.kernels import grid as kgrid
from scalesynth.mechanisms import get
from numba.core import config

out = {"target": config.CPU_NAME or "host"}
e = np.array([0.0, 0.3, 1.0])
m = get("2pauu-ppap")
d, o = m.default_design(), m.resolve_options({})
g = make_grid(m, d, o, 72)
p = np.repeat(m.pack(d, o)[None, :], 8, axis=0)
lo, st = np.repeat(g.lo[None, :], 8, axis=0), np.repeat(g.step[None, :], 8, axis=0)
kgrid.population_stats(m.field_kernel, m.n_fields, p[:1], lo[:1], st[:1], g.shape, e)
t = time.process_time()
for _ in range(3):
    kgrid.population_stats(m.field_kernel, m.n_fields, p, lo, st, g.shape, e)
out["2pauu-ppap uniform N=72, 24 designs (CPU s)"] = round(time.process_time() - t, 3)
m = get("ups-sspr")
d, o = m.resolve_design({}), m.resolve_options({})
pk = m.pack(d, o)[None, :]
adaptive_population_stats(m, [d], o, pk, Tolerance(), e)
t = time.process_time()
for _ in range(20):
    adaptive_population_stats(m, [d], o, pk, Tolerance(), e)
out["ups-sspr adaptive, 20 calls (CPU s)"] = round(time.process_time() - t, 4)
print(json.dumps(out))
"""


def _host() -> dict[str, str]:
    import llvmlite.binding as ll

    return {"NUMBA_CPU_NAME": ll.get_host_cpu_name(), "NUMBA_CPU_FEATURES": ll.get_host_cpu_features().flatten()}


def bench_cpu_target(rounds: int = 3, before: str | None = None) -> dict:
    """Rows {variant, round, target, <timed>: CPU s} for every target (and ``before``), rounds alternating."""
    targets = {"host": _host(), "x86-64": {"NUMBA_CPU_NAME": "x86-64", "NUMBA_CPU_FEATURES": ""},
               "x86-64-v3 (pinned)": {"NUMBA_CPU_NAME": "x86-64-v3", "NUMBA_CPU_FEATURES": ""}}
    if before:
        targets["before: fast-math, host"] = {**_host(), "PYTHONPATH": os.path.join(os.path.abspath(before), "src")}
    rows = []
    load = [os.getloadavg()[0]]
    with tempfile.TemporaryDirectory() as tmp:
        for rnd in range(rounds + 1):  # round 0 compiles
            for label, extra in targets.items():
                env = dict(os.environ, NUMBA_NUM_THREADS="1", NUMBA_CACHE_DIR=os.path.join(tmp, label), **extra)
                out = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True, text=True,
                                     timeout=1800, check=True)
                if rnd:
                    row = {"variant": label, "round": rnd, **json.loads(out.stdout.strip().splitlines()[-1])}
                    rows.append(row)
                    print(row, flush=True)
    load.append(os.getloadavg()[0])
    commit = None
    if before:
        commit = subprocess.run(["git", "-C", before, "rev-parse", "--short", "HEAD"], capture_output=True,
                                text=True, timeout=60).stdout.strip() or None
    return {"rounds": rounds, "before": before, "before_commit": commit, "rows": rows, "load_average_1min": load}


def markdown(entry: dict) -> list[str]:
    """The median CPU seconds per variant and timed kernel, and each one's ratio to the pinned target."""
    import statistics

    rows = entry["result"]["rows"]
    timed = [k for k in rows[0] if k.endswith("(CPU s)")]
    variants = list(dict.fromkeys(r["variant"] for r in rows))
    med = {(v, k): statistics.median(r[k] for r in rows if r["variant"] == v) for v in variants for k in timed}
    pinned = "x86-64-v3 (pinned)"
    out = ["The same kernels compiled for the host CPU, plain x86-64, the pinned x86-64-v3 level, and (where given) "
           "the tree before fast-math was turned off (`--before`), each in its own process and Numba cache, "
           f"rounds alternating ({entry['result']['rounds']} rounds, median; load average "
           f"{[round(x, 1) for x in entry['result']['load_average_1min']]}). Ratios to the pinned target; CPU seconds, one "
           "Numba thread."
           + (f" `before`: commit {entry['result']['before_commit']} (fast-math flags nsz, arcp, contract, afn)."
              if entry["result"].get("before_commit") else ""), "",
           "| variant | " + " | ".join(timed) + " |", "|---|" + "---|" * len(timed)]
    for v in variants:
        cells = [f"{med[(v, k)]:.4g} ({med[(v, k)] / med[(pinned, k)]:.2f}x)" for k in timed]
        out.append(f"| {v} | " + " | ".join(cells) + " |")
    return out + [""]


if __name__ == "__main__":
    args = sys.argv[1:]
    tree = None
    if "--before" in args:
        k = args.index("--before")
        tree = args[k + 1]
        del args[k : k + 2]
    bench_cpu_target(int(args[0]) if args else 2, tree)
