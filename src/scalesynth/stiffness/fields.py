"""Per-voxel stiffness fields and their statistics over the workspace and the task box (Numba, deterministic).

Field-kernel contract (until the metric catalogue's multi-field point kernels take them over; docs/stiffness.md):
a mechanism with a stiffness model has a method ``stiffness_field(options)`` returning an ``@njit`` function
``field(p, x, y, z) -> (ok, stiffness_min, deflection)`` (or raising InvalidParameter for options it cannot
evaluate per voxel) reading the same packed vector as its point kernel:
``ok`` is False where the pose is unreachable under the limits (the point kernel's -1); ``stiffness_min`` (N per
length unit) is the smallest eigenvalue of the translational stiffness felt by a pure force; ``deflection`` (length
unit) the magnitude of the deflection under the packed load. At a singular pose stiffness_min = 0 and
deflection = inf (never NaN).

Metrics (units: length unit of the mechanism, N): ``deflection_max``, ``deflection_mean``, ``stiffness_min``
(the smallest over the voxels), ``stiffness_mean`` over the reachable workspace, and the same with the prefix
``task_`` over the reachable cells of the task box. An empty set gives deflection inf and stiffness 0 (the worst
values, so a constraint ``deflection_max <= d`` rejects the design), never NaN.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numba import njit, prange

from scalesynth.kernels.flags import FASTMATH

S_COUNT, S_DMAX, S_DSUM, S_KMIN, S_KSUM = 0, 1, 2, 3, 4
N_STATS = 5
WORKSPACE_METRICS = ("deflection_max", "deflection_mean", "stiffness_min", "stiffness_mean")
TASK_METRICS = tuple("task_" + m for m in WORKSPACE_METRICS)
UNITS = {"deflection_max": "length", "deflection_mean": "length", "stiffness_min": "N/length",
         "stiffness_mean": "N/length"}


@njit(parallel=True, fastmath=FASTMATH)
def population_stiffness_stats(field, params, lo, step, shape):
    """[count, max deflection, sum deflection, min stiffness_min, sum stiffness_min] per design, each design on its
    own grid (params (n, k), lo/step (n, 3), shape int64[3]); parallel over (design, x-slab), reduced in slab order."""
    n_designs = params.shape[0]
    nx, ny, nz = shape[0], shape[1], shape[2]
    partial = np.zeros((n_designs * nx, N_STATS))
    for task in prange(n_designs * nx):
        d = task // nx
        i = task - d * nx
        p = params[d]
        x = lo[d, 0] + (i + 0.5) * step[d, 0]
        count = 0.0
        dmax = 0.0
        dsum = 0.0
        kmin = math.inf
        ksum = 0.0
        for j in range(ny):
            y = lo[d, 1] + (j + 0.5) * step[d, 1]
            for k in range(nz):
                z = lo[d, 2] + (k + 0.5) * step[d, 2]
                ok, kv, dv = field(p, x, y, z)
                if ok:
                    count += 1.0
                    dsum += dv
                    ksum += kv
                    if dv > dmax:
                        dmax = dv
                    if kv < kmin:
                        kmin = kv
        row = partial[task]
        row[S_COUNT] = count
        row[S_DMAX] = dmax
        row[S_DSUM] = dsum
        row[S_KMIN] = kmin
        row[S_KSUM] = ksum
    return _reduce(partial, n_designs, nx)


@njit(cache=True)
def _reduce(partial, n_designs, nx):
    out = np.zeros((n_designs, N_STATS))
    for d in range(n_designs):
        acc = out[d]
        acc[S_KMIN] = math.inf
        for i in range(nx):
            row = partial[d * nx + i]
            acc[S_COUNT] += row[S_COUNT]
            acc[S_DSUM] += row[S_DSUM]
            acc[S_KSUM] += row[S_KSUM]
            if row[S_DMAX] > acc[S_DMAX]:
                acc[S_DMAX] = row[S_DMAX]
            if row[S_KMIN] < acc[S_KMIN]:
                acc[S_KMIN] = row[S_KMIN]
    return out


@njit(parallel=True, fastmath=FASTMATH)
def sample_stiffness(field, p, lo, step, shape):
    """(stiffness_min, deflection) at every node of one design's grid, shape (2, nx, ny, nz); NaN-free: unreachable
    nodes hold stiffness -1 and deflection -1."""
    nx, ny, nz = shape[0], shape[1], shape[2]
    out = np.empty((2, nx, ny, nz))
    for i in prange(nx):
        x = lo[0] + (i + 0.5) * step[0]
        for j in range(ny):
            y = lo[1] + (j + 0.5) * step[1]
            for k in range(nz):
                z = lo[2] + (k + 0.5) * step[2]
                ok, kv, dv = field(p, x, y, z)
                out[0, i, j, k] = kv if ok else -1.0
                out[1, i, j, k] = dv if ok else -1.0
    return out


def stats_to_metrics(stats: np.ndarray, prefix: str = "") -> dict[str, np.ndarray]:
    """Metric arrays from raw sums; empty sets give deflection inf and stiffness 0."""
    count = stats[:, S_COUNT]
    safe = np.where(count > 0, count, 1.0)
    names = TASK_METRICS if prefix else WORKSPACE_METRICS
    with np.errstate(invalid="ignore"):  # inf / count stays inf
        dmean = stats[:, S_DSUM] / safe
    return {
        names[0]: np.where(count > 0, stats[:, S_DMAX], math.inf),
        names[1]: np.where(count > 0, dmean, math.inf),
        names[2]: np.where(count > 0, stats[:, S_KMIN], 0.0),
        names[3]: np.where(count > 0, stats[:, S_KSUM] / safe, 0.0),
    }


def has_fields(mech) -> bool:
    return callable(getattr(mech, "stiffness_field", None))


def field_or_none(mech, options: Mapping[str, Any]):
    """The mechanism's field kernel for these options, or None where it has none (or not for these options)."""
    from scalesynth.errors import InvalidParameter

    if not has_fields(mech):
        return None
    try:
        return mech.stiffness_field(options)
    except InvalidParameter:
        return None


def check_field_available(mech, options: Mapping[str, Any], where: str) -> None:
    """Raise ValueError ('<where>: ...') when stiffness metrics cannot be evaluated for this mechanism/options."""
    from scalesynth.errors import InvalidParameter

    if not has_fields(mech):
        raise ValueError(f"{where}: {mech.name} has no per-voxel stiffness fields yet (see docs/stiffness.md)")
    try:
        mech.stiffness_field(options)
    except InvalidParameter as err:
        raise ValueError(f"{where}: {err}") from None


def stiffness_metrics(mech, options: Mapping[str, Any], packed: np.ndarray, lo: np.ndarray, step: np.ndarray,
                      shape: np.ndarray, task_box: Mapping[str, Any] | None = None,
                      task_resolution: int | None = None) -> dict[str, np.ndarray]:
    """Workspace stiffness metrics of many designs (packed (n, k), lo/step (n, 3), shape int64[3], as the LCI
    evaluator), plus the task-box ones when ``task_box`` ({axis: [lo, hi]}) is given (``task_resolution`` cells per
    axis). Raises InvalidParameter when the mechanism has no stiffness field."""
    from scalesynth.errors import InvalidParameter

    if not has_fields(mech):
        raise InvalidParameter(f"mechanism: {mech.name} has no per-voxel stiffness fields yet")
    field = mech.stiffness_field(options)
    out = stats_to_metrics(population_stiffness_stats(field, packed, lo, step, shape))
    if task_box is not None:
        n = packed.shape[0]
        ndim = len(mech.task_axes)
        tlo, tstep = np.zeros(3), np.ones(3)
        tshape = np.ones(3, dtype=np.int64)
        for a, name in enumerate(mech.task_axes):
            tlo[a], hi = task_box[name]
            tshape[a] = task_resolution
            tstep[a] = (hi - tlo[a]) / task_resolution
        tshape[ndim:] = 1
        stats = population_stiffness_stats(field, packed, np.tile(tlo, (n, 1)), np.tile(tstep, (n, 1)), tshape)
        out.update(stats_to_metrics(stats, "task_"))
    return out
