"""Compile once: grid kernels bound to a mechanism's field kernel (kernels.bind) are loaded from Numba's disk cache
by a second process instead of being compiled again, for one kernel and for every CLI command of every mechanism's
config (counted by the dispatcher's cache statistics and Numba's compile events, not timed)."""

import json
import os
import subprocess
import sys

import pytest

PROBE = """
import json
import numpy as np
from scalesynth.evaluate import make_grid
from scalesynth.kernels import grid as kgrid
from scalesynth.kernels.bind import bind
from scalesynth.mechanisms import get
m = get("planar-fivebar")
d, o = m.default_design(), m.resolve_options({})
g = make_grid(m, d, o, 6)
p = m.pack(d, o)[None, :]
s = kgrid.population_stats(m.field_kernel, m.n_fields, p, g.lo[None, :], g.step[None, :], g.shape,
                           np.array([0.0, 0.3, 1.0]))
k = bind(kgrid._population_stats, m.field_kernel, m.n_fields, **kgrid._THREADED)  # the memoised one
print(json.dumps({"hits": sum(k.stats.cache_hits.values()), "misses": sum(k.stats.cache_misses.values()),
                  "count": float(s[0, 0])}))
"""


def test_bound_grid_kernel_hits_the_disk_cache_in_a_second_process(tmp_path):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path), NUMBA_NUM_THREADS="1")
    runs = []
    for _ in range(2):
        out = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True, text=True, check=True,
                             timeout=600)
        runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
    assert runs[0]["misses"] == 1 and runs[0]["hits"] == 0
    assert runs[1]["hits"] == 1 and runs[1]["misses"] == 0
    assert runs[0]["count"] == runs[1]["count"] > 0


# every mechanism's config (CLI commands that evaluate or draw), see compile_probe.commands
COMMAND_CONFIGS = ("paper_2pauu_ppap.yaml", "fivebar_packing.yaml", "pprs_rprs.yaml", "rps_upu.yaml",
                   "rps_upu_tool.yaml", "ups_sspr.yaml")


@pytest.mark.slow
@pytest.mark.parametrize("config", COMMAND_CONFIGS)
def test_second_process_compiles_nothing_for_any_command(tmp_path, root, config):
    """Every command of a mechanism's config run in one process (which compiles whatever the cache lacks),
    then again in a second process sharing the cache directory: the second records no Numba compilation at all
    (Numba's numba:compile event), and every command succeeds. Uses the suite's cache directory, so a warm cache
    makes the first process cheap; the claim checked is the same either way."""
    from compile_probe import commands

    env = dict(os.environ, NUMBA_NUM_THREADS="1", MPLBACKEND="Agg")
    reports = []
    for rnd in (1, 2):
        args = []
        for _, cmd in commands(root / "configs" / config, tmp_path / f"out{rnd}", small=True):
            args += [*cmd, "--"]
        report = tmp_path / f"round{rnd}.json"
        proc = subprocess.run([sys.executable, str(root / "tests" / "compile_probe.py"), str(report), *args[:-1]],
                              env=env, capture_output=True, text=True, timeout=900, cwd=root)
        assert report.exists(), proc.stderr[-2000:]
        reports.append(json.loads(report.read_text()))
    labels = [label for label, _ in commands(root / "configs" / config, tmp_path, small=True)]
    assert {"evaluate", "optimize", "show", "plot-bands"} <= set(labels)
    for label, r in zip(labels, reports[1], strict=True):
        assert r["exit_code"] == 0, (label, proc.stderr[-2000:])
        assert r["compiled"] == [], f"{label} compiled {r['compiled']} in the second process"
