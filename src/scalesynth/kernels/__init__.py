"""Numba kernels: closed-form conditioning and the generic voxel-grid evaluator.

Every module with a disk-cached Numba function is in this package or imports from it, so importing it first
makes Numba's cache safe for several processes (kernels.cache_lock) before anything is compiled or loaded."""

from scalesynth import compile_notice as _compile_notice
from scalesynth.kernels import cache_lock as _cache_lock

_cache_lock.install()
_compile_notice.attach()  # a CLI process that compiles says so once (a no-op unless the CLI enabled it)
