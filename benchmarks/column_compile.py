"""The column algorithm compiled once (issue 30): compile CPU, outputs and speed of ``adaptive_population_stats``
in this tree against another tree, each in its own processes with its own empty Numba cache.

    python benchmarks/column_compile.py OTHER_TREE        # e.g. a `git worktree add` of the commit before

Per tree, one process with an empty cache evaluates 4 designs (each config's first bound parameter x 0.9 .. 1.1) of
8 mechanisms, interval columns on then off, printing the CPU seconds of each call (the first calls compile) and
saving every output array; the arrays of the two trees are then compared byte for byte. Speed: a process per tree
and mechanism (warm cache, NUMBA_NUM_THREADS=1), 40 designs, best of three, alternating trees, twice.
Figures: benchmarks/notes/column_compile_once.md.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CASES = [("rps-upu-tool", "rps_upu_tool"), ("delta", "delta"), ("hexa", "hexa"), ("planar-fivebar", "fivebar_packing"),
         ("pprs-rprs", "pprs_rprs"), ("2pauu-ppap", "paper_2pauu_ppap"), ("linear-delta", "linear_delta"),
         ("hexapod", "hexapod")]
SPEED = [("delta", "delta", False), ("rps-upu-tool", "rps_upu_tool", True)]
EDGES = [0.0, 0.2, 0.5, 1.0]

CHILD = """
import sys, time
import numpy as np
from scalesynth.config import load_config
from scalesynth.evaluation.adaptive import adaptive_population_stats
from scalesynth.evaluation.plans import Tolerance
from scalesynth.mechanisms import get

def population(name, config, n, lo, hi):
    cfg = load_config(config)
    mech, base, options = get(name), cfg.resolved_design(), cfg.resolved_options()
    k0 = next(iter(cfg.bounds))
    designs = [{**base, k0: base[k0] * f} for f in np.linspace(lo, hi, n)]
    return mech, designs, options, np.stack([mech.pack(d, options) for d in designs])

def stats(mech, designs, options, packed, intervals):
    return adaptive_population_stats(mech, designs, options, packed, Tolerance(), np.array(EDGES),
                                     intervals=intervals)
"""


def _run(tree: Path, code: str, env: dict) -> str:
    env = dict(env, PYTHONPATH=str(tree / "src"))
    out = subprocess.run([sys.executable, "-c", CHILD.replace("EDGES", repr(EDGES)) + code], env=env, text=True,
                         capture_output=True, timeout=3600, check=True)
    return out.stdout


def outputs(tree: Path, npz: Path, cache: Path) -> None:
    """Compile CPU per call, and every output array into ``npz``, of one tree with an empty cache."""
    code = f"""
res = {{}}
t0 = time.process_time()
for name, config in {[(n, str(ROOT / "configs" / f"{c}.yaml")) for n, c in CASES]!r}:
    mech, designs, options, packed = population(name, config, 4, 0.9, 1.1)
    for iv in (True, False):
        t = time.process_time()
        r = stats(mech, designs, options, packed, iv)
        for f in ("stats", "error_volume", "error_gci", "levels", "evaluations"):
            res[f"{{name}}-{{iv}}-{{f}}"] = getattr(r, f)
        print(f"  {{name}} intervals={{iv}}: {{time.process_time() - t:.2f}} s CPU", flush=True)
np.savez({str(npz)!r}, **res)
print(f"  total {{time.process_time() - t0:.1f}} s CPU")
"""
    print(_run(tree, code, dict(os.environ, NUMBA_CACHE_DIR=str(cache))), end="")


def speed(tree: Path, cache: Path, name: str, config: str, intervals: bool) -> float:
    """ms per design, warm cache, one thread, 40 designs, best of three."""
    code = f"""
mech, designs, options, packed = population({name!r}, {str(ROOT / "configs" / f"{config}.yaml")!r}, 40, 0.85, 1.15)
stats(mech, designs[:2], options, packed[:2], {intervals})
best = 1e9
for _ in range(3):
    t = time.perf_counter()
    stats(mech, designs, options, packed, {intervals})
    best = min(best, time.perf_counter() - t)
print(1000 * best / len(designs))
"""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache), NUMBA_NUM_THREADS="1")
    return float(_run(tree, code, env).split()[-1])


def main(other: Path) -> None:
    trees = {"other": other.resolve(), "this": ROOT}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for label, tree in trees.items():
            print(f"{label} ({tree}), empty cache:")
            outputs(tree, tmp / f"{label}.npz", tmp / f"cache-{label}")
        a, b = np.load(tmp / "other.npz"), np.load(tmp / "this.npz")
        differ = [k for k in a.files if k not in b.files or a[k].tobytes() != b[k].tobytes()]
        print(f"{len(a.files)} arrays; differing: {differ or 'none'}")
        for rnd in (1, 2):
            for name, config, intervals in SPEED:
                ms = {label: speed(tree, tmp / f"cache-{label}", name, config, intervals)
                      for label, tree in trees.items()}
                print(f"round {rnd}: {name} intervals={intervals}: other {ms['other']:.2f}, this {ms['this']:.2f} "
                      "ms/design")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        raise SystemExit("usage: python benchmarks/column_compile.py OTHER_TREE")
    main(Path(sys.argv[1]))
