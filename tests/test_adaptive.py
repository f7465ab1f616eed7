"""The accuracy-targeted (adaptive) evaluator: the Numba kernel against its NumPy twin (tests/naive.py, the same
algorithm level by level), the seed-000 volume against the exact quadrature, determinism, and the config form."""

import numpy as np
import pytest
import yaml

from scalesynth.config import config_from_dict, load_config
from scalesynth.errors import ConfigError
from scalesynth.evaluate import Tolerance, adaptive_population_stats, evaluate_config, make_grid
from scalesynth.kernels import grid as kgrid
from scalesynth.kernels.adaptive import adaptive_stats
from scalesynth.mechanisms import available, get
from test_registry import config_for

from exact_volume import exact_volume
from naive import adaptive_stats as adaptive_twin

EDGES = np.array([0.0, 0.1, 0.3, 1.0])


@pytest.mark.parametrize("name", available())
def test_adaptive_kernel_equals_numpy_twin(name):
    """Same refinement decisions, leaves and weights: every statistic of every field equal to the twin's (counts
    exactly: the weights are binary fractions), and the same number of field evaluations. The twin evaluates the
    fields through the mechanism's kernel (population_points_fields) so that only the algorithm is compared; the
    kernels themselves are checked against NumPy SVD twins in test_fields.py."""
    mech = get(name)
    cfg = load_config(config_for(name))
    design, options = cfg.resolved_design(), cfg.resolved_options()
    ndim = len(mech.task_axes)
    g = make_grid(mech, design, options, 8 if ndim == 2 else 5)
    packed = mech.pack(design, options)

    def fields(pts):
        return kgrid.population_points_fields(mech.field_kernel, mech.n_fields, packed[None, :], pts)[0]

    for levels in (0, 2):
        s, s2, ev = adaptive_stats(mech.field_kernel, mech.n_fields, packed[None, :], g.lo[None, :],
                                   g.step[None, :], g.shape, EDGES, ndim, levels, 0.1)
        t, t2, tev = adaptive_twin(fields, mech.n_fields, g.lo, g.step, g.shape, EDGES, ndim, levels, 0.1)
        assert s[0, 0] > 0, name
        for row, twin in ((s[0], t), (s2[0], t2)):
            assert row[0] == twin[0]
            bands = kgrid.band_column(mech.n_fields, 0)
            assert np.array_equal(row[bands:], twin[bands:])
            np.testing.assert_allclose(row, twin, rtol=1e-10, atol=1e-12 * np.abs(twin).max())
        assert ev[0] == tev
        if levels == 0:
            assert np.array_equal(s, s2)


def test_adaptive_seed000_volume_meets_tolerance_against_exact_quadrature():
    """Seed 000's workspace volume has an exact 1-D quadrature (spec §1.9): the adaptive evaluator at the default
    tolerance (0.2 %) meets it on the Table-4 design, and its error estimate is below the tolerance it reports."""
    mech = get("2pauu-ppap")
    design = dict(m=0.857, n=0.706, l1=1.499, l2=1.5, c=0.1)
    options = mech.resolve_options({})
    design = mech.resolve_design(design)
    tol = Tolerance()
    r = adaptive_population_stats(mech, [design], options, mech.pack(design, options)[None, :], tol, EDGES)
    volume = r.stats[0, 0] * r.cell[0]
    assert volume == pytest.approx(exact_volume(**design), rel=tol.volume)
    assert r.error_volume[0] <= tol.volume
    assert r.error_gci[0] <= tol.gci


def test_adaptive_is_deterministic_and_weights_are_consistent():
    """Two runs give byte-identical rows; every field's statistics use the same weights (the band counts add up
    to the count)."""
    mech = get("rps-upu")
    cfg = load_config(config_for("rps-upu"))
    design, options = cfg.resolved_design(), cfg.resolved_options()
    packed = mech.pack(design, options)[None, :]
    a = adaptive_population_stats(mech, [design], options, packed, Tolerance(), EDGES)
    b = adaptive_population_stats(mech, [design], options, packed, Tolerance(), EDGES)
    assert a.stats.tobytes() == b.stats.tobytes()
    bands = a.stats[0, kgrid.band_column(mech.n_fields, 0):]
    assert bands.sum() == pytest.approx(a.stats[0, 0], rel=1e-12)


def test_tolerance_config_and_resolution_override():
    """`grid: {tolerance: ...}` without a resolution runs the adaptive evaluator and reports its error estimates
    (within the tolerance on the config's design); an explicit resolution (what `--resolution N` sets) forces the
    uniform grid; a bad tolerance is a one-line config error naming the field."""
    data = yaml.safe_load(config_for("rps-upu").read_text())
    data["grid"] = {"tolerance": {"volume": 0.002, "gci": 5.0e-4}}
    cfg = config_from_dict(data)
    assert cfg.grid.adaptive
    rep = evaluate_config(cfg)
    assert 0.0 <= rep.metrics["error_volume"] <= 0.002
    assert 0.0 <= rep.metrics["error_gci"] <= 5.0e-4
    forced = config_from_dict(data, ["grid.resolution=24"])
    assert not forced.grid.adaptive
    rep24 = evaluate_config(forced)
    assert "error_volume" not in rep24.metrics and rep24.resolution == 24
    # within the tolerance of a fine uniform grid (192^3, 8x the cells per axis of the 24 above)
    fine = evaluate_config(config_from_dict(data, ["grid.resolution=192"]))
    assert rep.metrics["gci"] == pytest.approx(fine.metrics["gci"], abs=5.0e-4)
    assert rep.measure == pytest.approx(fine.measure, rel=0.002)
    data["grid"] = {"tolerance": {"volume": -1.0}}
    with pytest.raises(ConfigError, match="grid.tolerance.volume"):
        config_from_dict(data)
