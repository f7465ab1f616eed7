"""Issue 15, plot-bands' first evaluation: an older tree against this one, alternating, in one run.

    git archive <commit> src | tar -x -C /tmp/base
    python benchmarks/plot_bands_ab.py /tmp/base/src [ROUNDS]

Per mechanism (benchmarks/adaptive.py CONFIGS): one short optimize (8 x 2, as ``compile_probe.commands()``) makes
the run, one plot-bands per tree fills that tree's Numba cache (one directory each), then ROUNDS rounds run
plot-bands once per tree, alternating, every process under this tree's tests/compile_probe.py (wall and CPU
seconds from the process start to the end of its first evaluation, and of the whole process). Prints one JSON
object: per mechanism and tree the rows [first CPU s, first wall s, whole CPU s, whole wall s].
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

from adaptive import CONFIGS  # noqa: E402


def probe(src: Path, cache: Path, args: list[str], report: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(src), NUMBA_CACHE_DIR=str(cache), MPLBACKEND="Agg")
    subprocess.run([sys.executable, str(ROOT / "tests" / "compile_probe.py"), str(report), *args], env=env,
                   capture_output=True, text=True, cwd=ROOT, check=True)
    (r,) = json.loads(report.read_text())
    if r["exit_code"] or r["compiled"] and "fill" not in report.name:
        raise RuntimeError(f"{args}: exit {r['exit_code']}, compiled {r['compiled']}")
    return r


def main(base_src: Path, rounds: int) -> dict:
    trees = {"before": base_src, "after": ROOT / "src"}
    out = {"date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), "load_before": os.getloadavg()[0],
           "rounds": rounds, "rows": {}}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for name, config in CONFIGS.items():
            run = tmp / name / "run"
            probe(trees["after"], tmp / "cache-after", ["optimize", str(ROOT / "configs" / config), "--out",
                  str(run), "-q", "--set", "algorithm.pop_size=8", "--set", "algorithm.n_gen=2"], tmp / "fill.json")
            for tree, src in trees.items():
                probe(src, tmp / f"cache-{tree}", ["plot-bands", str(run)], tmp / "fill.json")
            rows = {tree: [] for tree in trees}
            for _ in range(rounds):
                for tree, src in trees.items():
                    r = probe(src, tmp / f"cache-{tree}", ["plot-bands", str(run)], tmp / "r.json")
                    rows[tree].append([r["first_grid_cpu_s"], r["first_grid_s"], r["cpu_s"], r["wall_s"]])
            out["rows"][name] = rows
            print(name, {t: sorted(x[0] for x in v)[len(v) // 2] for t, v in rows.items()}, file=sys.stderr)
    out["load_after"] = os.getloadavg()[0]
    return out


if __name__ == "__main__":
    print(json.dumps(main(Path(sys.argv[1]).resolve(), int(sys.argv[2]) if len(sys.argv) > 2 else 3), indent=1))
