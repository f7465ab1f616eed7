"""`scalesynth show` of a 3-D design at resolution 96: wall and CPU seconds of whole CLI processes.

Run: python benchmarks/show_speed.py [--resolution 96] [--repeat 2]. The first process fills Numba's disk cache
(the kernels that can be cached); later ones are the "warm cache" case. The grid sampler takes the mechanism's
field kernel as an argument and is compiled in every process (Numba cannot cache such specialisations), so its
compile time is part of every run. Writes benchmarks/results/show.json; RESULTS.md's "show" section quotes it.
"""

from __future__ import annotations

import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from datetime import UTC, datetime
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def child_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def one(config: str, resolution: int, out: Path) -> dict:
    cmd = [sys.executable, "-m", "scalesynth", "show", config, "--resolution", str(resolution), "--out", str(out),
           "--json"]
    c0, t0 = child_cpu(), time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, env=dict(os.environ, MPLBACKEND="Agg"))
    wall, cpu = time.perf_counter() - t0, child_cpu() - c0
    if r.returncode:
        raise SystemExit(r.stderr)
    info = json.loads(r.stdout)
    return {"wall_s": round(wall, 2), "cpu_s": round(cpu, 2), "inside": info["seconds"]}


def main(argv: list[str]) -> None:
    resolution = int(argv[argv.index("--resolution") + 1]) if "--resolution" in argv else 96
    repeat = int(argv[argv.index("--repeat") + 1]) if "--repeat" in argv else 2
    config = "configs/paper_2pauu_ppap.yaml"
    with tempfile.TemporaryDirectory() as tmp:
        runs = [one(config, resolution, Path(tmp) / f"r{k}") for k in range(repeat + 1)]
    data = {
        "date": datetime.now(UTC).isoformat(timespec="minutes"),
        "machine": f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores",
        "load_average_1min": round(os.getloadavg()[0], 1),
        "numba_threads": os.environ.get("NUMBA_NUM_THREADS", "default"),
        "command": f"scalesynth show {config} --resolution {resolution}",
        "first_process": runs[0],
        "warm_cache": runs[1:],
    }
    path = ROOT / "benchmarks" / "results" / "show.json"
    path.write_text(json.dumps(data, indent=2) + "\n")
    print(json.dumps(data, indent=2))


if __name__ == "__main__":
    main(sys.argv[1:])
