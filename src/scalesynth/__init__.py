"""scalesynth: multi-objective dimensional (scale) synthesis of parallel mechanisms.

Public API (``docs/api.md``)::

    import scalesynth as ss
    report = ss.evaluate("2pauu-ppap", {"m": 0.857, "n": 0.706, "l1": 1.499, "l2": 1.5, "c": 0.1}, keep_grid=True)
    result = ss.optimize(ss.load_config("q.yaml"), "results/q")
    front = ss.load_result("results/q").pareto          # pandas DataFrame

Importing this package is cheap: the names below are loaded on first use (no NumPy, Numba or pymoo import, and
no kernel compilation, until a function is called).
"""

from __future__ import annotations

import functools
import importlib
import sys
import types
from typing import Any

__version__ = "0.1.0"

# before anything imports Numba: compile for one fixed x86-64 level, not the host CPU (numba_target)
from scalesynth import numba_target as _numba_target  # noqa: E402

_numba_target.pin()

# public name -> module that defines it
_EXPORTS = {
    "load_config": "scalesynth.api",
    "evaluate": "scalesynth.api",
    "evaluate_config": "scalesynth.api",
    "optimize": "scalesynth.api",
    "load_result": "scalesynth.api",
    "mechanisms": "scalesynth.api",
    "get_mechanism": "scalesynth.api",
    "RunConfig": "scalesynth.config",
    "WorkspaceReport": "scalesynth.evaluate",
    "Grid": "scalesynth.evaluate",
    "RunResult": "scalesynth.optimize",
    "Mechanism": "scalesynth.mechanisms.base",
    "ScalesynthError": "scalesynth.errors",
    "ConfigError": "scalesynth.errors",
}

__all__ = [  # the same names as _EXPORTS (tests/test_api.py checks)
    "__version__",
    "load_config",
    "evaluate",
    "evaluate_config",
    "optimize",
    "load_result",
    "mechanisms",
    "get_mechanism",
    "RunConfig",
    "WorkspaceReport",
    "Grid",
    "RunResult",
    "Mechanism",
    "ScalesynthError",
    "ConfigError",
]

def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'scalesynth' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


# ``evaluate``, ``optimize`` and ``mechanisms`` are public functions and also the names of submodules. Importing a
# submodule sets it as an attribute of the package; data descriptors on the package's class win over that, so
# ``scalesynth.evaluate`` is always a _FunctionAndModule: calling it calls the API function, and any other attribute
# is the submodule's, so ``import scalesynth.mechanisms.rps_upu as m`` and ``scalesynth.evaluate.make_grid`` still work.
class _FunctionAndModule:
    def __init__(self, name: str):
        func = getattr(importlib.import_module(_EXPORTS[name]), name)
        functools.update_wrapper(self, func)
        self._submodule = f"{__name__}.{name}"

    def __call__(self, *args, **kwargs):
        return self.__wrapped__(*args, **kwargs)

    def __getattr__(self, attr: str):
        return getattr(importlib.import_module(self._submodule), attr)

    def __repr__(self) -> str:
        return f"<function scalesynth.{self.__name__} (attributes: module {self._submodule})>"


def _function_property(name: str) -> property:
    def get(self):
        cache = self.__dict__.setdefault("_function_and_module", {})
        if name not in cache:
            cache[name] = _FunctionAndModule(name)
        return cache[name]

    def set_(self, value):
        if not isinstance(value, types.ModuleType):  # the import system's setattr of the submodule is ignored
            raise AttributeError(f"scalesynth.{name} is read-only")

    return property(get, set_, doc=f"scalesynth.api.{name}")


class _Package(types.ModuleType):
    evaluate = _function_property("evaluate")
    optimize = _function_property("optimize")
    mechanisms = _function_property("mechanisms")


sys.modules[__name__].__class__ = _Package
