"""Tool-point position workspace of the 2-RPS-UPU (seed 002, spec §2.8): the same mechanism as `rps-upu`, with the
task space (x, y, z) of a tool point T = O' + R (0, 0, -d). Defined in rps_upu.py; registered from this module."""

from scalesynth.mechanisms.rps_upu import TOOL_MECHANISM as MECHANISM

__all__ = ["MECHANISM"]
