"""scalesynth benchmarks (plain Python; run from the repository root with the project's venv):

    python benchmarks/bench.py all          # everything below, then rewrite benchmarks/RESULTS.md
    python benchmarks/bench.py evaluator    # Numba vs NumPy twin throughput, same process (issue targets 1)
    python benchmarks/bench.py accuracy     # volume/GCI error of the paper config's resolution
    python benchmarks/bench.py paper        # the paper-scale synthesis in a fresh process: wall time, peak memory
    python benchmarks/bench.py growth       # time against N and against population size
    python benchmarks/bench.py compile      # JIT: first call (empty cache) vs second process (cache)
    python benchmarks/bench.py stiffness    # five-bar stiffness fields vs the kinematic fields alone, per voxel
    python benchmarks/bench.py fastpath     # seed 000's fast path: this tree vs a baseline git ref (default 2524d65)
    python benchmarks/bench.py compile_commands  # every CLI command per mechanism: second process compiles nothing
    python benchmarks/bench.py adaptive [MECH ...]  # adaptive evaluator vs uniform grids and its NumPy twin (merged)
    python benchmarks/bench.py adaptive_twin [MECH ...]  # the NumPy twin timing alone, merged into adaptive.json
    python benchmarks/bench.py synthesis [CONFIG.yaml ...]  # every config (or these, merged into the stored part):
                                            # ms/design, projected 200 x 200 NSGA-II loop, peak memory
    python benchmarks/bench.py task_accuracy  # configs with a task box: its uniform grid against a 3x finer one
    python benchmarks/bench.py show [--resolution 96] [--repeat 2]  # `scalesynth show`: wall, CPU, JIT s per process

Each part stores its numbers in benchmarks/results/<part>.json; RESULTS.md is rebuilt from all stored parts.
Speed targets are compared as ratios measured in one run; absolute times are stated with the machine.
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "benchmarks"))

import adaptive as adaptive_bench  # noqa: E402  (benchmarks/adaptive.py: issue-15 parts)
import compile_once  # noqa: E402  (benchmarks/compile_once.py: issue 15, compile once per command)
import cpu_target  # noqa: E402  (benchmarks/cpu_target.py: issue 27, what reproducible bits cost)
import cycle_dynamics  # noqa: E402  (benchmarks/cycle_dynamics.py: issue 29, link dynamics in the search)
import described  # noqa: E402  (benchmarks/described.py: issue 28, the described mechanisms' performance)
import show_speed  # noqa: E402  (benchmarks/show_speed.py: issue 14, show of a 3-D design)
import synthesis  # noqa: E402  (benchmarks/synthesis.py: issue 15, per-config paper-scale table and memory)
import task_accuracy  # noqa: E402  (benchmarks/task_accuracy.py: issue 15, the uniform task grids' accuracy)

from scalesynth.config import load_config  # noqa: E402
from scalesynth.evaluate import config_tolerance, evaluate_population, make_grid, uniform_resolution  # noqa: E402
from scalesynth.kernels import grid as kgrid  # noqa: E402
from scalesynth.mechanisms import get  # noqa: E402

from exact_volume import exact_volume  # noqa: E402
from naive import grid_metrics, grid_nodes, pauu_lci  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results"
PAPER = ROOT / "configs" / "paper_2pauu_ppap.yaml"
TABLE4 = [
    dict(m=0.857, n=0.706, l1=1.499, l2=1.5, c=0.1),
    dict(m=0.719, n=0.579, l1=1.499, l2=1.5, c=0.1),
    dict(m=0.516, n=0.342, l1=1.5, l2=1.5, c=0.1),
    dict(m=0.500, n=0.506, l1=1.5, l2=1.5, c=0.1),
    dict(m=0.509, n=0.339, l1=1.5, l2=1.5, c=0.1),
    dict(m=0.506, n=0.330, l1=1.5, l2=1.5, c=0.1),
]
EDGES = np.array([0.0, 0.1, 0.3, 1.0])
M = get("2pauu-ppap")


def machine() -> dict:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import numba

    return {"cpu": cpu, "cores": os.cpu_count(), "numba_threads": numba.get_num_threads(),
            "python": platform.python_version(), "numba": numba.__version__, "numpy": np.__version__}


def best_of(fn, repeat: int) -> float:
    fn()  # warm-up (compilation, caches)
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def bench_evaluator() -> dict:
    opts = M.resolve_options({})
    designs = [M.resolve_design(d) for d in TABLE4]
    packed = np.stack([M.pack(d, opts) for d in designs])
    rows = []
    for n in (64, 128):
        grids = [make_grid(M, d, opts, n) for d in designs]
        lo = np.stack([g.lo for g in grids])
        step = np.stack([g.step for g in grids])
        shape = grids[0].shape
        voxels = len(designs) * n**3
        t_fast = best_of(lambda: M.grid_stats(packed, lo, step, shape, EDGES), 5)  # noqa: B023
        t_generic = best_of(
            lambda: kgrid.population_stats(M.field_kernel, M.n_fields, packed, lo, step, shape, EDGES), 3  # noqa: B023
        )

        def numpy_twin():
            for d, g in zip(designs, grids, strict=True):  # noqa: B023
                X, Y, Z = grid_nodes(g.lo, g.step, g.shape)
                grid_metrics(pauu_lci(d, opts, X, Y, Z), g.cell_measure, EDGES)

        t_numpy = best_of(numpy_twin, 1)
        rows.append({
            "N": n, "designs": len(designs), "voxels": voxels,
            "numba_fast_s": t_fast, "numba_generic_s": t_generic, "numpy_s": t_numpy,
            "numba_fast_Mvox_s": voxels / t_fast / 1e6, "numba_generic_Mvox_s": voxels / t_generic / 1e6,
            "numpy_Mvox_s": voxels / t_numpy / 1e6, "ratio_fast_vs_numpy": t_numpy / t_fast,
            "ratio_generic_vs_numpy": t_numpy / t_generic,
        })
        print(f"N={n}: fast {voxels / t_fast / 1e6:.1f} Mvox/s, generic {voxels / t_generic / 1e6:.1f}, "
              f"numpy {voxels / t_numpy / 1e6:.3f}; fast/numpy = {t_numpy / t_fast:.0f}x", flush=True)
    return {"rows": rows}


def config_resolution(cfg) -> int | None:
    """The uniform grid a config's workspace runs: ``grid.resolution``, or with ``grid.tolerance`` the grid
    calibrated for it (2pauu-ppap, Mechanism.uniform_plan); None: the adaptive evaluator."""
    tolerance = config_tolerance(cfg)
    return cfg.grid.resolution if tolerance is None else uniform_resolution(cfg.mech, tolerance)


def bench_accuracy(n_random: int = 40) -> dict:
    cfg = load_config(PAPER)
    res = config_resolution(cfg)
    rng = np.random.default_rng(0)
    designs = [dict(d) for d in TABLE4]
    b = cfg.bounds
    for _ in range(n_random):
        designs.append({k: float(rng.uniform(*b[k])) for k in ("m", "n", "l1", "l2", "c")})
    coarse = evaluate_population(M, designs, resolution=res)
    fine = evaluate_population(M, designs, resolution=2 * res)
    exact = np.array([exact_volume(**d) for d in designs])
    vol_err = np.abs(coarse["volume_m3"] / exact - 1)
    gci_err = np.abs(coarse["gci"] - fine["gci"])
    out = {"resolution": res, "designs": len(designs), "max_volume_rel_error": float(vol_err.max()),
           "max_gci_abs_error_vs_2x": float(gci_err.max()),
           "table4_max_volume_rel_error": float(vol_err[:6].max()),
           "table4_max_gci_abs_error_vs_2x": float(gci_err[:6].max())}
    print(out, flush=True)
    return out


# Runs `python -m scalesynth ARGS` and writes the process's own peak RSS (VmHWM, kB) to $SCALESYNTH_BENCH_HWM when it
# ends. getrusage(RUSAGE_CHILDREN) / wait4 are not used: a child forked from this (by then large) benchmark process
# carries the parent's resident pages into its ru_maxrss before exec, which once reported 1.1 GiB for a 0.33 GiB run.
HWM_SNIPPET = """
import os, runpy, sys
sys.argv = ["scalesynth", *sys.argv[1:]]
try:
    runpy.run_module("scalesynth", run_name="__main__")
finally:
    hwm = next(line.split()[1] for line in open("/proc/self/status") if line.startswith("VmHWM:"))
    open(os.environ["SCALESYNTH_BENCH_HWM"], "w").write(hwm)
"""


def _run_subprocess(cmd: list[str], env: dict) -> tuple[float, float, subprocess.CompletedProcess]:
    """Run ``cmd`` (``[python, "-m", "scalesynth", ...]``); (wall s, the child's own peak RSS in MiB, process)."""
    assert cmd[1:3] == ["-m", "scalesynth"], cmd
    with tempfile.NamedTemporaryFile(suffix=".hwm") as hwm:
        t0 = time.perf_counter()
        proc = subprocess.run([cmd[0], "-c", HWM_SNIPPET, *cmd[3:]], env=dict(env, SCALESYNTH_BENCH_HWM=hwm.name),
                              capture_output=True, text=True)
        wall = time.perf_counter() - t0
        if proc.returncode != 0:
            raise RuntimeError(proc.stderr)
        peak_kib = float(Path(hwm.name).read_text())
    return wall, peak_kib / 1024.0, proc


def bench_paper() -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, MPLBACKEND="Agg", NUMBA_CACHE_DIR=str(Path(tmp) / "numba-cache"))
        out = Path(tmp) / "run"
        cmd = [sys.executable, "-m", "scalesynth", "optimize", str(PAPER), "--out", str(out), "--no-plots", "-q"]
        wall_cold, peak_cold, _ = _run_subprocess(cmd, env)
        manifest = json.loads((out / "manifest.json").read_text())
        result = {"command": "scalesynth optimize configs/paper_2pauu_ppap.yaml --no-plots -q",
                  "wall_s_cold_cache": wall_cold, "peak_rss_mib": peak_cold,
                  "loop_wall_s": manifest["wall_seconds"], "evaluations": manifest["evaluations"],
                  "resolution": config_resolution(load_config(PAPER)), "hypervolume": manifest["hypervolume"],
                  "pareto_size": manifest["pareto_size"]}
        out2 = Path(tmp) / "run2"
        cmd[cmd.index(str(out))] = str(out2)
        wall_warm, _, _ = _run_subprocess(cmd, env)
        result["wall_s_warm_cache"] = wall_warm
        result["byte_identical_rerun"] = (out / "pareto.csv").read_bytes() == (out2 / "pareto.csv").read_bytes()
    print(result, flush=True)
    return result


def bench_growth() -> dict:
    opts = M.resolve_options({})
    rng = np.random.default_rng(1)
    pool = [M.resolve_design({k: float(rng.uniform(*r)) for k, r in
                              dict(m=(0.5, 1.5), n=(0.2, 1), l1=(0.5, 1.5), l2=(0.5, 1.5), c=(0.1, 0.5)).items()})
            for _ in range(400)]

    def timed(designs, n):
        packed = np.stack([M.pack(d, opts) for d in designs])
        grids = [make_grid(M, d, opts, n) for d in designs]
        lo = np.stack([g.lo for g in grids])
        step = np.stack([g.step for g in grids])
        return best_of(lambda: M.grid_stats(packed, lo, step, grids[0].shape, EDGES), 3)

    by_n = [{"N": n, "seconds": timed(pool[:50], n)} for n in (32, 48, 64, 96, 128, 192)]
    by_pop = [{"designs": k, "seconds": timed(pool[:k], 64)} for k in (25, 50, 100, 200, 400)]
    slope_n = float(np.polyfit(np.log([r["N"] for r in by_n]), np.log([r["seconds"] for r in by_n]), 1)[0])
    slope_pop = float(np.polyfit(np.log([r["designs"] for r in by_pop]), np.log([r["seconds"] for r in by_pop]), 1)[0])
    out = {"by_N": by_n, "by_population": by_pop, "exponent_N": slope_n, "exponent_population": slope_pop}
    print(out, flush=True)
    return out


COMPILE_SNIPPET = """
import time
t0 = time.perf_counter()
from scalesynth.mechanisms import get
from scalesynth.evaluate import evaluate
t1 = time.perf_counter()
evaluate(get("2pauu-ppap"), {}, resolution=8)
t2 = time.perf_counter()
print(t1 - t0, t2 - t1)
"""


def bench_compile() -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, NUMBA_CACHE_DIR=str(Path(tmp) / "cache"))
        runs = []
        for _ in range(2):
            proc = subprocess.run([sys.executable, "-c", COMPILE_SNIPPET], env=env, capture_output=True, text=True)
            imp, first = (float(v) for v in proc.stdout.split())
            runs.append({"import_s": imp, "first_evaluate_s": first})
    out = {"empty_cache": runs[0], "cached": runs[1]}
    print(out, flush=True)
    return out


STIFFNESS_CASES = (  # (label, config, module.kernel of the kinematic part, kinematic slots, grid N per axis,
    # designs[, a flag option that switches the stiffness on: then `kinematic` is that kernel with it off, `full` with
    # it on]); `full` is the mechanism's field kernel
    ("planar-fivebar", "fivebar_stiffness.yaml", "planar_fivebar.kinematic_fields", 6, 256, 40),  # LCI, sigmas,
    # clearance (slot 5; the stiffness slots 3 and 4 written 0)
    ("ups-sspr", "ups_sspr.yaml", "ups_sspr.kinematic_fields", 6, 40, 20),  # the same (clearance slot 5)
    ("pprs-rprs", "pprs_rprs.yaml", "pprs_rprs.kinematic_fields", 4, 40, 20),  # kinematic: LCI, sigmas, clearance
    ("2pauu-ppap", "paper_2pauu_ppap.yaml", "pauu_ppap.point_fields", 6, 40, 20, "stiffness_metrics"),  # the same:
    # LCI, sigmas, clearance (the generic kernel, which the stiffness metrics need; the fast path computes neither)
    ("rps-upu", "rps_upu.yaml", "rps_upu.kinematic_fields", 4, 40, 20),  # LCI, sigmas, clearance
    ("rps-upu-tool", "rps_upu_tool.yaml", "rps_upu.tool_kinematic_fields", 4, 40, 20),  # the same
)


def bench_stiffness(repeat: int = 5) -> dict:
    """Per-voxel cost of the stiffness fields of every mechanism that has them per voxel: the full field kernel
    (LCI, sigma_min, sigma_max, clearance, stiffness_min, deflection) against the rest alone (``kinematic_fields``:
    every field but the stiffness), same designs, grids and process, timed alternately (best of ``repeat``)."""
    import importlib

    rows = []
    for label, config, kin_name, n_kin, n, n_designs, *flag in STIFFNESS_CASES:
        module, kernel = kin_name.rsplit(".", 1)
        kin_kernel = getattr(importlib.import_module(f"scalesynth.mechanisms.{module}"), kernel)
        cfg = load_config(ROOT / "configs" / config)
        mech, opts = cfg.mech, cfg.resolved_options()
        full_kernel = mech.field_kernel
        rng = np.random.default_rng(12)
        designs = [mech.resolve_design({k: float(rng.uniform(*cfg.bounds[k])) for k in cfg.bounds})
                   for _ in range(n_designs)]
        packed = np.stack([mech.pack(d, opts) for d in designs])
        packed_kin = packed
        if flag:
            on = mech.resolve_options({**cfg.options, flag[0]: True})
            packed_kin = np.stack([mech.pack(d, mech.resolve_options({**cfg.options, flag[0]: False}))
                                   for d in designs])
            packed = np.stack([mech.pack(d, on) for d in designs])
        grids = [make_grid(mech, d, opts, n) for d in designs]
        lo = np.stack([g.lo for g in grids])
        step = np.stack([g.step for g in grids])
        shape = grids[0].shape
        n_full = mech.n_fields

        def kinematic(kin_kernel=kin_kernel, n_kin=n_kin, packed=packed_kin, lo=lo, step=step, shape=shape):
            return kgrid.population_stats(kin_kernel, n_kin, packed, lo, step, shape, EDGES)

        def full(full_kernel=full_kernel, n_full=n_full, packed=packed, lo=lo, step=step, shape=shape):
            return kgrid.population_stats(full_kernel, n_full, packed, lo, step, shape, EDGES)

        kinematic()
        full()
        t_kin, t_full = [], []
        for _ in range(repeat):
            for fn, acc in ((kinematic, t_kin), (full, t_full)):
                t0 = time.perf_counter()
                fn()
                acc.append(time.perf_counter() - t0)
        voxels = n_designs * int(np.prod(shape))
        reachable = float(full()[:, 0].sum())
        row = {"load_average": os.getloadavg()[0], "mechanism": label, "config": config, "designs": n_designs, "N": n, "dims": len(mech.task_axes),
               "fields": n_full, "voxels": voxels, "reachable_voxels": reachable,
               "kinematic_s": min(t_kin), "full_s": min(t_full), "ratio": min(t_full) / min(t_kin),
               "ns_per_reachable_voxel_kinematic": 1e9 * min(t_kin) / reachable,
               "ns_per_reachable_voxel_full": 1e9 * min(t_full) / reachable}
        print(f"stiffness {label}: kinematic {row['kinematic_s']:.4f} s, with stiffness {row['full_s']:.4f} s, "
              f"ratio {row['ratio']:.2f}", flush=True)
        rows.append(row)
    return {"rows": rows}


# Throughput of seed 000's fast path (M.grid_stats) on the Table-4 designs, best of 7 after a warm-up, in CPU time
# of the process (one Numba thread: on a shared, loaded machine wall time measures the other jobs); run in a
# subprocess on either source tree (PYTHONPATH), so that the baseline and this tree are measured alike.
FASTPATH_SNIPPET = """
import json, time
import numpy as np
from scalesynth.evaluate import make_grid
from scalesynth.mechanisms import get
M = get("2pauu-ppap")
T4 = TABLE4_HERE
opts = M.resolve_options({})
designs = [M.resolve_design(d) for d in T4]
packed = np.stack([M.pack(d, opts) for d in designs])
edges = np.array([0.0, 0.1, 0.3, 1.0])
out = {}
for n in (64, 128):
    grids = [make_grid(M, d, opts, n) for d in designs]
    lo = np.stack([g.lo for g in grids]); step = np.stack([g.step for g in grids])
    M.grid_stats(packed, lo, step, grids[0].shape, edges)
    best = 1e9
    for _ in range(15):
        t0 = time.process_time(); M.grid_stats(packed, lo, step, grids[0].shape, edges)
        best = min(best, time.process_time() - t0)
    out[str(n)] = len(designs) * n ** 3 / best / 1e6
print(json.dumps(out))
""".replace("TABLE4_HERE", repr(TABLE4))


# Issue 10's reference for the fast path: 2524d65 is the last main commit before the multi-field merge (3e75d8e),
# the one-field (LCI only) fast path whose throughput the multi-field one must stay within 10 % of. "main" would
# compare the tree with itself once the multi-field kernels are merged.
FASTPATH_BASELINE = "2524d65"
MULTI_FIELD_DATE = "2026-12-01 16:51"  # commit date of 3e75d8e: parts measured earlier ran the one-field kernels


def bench_fastpath(baseline: str = FASTPATH_BASELINE, rounds: int = 3) -> dict:
    """Seed 000's fast path before (git ref ``baseline``) and after (this tree), alternating A/B subprocesses
    ``rounds`` times with NUMBA_NUM_THREADS=1 (a shared machine: one thread each, ratios in one run)."""
    load_before = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", baseline, "src"], capture_output=True, check=True)
        subprocess.run(["tar", "-x", "-C", tmp], input=archive.stdout, check=True)
        trees = {"baseline": Path(tmp) / "src", "this tree": ROOT / "src"}
        env = dict(os.environ, NUMBA_NUM_THREADS="1", NUMBA_CACHE_DIR=str(Path(tmp) / "cache"))
        best: dict[str, dict[str, float]] = {k: {} for k in trees}
        for _ in range(rounds):
            for label, src in trees.items():
                proc = subprocess.run([sys.executable, "-c", FASTPATH_SNIPPET], env=dict(env, PYTHONPATH=str(src)),
                                      capture_output=True, text=True, check=True)
                for n, rate in json.loads(proc.stdout).items():
                    best[label][n] = max(best[label].get(n, 0.0), rate)
    rows = [{"N": int(n), "baseline_Mvox_s": best["baseline"][n], "this_Mvox_s": best["this tree"][n],
             "ratio": best["this tree"][n] / best["baseline"][n]} for n in sorted(best["baseline"], key=int)]
    for r in rows:
        print(f"N={r['N']}: baseline {r['baseline_Mvox_s']:.1f} Mvox/s, this tree {r['this_Mvox_s']:.1f} "
              f"({100 * (r['ratio'] - 1):+.1f} %)", flush=True)
    return {"baseline": baseline, "rounds": rounds, "numba_threads": 1, "rows": rows,
            "load_average_1min": [load_before, os.getloadavg()[0]]}


PARTS = {"evaluator": bench_evaluator, "accuracy": bench_accuracy, "paper": bench_paper, "growth": bench_growth,
         "compile": bench_compile, "fastpath": bench_fastpath, "stiffness": bench_stiffness,
         "adaptive": adaptive_bench.bench_adaptive, "compile_all": adaptive_bench.bench_compile_all,
         "compile_commands": compile_once.bench_compile_commands, "synthesis": synthesis.bench_synthesis,
         "task_accuracy": task_accuracy.bench_task_accuracy, "show": show_speed.bench_show,
         "cpu_target": cpu_target.bench_cpu_target, "cycle_dynamics": cycle_dynamics.bench_cycle_dynamics,
         "described": described.bench_described}


def write_results_md() -> None:
    data = {}
    for name in PARTS:
        path = RESULTS / f"{name}.json"
        if path.exists():
            data[name] = json.loads(path.read_text())
    lines = ["# Benchmark results", "",
             "Rebuilt by `python benchmarks/bench.py all` (or one part: " + ", ".join(f"`{p}`" for p in PARTS) + ").",
             "Each section states the machine and date it was measured on.", ""]
    lines += _targets(data)
    lines += _issue15_summary(data)
    for part, title in (("compile_all", "Issue 15: compile once, per mechanism"),
                        ("adaptive", "Issue 15: adaptive evaluator against uniform grids at equal accuracy")):
        if part in data:
            lines += _header(title, data[part]) + adaptive_bench.markdown({part: data[part]})
    for part, title, module in (
            ("compile_commands", "Issue 15: compile once, every command of every mechanism", compile_once),
            ("synthesis", "Issue 15: every config at paper scale (200 x 200): time per design, NSGA-II loop, "
             "peak memory", synthesis),
            ("task_accuracy", "Issue 15: task boxes on their uniform grids: accuracy against a 3x finer grid",
             task_accuracy),
            ("show", "Issue 14: `scalesynth show` of a 3-D design at resolution 96 (target: within 10 s with a warm "
             "cache)", show_speed),
            ("cpu_target", "Issue 27: what reproducible bits cost (IEEE arithmetic, the pinned CPU target)",
             cpu_target),
            ("cycle_dynamics", "Issue 29: link dynamics in the search's cycle metrics (target: at most 2x massless)",
             cycle_dynamics),
            ("described", "Issue 28: described mechanisms (Delta, hexapod): calibrated accuracy, paper-scale search, "
             "voxels/s, first process, memory", described)):
        if part in data and "result" in data[part]:
            lines += _header(title, data[part]) + module.markdown(data[part])
    if "evaluator" in data:
        d = data["evaluator"]
        lines += _header("Evaluator throughput: Numba vs NumPy twin (same process, Table-4 designs)", d)
        lines += ["Grid-equivalent voxels per second (designs x N^3 / seconds). `numba fast` is the evaluator the",
                  "optimiser uses (column intervals + symmetry), `numba generic` the registry-wide point-kernel grid",
                  "evaluator, `numpy` the obvious vectorised NumPy code of `tests/naive.py` (np.linalg.svd per voxel).",
                  "", "| N | numba fast (Mvox/s) | numba generic (Mvox/s) | numpy (Mvox/s) | fast / numpy | generic / numpy |",
                  "|---|---|---|---|---|---|"]
        for r in d["result"]["rows"]:
            lines.append(f"| {r['N']} | {r['numba_fast_Mvox_s']:.1f} | {r['numba_generic_Mvox_s']:.1f} | "
                         f"{r['numpy_Mvox_s']:.3f} | {r['ratio_fast_vs_numpy']:.0f}x | {r['ratio_generic_vs_numpy']:.0f}x |")
        lines.append("")
    if "accuracy" in data:
        r = data["accuracy"]["result"]
        lines += _header("Accuracy of the paper config's resolution", data["accuracy"])
        lines += [f"Resolution {r['resolution']} on the six Table-4 designs and {r['designs'] - 6} random designs in the",
                  "paper's bounds: volume against the exact quadrature of spec §1.9, GCI against a 2x finer grid.", "",
                  "| | max volume error | max GCI error |", "|---|---|---|",
                  f"| Table-4 designs | {100 * r['table4_max_volume_rel_error']:.3f} % | {r['table4_max_gci_abs_error_vs_2x']:.5f} |",
                  f"| all {r['designs']} designs | {100 * r['max_volume_rel_error']:.3f} % | {r['max_gci_abs_error_vs_2x']:.5f} |",
                  ""]
    if "paper" in data:
        r = data["paper"]["result"]
        lines += _header("Paper-scale synthesis (population 200, 200 generations)", data["paper"])
        lines += [f"`{r['command']}` in a fresh process, resolution {r['resolution']}, {r['evaluations']} evaluations.", "",
                  "| | value |", "|---|---|",
                  f"| wall time, empty Numba cache (includes JIT compilation) | {r['wall_s_cold_cache']:.1f} s |",
                  f"| wall time, warm cache | {r['wall_s_warm_cache']:.1f} s |",
                  f"| NSGA-II loop alone (manifest wall_seconds) | {r['loop_wall_s']:.1f} s |",
                  f"| peak memory (max RSS) | {r['peak_rss_mib']:.0f} MiB |",
                  f"| final hypervolume | {r['hypervolume']:.6g} |",
                  f"| Pareto designs | {r['pareto_size']} |",
                  f"| re-run byte-identical pareto.csv | {r['byte_identical_rerun']} |", ""]
    if "growth" in data:
        r = data["growth"]["result"]
        lines += _header("Cost growth", data["growth"])
        lines += ["Fast evaluator, best of 3. Against N (50 random designs):", "", "| N | seconds | ns per grid cell and design |",
                  "|---|---|---|"]
        for row in r["by_N"]:
            lines.append(f"| {row['N']} | {row['seconds']:.4f} | {1e9 * row['seconds'] / row['N'] ** 3 / 50:.2f} |")
        lines += ["", f"Fitted exponent in N: **{r['exponent_N']:.2f}** (N^3 would be 3).", "",
                  "Against population size (N = 64):", "", "| designs | seconds | ms / design |", "|---|---|---|"]
        for row in r["by_population"]:
            lines.append(f"| {row['designs']} | {row['seconds']:.4f} | {1e3 * row['seconds'] / row['designs']:.2f} |")
        lines += ["", f"Fitted exponent in designs: **{r['exponent_population']:.2f}** (linear would be 1).", ""]
    if "compile" in data:
        r = data["compile"]["result"]
        lines += _header("JIT compilation", data["compile"])
        lines += ["Two fresh processes sharing one empty NUMBA_CACHE_DIR: the first compiles, the second loads the cache.",
                  "", "| process | import (s) | first evaluate, incl. compile or cache load (s) |", "|---|---|---|",
                  f"| first (empty cache) | {r['empty_cache']['import_s']:.2f} | {r['empty_cache']['first_evaluate_s']:.2f} |",
                  f"| second (cached) | {r['cached']['import_s']:.2f} | {r['cached']['first_evaluate_s']:.2f} |", ""]
    if "stiffness" in data:
        rows = _stiffness_rows(data["stiffness"]["result"])
        lines += _header("Per-voxel cost of the stiffness fields", data["stiffness"])
        lines += ["Random designs in the bounds of each config, N per axis grids over their bounding boxes, the generic",
                  "grid evaluator; best of 5, the two kernels timed alternately in one process. `kinematic` = LCI,",
                  "sigma_min, sigma_max, clearance (the field kernel without stiffness); `with stiffness` adds stiffness_min and",
                  "deflection (five-bar: closed-form per-leg condensation, 2x2 platform stiffness; ups-sspr: closed-form",
                  "per-chain condensation in the wrench form of `scalesynth.stiffness.legs`, 6x6 platform stiffness,",
                  "3x3 Schur complement; pprs-rprs: closed-form per-chain condensation; 2pauu-ppap: closed-form",
                  "per-chain condensation, 3x3 translational stiffness; rps-upu: closed-form per-leg condensation at",
                  "the constraint-consistent placement, rps-upu-tool with a Newton solve for that placement per voxel;",
                  "`kinematic` = every field but the stiffness, the clearance included: issue 12's target was stated",
                  "against the LCI alone, before every kernel gained the clearance field; the ratio is the stiffness's",
                  "increment over what the kernel computes without it).", "",
                  f"Conditions: NUMBA_NUM_THREADS=1 on the shared 2-core machine, load average {_load_text(rows)}, so",
                  "the absolute times are several times an idle machine's; the ratios come from one run.", "",
                  "| mechanism | designs x grid | kinematic (s) | with stiffness (s) | ns per reachable voxel, kinematic | "
                  "with stiffness | ratio |", "|---|---|---|---|---|---|---|"]
        for r in rows:
            grid = "x".join([str(r["N"])] * r.get("dims", 2))
            lines.append(f"| {r['mechanism']} | {r['designs']} x {grid} | {r['kinematic_s']:.4f} | {r['full_s']:.4f} | "
                         f"{r['ns_per_reachable_voxel_kinematic']:.1f} | {r['ns_per_reachable_voxel_full']:.1f} | "
                         f"**{r['ratio']:.2f}** |")
        lines += ["", "Target: ratio <= 3.", ""]
    if "fastpath" in data:
        r = data["fastpath"]["result"]
        lines += _header("Seed 000 fast path: before and after the multi-field kernels (issue 10)", data["fastpath"])
        lines += [f"`M.grid_stats` on the six Table-4 designs, best of 15 per process (CPU time), {r['rounds']} alternating",
                  f"processes per tree, NUMBA_NUM_THREADS={r['numba_threads']} for both (the machine was shared "
                  "with other jobs,", f"so one thread each; compare the ratio). Baseline: git ref `{r['baseline']}` "
                  "(LCI only); this tree: LCI, sigma_min and sigma_max through the shared accumulator."]
        if "load_average_1min" in r:
            lines.append("1-minute load average {:.1f} before, {:.1f} after the run.".format(*r["load_average_1min"]))
        lines += ["",
                  "| N | baseline (Mvox/s) | this tree (Mvox/s) | change |", "|---|---|---|---|"]
        for row in r["rows"]:
            lines.append(f"| {row['N']} | {row['baseline_Mvox_s']:.1f} | {row['this_Mvox_s']:.1f} | "
                         f"{100 * (row['ratio'] - 1):+.1f} % |")
        lines += ["", "The multi-field fast path first measured 14-17 % slower. Two changes closed the gap (statistics",
                  "rows bitwise unchanged): the accumulator reduces LCI, sigma_min, sigma_max and the first two band",
                  "edges in one loop, whose independent sums overlap (one pass per sum had waited on each sum's add",
                  "latency, since the sums are not reassociated), and the per-column pass that turns eigenvalues into",
                  "the three fields is branch-free again, so that LLVM vectorises it (its conditional expressions had",
                  "become branches the vectoriser gave up on: it ran scalar sqrt and division per cell).", ""]
        stale = [f"`{p}` ({data[p]['date']})" for p in ("evaluator", "paper", "growth")
                 if p in data and data[p]["date"] < MULTI_FIELD_DATE]
        if stale:
            lines += [f"Measured before the multi-field kernels ({MULTI_FIELD_DATE} UTC) and pending re-measurement "
                      "on an idle machine: " + ", ".join(stale) + ".", ""]
    # sections written by hand from standalone scripts (e.g. benchmarks/cycle_speed.py), kept verbatim
    for note in sorted((ROOT / "benchmarks" / "notes").glob("*.md")):
        lines += [note.read_text().rstrip("\n"), ""]
    (ROOT / "benchmarks" / "RESULTS.md").write_text("\n".join(lines) + "\n")


def _targets(data: dict) -> list[str]:
    """Issue targets against the stored measurements."""
    rows = []
    if "evaluator" in data:
        ev = data["evaluator"]["result"]["rows"]
        worst_ratio = min(r["ratio_fast_vs_numpy"] for r in ev)
        worst_rate = min(r["numba_fast_Mvox_s"] for r in ev)
        rows.append(("evaluator >= 200x the NumPy twin (N = 64, 128)", f"{worst_ratio:.0f}x (worst N)", worst_ratio >= 200))
        rows.append(("evaluator >= 200 M grid voxels/s on 2 threads", f"{worst_rate:.0f} M/s (worst N)", worst_rate >= 200))
    if "accuracy" in data:
        acc = data["accuracy"]["result"]
        ok = acc["max_volume_rel_error"] <= 0.005 and acc["max_gci_abs_error_vs_2x"] <= 0.002
        rows.append(("paper resolution: volume error <= 0.5 %, GCI error <= 0.002",
                     f"{100 * acc['max_volume_rel_error']:.2f} %, {acc['max_gci_abs_error_vs_2x']:.4f}", ok))
    if "paper" in data:
        pr = data["paper"]["result"]
        rows.append(("paper-scale run <= 60 s including JIT", f"{pr['wall_s_cold_cache']:.1f} s", pr["wall_s_cold_cache"] <= 60))
        rows.append(("paper-scale run peak memory <= 1 GiB", f"{pr['peak_rss_mib']:.0f} MiB", pr["peak_rss_mib"] <= 1024))
    if "growth" in data:
        gr = data["growth"]["result"]
        rows.append(("time grows no faster than N^3", f"exponent {gr['exponent_N']:.2f}", gr["exponent_N"] <= 3.05))
        rows.append(("time linear in designs", f"exponent {gr['exponent_population']:.2f}", gr["exponent_population"] <= 1.1))
    if "fastpath" in data:
        worst = min(row["ratio"] for row in data["fastpath"]["result"]["rows"])
        rows.append(("seed-000 fast path within 10 % of the baseline's throughput", f"{100 * (worst - 1):+.1f} % "
                     "(worst N)", worst >= 0.9))
    if "compile" in data:
        c = data["compile"]["result"]
        rows.append(("second process reuses compiled code", f"{c['empty_cache']['first_evaluate_s']:.1f} s -> "
                     f"{c['cached']['first_evaluate_s']:.2f} s", c["cached"]["first_evaluate_s"] < c["empty_cache"]["first_evaluate_s"] / 5))
    if "compile_commands" in data:
        mechs = data["compile_commands"]["result"]["mechanisms"]
        n2 = sum(r["round2"]["compiled"] for m in mechs for r in m["commands"])
        firsts = [next(r for r in m["commands"] if r["command"] == "evaluate")["round2"].get("first_grid_cpu_s")
                  for m in mechs]
        rows.append(("second process compiles nothing, every mechanism and command",
                     f"{n2} compilations in {sum(len(m['commands']) for m in mechs)} second processes", n2 == 0))
        if all(f is not None for f in firsts):
            rows.append(("second process reaches its first evaluation in < 1 s (CPU, from the process start), "
                         "every mechanism", f"{max(firsts):.2f} s CPU (worst)", max(firsts) < 1.0))
        others = [(r["round2"]["first_grid_cpu_s"], f"{m['mechanism']} {r['command']}") for m in mechs
                  for r in m["commands"] if r["round2"].get("first_grid_cpu_s") is not None]
        if others:
            rows.append(("... every command that evaluates, every mechanism", f"{max(others)[0]:.2f} s CPU (worst: "
                         f"{max(others)[1]})", max(others)[0] < 1.0))
    if "synthesis" in data:
        cfgs = [c for c in data["synthesis"]["result"]["configs"] if "error" not in c["loop"]]
        fast = [c["config"] for c in cfgs if c["loop"]["projected_loop_s"] <= synthesis.GOAL_LOOP_S]
        small = [c["config"] for c in cfgs if c["loop"]["peak_rss_mib"] <= synthesis.GOAL_PEAK_MIB]
        worst = max(c["loop"]["peak_rss_mib"] for c in cfgs) if cfgs else float("nan")
        n = len(data["synthesis"]["result"]["configs"])
        rows.append(("200 x 200 NSGA-II loop <= 30 s, every config (projected)", f"{len(fast)} of {n} configs",
                     len(fast) == n))
        rows.append(("paper-scale run peak memory <= 1 GiB, every config", f"{len(small)} of {n} configs "
                     f"(worst {worst:.0f} MiB)", len(small) == n))
    if "stiffness" in data:
        srows = _stiffness_rows(data["stiffness"]["result"])
        worst = max(r["ratio"] for r in srows)
        rows.append(("stiffness fields cost <= 3x the kinematic fields per voxel",
                     ", ".join(f"{r['mechanism']} {r['ratio']:.2f}x" for r in srows), worst <= 3))
    if not rows:
        return []
    out = ["## Targets", "", "| target | measured | met |", "|---|---|---|"]
    out += [f"| {t} | {m} | {'yes' if ok else 'NO'} |" for t, m, ok in rows]
    return out + [""]


def _src_commits_after(part: str, date: str) -> tuple[int, str] | None:
    """(non-merge commits touching src/ that HEAD has and the commit which first stored the measurement of ``date``
    in benchmarks/results/<part>.json has not, that commit's short hash): the source changes the measurement did
    not see, when it was committed with (or after) the tree it measured. None without git or when no commit has
    stored it yet (measured on the working tree)."""
    rel = f"benchmarks/results/{part}.json"

    def git(*args: str) -> str:
        return subprocess.run(["git", "-C", str(ROOT), *args], capture_output=True, text=True, check=True).stdout

    try:
        first = None
        for c in git("log", "--format=%h", "--", rel).split():  # newest first
            if date not in git("show", f"{c}:{rel}"):
                break
            first = c
        if first is None:
            return None
        return int(git("rev-list", "--count", "--no-merges", f"{first}..HEAD", "--", "src").strip()), first
    except (OSError, subprocess.CalledProcessError):
        return None


def _issue15_summary(data: dict) -> list[str]:
    """Issue 15's table per mechanism and config, from the stored adaptive, compile_commands (or compile_all) and
    synthesis parts; each cell from its part, which keeps its own date and machine (listed below the table)."""
    ad = {m["mechanism"]: m for m in data.get("adaptive", {}).get("result", {}).get("mechanisms", [])}
    syn = {c["config"]: c for c in data.get("synthesis", {}).get("result", {}).get("configs", [])}
    comp, comp_part = {}, None
    if "compile_commands" in data:
        comp_part = "compile_commands"
        for m in data["compile_commands"]["result"]["mechanisms"]:
            ev = next(r for r in m["commands"] if r["command"] == "evaluate")["round2"]
            comp[m["mechanism"]] = (m["first_process_compile_s"], ev.get("first_grid_s"), ev.get("first_grid_cpu_s"))
    elif "compile_all" in data:
        comp_part = "compile_all"
        for r in data["compile_all"]["result"]["rows"]:
            comp[r["mechanism"]] = (r["first_evaluation_s"], r["second_import_s"] + r["second_evaluation_s"], None)
    if not (ad or syn or comp):
        return []
    configs = sorted((ROOT / "configs").glob("*.yaml"))
    by_mech: dict[str, list[tuple[str, object]]] = {}
    for path in configs:
        cfg = load_config(path)
        by_mech.setdefault(cfg.mechanism, []).append((path.name, cfg))
    order = list(adaptive_bench.CONFIGS) + sorted(set(by_mech) - set(adaptive_bench.CONFIGS))
    yes = {True: "met", False: "**NOT met**"}
    out = ["## Issue 15: summary per mechanism", "",
           "One row per config in `configs/`, grouped by mechanism; the accuracy, equal-accuracy, NumPy-twin and compile "
           "columns are measured on the mechanism's benchmark config (the first row of each group; `-` on the others: "
           "not measured for that config). Every cell comes from the stored part named in its column; the parts were "
           "measured at different dates on shared 2-core machines (sources below the table, each with its Numba "
           "thread count); "
           "compare ratios within a part, not absolute times across parts. NumPy twin / Numba: the adaptive "
           "algorithm in NumPy (tests/naive.py::column_stats, vectorised over the active columns of a level, the "
           "fields by the NumPy field twins vectorised over all the points of a call: LCI, sigma_min and sigma_max, "
           "while the Numba kernel also computes the clearance and, where enabled, the stiffness fields) against the "
           "Numba kernel on the same designs, plan and tolerance, one thread each, wall time in one process; its rows "
           "(count, levels, field evaluations, error estimates, band measures, field statistics) are checked against "
           "the kernel's (adaptive section). No goal is stated for that ratio.", "",
           "| mechanism | config | evaluator (config now) | ms/design | accuracy vs 3x finer reference: volume, GCI "
           "(tolerance 0.2 %, 5e-4) | projected 200 x 200 NSGA-II loop (goal <= 30 s) | uniform at equal accuracy / "
           "adaptive, time (calls) (goal >= 10x) | NumPy twin / Numba (adaptive) | first-process compile s | second "
           "process to first evaluation, wall s (CPU s) (goal < 1 s CPU) |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    for mech in order:
        rows = by_mech.get(mech, [])
        bench_cfg = adaptive_bench.CONFIGS.get(mech)
        rows.sort(key=lambda r: r[0] != bench_cfg)
        a = ad.get(mech)
        for name, cfg in rows:
            label = synthesis.evaluator_label(cfg)
            adaptive_now = label.startswith("adaptive")
            s = syn.get(name)
            first = name == bench_cfg and a is not None
            # time per design: the config's evaluator now; a search that reads no workspace metric runs the
            # adaptive evaluator only for its final population, so its loop's cost is the synthesis part's
            from scalesynth.problem import SynthesisProblem

            problem = SynthesisProblem(cfg)
            searches_workspace = "workspace" in problem.searched_families
            full = (f"{1e3 * a['adaptive']['s_per_design']:.2f} (adaptive part: the evaluator with every field, "
                    "1 thread)") if adaptive_now and first and searches_workspace else None
            if s and s["evaluator"] == label:
                what = ("the searched task, path, design and cycle metrics" if not searches_workspace else
                        "the search's evaluation: the LCI's statistics alone" if problem.searched_fields is not None else
                        "the search's evaluation")
                ms = f"{1e3 * s['evaluation']['s_per_design']:.2f} (synthesis part: {what})"
                if full:
                    ms += f"; {full}"
            else:
                ms = full or "not measured"
            # accuracy of the config's evaluator (errors without slivers)
            acc = "-"
            if first and "volume_error_solid" in a["adaptive"]:
                tol, ad_row = a["tolerance"], a["adaptive"]
                ok = ad_row["volume_error_solid"] <= tol["volume"] and ad_row["gci_error_solid"] <= tol["gci"]
                adaptive_acc = (f"{100 * ad_row['volume_error_solid']:.3f} %, {ad_row['gci_error_solid']:.1e}: "
                                f"{yes[ok]} ({ad_row['designs_within_tolerance']} of {a['designs']} designs within it, "
                                "slivers included)")
                f = a.get("finer_check")
                if f:
                    adaptive_acc += (f"; the {len(f['designs'])} designs outside it against a uniform N = {f['N']}: "
                                     f"adaptive {100 * f['adaptive_volume_error']:.3f} %, "
                                     f"{f['adaptive_gci_error']:.1e}, the reference itself "
                                     f"{100 * f['reference_volume_error']:.3f} %, {f['reference_gci_error']:.1e}")
                    e = f.get("exact")
                    if e and "gci_columns" in e:
                        adaptive_acc += (f"; against the exact column volumes ({e['N_cross']}^2 columns) and the "
                                         f"GCI of {e['gci_columns']}^2 such columns: adaptive "
                                         f"{100 * e['adaptive_volume_error']:.3f} %, {e['adaptive_gci_error']:.1e}, "
                                         f"the reference {100 * e['reference_volume_error']:.3f} %, "
                                         f"{e['reference_gci_error']:.1e}: {yes[e['within']]} against them")
                    elif e:
                        adaptive_acc += (f"; their volume against the exact column volumes ({e['N_cross']}^2 "
                                         f"columns): adaptive {100 * e['adaptive_volume_error']:.3f} %, the reference "
                                         f"{100 * e['reference_volume_error']:.3f} %; with the GCI against "
                                         f"N = {f['N']}: {yes[e['within']]}")
                    elif "within" in f:
                        adaptive_acc += f": {yes[f['within']]} against it"
                if adaptive_now:
                    acc = adaptive_acc
                else:
                    eq, n = a.get("uniform_equal_accuracy_solid"), config_resolution(cfg)
                    if eq is None:
                        acc = (f"uniform N = {n}: {yes[False]} (no uniform grid below the reference N = "
                               f"{a['reference_N']} meets it)")
                    elif n < eq["N"]:
                        acc = f"uniform N = {n}: {yes[False]} (the coarsest uniform grid meeting it is N = {eq['N']})"
                    elif n == eq["N"]:
                        acc = (f"uniform N = {n}: {100 * eq['volume_error_solid']:.3f} %, {eq['gci_error_solid']:.1e}: {yes[True]}")
                    else:
                        acc = (f"{yes[True]} (N = {eq['N']}, coarser than N = {n}, meets it: "
                               f"{100 * eq['volume_error_solid']:.3f} %, {eq['gci_error_solid']:.1e})")
                    acc += f"; the adaptive evaluator (not the config's): {adaptive_acc}"
            # projected loop
            if s is None or "error" in s["loop"]:
                loop = "not measured"
            else:
                lp = s["loop"]
                loop = (f"{lp['projected_loop_s']:.0f} s ({lp['projected_loop_cpu_s']:.0f} s CPU): "
                        f"{yes[lp['projected_loop_s'] <= synthesis.GOAL_LOOP_S]}")
                if s["evaluator"] != label:
                    loop = f"{loop}, measured with {s['evaluator']}, before the config changed to " + (
                        "grid.tolerance" if adaptive_now else label)
                    if first and adaptive_now:
                        ev40 = a["adaptive"]["s_per_design"] * synthesis.PAPER_DESIGNS
                        loop += (f"; the adaptive evaluator alone x 40 000 designs: {ev40:.0f} s "
                                 f"({yes[False] if ev40 > synthesis.GOAL_LOOP_S else 'loop not measured'})")
            # equal accuracy and the NumPy twin (the benchmark config only)
            eqr = twin = "-"
            if first and "volume_error_solid" in a["adaptive"]:
                us, ar = a.get("uniform_equal_accuracy_solid"), a["adaptive"]
                if us is None:
                    t = a["reference_s_per_design"] / ar["s_per_design"]
                    c = a["reference_N"] ** a.get("ndim", 3) / ar["kernel_calls"]
                    eqr = (f">= {t:.1f}x (>= {c:.1f}x), a lower bound (no uniform grid below the reference N = "
                           f"{a['reference_N']} meets the tolerance): {'**NOT shown**' if t < 10 else 'met'}")
                else:
                    t = us["s_per_design"] / ar["s_per_design"]
                    eqr = f"{t:.2f}x ({us['kernel_calls'] / ar['kernel_calls']:.2f}x), N = {us['N']}: {yes[t >= 10]}"
                tw = a.get("numpy_twin")
                if tw is not None:
                    when = f", {tw['date']}" if tw.get("separate_run") else ""
                    twin = (f"**{tw['ratio']:.1f}x**: {1e3 * tw['twin_s_per_design']:.1f} against "
                            f"{1e3 * tw['kernel_s_per_design']:.2f} ms/design ({tw['designs']} designs{when}; rows "
                            f"{'agree' if tw['agree'] else 'DO NOT agree'})")
                elif "numpy_twin_s_per_design" in a:
                    twin = (f"{a['numpy_twin_s_per_design'] / a['adaptive_same_designs_s']:.0f}x (earlier unchecked "
                            "timing)")
                else:
                    twin = "not measured"
            cp = "-"
            sp = "-"
            if name == (bench_cfg or rows[0][0]) and mech in comp:
                c1, w2, c2 = comp[mech]
                cp = f"{c1:.1f}"
                if comp_part == "compile_commands" and w2 is not None:
                    sp = f"{w2:.2f} ({c2:.2f}): {yes[c2 < 1.0]}"
                elif w2 is not None:
                    sp = f"{w2:.2f} (imports included; CPU not recorded)"
            out.append(f"| {mech} | {name} | {label} | {ms} | {acc} | {loop} | {eqr} | {twin} | {cp} | {sp} |")
    why = [f"- {mech}: {text}" for mech, text in adaptive_bench.EQUAL_ACCURACY_NOTES.items()
           if mech in ad and "**NOT" in next((r for r in out if r.startswith(f"| {mech} |")), "")]
    if why:
        out += ["", "Equal accuracy not met, and why:", "", *why]
    out += ["", "Sources (each section below keeps its own machine, date and conditions):", ""]
    notes = {"adaptive": "accuracy (20 random designs, errors without slivers: reference measure below 1 % of the "
                         "median), adaptive ms/design, equal-accuracy ratio, NumPy twin",
             "compile_commands": "first-process compile seconds (every command, empty cache) and the second "
                                 "`evaluate` process's time to its first grid evaluation",
             "compile_all": "first-process and second-process times to the first evaluation",
             "synthesis": "uniform configs' ms/design (`evaluate_config_population`, 40 random designs) and the "
                          "projected 200 x 200 loop (population 200, 4 generations, plots and report)"}
    for part in ("adaptive", "compile_commands", "synthesis"):
        if part == "compile_commands" and comp_part == "compile_all":
            part = "compile_all"
        if part not in data:
            continue
        dates = [data[part]["date"]]
        twins = []
        if part == "adaptive":
            dates = sorted({m.get("date", data[part]["date"]) for m in ad.values()})
            twins = sorted({m["numpy_twin"]["date"] for m in ad.values() if m.get("numpy_twin", {}).get("date")})
        when = []
        for d in dates + twins:
            after = _src_commits_after(part, d)
            label = f"NumPy twin {d}" if d in twins else d
            plural = "s" if after and after[0] != 1 else ""
            when.append(f"{label} ({after[0]} commit{plural} to src/ after {after[1]}, which stored it: not "
                        f"re-measured after {'them' if plural else 'it'})" if after and after[0] else label)
        threads = data[part].get("machine", {}).get("numba_threads")
        on = f", {threads} Numba thread{'s' if threads != 1 else ''}" if threads is not None else ""
        out.append(f"- `{part}` ({notes[part]}): measured {'; '.join(when)}{on}.")
    return out + [""]


def _load_text(rows: list[dict]) -> str:
    loads = [r["load_average"] for r in rows if "load_average" in r]
    return f"{min(loads):.1f} to {max(loads):.1f}" if loads else "not recorded"


def _stiffness_rows(result: dict) -> list[dict]:
    """Rows of the stored stiffness part (a result stored before ups-sspr had fields is the five-bar's alone)."""
    if "rows" in result:
        return result["rows"]
    return [dict(result, mechanism="planar-fivebar", dims=2)]


def _header(title: str, entry: dict) -> list[str]:
    m = entry["machine"]
    return [f"## {title}", "",
            f"Measured {entry['date']} on {m['cpu']}, {m['cores']} cores, {m['numba_threads']} Numba threads, Python "
            f"{m['python']}, numba {m['numba']}, numpy {m['numpy']}. Command: `python benchmarks/bench.py "
            f"{entry['part']}`.", ""]


def main(argv: list[str]) -> None:
    if argv and argv[0] == "adaptive" and len(argv) > 1:  # adaptive MECH ...: a subset, merged into the stored part
        _run_part("adaptive", lambda: _merge_adaptive(adaptive_bench.bench_adaptive(argv[1:])))
        write_results_md()
        return
    if argv and argv[0] == "synthesis" and len(argv) > 1:  # synthesis CONFIG ...: rows merged into the stored part
        _merge_synthesis(synthesis.bench_synthesis([Path(a).name for a in argv[1:]]))
        write_results_md()
        return
    if argv and argv[0] == "cpu_target" and len(argv) > 1:  # cpu_target --before TREE: that tree timed too
        if argv[1:2] != ["--before"] or len(argv) != 3:
            raise SystemExit("usage: bench.py cpu_target [--before TREE]")
        _run_part("cpu_target", lambda: cpu_target.bench_cpu_target(3, argv[2]))
        write_results_md()
        return
    if argv and argv[0] == "show" and len(argv) > 1:  # show --resolution N --repeat K
        resolution, repeat = show_speed.parse_args(argv[1:])
        _run_part("show", lambda: show_speed.bench_show(resolution, repeat))
        write_results_md()
        return
    if argv and argv[0] == "adaptive_twin":  # the NumPy twin timing alone, merged into the stored adaptive rows
        _merge_twin(adaptive_bench.bench_twin(argv[1:]))
        write_results_md()
        return
    parts = list(PARTS) if not argv or argv[0] == "all" else argv
    for name in parts:
        if name not in PARTS:
            raise SystemExit(f"unknown part {name!r}; choose from all, {', '.join(PARTS)}")
    for name in parts:
        _run_part(name, PARTS[name])
    write_results_md()


def _run_part(name: str, fn) -> None:
    RESULTS.mkdir(parents=True, exist_ok=True)
    print(f"== {name}", flush=True)
    result = fn()
    entry = {"part": name, "date": datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"), "machine": machine(),
             "result": result}
    (RESULTS / f"{name}.json").write_text(json.dumps(entry, indent=2) + "\n")


def _merge_adaptive(new: dict) -> dict:
    """The stored adaptive rows with those of ``new`` replaced or added (per mechanism, config order)."""
    path = RESULTS / "adaptive.json"
    rows = {m["mechanism"]: m for m in (json.loads(path.read_text())["result"]["mechanisms"] if path.exists() else [])}
    rows.update({m["mechanism"]: m for m in new["mechanisms"]})
    return {"mechanisms": [rows[k] for k in adaptive_bench.CONFIGS if k in rows]}


def _merge_synthesis(new: dict) -> None:
    """Store the config rows of ``new`` (bench_synthesis on a subset) in the stored synthesis part, replacing those
    configs' rows, each with its own date, load, thread setting and machine; the other rows and the part's own
    date and load are kept."""
    path = RESULTS / "synthesis.json"
    if not path.exists():
        raise SystemExit("no stored synthesis part: run `python benchmarks/bench.py synthesis` first")
    entry = json.loads(path.read_text())
    when = {"date": datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"), "machine": machine(),
            **{k: new[k] for k in ("load_average_start", "load_average_end", "numba_threads_env")}}
    rows = {r["config"]: r for r in entry["result"]["configs"]}
    rows.update({r["config"]: dict(r, measured=when) for r in new["configs"]})
    entry["result"]["configs"] = [rows[k] for k in sorted(rows)]
    path.write_text(json.dumps(entry, indent=2) + "\n")


def _merge_twin(new: dict) -> None:
    """Store the twin timings of ``new`` (mechanism -> bench_twin row) in the stored adaptive rows of those
    mechanisms, each with its own date, load and machine; the rest of adaptive.json (its date included) is kept."""
    path = RESULTS / "adaptive.json"
    if not path.exists():
        raise SystemExit("no stored adaptive part: run `python benchmarks/bench.py adaptive` first")
    entry = json.loads(path.read_text())
    rows = {m["mechanism"]: m for m in entry["result"]["mechanisms"]}
    for name, twin in new.items():
        if name not in rows:
            print(f"{name}: no stored adaptive row; run `python benchmarks/bench.py adaptive {name}` (not merged)")
            continue
        rows[name]["numpy_twin"] = dict(twin, machine=machine())
        rows[name].pop("numpy_twin_s_per_design", None)  # the earlier unchecked timing
        rows[name].pop("adaptive_same_designs_s", None)
    path.write_text(json.dumps(entry, indent=2) + "\n")


if __name__ == "__main__":
    main(sys.argv[1:])
