"""Numba kernels: closed-form conditioning and the generic voxel-grid evaluator.

Every module with a disk-cached Numba function is in this package or imports from it, so importing it first
makes Numba's cache safe for several processes (kernels.cache_lock) before anything is compiled or loaded, after the
NUMBA_* variables are checked and with a fallback where no cache location is writable (scalesynth.environment)."""

from scalesynth import environment as _environment

_environment.check()  # NUMBA_* variables, before Numba is imported

from scalesynth import compile_notice as _compile_notice  # noqa: E402
from scalesynth.kernels import cache_lock as _cache_lock  # noqa: E402

_cache_lock.install()
_environment.tolerate_missing_cache()  # no writable cache location: compile in memory, one warning
_compile_notice.attach()  # a CLI process that compiles says so once (a no-op unless the CLI enabled it)
