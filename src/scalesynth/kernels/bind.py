"""Compile once: grid kernels bound to one field kernel, cached on disk like any module-level @njit function.

Numba cannot disk-cache a function that takes another jitted function as an argument ("dynamic globals"), nor a
closure over one (its cache key pickles the dispatcher, whose uuid differs per process). A *template* here is a
plain Python function that calls the field kernel through the global names ``FIELD_KERNEL`` / ``N_FIELDS``;
``bind`` makes a copy of it whose globals hold one mechanism's kernel, so Numba compiles a direct call and the
result caches and hits across processes.

Cache identity of a bound copy: its file is the field kernel's source file (Numba's staleness check follows that
file's time stamp and size) and its name carries a hash of the sources of ``scalesynth/kernels/*.py``,
``scalesynth/stiffness/legs.py`` and of that file, so editing either the mechanism or a shared kernel module
compiles afresh (Numba alone would not notice an edited callee in another file).

``shared`` compiles a template that takes its per-mechanism kernel as an argument (a Numba first-class function)
once for every mechanism: an explicit signature makes the argument a function pointer, which Numba can
disk-cache. A large driver (the column algorithm of kernels/adaptive.py) then compiles once per machine instead of
once per mechanism and plan variant; the bound kernel it calls must be compiled with the matching signature
(``bind(..., signature=...)``).
"""

from __future__ import annotations

import hashlib
import os
import re
import types
from collections.abc import Callable
from pathlib import Path
from typing import Any

from numba import njit

_KERNELS_DIR = Path(__file__).resolve().parent
# numba helpers outside kernels/ that field kernels inline (their edits must compile afresh too)
_INLINED = [_KERNELS_DIR.parent / "stiffness" / "legs.py"]
_BOUND: dict[tuple[Any, int, str], Any] = {}
_SOURCE_HASH: dict[str, str] = {}


def _sources_hash(kernel_file: str) -> str:
    """Short hash of the kernel package's sources and the field kernel's file ('' if a file cannot be read)."""
    h = _SOURCE_HASH.get(kernel_file)
    if h is None:
        digest = hashlib.sha256()
        try:
            for path in sorted(_KERNELS_DIR.glob("*.py")) + _INLINED + [Path(kernel_file)]:
                digest.update(path.read_bytes())
            h = digest.hexdigest()[:12]
        except OSError:
            h = ""
        _SOURCE_HASH[kernel_file] = h
    return h


def bind(template: Callable, field_kernel: Any, n_fields: int, extra: dict[str, Any] | None = None,
         signature: Any = None, **jit_options) -> Any:
    """The template compiled for ``field_kernel`` (an @njit dispatcher) with ``n_fields`` slots; memoised per
    process, disk-cached when the kernel comes from a real source file. ``extra``: more globals of the copy
    (e.g. ``REACH_KERNEL``), kernels from the field kernel's file or kernels/ (the cache follows those files).
    ``signature``: compile for this Numba signature alone, at once (so the result can be passed to a ``shared``
    template whose signature names it as a function type); None: lazily, for the argument types of each call."""
    extra = dict(extra or {})
    key = (field_kernel, int(n_fields), template.__name__, tuple(sorted(extra.items(), key=lambda kv: kv[0])),
           str(signature))
    out = _BOUND.get(key)
    if out is not None:
        return out
    py = getattr(field_kernel, "py_func", field_kernel)
    kernel_file = py.__code__.co_filename
    cacheable = os.path.isfile(kernel_file) and bool(_sources_hash(kernel_file))
    module = re.sub(r"\W", "_", getattr(py, "__module__", "") or "kernel")
    qual = re.sub(r"\W", "_", py.__qualname__)
    name = f"{template.__name__.lstrip('_')}__{module}__{qual}__{n_fields}"
    tag = _sources_hash(kernel_file) if cacheable else ""
    if extra:  # the extra kernels' names folded into the 12-digit tag: another one is another copy, and the cache
        # file names (near the 255-byte limit of a file name for the nested copies) get no longer
        fns = {k: getattr(v, "py_func", v) for k, v in extra.items()}
        names = ",".join(f"{k}={getattr(f, '__module__', '')}.{getattr(f, '__qualname__', repr(f))}"
                         for k, f in sorted(fns.items()))
        tag = hashlib.sha256(f"{tag};{names}".encode()).hexdigest()[:12]
    if tag:
        name += f"__{tag}"
    code = template.__code__.replace(co_name=name, co_qualname=name,
                                     co_filename=kernel_file if cacheable else template.__code__.co_filename)
    env = dict(template.__globals__)
    env["FIELD_KERNEL"] = field_kernel
    env["N_FIELDS"] = int(n_fields)
    env.update(extra)
    fn = types.FunctionType(code, env, name, template.__defaults__)
    fn.__qualname__ = name
    fn.__module__ = template.__module__
    jit = njit(cache=cacheable, **jit_options) if signature is None else njit(signature, cache=cacheable,
                                                                             **jit_options)
    out = _BOUND[key] = jit(fn)
    return out


def shared(template: Callable, signature: Any, extra: dict[str, Any] | None = None, **jit_options) -> Any:
    """``template`` compiled once for ``signature`` (memoised per process, disk-cached): a copy named with the hash
    of the kernel package's sources (an edited callee in another file of kernels/ compiles afresh), whose globals
    add ``extra`` (e.g. another shared kernel it calls)."""
    extra = dict(extra or {})
    key = (template, "shared", tuple(sorted(extra.items(), key=lambda kv: kv[0])), str(signature))
    out = _BOUND.get(key)
    if out is not None:
        return out
    source = template.__code__.co_filename
    tag = _sources_hash(source)
    name = f"{template.__name__.lstrip('_')}__shared" + (f"__{tag}" if tag else "")
    code = template.__code__.replace(co_name=name, co_qualname=name)
    env = dict(template.__globals__)
    env.update(extra)
    fn = types.FunctionType(code, env, name, template.__defaults__)
    fn.__qualname__ = name
    fn.__module__ = template.__module__
    out = _BOUND[key] = njit(signature, cache=bool(tag), **jit_options)(fn)
    return out
