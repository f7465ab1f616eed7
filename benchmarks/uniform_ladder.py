"""Errors of a mechanism's uniform grids against the benchmark's 3x finer reference, on one set of random designs.

    python benchmarks/uniform_ladder.py MECH [SEED] [N ...] [--ref N_REF]

MECH as in ``benchmarks/adaptive.py`` (its config, ``random_designs(cfg, 20, seed=SEED)``, reference N = 3 x
``OLD_RESOLUTION``, or N_REF: tolerances tighter than the benchmark's need a finer one); prints, per N, the worst relative volume error, the worst absolute GCI error (every design,
slivers included) and the wall ms/design of ``Mechanism.grid_stats`` (default Numba threads). Used to check whether
a config's uniform resolution meets the tolerance on a second design set (seed 1), not only on the benchmark's.
"""

from __future__ import annotations

import sys

import numpy as np
from adaptive import CONFIGS, OLD_RESOLUTION, ROOT, errors, random_designs, uniform

from scalesynth.config import load_config


def main(argv: list[str]) -> None:
    n_ref = None
    if "--ref" in argv:
        i = argv.index("--ref")
        n_ref = int(argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
    name = argv[0]
    seed = int(argv[1]) if len(argv) > 1 else 0
    ladder = [int(a) for a in argv[2:]] or [24, 32, 40, 48, 56, 64, 72, 84, 112]
    cfg = load_config(ROOT / "configs" / CONFIGS[name])
    mech, options = cfg.mech, cfg.resolved_options()
    edges = np.asarray(cfg.dexterity.band_edges, dtype=float)
    designs = random_designs(cfg, 20, seed=seed)
    n_ref = n_ref or 3 * OLD_RESOLUTION[name]
    ref_vol, ref_gci, _ = uniform(mech, designs, options, n_ref, edges, cfg.grid.region)
    print(f"{name}, seed {seed}, 20 designs, reference N = {n_ref}")
    print("| N | max volume error | max GCI error | ms/design |")
    print("|---|---|---|---|")
    for n in ladder:
        vol, gci, sec = uniform(mech, designs, options, n, edges, cfg.grid.region)
        ev, eg = errors(vol, gci, ref_vol, ref_gci)
        print(f"| {n} | {100 * ev:.3f} % | {eg:.1e} | {1e3 * sec:.2f} |")


if __name__ == "__main__":
    main(sys.argv[1:])
