"""The adaptive evaluator's sparse cell store (kernels.adaptive: initial_cells, refine_cells, leaf_sums,
flag_columns' neighbours) against its obvious dense twin: the finest level's full grid, every refined cell's
value repeated over its 3 x 3 (planar 3) children with np.repeat, neighbours by clamped index, sums over the whole
grid times the cell area. Random values and random refinement over three levels, planar and 3-D."""

import numpy as np
import pytest

from scalesynth.kernels.adaptive import _neighbour_values, initial_cells, leaf_sums, refine_cells


@pytest.mark.parametrize("ndim, nx, ny", [(3, 5, 4), (3, 1, 3), (2, 7, 1)])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_cell_store_matches_the_dense_grid(ndim, nx, ny, seed):
    rng = np.random.default_rng(seed)
    ry = 3 if ndim == 3 else 1
    gl, gs, gchild, gi, nb = initial_cells(nx, ny, ndim)
    ci, cj = (v.ravel() for v in np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij"))
    dense_l, dense_s = np.zeros((nx, ny)), np.zeros((nx, ny))
    seg = np.zeros(6, dtype=np.int64)
    checked = 0
    for level in range(4):
        # this level's columns get new values (some 0: no measure), in the store and the dense grid alike
        new_l = np.where(rng.random(ci.size) < 0.2, 0.0, rng.random(ci.size))
        new_s = new_l * rng.random(ci.size)
        gl[gi], gs[gi] = new_l, new_s
        dense_l[ci, cj], dense_s[ci, cj] = new_l, new_s
        area = 1.0 / 3.0 ** (level * (ndim - 1))
        seg[level + 1] = gl.shape[0]
        vol, ssum = leaf_sums(gl, gs, gchild, seg, level, ndim)
        assert vol == pytest.approx(dense_l.sum() * area, rel=1e-13)
        assert ssum == pytest.approx(dense_s.sum() * area, rel=1e-13)
        for a in range(ci.size):
            for axis in range(ndim - 1):
                size = dense_l.shape[axis]
                lo = (max(ci[a] - 1, 0), cj[a]) if axis == 0 else (ci[a], max(cj[a] - 1, 0))
                hi = (min(ci[a] + 1, size - 1), cj[a]) if axis == 0 else (ci[a], min(cj[a] + 1, size - 1))
                for store, dense in ((gl, dense_l), (gs, dense_s)):
                    assert _neighbour_values(store, nb, a, axis, store[gi[a]]) == (dense[lo], dense[hi])
                # -1 exactly at the box
                idx = ci[a] if axis == 0 else cj[a]
                assert (nb[a, 2 * axis] < 0) == (idx == 0)
                assert (nb[a, 2 * axis + 1] < 0) == (idx == size - 1)
                checked += 1
        if level == 3:
            break
        flags = rng.random(ci.size) < 0.35
        flags[rng.integers(ci.size)] = True  # at least one refined cell per level
        gl, gs, gchild, gi, nb = refine_cells(gl, gs, gchild, gi, nb, flags, ci.size, ndim)
        da, db = (v.ravel() for v in np.meshgrid(np.arange(3), np.arange(ry), indexing="ij"))
        ci = (3 * ci[flags][:, None] + da[None, :]).ravel()
        cj = (3 * cj[flags][:, None] + db[None, :]).ravel() if ndim == 3 else np.zeros(ci.size, dtype=np.int64)
        dense_l = np.repeat(np.repeat(dense_l, 3, axis=0), ry, axis=1)
        dense_s = np.repeat(np.repeat(dense_s, 3, axis=0), ry, axis=1)
        # a child starts at its parent's value
        np.testing.assert_array_equal(gl[gi], dense_l[ci, cj])
    assert checked > 20  # the comparisons ran (planar 7 columns: about 40)
