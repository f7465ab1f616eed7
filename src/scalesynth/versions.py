"""Dependency versions: compare those recorded in a run's manifest with the installed ones.

Byte-identical results are promised only for the same machine type and the same versions of scalesynth's
dependencies, so ``scalesynth reproduce`` warns first when they differ. The recorded set is written by
``optimize._versions`` into ``manifest.json["versions"]``.
"""

from __future__ import annotations


def installed_versions() -> dict[str, str]:
    """{package: version} of scalesynth, Python and every dependency that a manifest records."""
    from scalesynth.optimize import _versions

    return _versions()


def version_differences(recorded: dict[str, str] | None) -> list[str]:
    """'name recorded -> installed' for every package (and Python) of a manifest's ``versions`` whose installed
    version differs ('not installed' when it is missing); ``[]`` when all agree."""
    if not recorded:
        return ["the manifest records no versions"]
    now = installed_versions()
    return [f"{name} {was} -> {now.get(name, 'not installed')}" for name, was in recorded.items()
            if now.get(name, "not installed") != was]
