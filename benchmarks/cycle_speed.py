"""Cycle metrics per design: the fast path (vectorised cycle_kinematics, kernel clearance) against the reference
per-pose analysis (inverse_kinematics, velocity_map, link_geometry per sample), in one process.

Run: python benchmarks/cycle_speed.py [--designs 20]. For each config with a cycle: its own design (a followable
cycle: every step of the analysis runs), repeated ``--designs`` times, and ``--designs`` designs drawn uniformly from
the config's bounds (seed 0; those whose cycle cannot be followed stop early, in both paths alike: the optimiser
pays for them too), analysed both ways after one warm-up call (compilation excluded). Prints and writes
benchmarks/results/cycle_speed.json with the mean seconds per design and the ratios. RESULTS.md quotes it.
"""

from __future__ import annotations

import json
import os
import platform
import sys
import time
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = ("fivebar_pnp_cycle.yaml", "pprs_rprs.yaml", "paper_2pauu_ppap.yaml", "rps_upu.yaml", "rps_upu_tool.yaml",
           "ups_sspr.yaml")


def per_design(cfg, designs, reference: bool) -> float:
    from scalesynth.cycle import analysis
    from scalesynth.errors import ScalesynthError

    def one(d):
        try:
            analysis.analyse(cfg.mech, d, cfg.resolved_options(), cfg.cycle, cfg.units.length, reference=reference)
        except ScalesynthError:
            pass

    one(designs[0])  # warm-up: compile and load the kernels
    t0 = time.perf_counter()
    for d in designs:
        one(d)
    return (time.perf_counter() - t0) / len(designs)


def main(argv: list[str]) -> None:
    from scalesynth.config import load_config

    n = int(argv[argv.index("--designs") + 1]) if "--designs" in argv else 20
    rows = []
    for name in CONFIGS:
        cfg = load_config(ROOT / "configs" / name)
        rng = np.random.default_rng(0)
        base = cfg.resolved_design()
        designs = [{**base, **{k: float(rng.uniform(lo, hi)) for k, (lo, hi) in cfg.bounds.items()}} for _ in range(n)]
        row = {"config": name, "mechanism": cfg.mech.name, "samples": cfg.cycle.samples}
        for kind, ds in (("config_design", [base] * n), ("random_designs", designs)):
            fast = per_design(cfg, ds, reference=False)
            ref = per_design(cfg, ds, reference=True)
            row[kind] = {"reference_s": round(ref, 4), "fast_s": round(fast, 4), "ratio": round(ref / fast, 1)}
            print(f"{name:26s} {cfg.cycle.samples:4d} samples {kind:15s} reference {ref * 1e3:8.1f} ms  "
                  f"fast {fast * 1e3:7.1f} ms  x{ref / fast:.1f}", flush=True)
        rows.append(row)
    data = {"date": datetime.now(UTC).isoformat(timespec="minutes"),
            "machine": f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores",
            "numba_threads": os.environ.get("NUMBA_NUM_THREADS"), "designs": n, "rows": rows}
    out = ROOT / "benchmarks" / "results" / "cycle_speed.json"
    out.write_text(json.dumps(data, indent=2) + "\n")


if __name__ == "__main__":
    main(sys.argv[1:])
