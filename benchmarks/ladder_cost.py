"""What the calibration ladder's z-confirmations cost (issue 28): ``calibrated_population_stats`` of 12 random designs
within a config's bounds (seed 3), at the config's tolerance, with one and with two z-confirmations per rung,
alternating, in this process (one Numba thread recommended: NUMBA_NUM_THREADS=1).

    python benchmarks/ladder_cost.py hexapod hexa              # configs/<name>.yaml, their own tolerance
    python benchmarks/ladder_cost.py --tight delta             # at volume 0.2 %, GCI 5e-4

The ladder uses two confirmations only where the columns run on nodes (no interval kernel): the one-confirmation
runs here patch ``calibration.NODE_ZCONFIRM``. Figures: benchmarks/notes/ladder_node_confirmations.md.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from scalesynth import calibration
from scalesynth.config import load_config
from scalesynth.evaluation.plans import Tolerance
from scalesynth.mechanisms import get

ROOT = Path(__file__).resolve().parents[1]
N_DESIGNS = 12


def bench(config: str, tight: bool) -> None:
    cfg = load_config(ROOT / "configs" / f"{config}.yaml",
                      ["grid.tolerance.volume=0.002", "grid.tolerance.gci=0.0005"] if tight else None)
    mech, base, options = get(cfg.mechanism), cfg.resolved_design(), cfg.resolved_options()
    rng = np.random.default_rng(3)
    designs = [{**base, **{k: float(rng.uniform(b[0], b[1])) for k, b in cfg.bounds.items()}}
               for _ in range(N_DESIGNS)]
    packed = np.stack([mech.pack(d, options) for d in designs])
    tolerance = Tolerance(cfg.grid.tolerance.volume, cfg.grid.tolerance.gci)
    nodes = mech.interval_kernel_for(options) is None
    default = calibration.NODE_ZCONFIRM

    def run(confirmations: int):
        calibration.NODE_ZCONFIRM = confirmations
        try:
            t = time.process_time()
            r = calibration.calibrated_population_stats(mech, designs, options, packed, tolerance,
                                                        np.array([0.0, 0.2, 0.5, 1.0]), cfg.grid.region)
            return time.process_time() - t, r
        finally:
            calibration.NODE_ZCONFIRM = default

    run(default)  # compile
    print(f"{config} ({mech.name}, tolerance {tolerance.volume}, {tolerance.gci}; node columns: {nodes})")
    for confirmations in (1, 2, 1, 2):
        t, r = run(confirmations)
        print(f"  z-confirmations {confirmations}: {1e3 * t / N_DESIGNS:.1f} ms/design CPU, "
              f"{r.evaluations.mean():.0f} kernel calls/design, accepted at rungs {np.bincount(r.levels).tolist()}",
              flush=True)


if __name__ == "__main__":
    args = sys.argv[1:]
    tight = "--tight" in args
    names = [a for a in args if a != "--tight"]
    if not names:
        raise SystemExit("usage: python benchmarks/ladder_cost.py [--tight] CONFIG ...")
    for name in names:
        bench(name, tight)
