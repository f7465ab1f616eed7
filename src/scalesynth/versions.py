"""Dependency versions: compare those recorded in a run's manifest with the installed ones.

Byte-identical results are promised only for the same machine type and the same versions of scalesynth's
dependencies, so ``scalesynth reproduce`` warns first when they differ. The recorded set is written by
``optimize.run`` into ``manifest.json["versions"]`` (``installed_versions``).
"""

from __future__ import annotations

import platform
from importlib import metadata

# the packages whose versions a manifest records (the ones that can change a result's bytes, and the CLI)
DEPENDENCIES = ("numpy", "numba", "llvmlite", "pymoo", "moocore", "pandas", "matplotlib", "pydantic", "pyyaml", "typer")


def installed_versions() -> dict[str, str]:
    """{package: version} of scalesynth, Python and every dependency that a manifest records, and the CPU target
    Numba compiles for (``numba_target``: name, and '+features' where set)."""
    from scalesynth import __version__
    from scalesynth.numba_target import describe

    target = describe()
    out = {"scalesynth": __version__, "python": platform.python_version(),
           "numba_target": target["cpu_name"] + (f"+{target['cpu_features']}" if target["cpu_features"] else "")}
    for name in DEPENDENCIES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "not installed"
    return out


def version_differences(recorded: dict[str, str] | None) -> list[str]:
    """'name recorded -> installed' for every package (and Python) of a manifest's ``versions`` whose installed
    version differs ('not installed' when it is missing); ``[]`` when all agree."""
    if not recorded:
        return ["the manifest records no versions"]
    now = installed_versions()
    return [f"{name} {was} -> {now.get(name, 'not installed')}" for name, was in recorded.items()
            if now.get(name, "not installed") != was]
