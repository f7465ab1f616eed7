"""Mechanism.lci_kernel: the search's kernel when its workspace metrics are the LCI's alone (measure, GCI, bands).
Its slot 0 must equal the field kernel's bit for bit, so a search with it gives the same numbers as a full
evaluation; the other columns are filled in for the final population (SynthesisProblem.complete_metrics)."""

import numpy as np
import pytest

from scalesynth import metrics as _metrics
from scalesynth.config import config_from_dict, load_config
from scalesynth.evaluate import Tolerance, adaptive_population_stats, evaluate_config_population, make_grid
from scalesynth.kernels import grid as kgrid
from scalesynth.mechanisms import available, get
from scalesynth.problem import SynthesisProblem
from test_adaptive import EDGES, _box, _option_variants, _random_designs
from test_registry import config_for

WITH_LCI_KERNEL = [n for n in available() if get(n).lci_kernel is not get(n).field_kernel]


def test_the_costly_mechanisms_have_an_lci_kernel():
    # the four whose field kernels carry a clearance, stiffness or 6 x 6 SVD the LCI does not need
    assert {"ups-sspr", "rps-upu", "rps-upu-tool", "pprs-rprs"} <= set(WITH_LCI_KERNEL)


@pytest.mark.parametrize("name", WITH_LCI_KERNEL)
def test_lci_kernel_slot0_is_the_field_kernels_bit_for_bit(name):
    """On a 24^3 grid over 1.1x the bounding box (in and out of the workspace) of the config's design and 5 random
    designs in its bounds, with the config's options and, where the mechanism has it, interference_free (then the
    clearance still decides reachability in the LCI kernel): slot 0 equal as bytes, reachable points included."""
    mech = get(name)
    cfg = load_config(config_for(name))
    designs = _random_designs(mech, cfg, 5, 11)
    for options in _option_variants(mech, cfg):
        reachable = 0
        for d in designs:
            lo, hi = _box(mech, d, options)
            mid, half = 0.5 * (lo + hi), 0.55 * (hi - lo)
            axes = [np.linspace(mid[a] - half[a], mid[a] + half[a], 24) if a < len(mech.task_axes)
                    else np.array([lo[a]]) for a in range(3)]
            pts = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
            packed = mech.pack(d, options)[None, :]
            full = kgrid.population_points_fields(mech.field_kernel, mech.n_fields, packed, pts)[0, :, 0]
            lci = kgrid.population_points_fields(mech.lci_kernel, mech.n_fields, packed, pts)[0, :, 0]
            assert full.tobytes() == lci.tobytes(), name
            reachable += int((full > 0).sum())
        assert reachable > 0, name  # LCI values, not only -1, were compared


@pytest.mark.parametrize("name", WITH_LCI_KERNEL)
def test_lci_only_statistics_equal_the_full_ones(name):
    """The LCI's statistics (count, sum, sum of squares, min, max; band measures) and, for the adaptive evaluator,
    the error estimates, levels and kernel calls: byte-identical with lci_only, on a uniform grid (N = 10) and the
    adaptive evaluator, config design and 3 random ones."""
    mech = get(name)
    cfg = load_config(config_for(name))
    options = cfg.resolved_options()
    designs = _random_designs(mech, cfg, 3, 5)
    packed = np.stack([mech.pack(d, options) for d in designs])
    nb = len(EDGES) - 1
    lci_cols = list(range(0, 5)) + list(range(1 + 4 * mech.n_fields, 1 + 4 * mech.n_fields + nb))
    grids = [make_grid(mech, d, options, 10) for d in designs]
    lo, step = np.stack([g.lo for g in grids]), np.stack([g.step for g in grids])
    full = mech.grid_stats(packed, lo, step, grids[0].shape, EDGES)
    part = mech.grid_stats(packed, lo, step, grids[0].shape, EDGES, lci_only=True)
    assert full[:, 0].sum() > 0, name
    assert full[:, lci_cols].tobytes() == part[:, lci_cols].tobytes(), name
    a = adaptive_population_stats(mech, designs, options, packed, Tolerance(), EDGES)
    b = adaptive_population_stats(mech, designs, options, packed, Tolerance(), EDGES, lci_only=True)
    assert a.stats[:, lci_cols].tobytes() == b.stats[:, lci_cols].tobytes(), name
    # every other field's sums are the full evaluation's (a field the LCI kernel computes too: ups-sspr's sigmas) or
    # exactly 0 (one it does not write: the buffers start at 0; they once summed whatever the allocation held, which
    # overflowed to inf in a search of rps-upu)
    others = [kgrid.field_column(f, s) for f in range(1, mech.n_fields) for s in (kgrid.STAT_SUM, kgrid.STAT_SUMSQ)]
    for lci, every in ((part, full), (b.stats, a.stats)):
        assert np.all((lci[:, others] == every[:, others]) | (lci[:, others] == 0.0)), name
    for attr in ("error_volume", "error_gci", "levels", "evaluations"):
        assert getattr(a, attr).tobytes() == getattr(b, attr).tobytes(), (name, attr)


RPS = load_config(config_for("rps-upu")).model_dump(mode="json", exclude_none=True)


def _rps_config(objectives, constraints=()):
    return config_from_dict({**RPS, "grid": {"resolution": 10}, "objectives": objectives,
                             "constraints": list(constraints)})


def _designs(n=6, seed=2):
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.uniform(40, 120, n), rng.uniform(20, 80, n), rng.uniform(20, 80, n)])


def test_fields_give_the_lci_columns_of_a_full_evaluation():
    cfg = _rps_config([{"metric": "volume", "sense": "max"}, {"metric": "gci", "sense": "max"}])
    problem = SynthesisProblem(cfg)
    ds = problem.designs(_designs())
    full = evaluate_config_population(cfg, ds)
    part = evaluate_config_population(cfg, ds, frozenset({"workspace"}), frozenset({"lci"}))
    entries = _metrics.catalogue(cfg.mech, "mm").values()
    field = {c: _metrics.field_of(m) for m in entries if m.family == "workspace" for c in m.columns(3)}
    assert set(part) == {k for k in full if field.get(k) == "lci"}
    assert {"volume_mm_rad2", "gci", "fci", "voxels", "band0_share"} <= set(part)
    assert "mean_clearance_mm" in full and "min_sigma_min" in full and "max_deflection_mm" in full
    assert "mean_clearance_mm" not in part and "min_sigma_min" not in part and "max_deflection_mm" not in part
    for k, v in part.items():
        assert v.tobytes() == full[k].tobytes(), k


def test_problem_searches_the_lci_alone_and_completes_every_other_field():
    """volume and GCI objectives: the search runs the LCI kernel (searched_fields {'lci'}), the sigma, clearance
    and stiffness columns are NaN in the generation matrices and complete_metrics fills them in, the whole matrix
    then equal (as bytes) to a full evaluation."""
    cfg = _rps_config([{"metric": "volume", "sense": "max"}, {"metric": "gci", "sense": "max"}])
    problem = SynthesisProblem(cfg)
    assert problem.searched_families == {"workspace"} and problem.searched_fields == {"lci"}
    X = _designs()
    M = problem.metrics(X)
    missing = problem.unsearched_columns()
    assert {"mean_clearance_mm", "max_sigma_max", "min_stiffness_min_N_per_mm"} <= set(missing)
    assert "gci" not in missing and "volume_mm_rad2" not in missing and "band2_share" not in missing
    cols = [problem.metric_columns.index(k) for k in missing]
    assert np.isnan(M[:, cols]).all() and not np.isnan(np.delete(M, cols, axis=1)).any()
    done = problem.complete_metrics(X, M)
    full = evaluate_config_population(cfg, problem.designs(X))
    assert done.tobytes() == np.column_stack([full[k] for k in problem.metric_columns]).tobytes()


def test_a_searched_field_statistic_runs_every_field():
    cfg = _rps_config([{"metric": "volume", "sense": "max"}, {"metric": "gci", "sense": "max"}],
                      [{"metric": "min_clearance", "min": 0.0}])
    problem = SynthesisProblem(cfg)
    assert problem.searched_fields is None
    assert not any(k.endswith("clearance_mm") or "sigma" in k for k in problem.unsearched_columns())
    M = problem.metrics(_designs())
    missing = problem.unsearched_columns()
    assert missing == ["link_length_sum_mm", "footprint_radius_mm"]  # the design family alone: not searched
    assert not np.isnan(np.delete(M, [problem.metric_columns.index(k) for k in missing], axis=1)).any()
