"""A tour of scalesynth's Python API (docs/api.md); the tests run it (tests/test_docs.py).

Usage: python examples/api_tour.py [OUT_DIR]   (default: a new temporary directory)

1. evaluate one design of the seed-000 mechanism and get its per-voxel LCI array, drawn as a 3-D scatter plot;
2. run a small NSGA-II synthesis from the packaged `quick` example;
3. read the results directory back into pandas.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import yaml  # noqa: E402

import scalesynth as ss  # noqa: E402
from scalesynth import examples  # noqa: E402


def evaluate_one(out: Path) -> dict:
    """Workspace of Table-4 group 1 on a 32^3 grid, and a 3-D plot of the reachable voxels coloured by LCI."""
    report = ss.evaluate("2pauu-ppap", {"m": 0.857, "n": 0.706, "l1": 1.499, "l2": 1.5, "c": 0.1},
                         resolution=32, keep_grid=True)
    lci, grid = report.lci_grid, report.grid  # (32, 32, 32) array, -1 where unreachable
    x, y, z = np.meshgrid(grid.axis(0), grid.axis(1), grid.axis(2), indexing="ij")  # cell centres, m
    reach = lci >= 0
    fig = plt.figure(figsize=(6, 5))
    ax = fig.add_subplot(111, projection="3d")
    sc = ax.scatter(x[reach], y[reach], z[reach], c=lci[reach], s=2, cmap="viridis", vmin=0, vmax=1)
    fig.colorbar(sc, ax=ax, label="LCI")
    ax.set(xlabel="x [m]", ylabel="y [m]", zlabel="z [m]",
           title=f"{report.measure_key} = {report.measure:.2f}, GCI = {report.gci:.3f}")
    fig.savefig(out / "workspace_lci.png", dpi=90)
    plt.close(fig)
    return {"volume_m3": report.measure, "gci": report.gci, "reachable_voxels": int(reach.sum()),
            "mean_lci_of_voxels": float(lci[reach].mean())}


def small_synthesis(out: Path) -> ss.RunResult:
    """The packaged `quick` example, made smaller (8 generations of 16 designs on a 16^3 grid)."""
    data = yaml.safe_load(examples.text("quick"))
    data["grid"]["resolution"] = 16
    data["algorithm"].update(pop_size=16, n_gen=8)
    return ss.optimize(data, out / "quick", plots=False)


def read_results(run_dir: Path) -> dict:
    """The front and the history as pandas DataFrames, and a short summary of them."""
    result = ss.load_result(run_dir)
    front = result.pareto.sort_values("volume_m3")  # one row per non-dominated design
    best_gci = front.loc[front["gci"].idxmax()]
    return {"designs_on_front": len(front), "hypervolume": float(result.history["hypervolume"].iloc[-1]),
            "best_gci": float(best_gci["gci"]), "its_volume_m3": float(best_gci["volume_m3"]),
            "columns": list(front.columns)}


def main(argv: list[str]) -> dict:
    out = Path(argv[1]) if len(argv) > 1 else Path(tempfile.mkdtemp(prefix="scalesynth-tour-"))
    out.mkdir(parents=True, exist_ok=True)
    summary = {"evaluate": evaluate_one(out)}
    run = small_synthesis(out)
    summary["optimize"] = {"out_dir": str(run.out_dir), "status": run.manifest["status"]}
    summary["results"] = read_results(run.out_dir)
    for part, values in summary.items():
        print(part, values)
    return summary


if __name__ == "__main__":
    main(sys.argv)
