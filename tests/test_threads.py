"""kernels.threads: the grid and column templates run their rows in Numba's number of threads (serial nogil
kernels over strides) and give the same bits whatever that number is (each row is the same compiled code; the
reduction is in a fixed order)."""

import numba
import numpy as np
import pytest

from scalesynth.config import load_config
from scalesynth.evaluation.grid import make_grid
from scalesynth.kernels import grid as kgrid
from scalesynth.kernels.adaptive import column_stats
from scalesynth.kernels.threads import in_threads
from scalesynth.mechanisms import get

pytestmark = pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="needs 2 Numba threads")


def _population(name, cfg, n=5):
    mech = get(name)
    base, options = cfg.resolved_design(), cfg.resolved_options()
    k0 = next(iter(cfg.bounds))
    designs = [{**base, k0: base[k0] * f} for f in np.linspace(0.9, 1.1, n)]
    return mech, designs, options, np.stack([mech.pack(d, options) for d in designs])


def _with_threads(k, fn):
    old = numba.get_num_threads()
    numba.set_num_threads(k)
    try:
        return fn()
    finally:
        numba.set_num_threads(old)


def test_grid_templates_give_the_same_bits_with_one_and_two_threads(root):
    """population_stats, population_points_fields, sample_fields and sample_grid of the five-bar (five designs, a
    12 x 12 grid) with 1 and with 2 threads: byte-identical arrays."""
    cfg = load_config(root / "configs" / "fivebar_packing.yaml")
    mech, designs, options, packed = _population("planar-fivebar", cfg)
    grids = [make_grid(mech, d, options, 12) for d in designs]
    lo, step = np.stack([g.lo for g in grids]), np.stack([g.step for g in grids])
    shape, edges = grids[0].shape, np.array([0.0, 0.2, 0.5, 1.0])
    pts = np.c_[grids[0].lo[0] + np.arange(40) * 0.7 * grids[0].step[0], np.full(40, grids[0].lo[1] + 5.0),
                np.zeros(40)]

    def run():
        return (kgrid.population_stats(mech.field_kernel, mech.n_fields, packed, lo, step, shape, edges),
                kgrid.population_points_fields(mech.field_kernel, mech.n_fields, packed, pts),
                kgrid.sample_fields(mech.field_kernel, mech.n_fields, packed[0], lo[0], step[0], shape),
                kgrid.sample_grid(mech.point_kernel, packed[0], lo[0], step[0], shape))

    one, two = _with_threads(1, run), _with_threads(2, run)
    assert one[0][:, 0].min() > 0.0  # every design reaches some cell
    for a, b in zip(one, two, strict=True):
        assert a.tobytes() == b.tobytes()


def test_column_template_gives_the_same_bits_with_one_and_two_threads(root):
    """column_stats of five 2pauu-ppap designs (nodes and bisection, two refinement levels) with 1 and 2 threads:
    byte-identical statistics, error estimates, levels and evaluation counts."""
    cfg = load_config(root / "configs" / "quick.yaml")
    mech, designs, options, packed = _population("2pauu-ppap", cfg)
    grids = [make_grid(mech, d, options, 8) for d in designs]
    lo = np.stack([g.lo for g in grids])
    hi = np.stack([g.lo + g.step * g.shape for g in grids])
    edges = np.array([0.0, 0.2, 0.5, 1.0])

    def run():
        return column_stats(mech.field_kernel, mech.n_fields, packed, lo, hi, 3, 6, 6, 5, 2, 0.002, 5e-4, edges,
                            reach_kernel=mech.reach_kernel)

    one, two = _with_threads(1, run), _with_threads(2, run)
    assert one[0][:, 0].min() > 0.0
    for a, b in zip(one, two, strict=True):
        assert np.asarray(a).tobytes() == np.asarray(b).tobytes()


def test_a_kernel_error_in_a_thread_is_raised_to_the_caller():
    """in_threads raises the exception a stride raised (here from Python, as a kernel's would propagate)."""
    seen = []

    def kernel(values, start, stride):
        seen.append((start, stride))
        if start == 1:
            raise ValueError("stride 1 failed")

    with pytest.raises(ValueError, match="stride 1 failed"):
        _with_threads(2, lambda: in_threads(kernel, 5, None))
    assert sorted(seen) == [(0, 2), (1, 2)]
    seen.clear()
    _with_threads(2, lambda: in_threads(kernel, 1, None))  # one item: one stride, in this thread
    assert seen == [(0, 1)]
