"""Voxels per second of the described 2T kernel template (describe/kernel2.py) against the hand-written five-bar
kernel (mechanisms/planar_fivebar.py) on the same grids, and against the NumPy twin (tests/naive_planar.py).

Usage: NUMBA_NUM_THREADS=1 python benchmarks/planar_template.py [N] [DESIGNS]   (default 256 x 256, 40 designs)

The same random designs (the fivebar_packing config's bounds, elbows out, the spec's corrected arm limits), the same
N x N grid over each design's box, population_stats (the evaluator's accumulator) with: the described kernel (LCI,
sigma_min, sigma_max; its LCI kernel point_lci), the described field kernel with its stiffness and clearance fields
off, with each on and with both (options.stiffness_metrics, clearance_metrics), the hand kernel's kinematic_fields
(those three plus the clearance) and its full point_fields (plus stiffness and deflection). Best of 3 after a compile
run; ratios are of one run.
"""

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import naive_planar  # noqa: E402
from scalesynth.kernels import grid as kgrid  # noqa: E402
from scalesynth.mechanisms import get  # noqa: E402
from scalesynth.mechanisms import planar_fivebar as pf  # noqa: E402

LIMITS = {"alpha1_limits": [-1.3962634015954636, 0.6108652381980153],
          "alpha2_limits": [2.530727415391778, 4.537856055185257]}


def best_of(fn, repeat=3):
    fn()
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def main(argv):
    n = int(argv[1]) if len(argv) > 1 else 256
    k = int(argv[2]) if len(argv) > 2 else 40
    hand, desc = get("planar-fivebar"), get("planar-fivebar-described")
    rng = np.random.default_rng(1)
    designs = [hand.resolve_design({"r": rng.uniform(50, 400), "l1": rng.uniform(250, 800),
                                    "l2": rng.uniform(500, 1400)}) for _ in range(k)]
    ho, do = hand.resolve_options({**LIMITS, "mode": "+-"}), desc.resolve_options(LIMITS)
    boxes = [hand.bounding_box(d, ho) for d in designs]
    lo = np.array([b[0] for b in boxes])
    shape = np.array([n, n, 1], dtype=np.int64)
    step = np.array([np.r_[(b[1][:2] - b[0][:2]) / n, 1.0] for b in boxes])
    edges = np.array([0.0, 0.1, 0.3, 1.0])
    ph = np.array([hand.pack(d, ho) for d in designs])
    pd = np.array([desc.pack(d, do) for d in designs])
    stiff = desc.resolve_options({**LIMITS, "stiffness_metrics": True})
    clear = desc.resolve_options({**LIMITS, "clearance_metrics": True})
    both = desc.resolve_options({**LIMITS, "stiffness_metrics": True, "clearance_metrics": True})
    ps, pc, pb = (np.array([desc.pack(d, o) for d in designs]) for o in (stiff, clear, both))
    nf = desc.n_fields
    runs = {
        "described (3 fields)": lambda: kgrid.population_stats(desc.lci_kernel, 3, pd, lo, step, shape, edges),
        "described, fields off": lambda: kgrid.population_stats(desc.field_kernel, nf, pd, lo, step, shape, edges),
        "described + stiffness": lambda: kgrid.population_stats(desc.field_kernel, nf, ps, lo, step, shape, edges),
        "described + clearance": lambda: kgrid.population_stats(desc.field_kernel, nf, pc, lo, step, shape, edges),
        "described, all 6": lambda: kgrid.population_stats(desc.field_kernel, nf, pb, lo, step, shape, edges),
        "hand kinematic_fields": lambda: kgrid.population_stats(pf.kinematic_fields, 6, ph, lo, step, shape, edges),
        "hand point_fields (6)": lambda: kgrid.population_stats(hand.field_kernel, 6, ph, lo, step, shape, edges),
    }
    voxels = k * n * n
    rates = {name: voxels / best_of(fn) / 1e6 for name, fn in runs.items()}
    # NumPy twin: one design, a 64 x 64 grid (it is slow)
    d = designs[0]
    r, l1, l2 = d["r"], d["l1"], d["l2"]
    legs = [{"type": "RR", "base": (r, 0.0), "arm": l1, "link": l2, "sigma": 1.0, "limits": LIMITS["alpha1_limits"]},
            {"type": "RR", "base": (-r, 0.0), "arm": l1, "link": l2, "sigma": -1.0,
             "limits": LIMITS["alpha2_limits"]}]
    m = 64
    xs = lo[0, 0] + (np.arange(m) + 0.5) * (boxes[0][1][0] - boxes[0][0][0]) / m
    ys = lo[0, 1] + (np.arange(m) + 0.5) * (boxes[0][1][1] - boxes[0][0][1]) / m
    pts = np.array([(x, y) for x in xs for y in ys])
    t = time.perf_counter()
    naive_planar.fields(legs, pts)
    rates["numpy twin"] = len(pts) / (time.perf_counter() - t) / 1e6
    base = rates["described (3 fields)"]
    for name, rate in rates.items():
        print(f"{name:24s} {rate:9.2f} Mvox/s {1e3 / rate:8.1f} ns/voxel   described / this = {base / rate:6.2f}")


if __name__ == "__main__":
    main(sys.argv)
