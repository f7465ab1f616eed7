"""Compile once: a grid kernel bound to a mechanism's field kernel (kernels.bind) is loaded from Numba's disk cache
by a second process instead of being compiled again (counted by the dispatcher's cache statistics, not timed)."""

import json
import os
import subprocess
import sys

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
k = bind(kgrid._population_stats, m.field_kernel, m.n_fields, **kgrid._PARALLEL)  # the memoised one
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
