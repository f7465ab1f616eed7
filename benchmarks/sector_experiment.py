"""Issue 28 experiment: the sector evaluator (describe/sector.py) on the Delta against the uniform N = 192 grid.

    python benchmarks/sector_experiment.py [n_designs] [seed] [nphi,ns,nz,nscan,nbisect[,zmin] ...]

Random designs in configs/delta.yaml's bounds (SECTOR_CONFIG=linear_delta.yaml: another config's), its region; per setting (angles, radii, z-points,
scan steps, bisections; with zmin the z-points are those of an interval as long as the box's z-range, shorter ones
proportionally fewer but at least zmin, as SectorPlan's min_z_points; without, every interval nz): worst volume error (relative) and GCI error (absolute) as multiples of the paper tolerance (0.2 %, 5e-4),
kernel calls and CPU ms per design. The reference rows are cached in /tmp (keyed by seed and count).
"""

from __future__ import annotations

import math
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

import synthesis  # noqa: E402

TOL_V, TOL_G = 0.002, 0.0005


def reference(cfg, designs, seed, n=192):
    from scalesynth.evaluation.grid import make_grid

    path = Path(f"/tmp/h31p_ref_{cfg.name}_{seed}_{len(designs)}_{n}.npz")
    if path.exists():
        z = np.load(path)
        return z["vol"], z["gci"]
    mech, options, region = cfg.mech, cfg.resolved_options(), cfg.grid.region
    packed = np.stack([mech.pack(mech.resolve_design(d), options) for d in designs])
    vol, gci = [], []
    edges = np.asarray(cfg.dexterity.band_edges, dtype=float)
    for k, d in enumerate(designs):
        g = make_grid(mech, mech.resolve_design(d), options, n, region)
        st = mech.grid_stats(packed[k:k + 1], g.lo[None], g.step[None], g.shape, edges)
        c = st[0, 0]
        vol.append(c * g.cell_measure)
        gci.append(st[0, 1] / c if c > 0 else 0.0)
    np.savez(path, vol=np.array(vol), gci=np.array(gci))
    return np.array(vol), np.array(gci)


def sector(cfg, designs, nphi, ns, nz, nscan, nbisect, zmin=None, sector_deg=60.0):
    from scalesynth.evaluation.grid import design_boxes
    from scalesynth.evaluation.sector import gauss_tables
    from scalesynth.kernels.grid import stat_columns
    from scalesynth.mechanisms.describe import sector as sk

    mech, options, region = cfg.mech, cfg.resolved_options(), cfg.grid.region
    packed = np.stack([mech.pack(mech.resolve_design(d), options) for d in designs])
    lo, hi = design_boxes(mech, [mech.resolve_design(d) for d in designs], options, region)
    rmax = np.sqrt(np.maximum(lo[:, 0] ** 2, hi[:, 0] ** 2) + np.maximum(lo[:, 1] ** 2, hi[:, 1] ** 2))
    edges = np.asarray(cfg.dexterity.band_edges, dtype=float)
    xp, wp = np.polynomial.legendre.leggauss(nphi)
    xs, ws = np.polynomial.legendre.leggauss(ns)
    if zmin is None:  # every interval nz points (the first experiment's fixed rule)
        xz, wz = gauss_tables(nz)
        xz[:] = xz[nz]
        wz[:] = wz[nz]
        zmin = nz
    else:
        xz, wz = gauss_tables(nz)
    n = len(designs)
    rows = np.zeros((n, stat_columns(sk.N_FIELDS, len(edges) - 1)))  # every field the kernel writes
    calls = np.zeros(n, dtype=np.int64)
    cell = np.ones(n) * 1e-6
    phi1 = math.radians(sector_deg)
    t0 = time.process_time()
    sk.population_sector_stats(packed, 0.0, phi1, rmax, lo[:, 2], hi[:, 2], nscan, nbisect, xp, wp, xs, ws, xz, wz,
                               zmin, edges, cell, rows, calls)
    cpu = time.process_time() - t0
    factor = 2.0 * math.pi / phi1
    vol = rows[:, 0] * cell * factor
    gci = np.where(rows[:, 0] > 0, rows[:, 1] / np.where(rows[:, 0] > 0, rows[:, 0], 1), 0.0)
    return vol, gci, calls, cpu


def main(argv):
    from scalesynth.config import load_config

    n = int(argv[0]) if argv else 24
    seed = int(argv[1]) if len(argv) > 1 else 11
    cfg = load_config(ROOT / "configs" / os.environ.get("SECTOR_CONFIG", "delta.yaml"), [])
    designs = synthesis.random_designs(cfg, n, seed=seed)
    rv, rg = reference(cfg, designs, seed)
    sector(cfg, designs[:1], 4, 4, 2, 4, 4)  # compile
    settings = [tuple(int(v) for v in s.split(",")) for s in (argv[2:] or ["8,12,4,16,30", "12,16,4,16,30",
                                                                          "16,24,6,24,40"])]
    for setting in settings:
        nphi, ns, nz, nscan, nb = setting[:5]
        zmin = setting[5] if len(setting) > 5 else None
        vol, gci, calls, cpu = sector(cfg, designs, nphi, ns, nz, nscan, nb, zmin)
        ev = np.abs(vol - rv) / np.where(rv > 0, rv, 1.0)
        eg = np.abs(gci - rg)
        print(f"nphi {nphi} ns {ns} nz {nz} zmin {zmin} nscan {nscan} nbis {nb}: vol err max {ev.max() / TOL_V:.2f}x "
              f"(design {ev.argmax()}), gci err max {eg.max() / TOL_G:.2f}x (design {eg.argmax()}), "
              f"calls/design {calls.mean():.0f}, cpu ms/design {1e3 * cpu / n:.3f}")
        sys.stdout.flush()
    print("ref vol", np.round(rv, 4).tolist())
    print("ref gci", np.round(rg, 4).tolist())


if __name__ == "__main__":
    main(sys.argv[1:])
