"""The CPU that Numba compiles scalesynth's kernels for: one fixed x86-64 feature level, not the host's.

Left alone, Numba compiles for the host CPU (``-march=native``), so the same kernel is different machine code on an
Intel Xeon and on an AMD EPYC, and its disk cache cannot be shared between them. scalesynth pins the target to the
x86-64-v3 level (AVX2, FMA, BMI2: every x86-64 server CPU since 2013-2015), or to plain x86-64 on a CPU without
those features, before Numba reads its configuration. Together with kernels free of value-changing fast-math flags
(``kernels.flags``), results are byte-identical across CPUs and whether a kernel was compiled in this process or
loaded from the disk cache (tests/test_reproducible_bits.py). The target is recorded in every run's manifest.

A user's own ``NUMBA_CPU_NAME`` (and ``NUMBA_CPU_FEATURES``) wins. This module imports nothing heavy: it runs when
``scalesynth`` is imported.
"""

from __future__ import annotations

import os
import platform
import sys

PINNED = "x86-64-v3"
FALLBACK = "x86-64"
# the x86-64-v3 level's features, as /proc/cpuinfo names them (lzcnt is 'abm' there)
_V3_FLAGS = frozenset({"avx", "avx2", "bmi1", "bmi2", "f16c", "fma", "abm", "movbe", "xsave"})


def _host_has_v3() -> bool:
    """Whether /proc/cpuinfo lists every x86-64-v3 feature (False where it cannot be read)."""
    try:
        with open("/proc/cpuinfo", encoding="ascii", errors="replace") as f:
            for line in f:
                if line.startswith("flags"):
                    return _V3_FLAGS <= set(line.split(":", 1)[1].split())
    except OSError:
        pass
    return False


def choose() -> tuple[str, str] | None:
    """(cpu name, features) to pin, or None to leave Numba's choice (not x86-64, or set by the user)."""
    if "NUMBA_CPU_NAME" in os.environ or platform.machine().lower() not in ("x86_64", "amd64"):
        return None
    return (PINNED if _host_has_v3() else FALLBACK), ""


def pin() -> None:
    """Set Numba's target CPU (environment, and Numba's config where Numba is already imported)."""
    choice = choose()
    if choice is None:
        return
    name, features = choice
    os.environ["NUMBA_CPU_NAME"] = name
    os.environ["NUMBA_CPU_FEATURES"] = features
    config = sys.modules.get("numba.core.config")
    if config is not None:  # imported before scalesynth: its codegen reads these when it is first created
        config.CPU_NAME = name
        config.CPU_FEATURES = features


def describe() -> dict[str, str]:
    """The target in force, for a run's manifest: {"cpu_name", "cpu_features"} ('host' where Numba's own)."""
    from numba.core import config

    return {"cpu_name": config.CPU_NAME or "host", "cpu_features": config.CPU_FEATURES or ""}
