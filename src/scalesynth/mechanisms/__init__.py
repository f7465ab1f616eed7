"""Registry of mechanisms. Each module in this package that defines ``MECHANISM`` is registered on import.

Each description file ``NAME.yaml`` here is a described mechanism, registered as NAME (describe/, docs/describing.md).
Adding a mechanism = adding one module, or one description file, here (plus its config and spec-case tests); nothing
else changes. ``get(name)`` imports only the module the name suggests (``_module_name``: '2pauu-ppap' ->
``pauu_ppap``), or loads only the description file ``name.yaml``, so a process that uses one mechanism loads no other
(their imports and Numba dispatchers cost a fresh process tens of milliseconds); any other name, and ``available()``,
load every one.
"""

from __future__ import annotations

import importlib
import pkgutil
import re
from pathlib import Path

from scalesynth.errors import UnknownMechanism
from scalesynth.mechanisms.base import Mechanism

_REGISTRY: dict[str, Mechanism] = {}
_LOADED = False
_HERE = Path(__file__).resolve().parent


def register(mech: Mechanism) -> Mechanism:
    if mech.name in _REGISTRY and _REGISTRY[mech.name] is not mech:
        raise ValueError(f"mechanism {mech.name!r} registered twice")
    _REGISTRY[mech.name] = mech
    return mech


def _load_all() -> None:
    global _LOADED
    if _LOADED:
        return
    for info in pkgutil.iter_modules(__path__):
        if info.name.startswith("_") or info.name == "base":
            continue
        module = importlib.import_module(f"{__name__}.{info.name}")
        mech = getattr(module, "MECHANISM", None)
        if isinstance(mech, Mechanism):
            register(mech)
    for path in sorted(_HERE.glob("*.yaml")):
        _load_description(path.stem)
    _LOADED = True


def _load_description(name: str) -> None:
    """Register the built-in description file ``name.yaml``, once."""
    if name in _REGISTRY:
        return
    from scalesynth.mechanisms.describe import builtin

    mech = builtin(name)
    if mech.name != name:
        raise ValueError(f"mechanisms/{name}.yaml: its description is named {mech.name!r}, not {name!r}")
    register(mech)


def available() -> list[str]:
    _load_all()
    return sorted(_REGISTRY)


def _module_name(name: str) -> str:
    """The module a mechanism name suggests: non-identifier characters -> '_', leading digits and '_' dropped."""
    return re.sub(r"\W", "_", name.lower()).lstrip("0123456789_")


def _load_one(name: str) -> None:
    """Import and register the module ``name`` suggests, if this package has one (a cheap directory listing)."""
    if re.fullmatch(r"[a-z][a-z0-9-]{0,39}", name) and (_HERE / f"{name}.yaml").is_file():
        _load_description(name)
        return
    module = _module_name(name)
    if module == "base" or module not in {info.name for info in pkgutil.iter_modules(__path__)}:
        return
    mech = getattr(importlib.import_module(f"{__name__}.{module}"), "MECHANISM", None)
    if isinstance(mech, Mechanism):
        register(mech)


def find(name: str) -> Mechanism | None:
    """The registered mechanism ``name``, or None, loading at most the module or description file the name suggests
    (every mechanism lives there: tests/test_lazy_imports.py), so asking about a user's name loads nothing else."""
    if name not in _REGISTRY and not _LOADED:
        _load_one(name)
    return _REGISTRY.get(name)


def get(name: str) -> Mechanism:
    if name not in _REGISTRY and not _LOADED:
        _load_one(name)
    if name not in _REGISTRY:
        _load_all()
    try:
        return _REGISTRY[name]
    except KeyError:
        from scalesynth.names import hint

        raise UnknownMechanism(f"mechanism: unknown mechanism {str(name)[:60]!r} "
                               + hint(str(name), sorted(_REGISTRY), "available",
                                      more="`scalesynth mechanisms` lists them")) from None
