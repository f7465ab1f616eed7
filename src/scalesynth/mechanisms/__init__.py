"""Registry of mechanisms. Each module in this package that defines ``MECHANISM`` is registered on import.

Adding a mechanism = adding one module here (plus its config and spec-case tests); nothing else changes.
"""

from __future__ import annotations

import importlib
import pkgutil

from scalesynth.errors import UnknownMechanism
from scalesynth.mechanisms.base import Mechanism

_REGISTRY: dict[str, Mechanism] = {}
_LOADED = False


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
    _LOADED = True


def available() -> list[str]:
    _load_all()
    return sorted(_REGISTRY)


def get(name: str) -> Mechanism:
    _load_all()
    try:
        return _REGISTRY[name]
    except KeyError:
        raise UnknownMechanism(
            f"mechanism: unknown mechanism {name!r} (available: {', '.join(sorted(_REGISTRY))})"
        ) from None
