"""Numba kernels: closed-form conditioning and the generic voxel-grid evaluator."""
