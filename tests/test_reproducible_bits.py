"""Byte-identical results whatever the Numba cache state and the CPU target (issue 27).

With value-changing fast-math flags, ups-sspr's adaptive statistics differed in their last bits between a process
that compiled the kernels and one that loaded the same kernels from the disk cache (sha256 prefixes 3206e9b4 and
b4ad98a2 on 450c242), and a resumed run or `reproduce` could differ from the original. Each probe runs in its own
process on a cache directory of this test's, so the states are the ones named, not whatever the suite left.
"""

import json
import os
import subprocess
import sys

PROBE = r"""
import hashlib, json, sys
import numpy as np
from scalesynth.evaluate import Tolerance, adaptive_population_stats, make_grid
from scalesynth.kernels import grid as kgrid
from scalesynth.mechanisms import get
from scalesynth.numba_target import describe

what = sys.argv[1]
edges = np.array([0.0, 0.3, 1.0])
if what == "ups-callees":  # the field and reach kernels alone, so the evaluator's own kernels find them cached
    m = get("ups-sspr")
    d, o = m.resolve_design({}), m.resolve_options({})
    p, cell = m.pack(d, o), np.zeros(m.n_fields)
    for k in {m.field_kernel, m.reach_kernel}:
        k(p, 0.01, 0.02, 0.3, cell)
    digest = ""
elif what == "ups-adaptive":
    m = get("ups-sspr")
    d, o = m.resolve_design({}), m.resolve_options({})
    r = adaptive_population_stats(m, [d], o, m.pack(d, o)[None, :], Tolerance(), edges)
    digest = hashlib.sha256(r.stats.tobytes() + r.error_volume.tobytes() + r.error_gci.tobytes()).hexdigest()
else:  # 'grid': the uniform evaluator on 2pauu-ppap, the paper run's path
    m = get("2pauu-ppap")
    d, o = m.default_design(), m.resolve_options({})
    g = make_grid(m, d, o, 24)
    s = kgrid.population_stats(m.field_kernel, m.n_fields, m.pack(d, o)[None, :], g.lo[None, :], g.step[None, :],
                               g.shape, edges)
    digest = hashlib.sha256(s.tobytes()).hexdigest()
print(json.dumps({"digest": digest, "target": describe()}))
"""


def _probe(what: str, cache_dir, **env_extra) -> dict:
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache_dir), NUMBA_NUM_THREADS="1", **env_extra)
    out = subprocess.run([sys.executable, "-c", PROBE, what], env=env, capture_output=True, text=True, timeout=900)
    assert out.returncode == 0, out.stderr[-3000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_compiled_in_process_mixed_and_loaded_from_the_cache_give_the_same_bits(tmp_path):
    """Three states of one cache: the evaluator's kernels compiled in this process against field kernels loaded
    from the cache (mixed), then everything loaded from the cache; and a fresh cache where everything compiles."""
    mixed = tmp_path / "mixed"
    _probe("ups-callees", mixed)
    compiled_over_cached_callees = _probe("ups-adaptive", mixed)["digest"]
    all_loaded = _probe("ups-adaptive", mixed)["digest"]
    all_compiled = _probe("ups-adaptive", tmp_path / "fresh")["digest"]
    assert compiled_over_cached_callees == all_loaded == all_compiled


def test_other_cpu_targets_give_the_same_bits(tmp_path):
    """The pinned target against plain x86-64 (no AVX, no FMA) and the host's own CPU: the machine code differs,
    the results must not (the way an Intel and an AMD machine differ, made here on one machine). The paper run's
    uniform evaluator on 2pauu-ppap."""
    what = "grid"
    pinned = _probe(what, tmp_path / "pinned")
    assert pinned["target"]["cpu_name"] in ("x86-64-v3", "x86-64")
    generic = _probe(what, tmp_path / "generic", NUMBA_CPU_NAME="generic", NUMBA_CPU_FEATURES="")
    assert generic["target"]["cpu_name"] == "generic"
    import llvmlite.binding as ll

    host = _probe(what, tmp_path / "host", NUMBA_CPU_NAME=ll.get_host_cpu_name(),
                  NUMBA_CPU_FEATURES=ll.get_host_cpu_features().flatten())
    assert pinned["digest"] == generic["digest"] == host["digest"]


def test_the_target_is_pinned_and_a_users_choice_wins(tmp_path):
    code = "import scalesynth, os; print(os.environ.get('NUMBA_CPU_NAME'))"
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_CPU_")}
    pinned = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert pinned.stdout.strip() in ("x86-64-v3", "x86-64")
    own = subprocess.run([sys.executable, "-c", code], env=dict(env, NUMBA_CPU_NAME="generic"), capture_output=True,
                         text=True, timeout=120)
    assert own.stdout.strip() == "generic"
