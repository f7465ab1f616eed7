"""Issue 15, compile once: every CLI command of every mechanism's config, in fresh processes sharing one Numba
cache directory, first with the cache empty, then again (the "second process").

    python benchmarks/bench.py compile_commands

Per mechanism (one empty cache directory each) the commands run one process each, in the order of
``commands()``: round 1 fills the cache (each command compiles what the earlier ones did not), round 2 repeats
them and must compile nothing. Every process records its Numba compilations with tests/compile_probe.py (Numba's
``numba:compile`` event fires only for a real compilation, not for a cache load).
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


def bench_mechanism(name: str) -> dict:
    config = CONFIGS[name]
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
            "first_process_compile_s": sum(r["round1"]["compile_s"] for r in rows)}


def bench_compile_commands(names: list[str] | None = None) -> dict:
    return {"mechanisms": [bench_mechanism(n) for n in (names or list(CONFIGS))]}


def markdown(entry: dict) -> list[str]:
    out = ["Each command in its own fresh process (tests/compile_probe.py), one empty Numba cache directory per",
           "mechanism. Round 1 runs the commands in this order on the empty cache (each compiles what the earlier",
           "ones left), round 2 repeats them: the second process. `compiled`: Numba compilations (nested callees",
           "included); `compile s`: wall seconds inside them; `JIT s`: wall seconds inside Numba's dispatcher",
           "(compilations and disk-cache loads; about 0.5 s of a second process's first load is Numba importing its",
           "own typing registries, once per process); wall and CPU seconds of the whole process (interpreter start,",
           "imports, the command's work, drawing). optimize: 8 designs x 2 generations with plots and report; show",
           "at the config's resolution.", "",
           "| mechanism | command | round 1: compiled, compile s | round 2: compiled | round 2: JIT s | round 2: wall "
           "s (CPU s) | round 2 exit |", "|---|---|---|---|---|---|---|"]
    for m in entry["result"]["mechanisms"]:
        for r in m["commands"]:
            a, b = r["round1"], r["round2"]
            out.append(f"| {m['mechanism']} | {r['command']} | {a['compiled']}, {a['compile_s']:.1f} s | "
                       f"**{b['compiled']}** | {b.get('jit_s', float('nan')):.2f} | {b['wall_s']:.2f} "
                       f"({b['cpu_s']:.2f}) | {b['exit_code']} |")
    out += ["", "First-process compile time per mechanism (round 1, every command, empty cache), and the second "
            "process of `evaluate`: from the process start to the end of its first workspace-grid evaluation "
            "(`Mechanism.grid_stats`: interpreter, imports, config, cache loads, the grid) and the whole process "
            "(with the task, path and cycle metrics the config asks for):", "",
            "| mechanism | config | compile s, first process (all commands) | of which evaluate | round 2 "
            "compilations (all commands) | second process: first evaluation, wall s (CPU s) | second-process "
            "evaluate, whole: wall s (CPU s) |", "|---|---|---|---|---|---|---|"]
    for m in entry["result"]["mechanisms"]:
        n2 = sum(r["round2"]["compiled"] for r in m["commands"])
        ev = next(r for r in m["commands"] if r["command"] == "evaluate")
        e2 = ev["round2"]
        first = (f"{e2['first_grid_s']:.2f} ({e2['first_grid_cpu_s']:.2f})" if e2.get("first_grid_s") is not None
                 else "not measured")
        out.append(f"| {m['mechanism']} | {m['config']} | {m['first_process_compile_s']:.1f} | "
                   f"{ev['round1']['compile_s']:.1f} | {n2} | {first} | {e2['wall_s']:.2f} ({e2['cpu_s']:.2f}) |")
    return out + [""]


if __name__ == "__main__":
    print(json.dumps(bench_compile_commands(sys.argv[1:] or None), indent=1))
