"""Searched cycle metrics per design: the population path (``cycle.population.population_metrics``) against the
per-design loop of ``cycle.analysis.metrics`` it replaced, in one process.

Run: NUMBA_NUM_THREADS=2 python benchmarks/cycle_batch.py [--config configs/fivebar_pnp_cycle.yaml]
[--designs 200] [--repeats 7]. Draws the designs uniformly from the config's bounds (seed 0), warms both paths up
(compilation excluded), checks that both give the same arrays, then alternates the two ``--repeats`` times and
prints the median ms per design of each: the cycle metrics alone, and ``evaluate_config_population`` with each.
benchmarks/notes/cycle_batch.md quotes it.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def per_design_loop(mech, designs, options, cyc, length_unit):
    """The old path: analysis.metrics per design."""
    from scalesynth.cycle import analysis

    rows = [analysis.metrics(mech, d, options, cyc, length_unit) for d in designs]
    return {k: np.array([r.get(k, 0.0) for r in rows], dtype=float) for k in analysis.METRICS}


def main(argv: list[str]) -> None:
    from scalesynth.config import load_config
    from scalesynth.cycle import population
    from scalesynth.evaluate import evaluate_config_population

    path = argv[argv.index("--config") + 1] if "--config" in argv else str(ROOT / "configs" / "fivebar_pnp_cycle.yaml")
    n = int(argv[argv.index("--designs") + 1]) if "--designs" in argv else 200
    repeats = int(argv[argv.index("--repeats") + 1]) if "--repeats" in argv else 7
    cfg = load_config(path)
    rng = np.random.default_rng(0)
    base = cfg.resolved_design()
    designs = [{**base, **{k: float(rng.uniform(lo, hi)) for k, (lo, hi) in cfg.bounds.items()}} for _ in range(n)]
    args = (cfg.mech, designs, cfg.resolved_options(), cfg.cycle, cfg.units.length)
    batched = population.population_metrics
    paths = {"loop": per_design_loop, "population": batched}
    first = {name: f(*args) for name, f in paths.items()}  # warm-up and the equality check
    same = all(np.array_equal(first["loop"][k], first["population"][k]) for k in first["loop"])
    followed = int(np.sum(first["loop"]["cycle_min_clearance"] > -1e12))
    times = {f"{what} {name}": [] for what in ("cycle", "evaluate") for name in paths}
    for _ in range(repeats):
        for name, f in paths.items():
            t0 = time.perf_counter()
            f(*args)
            times[f"cycle {name}"].append((time.perf_counter() - t0) / n * 1e3)
        for name, f in paths.items():
            population.population_metrics = f  # metrics._cycle_values imports it at call time
            try:
                t0 = time.perf_counter()
                evaluate_config_population(cfg, designs)
                times[f"evaluate {name}"].append((time.perf_counter() - t0) / n * 1e3)
            finally:
                population.population_metrics = batched
    print(f"{Path(path).name}: {n} designs ({followed} followed), bit-identical: {same}, median of {repeats}")
    med = {k: statistics.median(v) for k, v in times.items()}
    for what in ("cycle", "evaluate"):
        loop, pop = med[f"{what} loop"], med[f"{what} population"]
        print(f"  {what:8s} loop {loop:7.3f} ms/design  population {pop:7.3f} ms/design  x{loop / pop:.1f}")


if __name__ == "__main__":
    main(sys.argv[1:])
