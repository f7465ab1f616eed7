"""Numba settings used by every kernel, in one place.

No fast-math flag that can change a value (``contract``, ``arcp``, ``afn``, ``reassoc``, ``nsz``; ``nnan``/``ninf``
would also hide the sentinels of unreachable voxels): with them, LLVM rewrites arithmetic differently depending on
what it can see, so the same kernel gave other last bits when it was compiled in this process (its callees' IR
inlined) than when it was loaded from Numba's disk cache, and other bits again on another CPU (fused multiply-adds
where the target has FMA). A resumed run, ``reproduce`` and a run on an AMD instead of an Intel machine then
differed. IEEE arithmetic keeps every result byte-identical across cache states and CPUs
(tests/test_reproducible_bits.py; the compile target is pinned by ``scalesynth.numba_target``).
"""

FASTMATH = False
