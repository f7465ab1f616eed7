"""The rotary Delta, a described mechanism: everything is in delta.yaml beside this file (the leg library and the
kernel template in describe/ do the rest); docs/mechanisms/delta.md."""

from scalesynth.mechanisms.describe import builtin

MECHANISM = builtin("delta")
