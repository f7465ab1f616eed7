"""Numba's disk cache under concurrent saves (scalesynth.kernels.cache_lock).

Two processes save different signatures of one function into one cache directory, each paused after reading the
index until the other has read it too (or 2 s have passed), which is the interleaving numba issue #4807 describes.
Unlocked (Numba's own code), both take data file 1 and the index names the other process's data for one key: the
race is real, so the check can fail. Locked, the second process cannot read the index until the first has saved,
so both entries survive, each naming its own data."""

import json
import os
import subprocess
import sys

CHILD = r"""
import os, sys, time
from numba.core import caching
lock, cache_dir, me, other = sys.argv[1] == "1", sys.argv[2], sys.argv[3], sys.argv[4]
if lock:
    from scalesynth.kernels import cache_lock
    assert cache_lock.installed()
load_index = caching.IndexDataCacheFile._load_index

def paused_load_index(self):
    out = load_index(self)
    open(os.path.join(cache_dir, "read-" + me), "w").close()
    deadline = time.time() + 2.0
    while not os.path.exists(os.path.join(cache_dir, "read-" + other)) and time.time() < deadline:
        time.sleep(0.005)
    return out

caching.IndexDataCacheFile._load_index = paused_load_index
f = caching.IndexDataCacheFile(cache_dir, "kernel-1.py311", "stamp")
f.save(("signature", me), ("compiled for", me))
"""

READ = r"""
import json, sys
from numba.core import caching
f = caching.IndexDataCacheFile(sys.argv[1], "kernel-1.py311", "stamp")
overloads = f._load_index()
print(json.dumps({k[1]: [name, list(f._load_data(name))] for k, name in overloads.items()}))
"""


def _race(tmp_path, lock: bool) -> dict:
    cache_dir = tmp_path / ("locked" if lock else "unlocked")
    cache_dir.mkdir()
    env = dict(os.environ, NUMBA_NUM_THREADS="1")
    procs = [subprocess.Popen([sys.executable, "-c", CHILD, "1" if lock else "0", str(cache_dir), me, other],
                              env=env) for me, other in (("a", "b"), ("b", "a"))]
    for p in procs:
        assert p.wait(timeout=120) == 0
    out = subprocess.run([sys.executable, "-c", READ, str(cache_dir)], env=env, capture_output=True, text=True,
                         check=True, timeout=120)
    return json.loads(out.stdout)


def test_unlocked_numba_cache_loses_an_entry_or_mixes_them_up(tmp_path):
    entries = _race(tmp_path, lock=False)
    # both processes read an empty index, so both named their data file 1: one entry survives, and its data file
    # is the last one written, which may be the other process's
    assert len(entries) == 1
    ((key, (name, _)),) = entries.items()
    assert name.endswith(".1.nbc")


def test_locked_numba_cache_keeps_both_entries_each_with_its_own_code(tmp_path):
    entries = _race(tmp_path, lock=True)
    assert set(entries) == {"a", "b"}
    for key, (_, data) in entries.items():
        assert data == ["compiled for", key]
    assert sorted(name for name, _ in entries.values()) == ["kernel-1.py311.1.nbc", "kernel-1.py311.2.nbc"]


def test_every_cached_kernel_module_installs_the_lock():
    """Importing any module with a disk-cached Numba function locks the cache (it imports scalesynth.kernels)."""
    from pathlib import Path

    import scalesynth

    src = Path(scalesynth.__file__).parent
    modules = sorted(".".join(p.relative_to(src.parent).with_suffix("").parts) for p in src.rglob("*.py")
                     if "njit(cache=True" in p.read_text() or p.name == "bind.py")
    assert len(modules) >= 10
    probe = ("import importlib, sys\nfrom numba.core import caching\n"
             "importlib.import_module(sys.argv[1])\n"
             "print(bool(getattr(caching.IndexDataCacheFile, '_scalesynth_locked', False)))")
    for module in modules:
        out = subprocess.run([sys.executable, "-c", probe, module], capture_output=True, text=True, check=True,
                             timeout=120)
        assert out.stdout.strip() == "True", module


def test_the_lock_holds_on_a_read_only_lock_file(tmp_path):
    """The lock file is opened read-only (flock needs no write access, so users who may read but not write another's
    lock file still lock): a read-only open of a 0444 file takes a real lock, which another process cannot take while
    it is held. (Run as root, the mode restricts nothing; the check is then that the read-only open locks at all.)"""
    import stat

    from scalesynth.kernels import cache_lock

    lock_file = tmp_path / cache_lock.LOCK_NAME
    lock_file.touch()
    lock_file.chmod(stat.S_IRUSR | stat.S_IRGRP | stat.S_IROTH)  # 0444
    probe = ("import fcntl, os, sys\nfd = os.open(sys.argv[1], os.O_RDONLY)\n"
             "try:\n    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)\nexcept BlockingIOError:\n    print('busy')\n"
             "else:\n    print('free')\n")

    def other_process_sees() -> str:
        return subprocess.run([sys.executable, "-c", probe, str(lock_file)], capture_output=True, text=True,
                              check=True, timeout=60).stdout.strip()

    with cache_lock._flock(str(tmp_path), exclusive=True):
        assert other_process_sees() == "busy"
    assert other_process_sees() == "free"
