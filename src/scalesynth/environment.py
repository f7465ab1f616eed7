"""The NUMBA_* environment variables scalesynth relies on, checked before Numba starts, and a disk cache that may
be missing.

Numba reads its environment once, when it is first imported: a thread count of 0 or -1 makes that import raise, a
value it cannot parse (``abc``, ``1e20``) becomes a multi-line warning and a default, a huge count aborts the
process when the thread pool starts, and a threading layer it does not know fails inside the first parallel
kernel. :func:`check` refuses such values first, with one line naming the variable (``ConfigError``, exit code 2
on the command line); the CLI entry, the Python API and ``scalesynth.kernels`` call it before Numba is imported.

Numba caches compiled kernels on disk, in the first location it can write: ``NUMBA_CACHE_DIR``, the package's
``__pycache__`` folders, the user's cache directory. Where none is writable (a read-only installation and home),
:func:`tolerate_missing_cache` makes each kernel compile in memory instead of failing, after one warning line.
NUMBA_CPU_NAME and NUMBA_CPU_FEATURES are not checked here (scalesynth sets the CPU target itself).
"""

from __future__ import annotations

import os
import sys

from scalesynth.errors import ConfigError

MAX_THREADS = 1024  # Numba starts this many threads per process at its first parallel kernel
THREADING_LAYERS = ("default", "safe", "forksafe", "threadsafe", "tbb", "omp", "workqueue")
MAX_SHOWN = 40  # characters of a bad value quoted in the message

_checked = False
_cache_warned = False


def _shown(value: str) -> str:
    return repr(value if len(value) <= MAX_SHOWN else value[:MAX_SHOWN] + "...")


def check(environ: dict[str, str] | None = None) -> None:
    """Refuse a bad NUMBA_NUM_THREADS, NUMBA_DISABLE_JIT, NUMBA_THREADING_LAYER or NUMBA_CACHE_DIR: ConfigError,
    one line naming the variable. Checks os.environ once per process, or ``environ`` (tests) every time."""
    global _checked
    if environ is None:
        if _checked:
            return
        _check(os.environ)
        _checked = True
    else:
        _check(environ)


def _check(env) -> None:
    def get(name):
        value = env.get(name)
        return None if value is None or not value.strip() else value

    threads = get("NUMBA_NUM_THREADS")
    if threads is not None:
        text = threads.strip()
        if not (text.isascii() and text.isdigit()) or not 1 <= int(text) <= MAX_THREADS:
            raise ConfigError(f"NUMBA_NUM_THREADS: expected the threads per process, an integer from 1 to "
                              f"{MAX_THREADS}, got {_shown(threads)}")
    jit = get("NUMBA_DISABLE_JIT")
    if jit is not None and jit.strip() not in ("0", "1"):
        raise ConfigError(f"NUMBA_DISABLE_JIT: expected 0 or 1, got {_shown(jit)}")
    layer = get("NUMBA_THREADING_LAYER")
    if layer is not None and layer.strip().lower() not in THREADING_LAYERS:
        raise ConfigError(f"NUMBA_THREADING_LAYER: expected one of {', '.join(THREADING_LAYERS)}, "
                          f"got {_shown(layer)}")
    cache_dir = env.get("NUMBA_CACHE_DIR")
    if cache_dir and "\0" in cache_dir:
        raise ConfigError("NUMBA_CACHE_DIR: the path contains a NUL character")


def tolerate_missing_cache() -> None:
    """Make Numba compile a ``cache=True`` function in memory, after one warning line on stderr, where it finds no
    writable cache location (it would raise 'no locator available' when the function is defined)."""
    from numba.core import dispatcher

    original = dispatcher.Dispatcher.enable_caching
    if getattr(original, "_scalesynth_tolerant", False):
        return

    def enable_caching(self):
        try:
            original(self)
        except RuntimeError as err:
            if "no locator available" not in str(err):
                raise
            _warn_no_cache()

    enable_caching._scalesynth_tolerant = True
    dispatcher.Dispatcher.enable_caching = enable_caching


def _warn_no_cache() -> None:
    global _cache_warned
    if _cache_warned:
        return
    _cache_warned = True
    sys.stderr.write("warning: no writable Numba cache location (NUMBA_CACHE_DIR, the package's __pycache__, the "
                     "user cache): kernels compile in memory every run; set NUMBA_CACHE_DIR to a writable "
                     "directory\n")
    sys.stderr.flush()
