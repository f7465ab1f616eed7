"""Issue 29's performance target: the population cycle metrics with link dynamics cost at most 2x the massless
ones per design (``cycle.population.population_metrics``, the search's path), per mechanism with link geometry.

Run: python benchmarks/bench.py cycle_dynamics (or python benchmarks/cycle_dynamics.py [--designs 4]
[--repeats 7]). Per config with a cycle: ``--designs`` designs near the config's own (each bounded variable moved
by up to 1% of its range, seed 0: designs whose cycle is followed, so every step runs), one warm-up call of each
mode (compilation excluded), then the two modes alternated ``--repeats`` times; the best CPU time of each (process
time: the machine is shared). ``massless``: ``dynamics.masses: {}`` (every body massless; the payload alone);
``links``: the default mass model (tubes of the options' sections on every link). Stored as
benchmarks/results/cycle_dynamics.json; RESULTS.md's section is rebuilt from it.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = ("fivebar_pnp_cycle.yaml", "paper_2pauu_ppap.yaml", "pprs_rprs.yaml", "rps_upu.yaml", "rps_upu_tool.yaml",
           "ups_sspr.yaml", "delta.yaml", "linear_delta.yaml")
TARGET = 2.0


def one(config: str, n_designs: int, repeats: int) -> dict:
    from scalesynth.config import load_config
    from scalesynth.cycle import population
    from scalesynth.dynamics.config import DynamicsConfig

    cfg = load_config(ROOT / "configs" / config)
    rng = np.random.default_rng(0)
    base = cfg.resolved_design()
    designs = [{**base, **{k: float(base[k] + 0.01 * rng.uniform(-1.0, 1.0) * (hi - lo))
                           for k, (lo, hi) in cfg.bounds.items()}} for _ in range(n_designs)]
    options, cyc = cfg.resolved_options(), cfg.cycle.model_copy()
    modes = {"massless": DynamicsConfig(masses={}), "links": None}

    def run(dyn):
        cyc._dynamics = dyn
        t = time.process_time()
        out = population.population_metrics(cfg.mech, designs, options, cyc, cfg.units.length)
        return time.process_time() - t, out

    followed = {name: int(np.sum(run(dyn)[1]["cycle_min_clearance"] > -1e12)) for name, dyn in modes.items()}
    best = {name: np.inf for name in modes}
    for _ in range(repeats):
        for name, dyn in modes.items():
            best[name] = min(best[name], run(dyn)[0])
    ms = {name: round(1e3 * t / n_designs, 3) for name, t in best.items()}
    return {"config": config, "mechanism": cfg.mech.name, "samples": cyc.samples, "designs": n_designs,
            "followed": followed["links"], "massless_ms_per_design": ms["massless"],
            "links_ms_per_design": ms["links"], "ratio": round(best["links"] / best["massless"], 2)}


def bench_cycle_dynamics(n_designs: int = 4, repeats: int = 7) -> dict:
    import os

    rows = []
    for config in CONFIGS:
        rows.append(one(config, n_designs, repeats))
        print(rows[-1], flush=True)
    return {"designs": n_designs, "repeats": repeats, "target_ratio": TARGET,
            "numba_threads": os.environ.get("NUMBA_NUM_THREADS", "default"),
            "load_average_1min": round(os.getloadavg()[0], 1), "rows": rows}


def markdown(entry: dict) -> list[str]:
    r = entry["result"]
    out = [f"`population_metrics` of {r['designs']} designs near each config's own (all followed unless the table "
           f"says), best CPU time of {r['repeats']} alternated runs, NUMBA_NUM_THREADS={r['numba_threads']}, load "
           f"average {r['load_average_1min']}. `massless`: `dynamics.masses: {{}}` (the payload alone); `links`: the "
           "default tube links (virtual work, `scalesynth.dynamics.inverse`). Target: links <= "
           f"{r['target_ratio']:g}x massless per design.", "",
           "| mechanism | config | samples | followed | massless ms/design | links ms/design | ratio | target |",
           "|---|---|---|---|---|---|---|---|"]
    for w in r["rows"]:
        met = "met" if w["ratio"] <= r["target_ratio"] else "NOT met"
        out.append(f"| {w['mechanism']} | {w['config']} | {w['samples']} | {w['followed']}/{w['designs']} | "
                   f"{w['massless_ms_per_design']:.2f} | {w['links_ms_per_design']:.2f} | {w['ratio']:.2f}x | {met} |")
    return out + [""]


def main(argv: list[str]) -> None:
    n = int(argv[argv.index("--designs") + 1]) if "--designs" in argv else 4
    repeats = int(argv[argv.index("--repeats") + 1]) if "--repeats" in argv else 7
    print(bench_cycle_dynamics(n, repeats))


if __name__ == "__main__":
    main(sys.argv[1:])
