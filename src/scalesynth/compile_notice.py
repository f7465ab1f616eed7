"""One line on stderr when a CLI process starts compiling Numba kernels (a first run can sit silent for minutes).

``enable()`` (the CLI's ``main``, unless -q/--quiet) asks for the notice; ``attach()`` (``scalesynth.kernels``,
imported before anything is compiled or loaded from Numba's disk cache) listens to Numba's ``numba:compile`` event.
Numba fires that event only when it compiles, never when it loads a function from its cache, so a process that
finds everything cached prints nothing. The line is printed once per process: the first compilation names what it
compiles (the mechanism, or the function) and where Numba caches it for later runs.

This module imports neither Numba nor the mechanism registry (both import ``scalesynth.kernels``, which imports
this); it looks the registry up in ``sys.modules``.
"""

from __future__ import annotations

import os
import sys

_STATE = {"enabled": False, "attached": False, "printed": False}


def enable(quiet: bool = False) -> None:
    """Ask for the notice in this process (once; ``quiet`` turns it off). Attaches at once if Numba's kernels are
    already imported."""
    _STATE["enabled"] = not quiet
    if not quiet and "scalesynth.kernels" in sys.modules:
        attach()


def attach() -> None:
    """Register the listener on Numba's compile event (idempotent; a no-op until ``enable``)."""
    if _STATE["attached"]:
        return
    from numba.core import event

    class _Listener(event.Listener):
        def on_start(self, ev) -> None:
            if _STATE["enabled"] and not _STATE["printed"]:
                _STATE["printed"] = True
                try:
                    line = notice_line(ev.data.get("dispatcher"))
                except Exception:  # a notice must never break a run
                    line = "note: compiling Numba kernels (first run only; cached for later runs)"
                print(line, file=sys.stderr, flush=True)

        def on_end(self, ev) -> None:
            pass

    event.register("numba:compile", _Listener())
    _STATE["attached"] = True


def _what(dispatcher) -> str:
    """'the planar-fivebar kernels' when the compiled function is (or is bound to) a mechanism's kernel, else
    'scalesynth.kernels.clearance.segment_distance'-like names."""
    py = getattr(dispatcher, "py_func", None)
    if py is None:
        return "Numba kernels"
    source = os.path.basename(getattr(py.__code__, "co_filename", "") or "")
    module = source[:-3] if source.endswith(".py") else ""
    registry = getattr(sys.modules.get("scalesynth.mechanisms"), "_REGISTRY", {}) or {}
    for name, mech in registry.items():  # a mechanism's kernels, and grid kernels bound to them, live in its file
        if module and type(mech).__module__ == f"scalesynth.mechanisms.{module}":
            return f"the {name} kernels"
    return f"{py.__module__}.{py.__qualname__.split('__')[0]}"


def notice_line(dispatcher) -> str:
    """The notice: what compiles, that it happens once, where it is cached; at most 200 characters."""
    cache = getattr(getattr(dispatcher, "_cache", None), "_cache_path", None)
    if cache:  # NUMBA_CACHE_DIR itself rather than its per-source subdirectory
        from numba.core import config

        cache = config.CACHE_DIR or cache
    where = f"cached in {cache}" if cache else "cached"
    line = (f"note: compiling {_what(dispatcher)} with Numba (first run only, may take minutes; {where} for later "
            "runs)")
    if len(line) > 200:  # a long cache path: keep the sentence without it
        line = f"note: compiling {_what(dispatcher)} with Numba (first run only, may take minutes; cached for later " \
               "runs)"
    return line[:200]
