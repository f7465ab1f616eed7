"""Issue 28 experiment: the sector evaluator (describe/sector.py) against the uniform N = 192 grid.

    python benchmarks/sector_experiment.py [n_designs] [seed] [nphi,ns,nz,nscan,nbisect[,zmin] ...]

Random designs in configs/delta.yaml's bounds (SECTOR_CONFIG=linear_delta.yaml: another config's), its region;
per setting (angles, radii, z-points, scan steps, bisections; with zmin the z-points are those of an interval as
long as the box's z-range, shorter ones proportionally fewer but at least zmin, as SectorPlan's min_z_points;
without, every interval nz): worst volume error (relative) and GCI error (absolute) as multiples of the paper
tolerance (0.2 %, 5e-4; SECTOR_TOL=V,G another), kernel calls and CPU ms per design. The reference rows are cached
in /tmp (keyed by config, seed and count). Environment:

* SECTOR_REF=tight: the reference is N = 192 over each design's own box (tight_box: the reachable set's extent)
  instead of its design box, which for a sliver is many times wider than the workspace; SECTOR_REF_N another N.
* SECTOR_SLIVERS=1 (the linear Delta): slivers (slivers()) instead of random designs.
* The linear Delta: each setting's volume also against the closed form (tests/naive_delta.linear_delta_volume).
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
sys.path.insert(0, str(ROOT / "tests"))  # naive_delta: the linear Delta's closed-form volume

import synthesis  # noqa: E402

# the paper tolerance; SECTOR_TOL=V,G another (e.g. configs/linear_delta.yaml's 0.01,0.002)
TOL_V, TOL_G = (float(v) for v in os.environ.get("SECTOR_TOL", "0.002,0.0005").split(","))


def _tag():
    return "_slivers" if os.environ.get("SECTOR_SLIVERS") else ""


def reference(cfg, designs, seed, n=192):
    from scalesynth.evaluation.grid import make_grid

    path = Path(f"/tmp/h31p_ref_{cfg.name}{_tag()}_{seed}_{len(designs)}_{n}.npz")
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


def tight_box(mech, p, lo, hi, n=512, grow=0.0):
    """The box of the reachable set found by the closed-form column intervals (kernel.column_intervals) on an
    n x n grid of columns over the design box's xy, grown by one column step and ``grow`` of its span on each
    side and, along z, the extremes of those columns' intervals (grown by 2 %): a sliver's workspace fills it (the design
    box of a sliver is many times wider than its workspace, so N cells per axis over it see few cells across it)."""
    from scalesynth.mechanisms.describe.kernel import column_intervals

    iv = np.empty((8, 2))
    sx, sy = (hi[0] - lo[0]) / n, (hi[1] - lo[1]) / n
    xs, ys = lo[0] + (np.arange(n + 1)) * sx, lo[1] + (np.arange(n + 1)) * sy
    box = [math.inf, -math.inf, math.inf, -math.inf, math.inf, -math.inf]
    for x in xs:
        for y in ys:
            k = column_intervals(p, x, y, lo[2], hi[2], iv)
            if k > 0:
                box = [min(box[0], x), max(box[1], x), min(box[2], y), max(box[3], y), min(box[4], iv[0, 0]),
                       max(box[5], iv[k - 1, 1])]
    if box[0] > box[1]:
        return None
    # z: the columns' extremes grown by 2 % of their span (the extremes between the sampled columns: a rim's
    # z varies as the square root of the distance to it, so a column step can miss a few mm)
    dz = 0.02 * (box[5] - box[4])
    # xy: grown by a step and by ``grow`` of the span found: a sharp tip (the corner between two discs' arcs)
    # reaches past the last column that hits it by more than a step
    dx, dy = sx + grow * (box[1] - box[0]), sy + grow * (box[3] - box[2])
    tlo = np.array([max(lo[0], box[0] - dx), max(lo[1], box[2] - dy), max(lo[2], box[4] - dz)])
    thi = np.array([min(hi[0], box[1] + dx), min(hi[1], box[3] + dy), min(hi[2], box[5] + dz)])
    return tlo, thi


def tight_reference(cfg, designs, seed, n=192):
    """reference() on each design's tight box (tight_box) instead of its design box: N = n cells per axis of the
    field kernel at cell centres (no intervals) over the reachable set's own extent."""
    from scalesynth.evaluation.grid import design_boxes

    path = Path(f"/tmp/h34lin_tight_{cfg.name}{_tag()}_{seed}_{len(designs)}_{n}.npz")
    if path.exists():
        z = np.load(path)
        return z["vol"], z["gci"]
    mech, options, region = cfg.mech, cfg.resolved_options(), cfg.grid.region
    resolved = [mech.resolve_design(d) for d in designs]
    packed = np.stack([mech.pack(d, options) for d in resolved])
    lo, hi = design_boxes(mech, resolved, options, region)
    edges = np.asarray(cfg.dexterity.band_edges, dtype=float)
    shape = np.array([n, n, n], dtype=np.int64)
    vol, gci = np.zeros(len(designs)), np.zeros(len(designs))
    for k in range(len(designs)):
        box = tight_box(mech, packed[k], lo[k], hi[k], grow=0.5) if np.all(hi[k, :3] > lo[k, :3]) else None
        if box is None:
            continue
        # again on the box found, over the design box's z: a sliver's extent to 1/512 of its width
        again = tight_box(mech, packed[k], np.append(box[0][:2], lo[k, 2]), np.append(box[1][:2], hi[k, 2]),
                          grow=0.05)
        box = again or box
        step = (box[1] - box[0]) / n
        st = mech.grid_stats(packed[k:k + 1], box[0][None], step[None], shape, edges)
        c = st[0, 0]
        vol[k] = c * float(np.prod(step))
        gci[k] = st[0, 1] / c if c > 0 else 0.0
    np.savez(path, vol=vol, gci=gci)
    return vol, gci


def linear_delta_volume(cfg, designs):
    """The linear Delta's volume by its closed form (tests/naive_delta.py: a double integral, n = 2000 on the box of
    the discs' intersection, a sliver's own), within the config's z-region."""
    from naive_delta import linear_delta_volume as closed_form

    zlim, options = cfg.grid.region["z"], cfg.resolved_options()
    return np.array([closed_form(d, options, zlim) for d in designs])


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


def slivers(cfg, n, seed):
    """n linear-Delta slivers: base_radius - platform_radius = a uniform in [0.3, 0.55] (the config's bounds) and
    forearm = a (1 + 10^u), u uniform in [-3, -1]: the workspace is nonempty iff forearm >= a, and just above it
    a thin prism about the axis (a curved triangle, corners at radius sqrt(l^2 - 3 a^2 / 4) - a / 2: about 1 mm to
    0.1 m across) the full stroke tall."""
    rng = np.random.default_rng(seed)
    base = cfg.resolved_design()
    out = []
    for _ in range(n):
        a, u = rng.uniform(0.3, 0.55), rng.uniform(-3.0, -1.0)
        out.append(dict(base, base_radius=a + base["platform_radius"], forearm=a * (1.0 + 10.0**u)))
    return out


def main(argv):
    from scalesynth.config import load_config

    n = int(argv[0]) if argv else 24
    seed = int(argv[1]) if len(argv) > 1 else 11
    cfg = load_config(ROOT / "configs" / os.environ.get("SECTOR_CONFIG", "delta.yaml"), [])
    designs = synthesis.random_designs(cfg, n, seed=seed)
    if os.environ.get("SECTOR_SLIVERS"):
        designs = slivers(cfg, n, seed)
    rv, rg = reference(cfg, designs, seed)
    if os.environ.get("SECTOR_REF") == "tight":  # the reference on each design's tight box (tight_box)
        box_v, box_g = rv, rg
        rv, rg = tight_reference(cfg, designs, seed, int(os.environ.get("SECTOR_REF_N", "192")))
        ev = np.abs(box_v - rv) / np.where(rv > 0, rv, 1.0)
        print(f"N = 192 on the design box against the tight box: volume {ev.max() / TOL_V:.2f}x "
              f"(design {ev.argmax()}), GCI {np.abs(box_g - rg).max() / TOL_G:.2f}x")
    exact = linear_delta_volume(cfg, designs) if cfg.mech.name == "linear-delta" else None
    if exact is not None:
        ev = np.abs(rv - exact) / np.where(exact > 0, exact, 1.0)
        print(f"reference against the closed-form volume: {ev.max() / TOL_V:.2f}x (design {ev.argmax()})")
    sector(cfg, designs[:1], 4, 4, 2, 4, 4)  # compile
    settings = [tuple(int(v) for v in s.split(",")) for s in (argv[2:] or ["8,12,4,16,30", "12,16,4,16,30",
                                                                          "16,24,6,24,40"])]
    for setting in settings:
        nphi, ns, nz, nscan, nb = setting[:5]
        zmin = setting[5] if len(setting) > 5 else None
        vol, gci, calls, cpu = sector(cfg, designs, nphi, ns, nz, nscan, nb, zmin)
        ev = np.abs(vol - rv) / np.where(rv > 0, rv, 1.0)
        eg = np.abs(gci - rg)
        if exact is not None:
            ec = np.abs(vol - exact) / np.where(exact > 0, exact, 1.0)
            print(f"  volume against the closed form: {ec.max() / TOL_V:.2f}x (design {ec.argmax()})")
        print(f"nphi {nphi} ns {ns} nz {nz} zmin {zmin} nscan {nscan} nbis {nb}: vol err max {ev.max() / TOL_V:.2f}x "
              f"(design {ev.argmax()}), gci err max {eg.max() / TOL_G:.2f}x (design {eg.argmax()}), "
              f"calls/design {calls.mean():.0f}, cpu ms/design {1e3 * cpu / n:.3f}")
        sys.stdout.flush()
    print("ref vol", np.round(rv, 4).tolist())
    print("ref gci", np.round(rg, 4).tolist())


if __name__ == "__main__":
    main(sys.argv[1:])
