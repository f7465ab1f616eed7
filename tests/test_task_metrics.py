"""Task-box coverage and path metrics, checked against the NumPy twin on the same nodes."""

import numpy as np
import pytest

from scalesynth.config import config_from_dict
from scalesynth.evaluate import evaluate_config, evaluate_config_population, sample_path

from conftest import TABLE4
from naive import grid_nodes, pauu_lci

BASE = {
    "name": "t",
    "mechanism": "2pauu-ppap",
    "design": TABLE4[1],
    "grid": {"resolution": 16},
    "task": {
        "box": {"x": [-0.5, 0.5], "y": [-0.4, 0.4], "z": [1.0, 3.3]},
        "resolution": 10,
        "path": [[0.0, 0.0, 1.5], [0.5, 0.0, 1.5], [0.5, 0.3, 2.5]],
        "path_samples": 50,
    },
}


def test_task_metrics_match_twin():
    cfg = config_from_dict(BASE)
    rep = evaluate_config(cfg)
    lo = np.array([-0.5, -0.4, 1.0])
    step = (np.array([0.5, 0.4, 3.3]) - lo) / 10
    X, Y, Z = grid_nodes(lo, step, (10, 10, 10))
    lci = pauu_lci(cfg.resolved_design(), cfg.resolved_options(), X, Y, Z)
    reach = lci[lci >= 0]
    assert rep.metrics["task_coverage"] == pytest.approx(reach.size / 1000, abs=1e-15)
    assert 0 < rep.metrics["task_coverage"] < 1  # the box pokes out of the workspace at its top
    assert rep.metrics["task_gci"] == pytest.approx(reach.mean(), rel=1e-9)
    assert rep.metrics["task_fci"] == pytest.approx(reach.std(), rel=1e-7)
    pts = sample_path(BASE["task"]["path"], 50)
    path = pauu_lci(cfg.resolved_design(), cfg.resolved_options(), pts[:, 0], pts[:, 1], pts[:, 2])
    assert (path >= 0).all()
    assert rep.metrics["path_min_lci"] == pytest.approx(path.min(), rel=1e-9)


def test_sample_path_even_arc_length():
    pts = sample_path([[0, 0], [3, 0], [3, 4]], 8)  # total length 7 -> spacing 1
    np.testing.assert_allclose(np.diff(np.cumsum(np.r_[0, np.linalg.norm(np.diff(pts, axis=0), axis=1)])), 1.0)
    assert pts.shape == (8, 3) and (pts[:, 2] == 0).all()


def test_path_leaving_workspace_gives_zero_min_lci():
    data = dict(BASE, task=dict(BASE["task"], path=[[0.0, 0.0, 1.5], [9.0, 0.0, 1.5]]))
    out = evaluate_config_population(config_from_dict(data), [TABLE4[1]])
    assert out["path_min_lci"][0] == 0.0
    assert 0 < out["path_reachable"][0] < 1
