"""Issue 15, every mechanism at paper scale: time per design of each config's evaluator, the NSGA-II loop of a
short run at population 200 projected to 40 000 designs (200 x 200), and the peak memory of that run.

    python benchmarks/bench.py synthesis [CONFIG.yaml ...]     # default: every config in configs/

Per config:

* evaluator: ``evaluate_config_population`` for the searched families and fields (exactly what the NSGA-II loop
  calls per generation, SynthesisProblem.metrics: the workspace grid or, with ``grid.tolerance``, the adaptive
  evaluator, when a workspace metric is searched, with the mechanism's LCI kernel when those metrics are the LCI's
  alone; task box, path, design and cycle metrics when one of theirs is) on ``N_DESIGNS`` random designs within the
  bounds in one call, in this process after a warm-up; seconds per design.
* NSGA-II: ``scalesynth optimize`` in a fresh process (tests-free snippet below) with ``algorithm.pop_size=200``
  and ``GENERATIONS`` generations, plots and report included (what a user runs); per generation it records the
  loop's wall and CPU seconds and the process's current and peak RSS, so the table shows whether memory grows
  with generations. Projection of the 200-generation loop: wall seconds per evaluation from generation 2 on
  (generation 1 includes the initial population's sampling) x 40 000.
* peak memory: the process's own peak RSS (VmHWM, read by the child at its end: the whole run, imports, kernels,
  the loop, plots). Not wait4/getrusage: their ru_maxrss includes the pages of this (large, by then) benchmark
  process that the child carries across fork until exec.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CONFIG_DIR = ROOT / "configs"
N_DESIGNS = 40
POP = 200
GENERATIONS = 4
PAPER_DESIGNS = 40_000
GOAL_LOOP_S = 30.0
GOAL_PEAK_MIB = 1024.0

RUN_SNIPPET = """
import json, sys, time
from pathlib import Path
from scalesynth.config import load_config
from scalesynth import optimize

def rss_mib():
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * 4096 / 2**20

def hwm_mib():  # this process's own peak RSS since exec (getrusage would include the forked parent's pages)
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) for line in fh if line.startswith("VmHWM:")) / 1024

cfg = load_config(sys.argv[1], sys.argv[3:])
marks = []
def progress(row):
    marks.append({"generation": row["generation"], "evaluations": row["evaluations"], "wall": time.perf_counter(),
                  "cpu": time.process_time(), "rss_mib": rss_mib(),
                  "peak_mib": hwm_mib()})
res = optimize.run(cfg, Path(sys.argv[2]), progress=progress)
print(json.dumps({"marks": marks, "loop_s": res.manifest["wall_seconds"], "evaluations": res.manifest["evaluations"],
                  "peak_after_plots_mib": hwm_mib()}))
"""


def random_designs(cfg, n: int, seed: int = 0) -> list[dict[str, float]]:
    rng = np.random.default_rng(seed)
    base = cfg.resolved_design()
    out = []
    for _ in range(n):
        d = dict(base)
        d.update({k: float(rng.uniform(lo, hi)) for k, (lo, hi) in cfg.bounds.items()})
        out.append(d)
    return out


def evaluator_label(cfg) -> str:
    """'adaptive, tolerance ...', 'calibrated uniform N = n, tolerance ...' (the tolerance form on a mechanism's
    calibrated grid, Mechanism.uniform_plan) or 'uniform N = n'."""
    from scalesynth.evaluate import config_tolerance, uniform_resolution

    tol = config_tolerance(cfg)
    if tol is not None:
        n = uniform_resolution(cfg.mech, tol)
        if n is not None:
            return f"calibrated uniform N = {n}, tolerance volume {tol.volume:g}, GCI {tol.gci:g}"
        return f"adaptive, tolerance volume {tol.volume:g}, GCI {tol.gci:g}"
    return f"uniform N = {cfg.grid.resolution}"


def time_evaluator(cfg) -> dict:
    """What the NSGA-II loop calls per generation: the searched families' metrics (SynthesisProblem.metrics)."""
    from scalesynth.evaluate import evaluate_config_population
    from scalesynth.problem import SynthesisProblem

    problem = SynthesisProblem(cfg)
    families, fields = problem.searched_families, problem.searched_fields
    designs = random_designs(cfg, N_DESIGNS)
    evaluate_config_population(cfg, designs[:2], families, fields)  # compile or load the kernels
    best = float("inf")
    cpu = float("inf")
    for _ in range(2):
        t0, c0 = time.perf_counter(), time.process_time()
        evaluate_config_population(cfg, designs, families, fields)
        best = min(best, time.perf_counter() - t0)
        cpu = min(cpu, time.process_time() - c0)
    return {"designs": N_DESIGNS, "s_per_design": best / N_DESIGNS, "cpu_s_per_design": cpu / N_DESIGNS}


def run_child(cmd: list[str], env: dict) -> tuple[subprocess.CompletedProcess, float, float]:
    """Run ``cmd``; (completed process, peak RSS in MiB from wait4, CPU seconds of the child)."""
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        proc = subprocess.Popen(cmd, env=env, stdout=out, stderr=err, text=True, cwd=ROOT)
        _, status, usage = os.wait4(proc.pid, 0)
        proc.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        done = subprocess.CompletedProcess(cmd, proc.returncode, out.read(), err.read())
    return done, usage.ru_maxrss / 1024.0, usage.ru_utime + usage.ru_stime


def time_loop(config: Path, env: dict, tmp: Path) -> dict:
    sets = [f"algorithm.pop_size={POP}", f"algorithm.n_gen={GENERATIONS}", "output.checkpoint_every=1000"]
    # warm-up: a tiny run with plots fills the Numba cache for every kernel the measured run uses
    run_child([sys.executable, "-c", RUN_SNIPPET, str(config), str(tmp / "warm"), "algorithm.pop_size=8",
               "algorithm.n_gen=1"], env)
    proc, _wait4_peak, cpu = run_child([sys.executable, "-c", RUN_SNIPPET, str(config), str(tmp / "run"), *sets], env)
    if proc.returncode:
        return {"error": proc.stderr.strip().splitlines()[-1] if proc.stderr.strip() else f"exit {proc.returncode}"}
    r = json.loads(proc.stdout.strip().splitlines()[-1])
    marks = r["marks"]
    first, last = marks[0], marks[-1]
    evals = last["evaluations"] - first["evaluations"]
    per_eval = (last["wall"] - first["wall"]) / evals if evals else float("nan")
    per_eval_cpu = (last["cpu"] - first["cpu"]) / evals if evals else float("nan")
    return {"pop_size": POP, "generations": GENERATIONS, "evaluations": r["evaluations"], "loop_s": r["loop_s"],
            "s_per_evaluation": per_eval, "cpu_s_per_evaluation": per_eval_cpu,
            "projected_loop_s": per_eval * PAPER_DESIGNS, "projected_loop_cpu_s": per_eval_cpu * PAPER_DESIGNS,
            "rss_by_generation_mib": [round(m["rss_mib"], 1) for m in marks],
            "peak_by_generation_mib": [round(m["peak_mib"], 1) for m in marks],
            "peak_rss_mib": r["peak_after_plots_mib"], "process_cpu_s": cpu}


def bench_config(config: Path) -> dict:
    from scalesynth.config import load_config

    cfg = load_config(config)
    env = dict(os.environ, MPLBACKEND="Agg")
    row = {"config": config.name, "mechanism": cfg.mechanism, "evaluator": evaluator_label(cfg),
           "resolution": cfg.grid.resolution, "task": cfg.task is not None}
    row["evaluation"] = time_evaluator(cfg)
    with tempfile.TemporaryDirectory() as tmp:
        row["loop"] = time_loop(config, env, Path(tmp))
    ev, lp = row["evaluation"], row["loop"]
    msg = f"{config.name}: {row['evaluator']}: {1e3 * ev['s_per_design']:.2f} ms/design"
    if "error" in lp:
        msg += f"; optimize failed: {lp['error']}"
    else:
        msg += (f"; loop {1e3 * lp['s_per_evaluation']:.2f} ms/evaluation -> {lp['projected_loop_s']:.0f} s per "
                f"40 000 designs; peak RSS {lp['peak_rss_mib']:.0f} MiB (by generation "
                f"{lp['rss_by_generation_mib']})")
    print(msg, flush=True)
    return row


def bench_synthesis(names: list[str] | None = None) -> dict:
    configs = [CONFIG_DIR / n for n in names] if names else sorted(CONFIG_DIR.glob("*.yaml"))
    load = os.getloadavg()
    rows = [bench_config(c) for c in configs]
    return {"configs": rows, "load_average_start": [round(v, 1) for v in load],
            "load_average_end": [round(v, 1) for v in os.getloadavg()],
            "numba_threads_env": os.environ.get("NUMBA_NUM_THREADS", "default"), "peak_method": "VmHWM"}


def markdown(entry: dict) -> list[str]:
    r = entry["result"]
    peak = ("the child's own VmHWM at its end" if r.get("peak_method") == "VmHWM" else
            "os.wait4, an upper bound: it also counts the benchmark process's pages the child held between fork and "
            "exec")
    out = [f"Load average (1, 5, 15 min) at the start {r['load_average_start']}, at the end {r['load_average_end']}; "
           f"NUMBA_NUM_THREADS={r['numba_threads_env']}. Wall times on a shared machine include waiting for a core; "
           "CPU seconds are the work itself (with 2 threads on 2 idle cores the loop's wall time would be at best "
           "about half of its CPU time).", "",
           f"`evaluator`: `evaluate_config_population` of the searched families (what the loop calls) on "
           f"{N_DESIGNS} random designs in the bounds, one call, best "
           f"of 2. `NSGA-II loop`: `optimize` with population {POP}, {GENERATIONS} generations in a fresh process "
           "(warm Numba cache), plots and report included; seconds per evaluation from generation 2 on, projected "
           f"to {PAPER_DESIGNS} designs (200 x 200). Peak memory: the whole process ({peak}), RSS by "
           "generation: current RSS after each generation.", "",
           "| config | mechanism | evaluator | ms/design | NSGA-II ms/evaluation (CPU) | projected 40 000-design "
           "loop, wall (CPU) | <= 30 s | peak RSS | RSS by generation (MiB) | <= 1 GiB |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    for row in r["configs"]:
        ev, lp = row["evaluation"], row["loop"]
        head = (f"| {row['config']}{' (*)' if 'measured' in row else ''} | {row['mechanism']} | {row['evaluator']} | "
                f"{1e3 * ev['s_per_design']:.2f} "
                f"({1e3 * ev['cpu_s_per_design']:.2f} CPU) |")
        if "error" in lp:
            out.append(head + f" failed: {lp['error']} | | | | | |")
            continue
        ok_t = "yes" if lp["projected_loop_s"] <= GOAL_LOOP_S else (
            "CPU/2 only" if lp["projected_loop_cpu_s"] / 2 <= GOAL_LOOP_S else "NO")
        ok_m = "yes" if lp["peak_rss_mib"] <= GOAL_PEAK_MIB else "NO"
        out.append(head + f" {1e3 * lp['s_per_evaluation']:.2f} ({1e3 * lp['cpu_s_per_evaluation']:.2f}) | "
                   f"{lp['projected_loop_s']:.0f} s ({lp['projected_loop_cpu_s']:.0f} s) | {ok_t} | "
                   f"{lp['peak_rss_mib']:.0f} MiB | {', '.join(f'{v:.0f}' for v in lp['rss_by_generation_mib'])} | "
                   f"{ok_m} |")
    out += ["", "`<= 30 s`: yes = the measured wall projection meets it; `CPU/2 only` = only an ideal 2-thread split "
            "of the measured CPU time would; NO = neither.", ""]
    again = [row for row in r["configs"] if "measured" in row]
    if again:  # rows re-measured alone (`bench.py synthesis CONFIG ...`), each under its own conditions
        out += ["(*) Re-measured alone (`python benchmarks/bench.py synthesis CONFIG`), not under the conditions above: "
                + "; ".join(f"{row['config']} {row['measured']['date']}, load average (1, 5, 15 min) "
                            f"{row['measured']['load_average_start']} at the start, "
                            f"{row['measured']['load_average_end']} at the end, NUMBA_NUM_THREADS="
                            f"{row['measured']['numba_threads_env']}" for row in again) + ".", ""]
    return out


if __name__ == "__main__":
    print(json.dumps(bench_synthesis(sys.argv[1:] or None), indent=1))
