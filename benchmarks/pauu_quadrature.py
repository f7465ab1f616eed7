"""Issue 15, 2pauu-ppap: can a high-order quadrature beat the uniform fast path 10x at equal accuracy?

    python benchmarks/pauu_quadrature.py [--designs 20]

The budget. The fast path (pauu_ppap.population_stats_fast) at N = 56, the coarsest uniform grid meeting the
tolerance (volume 0.2 %, GCI 5e-4) on the benchmark's designs (benchmarks/adaptive.py), visits only the cells of
its columns' closed-form z-intervals, on the quarter box of its two mirror symmetries, vectorised. 10x fewer
points at the same cost per point is the 10x budget this script prints (the adaptive evaluator's per-point cost is
higher still: it is the 0.03x of RESULTS.md).

The candidate. The reachable set of a column (x, y) is |z - e| in [b_lo, b_hi], the intersection of the two
chains' annuli, so the workspace is integrated exactly piece by piece: y over the pieces between the heights where
the annuli's intersection changes shape (rho = sqrt(l2^2 - y^2) in {|d| - l1, l1, l1 +- |d|, |d|}, d = m - n), x
over the pieces between |d| -+ r_i, l1 rho / |d| and the outer end r_o - |d| (r_o, r_i = l1 +- rho), z over the two
lobes e +- [b_lo, b_hi]. Each piece is mapped by t^2 (3 - 2 t), which makes the square-root ends of the column
lengths and of the LCI smooth, and integrated by a Gauss-Legendre rule: the volume converges spectrally. With
``split``, each lobe is also cut where the LCI has a V-shaped zero inside it (the direct singularity: the
xz-projections of the two links parallel, located along the column by sign changes on 400 samples): the best case
for the z rule. The LCI comes from the NumPy field twin (tests/naive.py::pauu_fields).

Errors are against the same rule at high order (24, 24, 20 points, split), itself checked against the benchmark's
reference (the uniform N = 168 grid; and within 8.6e-5 in GCI of N = 336 on seed 0's designs): the results are in benchmarks/notes/uniform_plans.md.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from adaptive import design_set, uniform  # noqa: E402  (puts tests/ on the path)

from scalesynth.evaluate import make_grid  # noqa: E402

import naive  # noqa: E402

RULES = ((4, 4, 3, False), (6, 6, 5, False), (8, 8, 6, False), (4, 4, 3, True), (5, 5, 3, True), (6, 6, 4, True),
         (8, 8, 4, True), (16, 16, 12, True))
REFERENCE_RULE = (24, 24, 20, True)


def rule(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights on [0, 1] of the n-point Gauss-Legendre rule after t -> t^2 (3 - 2 t)."""
    t, w = np.polynomial.legendre.leggauss(n)
    t = 0.5 * (t + 1.0)
    return t * t * (3.0 - 2.0 * t), 0.5 * w * 6.0 * t * (1.0 - t)


def pieces(cuts, lo: float, hi: float) -> list[tuple[float, float]]:
    """The pieces of [lo, hi] between the finite ``cuts`` inside it."""
    c = np.unique(np.concatenate([[lo, hi], np.clip([v for v in cuts if np.isfinite(v)], lo, hi)]))
    return [(a, b) for a, b in zip(c[:-1], c[1:], strict=True) if b > a]


def xz_parallel(x: float, y: float, b: np.ndarray, delta: float, l1: float, l2: float) -> np.ndarray:
    """w1z w2x - w1x w2z along a column of the '++' mode: zero where the xz-projections of the links are parallel
    (the direct singularity, LCI 0), w_i = D_i - C_i as pauu_ppap._fields computes them."""
    ws = []
    for a in (x - delta, -x - delta):
        r2 = a * a + b * b
        kk = (r2 + y * y + l1 * l1 - l2 * l2) / (2.0 * l1)
        s = np.sqrt(np.maximum(r2 - kk * kk, 0.0))
        ws.append((a - l1 * (a * kk + b * s) / r2, b + l1 * (-b * kk + a * s) / r2))
    (w1x, w1z), (w2x, w2z) = ws
    return -w1z * w2x - w1x * w2z


def quadrature(design, options, ny: int, nx: int, nz: int, split: bool) -> tuple[float, float, int]:
    """(volume, GCI, LCI points) of one '++' design without limits by the piecewise Gauss rules (quarter box)."""
    delta = design["m"] - design["n"]
    dd = abs(delta)
    l1, l2, e = design["l1"], design["l2"], 2.0 * design["c"]
    (py, wy), (px, wx), (pz, wz) = rule(ny), rule(nx), rule(nz)
    ycuts = [np.sqrt(l2 * l2 - r * r) for r in (dd - l1, l1, l1 + dd, l1 - dd, dd) if 0.0 < r < l2]
    volume = 0.0
    xs, ys, zs, ws = [], [], [], []
    for ya, yb in pieces(ycuts, 0.0, l2):
        for y, w_y in zip(ya + (yb - ya) * py, (yb - ya) * wy, strict=True):
            rho = np.sqrt(max(l2 * l2 - y * y, 0.0))
            ro, ri = l1 + rho, abs(l1 - rho)
            if ro - dd <= 0.0:
                continue
            xcuts = [dd - ri, dd + ri] + ([l1 * rho / dd] if dd > 0.0 else [])
            for xa, xb in pieces(xcuts, 0.0, ro - dd):
                for x, w_x in zip(xa + (xb - xa) * px, (xb - xa) * wx, strict=True):
                    bh2 = ro * ro - (x + dd) ** 2
                    bl2 = max(0.0, ri * ri - (x - dd) ** 2)
                    if bh2 <= bl2:
                        continue
                    bh, bl = np.sqrt(bh2), np.sqrt(bl2)
                    volume += w_y * w_x * 2.0 * (bh - bl)
                    for sign in (1.0, -1.0):
                        cuts = [bl, bh]
                        if split:
                            b = sign * (bl + (bh - bl) * np.linspace(0.0, 1.0, 401)[1:-1])
                            f = xz_parallel(x, y, b, delta, l1, l2)
                            for i in np.flatnonzero(np.sign(f[:-1]) != np.sign(f[1:])):
                                cuts.append(abs(b[i] - f[i] * (b[i + 1] - b[i]) / (f[i + 1] - f[i])))
                        cuts = np.sort(cuts)
                        for ua, ub in zip(cuts[:-1], cuts[1:], strict=True):
                            zs.append(e + sign * (ua + (ub - ua) * pz))
                            xs.append(np.full(nz, x))
                            ys.append(np.full(nz, y))
                            ws.append(w_y * w_x * (ub - ua) * wz)
    if volume <= 0.0:
        return 0.0, 0.0, 0
    x, y, z, w = (np.concatenate(v) for v in (xs, ys, zs, ws))
    lci = naive.pauu_fields(design, options, x, y, z)[..., 0]
    return 4.0 * volume, float(np.sum(w * np.maximum(lci, 0.0))) / volume, x.size


def fast_path_cells(mech, design, options, n: int) -> int:
    """Cells the fast path evaluates for one design on the uniform n-grid: the cells of its quarter box's columns
    within their z-intervals widened by one cell (population_stats_fast's _k_range), the two lobes merged where
    they touch."""
    g = make_grid(mech, design, options, n)
    dd = abs(design["m"] - design["n"])
    l1, l2, e = design["l1"], design["l2"], 2.0 * design["c"]
    x = g.lo[0] + (np.arange(n // 2, n) + 0.5) * g.step[0]
    y = g.lo[1] + (np.arange(n // 2, n) + 0.5) * g.step[1]
    x, y = np.meshgrid(x, y, indexing="ij")
    rho = np.sqrt(np.maximum(l2 * l2 - y * y, 0.0))
    bh2 = (l1 + rho) ** 2 - (np.abs(x) + dd) ** 2
    bl2 = (l1 - rho) ** 2 - (np.abs(x) - dd) ** 2
    ok = (y * y < l2 * l2) & (bh2 >= 0.0) & (bl2 <= bh2)
    bh, bl = np.sqrt(np.maximum(bh2, 0.0)), np.sqrt(np.maximum(bl2, 0.0))

    def k_range(zlo, zhi):
        k0 = np.clip(np.floor((zlo - g.lo[2]) / g.step[2] - 0.5).astype(int) - 1, 0, None)
        k1 = np.clip(np.ceil((zhi - g.lo[2]) / g.step[2] - 0.5).astype(int) + 1, None, n - 1)
        return k0, k1

    ku0, ku1 = k_range(e + bl, e + bh)
    kl0, kl1 = k_range(e - bh, e - bl)
    merged = kl1 >= ku0 - 1
    cells = np.where(merged, ku1 - kl0 + 1, (ku1 - ku0 + 1) + (kl1 - kl0 + 1))
    return int(cells[ok].sum())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--designs", type=int, default=20)
    args = ap.parse_args()
    s = design_set("2pauu-ppap", args.designs)
    if s.options["mode"] != "++" or any(s.options[k] is not None for k in ("theta1_limits", "theta2_limits",
                                                                             "stroke_limits", "z_min")):
        raise SystemExit("pauu_quadrature: the rules cover the '++' mode without limits (the paper config)")
    ref = np.array([quadrature(d, s.options, *REFERENCE_RULE)[:2] for d in s.designs])
    uv, ug, _ = uniform(s.mech, s.designs, s.options, 168, s.edges, s.region)
    print(f"reference rule {REFERENCE_RULE} against the uniform N = 168: volume "
          f"{np.max(np.abs(ref[:, 0] / uv - 1)) * 100:.3f} %, GCI {np.max(np.abs(ref[:, 1] - ug)):.1e} (worst)")
    cells = np.array([fast_path_cells(s.mech, d, s.options, 56) for d in s.designs])
    print(f"fast path at N = 56: {cells.mean():.0f} cells/design (max {cells.max()}); the 10x budget: "
          f"{cells.mean() / 10:.0f} points/design")
    print("| rule (y, x, z points per piece) | z split at the direct singularity | LCI points/design, mean (max) | "
          "worst volume error | worst GCI error | designs outside the GCI tolerance |")
    print("|---|---|---|---|---|---|")
    for ny, nx, nz, split in RULES:
        res = [quadrature(d, s.options, ny, nx, nz, split) for d in s.designs]
        v = np.array([r[0] for r in res])
        g = np.array([r[1] for r in res])
        pts = np.array([r[2] for r in res])
        ev = np.abs(v / ref[:, 0] - 1.0)
        eg = np.abs(g - ref[:, 1])
        print(f"| {ny}, {nx}, {nz} | {'yes' if split else 'no'} | {pts.mean():.0f} ({pts.max()}) | "
              f"{100 * ev.max():.3f} % | {eg.max():.1e} | {int((eg > s.tol.gci).sum())} of {len(s.designs)} |",
              flush=True)


if __name__ == "__main__":
    main()
