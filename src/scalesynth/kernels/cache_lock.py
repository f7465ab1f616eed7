"""Numba's on-disk cache, made safe for several processes compiling at once.

Numba keeps one index file per cached function, mapping each compiled signature to a numbered data file.
``IndexDataCacheFile.save`` reads the index, takes the first number the index does not use, and writes the index
and then the data, with no lock (numba issues #4807, #10128). Two processes saving *different* signatures of one
function at the same moment both take number 1: the index written last names the other process's compiled code,
and every later process loads that code for the wrong signature (wrong numbers, or a crash). scalesynth's generic
kernels have several signatures each, and its users run several processes on one cache: pytest-xdist, dask
workers of a batch, parallel ``scalesynth optimize`` runs. A kill -9 resume test in two pytest processes resumed
to a different front this way (CI, stop 25).

``install()`` wraps that class once per process:

- ``save`` holds an exclusive ``flock`` on the cache directory's lock file while it re-reads the index, writes the
  data file and only then the index (so an index never names a file not yet written);
- ``load`` holds a shared lock while it reads the index and the data file it names.

Saves take milliseconds, so processes wait at most that long. Where no lock file can be opened (a read-only cache
directory, where Numba does not write either) or ``fcntl`` does not exist, Numba's own code runs unlocked.
"""

from __future__ import annotations

import contextlib
import itertools
import os
from collections.abc import Iterator

try:
    import fcntl
except ImportError:  # not POSIX: no flock
    fcntl = None

LOCK_NAME = "scalesynth-numba-cache.lock"
_METHODS = ("save", "load", "_load_index", "_save_index", "_save_data", "_data_name")
_ATTRIBUTES = ("_cache_path",)  # set by the class's __init__


@contextlib.contextmanager
def _flock(cache_dir: str, exclusive: bool) -> Iterator[None]:
    """Hold an exclusive or shared flock on ``cache_dir``'s lock file (nothing held if it cannot be opened)."""
    fd = None
    if fcntl is not None:
        try:
            # read-only is enough for flock, so a user who can read but not write another's lock file still locks
            fd = os.open(os.path.join(cache_dir, LOCK_NAME), os.O_RDONLY | os.O_CREAT, 0o666)
        except OSError:
            fd = None
    try:
        if fd is not None:
            fcntl.flock(fd, fcntl.LOCK_EX if exclusive else fcntl.LOCK_SH)
        yield
    finally:
        if fd is not None:
            os.close(fd)  # releases the lock


def _locked_save(self, key, data) -> None:
    """Numba's save, as one step under the directory's exclusive lock, data file before index."""
    with _flock(self._cache_path, exclusive=True):
        overloads = self._load_index()
        data_name = overloads.get(key)
        if data_name is not None:  # the same signature compiled again: same code, overwrite its file
            self._save_data(data_name, data)
            return
        used = set(overloads.values())
        data_name = next(name for name in map(self._data_name, itertools.count(1)) if name not in used)
        self._save_data(data_name, data)
        overloads[key] = data_name
        self._save_index(overloads)


def install() -> bool:
    """Make this process's Numba cache saves and loads locked (idempotent). False if Numba's cache class lacks
    what the wrapper relies on (a Numba release that changed it): then Numba runs unchanged."""
    from numba.core import caching

    cls = caching.IndexDataCacheFile
    if getattr(cls, "_scalesynth_locked", False):
        return True
    init_names = getattr(getattr(cls.__init__, "__code__", None), "co_names", ())
    if fcntl is None or not all(hasattr(cls, m) for m in _METHODS) or not all(a in init_names for a in _ATTRIBUTES):
        return False
    unlocked_load = cls.load

    def locked_load(self, key):
        with _flock(self._cache_path, exclusive=False):
            return unlocked_load(self, key)

    cls.save = _locked_save
    cls.load = locked_load
    cls._scalesynth_locked = True
    return True


def installed() -> bool:
    """Whether this process's Numba cache is locked by ``install``."""
    from numba.core import caching

    return bool(getattr(caching.IndexDataCacheFile, "_scalesynth_locked", False))
