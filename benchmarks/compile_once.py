"""Issue 15, compile once: every CLI command of every mechanism's config, in fresh processes sharing one Numba
cache directory, first with the cache empty, then again (the "second process").

    python benchmarks/bench.py compile_commands

Per mechanism (one empty cache directory each) the commands run one process each, in the order of
``commands()``: round 1 fills the cache (each command compiles what the earlier ones did not), round 2 repeats
them and must compile nothing. Every process records its Numba compilations with tests/compile_probe.py (Numba's
``numba:compile`` event fires only for a real compilation, not for a cache load) and the time from its start to
the end of its first evaluation. ``numba_floor`` measures, with the same Python and cache, a process that only
imports NumPy and Numba and calls one trivial disk-cached function: the part of any second process's first
evaluation that scalesynth cannot remove.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PROBE = ROOT / "tests" / "compile_probe.py"
sys.path.insert(0, str(ROOT / "tests"))

from adaptive import CONFIGS  # noqa: E402  (one config per mechanism, shared by the issue-15 benchmarks)

from compile_probe import commands  # noqa: E402


def probe(args: list[str], env: dict, report: Path) -> dict:
    proc = subprocess.run([sys.executable, str(PROBE), str(report), *args], env=env, capture_output=True,
                          text=True, cwd=ROOT)
    if not report.exists():
        raise RuntimeError(f"{args}: probe failed: {proc.stderr[-2000:]}")
    (r,) = json.loads(report.read_text())
    r["stderr_tail"] = proc.stderr[-300:] if r["exit_code"] else ""
    return r


FLOOR_MODULE = """
from numba import njit


@njit(cache=True)
def one(x):
    return x + 1
"""
FLOOR_RUN = """
import sys, time
sys.path.insert(0, sys.argv[1])
import numpy
import floor_kernel
floor_kernel.one(1)
print(time.perf_counter() - T0, time.process_time())
"""


def numba_floor(runs: int = 5) -> dict:
    """Wall and CPU seconds (medians of ``runs`` second processes) from the process start to the return of one
    trivial disk-cached @njit function: interpreter, NumPy and Numba imports and Numba's first-dispatch set-up
    (typing and target registries; Numba's BLAS check imports scipy.linalg)."""
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "floor_kernel.py").write_text(FLOOR_MODULE)
        env = dict(os.environ, NUMBA_CACHE_DIR=str(Path(tmp) / "numba-cache"))
        env.setdefault("OPENBLAS_NUM_THREADS", "1")  # as scalesynth.cli sets it for every command
        code = "import time; T0 = time.perf_counter()\n" + FLOOR_RUN
        times = []
        for _ in range(runs + 1):  # the first run compiles and fills the cache
            out = subprocess.run([sys.executable, "-c", code, tmp], env=env, capture_output=True, text=True,
                                 check=True)
            times.append([float(v) for v in out.stdout.split()])
    walls, cpus = sorted(t[0] for t in times[1:]), sorted(t[1] for t in times[1:])
    return {"runs": runs, "wall_s": walls[runs // 2], "cpu_s": cpus[runs // 2]}


def bench_mechanism(name: str) -> dict:
    config = CONFIGS[name]
    load_before = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp / "numba-cache"), MPLBACKEND="Agg")
        rows = []
        for rnd in (1, 2):
            out = tmp / f"round{rnd}"
            for label, args in commands(ROOT / "configs" / config, out):
                r = probe(args, env, tmp / f"{label}-{rnd}.json")
                row = next((x for x in rows if x["command"] == label), None)
                if row is None:
                    row = {"command": label}
                    rows.append(row)
                row[f"round{rnd}"] = {k: r[k] for k in ("exit_code", "compile_s", "jit_s", "wall_s", "cpu_s",
                                                         "first_grid_s", "first_grid_cpu_s", "stderr_tail")}
                row[f"round{rnd}"]["compiled"] = len(r["compiled"])
                if rnd == 2:
                    row["round2"]["compiled_names"] = sorted(set(r["compiled"]))
                print(f"{name} {label} round {rnd}: exit {r['exit_code']}, {len(r['compiled'])} compiled "
                      f"({r['compile_s']:.2f} s), JIT {r['jit_s']:.2f} s, wall {r['wall_s']:.2f} s, cpu "
                      f"{r['cpu_s']:.2f} s", flush=True)
    return {"mechanism": name, "config": config, "commands": rows,
            "first_process_compile_s": sum(r["round1"]["compile_s"] for r in rows),
            "load_average_1min": [load_before, os.getloadavg()[0]]}


def bench_compile_commands(names: list[str] | None = None) -> dict:
    floor = numba_floor()
    mechs = [bench_mechanism(n) for n in (names or list(CONFIGS))]
    return {"numba_floor": floor, "numba_floor_after": numba_floor(), "mechanisms": mechs,
            "bytecode_cache": not os.environ.get("PYTHONDONTWRITEBYTECODE")}


def _first(r: dict) -> str:
    return "-" if r.get("first_grid_s") is None else f"{r['first_grid_s']:.2f} ({r['first_grid_cpu_s']:.2f})"


def markdown(entry: dict) -> list[str]:
    res = entry["result"]
    out = ["Each command in its own fresh process (tests/compile_probe.py), one empty Numba cache directory per",
           "mechanism. Round 1 runs the commands in this order on the empty cache (each compiles what the earlier",
           "ones left), round 2 repeats them: the second process. `compiled`: Numba compilations (nested callees",
           "included); `compile s`: wall seconds inside them; `JIT s`: wall seconds inside Numba's dispatcher",
           "(compilations and disk-cache loads, including Numba's once-per-process set-up on the first load); `first",
           "evaluation`: wall and CPU seconds from the process start to the end of its first evaluation (a workspace",
           "grid, uniform or adaptive; a field or LCI grid; a cycle; a pose's stiffness; `-`: none); `whole`: the",
           "whole process (interpreter start, imports, the command's work, drawing). optimize: 8 designs x 2",
           "generations with plots and report; show at the config's resolution."]
    if "numba_floor" in res:
        f0, f1 = res["numba_floor"], res["numba_floor_after"]
        out += ["", f"Floor: a process that only imports NumPy and Numba and calls one trivial disk-cached @njit "
                f"function takes {f0['cpu_s']:.2f} s CPU ({f0['wall_s']:.2f} s wall; median of {f0['runs']}) "
                f"before the runs, {f1['cpu_s']:.2f} s ({f1['wall_s']:.2f} s) after: the imports and Numba's "
                "first-dispatch set-up (its typing and target registries; its BLAS check imports scipy.linalg), "
                "part of every first evaluation below (OpenBLAS single-threaded, as the CLI runs it)."]
        if not res.get("bytecode_cache", True):
            out.append("PYTHONDONTWRITEBYTECODE was set: every process compiled scalesynth's modules from source "
                       "(an installed package has their bytecode; measured at about 0.04 s CPU per process).")
    out += ["", "| mechanism | command | round 1: compiled, compile s | round 2: compiled | round 2: JIT s | round 2: "
            "first evaluation, wall s (CPU s) | round 2: whole, wall s (CPU s) | round 2 exit |",
            "|---|---|---|---|---|---|---|---|"]
    for m in res["mechanisms"]:
        for r in m["commands"]:
            a, b = r["round1"], r["round2"]
            out.append(f"| {m['mechanism']} | {r['command']} | {a['compiled']}, {a['compile_s']:.1f} s | "
                       f"**{b['compiled']}** | {b.get('jit_s', float('nan')):.2f} | {_first(b)} | {b['wall_s']:.2f} "
                       f"({b['cpu_s']:.2f}) | {b['exit_code']} |")
    out += ["", "Per mechanism: first-process compile time (round 1, every command, empty cache); the second process "
            "of `evaluate` from its start to the end of its first workspace evaluation (interpreter, imports, "
            "config, cache loads, the grid) and whole (with the task, path and cycle metrics the config asks "
            "for); the slowest first evaluation of the other commands; the load average (1 min, 2 cores) before "
            "and after the mechanism's runs:", "",
            "| mechanism | config | compile s, first process (all commands) | of which evaluate | round 2 "
            "compilations (all commands) | evaluate, second process: first evaluation, wall s (CPU s) | evaluate, "
            "whole: wall s (CPU s) | other commands: slowest first evaluation, CPU s | load average |",
            "|---|---|---|---|---|---|---|---|---|"]
    for m in res["mechanisms"]:
        n2 = sum(r["round2"]["compiled"] for r in m["commands"])
        ev = next(r for r in m["commands"] if r["command"] == "evaluate")
        e2 = ev["round2"]
        others = [(r["round2"]["first_grid_cpu_s"], r["command"]) for r in m["commands"]
                  if r["command"] != "evaluate" and r["round2"].get("first_grid_cpu_s") is not None]
        slowest = f"{max(others)[0]:.2f} ({max(others)[1]})" if others else "-"
        load = m.get("load_average_1min")
        load = f"{load[0]:.1f}, {load[1]:.1f}" if load else "-"
        out.append(f"| {m['mechanism']} | {m['config']} | {m['first_process_compile_s']:.1f} | "
                   f"{ev['round1']['compile_s']:.1f} | {n2} | {_first(e2)} | {e2['wall_s']:.2f} ({e2['cpu_s']:.2f}) "
                   f"| {slowest} | {load} |")
    return out + [""]


if __name__ == "__main__":
    print(json.dumps(bench_compile_commands(sys.argv[1:] or None), indent=1))
