"""Run a population or grid kernel over its rows in Numba's number of threads, without compiling a parallel loop.

A kernel bound per mechanism (kernels.bind) with ``parallel=True`` costs a parfor compilation per binding (about
8 s of CPU for the column template, a third of its compile time, once per mechanism and plan variant). Its loop
needs no parfor: each item (a design, a design's x-slab, an x index) writes its own rows, so the kernel is
compiled serial with ``nogil=True`` over a stride of the items (``start, start + stride, ...``), and
``in_threads`` runs ``numba.get_num_threads()`` strides in threads. Each item is computed by the same compiled
code whatever the thread count and any reduction follows in a fixed order, so results do not depend on it.
"""

from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor

import numba

_POOL: dict[int, ThreadPoolExecutor] = {}  # per process (a forked child gets its own, its parent's threads are gone)
_LOCK = threading.Lock()


def _pool() -> ThreadPoolExecutor:
    pid = os.getpid()
    with _LOCK:
        pool = _POOL.get(pid)
        if pool is None:
            pool = _POOL[pid] = ThreadPoolExecutor(max(1, int(numba.config.NUMBA_NUM_THREADS)),
                                                   thread_name_prefix="scalesynth-kernel")
        return pool


def in_threads(kernel, n_items: int, *args) -> None:
    """Call ``kernel(*args, start, stride)`` for start = 0 .. threads - 1 with stride = threads, where threads is
    the calling thread's ``numba.get_num_threads()`` (at most ``n_items``): in this thread when it is 1, else in a
    process-wide pool of threads (the kernel must be compiled with ``nogil=True`` to run in parallel). Exceptions
    of the kernel are raised here."""
    threads = max(1, min(int(numba.get_num_threads()), int(n_items)))
    if threads == 1:
        kernel(*args, 0, 1)
        return
    futures = [_pool().submit(kernel, *args, start, threads) for start in range(threads)]
    for f in futures:
        f.result()
