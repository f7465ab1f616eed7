"""pprs-rprs: the 6 x 6 LCI kernel, one-sided Jacobi (A, the code before, kept as the fallback ``_jacobi_6x6``) against the certified Gram/Laguerre path
with its Jacobi fallback (B, ``pprs_rprs._sv_6x6``), in one process.

    NUMBA_NUM_THREADS=1 python benchmarks/pprs_lci_ab.py

Matrices: (a) 4000 random N(0, 1) 6 x 6; (b) 4000 with singular values exp(U(-7, 0)) (LCI down to 1e-3);
(c) the homogenised twist Jacobians (``PprsRprs.jacobians(...)["Js"]``) at the reachable nodes of a 12^3 grid
of each of the 20 random designs of ``benchmarks/adaptive.py`` (seed 0) and of the Table-1 design. Per set:
the largest relative LCI error of each variant against NumPy's SVD, then us per call (A and B alternating, best
of 7, each pass over the set 10 times) and the ratio A / B.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from numba import njit

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

from adaptive import design_set  # noqa: E402

from scalesynth.evaluate import make_grid  # noqa: E402
from scalesynth.kernels import grid as kgrid  # noqa: E402
from scalesynth.mechanisms.pprs_rprs import _jacobi_6x6 as jacobi_6x6  # noqa: E402
from scalesynth.mechanisms.pprs_rprs import _sv_6x6  # noqa: E402


@njit(cache=True)
def run_a(mats, reps):
    t = 0.0
    for _ in range(reps):
        for i in range(mats.shape[0]):
            t += jacobi_6x6(mats[i].copy())[0]  # the copy: A overwrites its input (as _conditioning's np.empty)
    return t


@njit(cache=True)
def run_b(mats, reps):
    t = 0.0
    for _ in range(reps):
        for i in range(mats.shape[0]):
            t += _sv_6x6(mats[i])[0]  # B allocates its own (16, 6) workspace (as _conditioning does)
    return t


def real_jacobians(n_grid: int = 12) -> np.ndarray:
    s = design_set("pprs-rprs")
    mech, opts = s.mech, s.options
    out = []
    for d in [mech.resolve_design({}), *s.designs]:
        g = make_grid(mech, d, opts, n_grid)
        lci = kgrid.sample_grid(mech.point_kernel, mech.pack(d, opts), g.lo, g.step, g.shape)
        for idx in np.argwhere(lci > 0):
            pose = np.concatenate([g.lo + (idx + 0.5) * g.step, opts["orientation"]])
            sols = {sol.label: sol.values for sol in mech.inverse_kinematics(d, opts, pose)}
            out.append(mech.jacobians(d, opts, pose, sols[opts["sigma"]])["Js"])
    return np.array(out)


def main() -> None:
    rng = np.random.default_rng(1)
    u, _, vt = np.linalg.svd(rng.normal(size=(4000, 6, 6)))
    sets = {
        "random N(0,1)": rng.normal(size=(4000, 6, 6)),
        "sigma exp(U(-7,0))": np.einsum("nij,nj,njk->nik", u, np.exp(rng.uniform(-7, 0, (4000, 6))), vt),
        "pprs-rprs Js": real_jacobians(),
    }
    for name, mats in sets.items():
        mats = np.ascontiguousarray(mats)
        sv = np.linalg.svd(mats, compute_uv=False)
        ref = sv[:, -1] / sv[:, 0]
        err_a = max(abs(jacobi_6x6(m.copy())[0] - r) / r for m, r in zip(mats, ref, strict=True))
        err_b = max(abs(_sv_6x6(m)[0] - r) / r for m, r in zip(mats, ref, strict=True))
        run_a(mats[:2], 1)
        run_b(mats[:2], 1)
        best = [np.inf, np.inf]
        reps = 10
        for _ in range(7):
            for k, f in enumerate((run_a, run_b)):
                t0 = time.perf_counter()
                f(mats, reps)
                best[k] = min(best[k], (time.perf_counter() - t0) / (reps * len(mats)) * 1e6)
        print(f"{name}: {len(mats)} matrices, LCI {ref.min():.2e}..{ref.max():.3f} ({np.mean(ref < 1e-3):.1%} below "
              f"1e-3); max rel error A {err_a:.1e}, B {err_b:.1e}; A {best[0]:.3f} us, B {best[1]:.3f} us, "
              f"A/B {best[0] / best[1]:.2f}x", flush=True)


if __name__ == "__main__":
    main()
