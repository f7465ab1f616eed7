"""What a dask worker runs for ``scalesynth batch``: one chunk of one (config, seed) task.

A chunk continues a run from the checkpoint bytes it is given (or starts it) in a scratch directory under the
worker's local directory, up to its next checkpoint generation, and returns either that checkpoint's bytes or,
after the last generation, the bytes of every results file. The scratch directory is removed before the chunk
returns: the worker keeps nothing, the client owns every result and checkpoint. A chunk never receives a client
path, so it cannot write into the client's directory even where the filesystem is shared.

Numba uses as many threads as the worker has (its ``nthreads``, not the node's cores), and a worker process runs
one chunk at a time (a lock), so a worker never runs more Numba threads than it was given.
"""

from __future__ import annotations

import shutil
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

from scalesynth.errors import ScalesynthError

# one chunk at a time per worker process: it uses all of the worker's threads for Numba
_WORKER_SLOT = threading.Lock()


class _Pause(Exception):
    """Raised from optimize.run's checkpoint hook to end a chunk at a checkpoint."""

    def __init__(self, generation: int, checkpoint: bytes):
        super().__init__(f"paused at generation {generation}")
        self.generation = generation
        self.checkpoint = checkpoint  # read in the hook: the staged file is the run's, not the chunk's, to keep


def one_line(err: BaseException) -> str:
    """A one-line description of an exception: the library's own message, else 'TypeName: message'."""
    text = str(err) if isinstance(err, ScalesynthError) else f"{type(err).__name__}: {err}"
    text = " ".join(text.split())
    return text or type(err).__name__


def worker_identity() -> dict[str, Any]:
    """Address, name, thread count and local (scratch) directory of the dask worker running this code; outside a
    worker (a direct call) the address is 'local' and the thread count Numba's startup maximum."""
    import numba

    try:
        from distributed import get_worker

        w = get_worker()
    except (ImportError, ValueError):
        return {"address": "local", "name": "local", "nthreads": int(numba.config.NUMBA_NUM_THREADS),
                "local_directory": None}
    return {"address": str(w.address), "name": str(w.name), "nthreads": int(w.state.nthreads),
            "local_directory": str(w.local_directory)}


def set_numba_threads(wanted: int) -> int:
    """Make Numba's parallel kernels launched from this thread use ``wanted`` threads, capped by the pool size
    fixed when Numba started (NUMBA_NUM_THREADS, default: the node's cores); returns the count in use."""
    import numba

    n = max(1, min(int(wanted), int(numba.config.NUMBA_NUM_THREADS)))
    numba.set_num_threads(n)  # thread-local: the task thread runs the kernels
    return int(numba.get_num_threads())


def run_chunk(data: dict[str, Any], seed: int, checkpoint: bytes | None) -> dict[str, Any]:
    """Run one chunk of the task (config data, seed) from ``checkpoint`` (None: from the start).

    Returns a dict with ``kind`` 'checkpoint' (``generation``, ``checkpoint`` bytes), 'finished' (``files``: name
    -> bytes of the results directory) or 'failed' (``error``: one line), and in every case ``worker``,
    ``worker_name``, ``worker_nthreads``, ``numba_threads``, ``seconds`` (time in the chunk) and ``versions``.
    Never raises: a failure is returned.
    """
    from scalesynth import io as rio
    from scalesynth import rundir
    from scalesynth.config import config_from_dict
    from scalesynth.optimize import _versions, run

    me = worker_identity()
    out: dict[str, Any] = {"worker": me["address"], "worker_name": me["name"], "worker_nthreads": me["nthreads"]}
    with _WORKER_SLOT:
        t0 = time.perf_counter()
        scratch = None
        try:
            out["numba_threads"] = set_numba_threads(me["nthreads"])
            out["versions"] = _versions()
            scratch = Path(tempfile.mkdtemp(prefix="scalesynth-chunk-", dir=me["local_directory"]))
            target = scratch / "run"  # optimize.run stages an unfinished run beside its target (scalesynth.rundir)
            if checkpoint is not None:
                staged = rundir.staging_path(target)
                staged.mkdir()
                (staged / rio.CHECKPOINT).write_bytes(checkpoint)
            cfg = config_from_dict(data)
            n_gen = cfg.algorithm.n_gen

            def pause(path: Path, generation: int) -> None:
                if generation < n_gen:  # the last checkpoint is followed by the results: let run() write them
                    raise _Pause(generation, path.read_bytes())

            try:
                run(cfg, target, seed=seed, resume=True, progress=None, plots=False, on_checkpoint=pause)
            except _Pause as p:
                out.update(kind="checkpoint", generation=p.generation, checkpoint=p.checkpoint)
            else:
                files = {name: (target / name).read_bytes() for name in rio.RESULT_FILES if (target / name).is_file()}
                out.update(kind="finished", files=files)
        except Exception as err:  # a task boundary: report any failure to the client
            out.update(kind="failed", error=one_line(err))
        finally:
            if scratch is not None:
                shutil.rmtree(scratch, ignore_errors=True)
            out["seconds"] = time.perf_counter() - t0
    return out
