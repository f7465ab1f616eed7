"""The adaptive evaluator before and after a change to its bookkeeping: same decisions, same numbers to rounding, time.

    NUMBA_NUM_THREADS=1 python benchmarks/adaptive_store_ab.py dump OUT.npz [N_DESIGNS] [SEEDS]   # default 60, 0,1,2
    python benchmarks/adaptive_store_ab.py compare A.npz B.npz

``dump``: per mechanism of benchmarks/adaptive.py's CONFIGS, ``random_designs`` of its config (N_DESIGNS per seed),
through the search's call (``adaptive_population_stats``, lci_only) and the full-fields call with the config's
tolerance: statistics rows, error estimates, levels and kernel calls; the lci_only call timed (best of 3, seconds per
design). Run it once on each version of ``src/`` (e.g. the old one from a ``git worktree`` with PYTHONPATH at its
src) with a fresh NUMBA_CACHE_DIR each. ``compare``: per mechanism, the designs whose levels or kernel calls differ,
the largest relative difference of the statistics and the estimates, and the time ratio B / A.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

from adaptive import CONFIGS, design_set  # noqa: E402

from scalesynth.evaluate import adaptive_population_stats  # noqa: E402


def _call(ds, designs, packed, lci_only):
    return adaptive_population_stats(ds.mech, designs, ds.options, packed, ds.tol, ds.edges, ds.cfg.grid.region,
                                     lci_only=lci_only)


def dump(out: str, n: int = 60, seeds: str = "0,1,2") -> None:
    data = {}
    for name in CONFIGS:
        sets = [design_set(name, n, int(s)) for s in seeds.split(",")]
        ds = sets[0]
        designs = [d for s in sets for d in s.designs]
        packed = np.concatenate([s.packed for s in sets])
        for lci_only in (True, False):
            r = _call(ds, designs, packed, lci_only)
            tag = f"{name}|{'lci' if lci_only else 'full'}"
            data[f"{tag}|stats"] = r.stats
            data[f"{tag}|est"] = np.c_[r.error_volume, r.error_gci]
            data[f"{tag}|calls"] = np.c_[r.levels, r.evaluations]
        best = np.inf
        for _ in range(3):
            t0 = time.perf_counter()
            _call(ds, designs, packed, True)
            best = min(best, time.perf_counter() - t0)
        data[f"{name}|seconds"] = np.array([best / len(designs)])
        print(f"{name}: {1e3 * best / len(designs):.3f} ms/design (lci_only, best of 3, {len(designs)} designs)",
              flush=True)
    np.savez(out, **data)


def _rel(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    both_inf = np.isinf(a) & np.isinf(b) & (np.sign(a) == np.sign(b))
    with np.errstate(invalid="ignore"):  # inf - inf where both are the same infinity (an empty min or max)
        d = np.where(both_inf, 0.0, np.abs(a - b))
    return float(np.max(d / np.maximum(np.maximum(np.abs(a), np.abs(b)), 1e-300), initial=0.0))


def compare(a_path: str, b_path: str) -> None:
    a, b = np.load(a_path), np.load(b_path)
    for name in CONFIGS:
        line = [f"{name}:"]
        for kind in ("lci", "full"):
            tag = f"{name}|{kind}"
            ca, cb = a[f"{tag}|calls"], b[f"{tag}|calls"]
            differ = int(np.any(ca != cb, axis=1).sum())
            same = np.all(ca == cb, axis=1)
            # the lci_only rows' other fields are not meaningful (adaptive_population_stats): compare the full ones
            ea, eb = a[f"{tag}|est"][same], b[f"{tag}|est"][same]
            dv, dg = (float(np.max(np.abs(ea[:, k] - eb[:, k]), initial=0.0)) for k in (0, 1))
            line.append(f"{kind}: {differ}/{len(ca)} designs with other levels or calls; the others: stats "
                        f"{_rel(a[f'{tag}|stats'][same], b[f'{tag}|stats'][same]):.1e} relative, estimates "
                        f"{dv:.1e} (volume, relative to the volume) and {dg:.1e} (GCI) apart")
        ta, tb = float(a[f"{name}|seconds"][0]), float(b[f"{name}|seconds"][0])
        line.append(f"time {1e3 * ta:.3f} -> {1e3 * tb:.3f} ms/design ({tb / ta:.2f}x)")
        print(" ".join(line[:1]) + "\n  " + "\n  ".join(line[1:]))


if __name__ == "__main__":
    if len(sys.argv) >= 3 and sys.argv[1] == "dump":
        dump(*sys.argv[2:3], *(int(v) if i == 0 else v for i, v in enumerate(sys.argv[3:5])))
    elif len(sys.argv) == 4 and sys.argv[1] == "compare":
        compare(sys.argv[2], sys.argv[3])
    else:
        sys.exit(__doc__)
