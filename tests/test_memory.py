"""Memory estimates before allocating (scalesynth.memory, issue 11 item 4): refusals with exit 2 naming the field,
the estimate and the limit; the estimates checked against what the allocations really take (tracemalloc)."""

import copy
import tracemalloc

import numpy as np
import pytest
from typer.testing import CliRunner

from scalesynth import memory
from scalesynth.cli import app
from scalesynth.config import config_from_dict
from scalesynth.optimize import run

from conftest import SMALL


def small(**algorithm):
    data = copy.deepcopy(SMALL)
    data["algorithm"].update(algorithm)
    return data


@pytest.mark.parametrize(("text", "expected"), [
    ("1000", 1000), ("512M", 512 * 1024**2), ("8GiB", 8 * 1024**3), ("1.5T", int(1.5 * 1024**4)),
    ("2kb", 2048), (" 3 G ", 3 * 1024**3),
])
def test_parse_size(text, expected):
    assert memory.parse_size(text) == expected


@pytest.mark.parametrize("text", ["", "abc", "-1G", "0", "1e400", "8XB", "nan"])
def test_parse_size_refuses(text):
    with pytest.raises(ValueError):
        memory.parse_size(text)


def test_huge_population_is_refused_before_anything_is_written(tmp_path, monkeypatch):
    monkeypatch.delenv(memory.ENV_VAR, raising=False)
    cfg = config_from_dict(small(pop_size=100_000))
    with pytest.raises(memory.MemoryLimitError) as err:
        run(cfg, tmp_path / "out", plots=False)
    msg = str(err.value)
    # 26 bytes per pair: 26 * 1e10 B = 242.1 GiB
    assert msg.startswith("algorithm.pop_size: ") and "242.1 GiB" in msg and "memory limit" in msg
    assert list(tmp_path.iterdir()) == []


def test_limit_from_the_environment(tmp_path, monkeypatch):
    monkeypatch.setenv(memory.ENV_VAR, "1M")
    r = CliRunner().invoke(app, ["optimize", "configs/quick.yaml", "--out", str(tmp_path / "o"), "-q"])
    assert r.exit_code == 2, r.output
    assert "above the memory limit 1.0 MiB (SCALESYNTH_MEMORY_LIMIT=1M)" in r.output
    assert len(r.output.strip().splitlines()) == 1 and not (tmp_path / "o").exists()
    monkeypatch.setenv(memory.ENV_VAR, "lots")
    r = CliRunner().invoke(app, ["evaluate", "configs/quick.yaml"])
    assert r.exit_code == 2 and "SCALESYNTH_MEMORY_LIMIT: expected a size" in r.output


def test_plot_task_resolution_is_bounded_by_memory(tmp_path, monkeypatch):
    monkeypatch.delenv(memory.ENV_VAR, raising=False)
    out = tmp_path / "t.png"
    r = CliRunner().invoke(app, ["plot-task", "configs/fivebar_packing.yaml", "--resolution", "100000",
                                 "--out", str(out)])
    assert r.exit_code == 2 and r.output.startswith("error: --resolution: a 100000 x 100000 LCI map needs about")
    assert not out.exists()


def test_duplicate_elimination_estimate_bounds_what_pymoo_allocates():
    """tracemalloc (NumPy reports its buffers to it) of pymoo's duplicate elimination on n = 1200 individuals:
    the peak is below the estimate (26 n^2 bytes) and above half of it, so the estimate is neither wild nor low."""
    from pymoo.core.duplicate import DefaultDuplicateElimination
    from pymoo.core.population import Population

    n = 1200
    X = np.random.default_rng(0).random((n, 5))
    pop, other = Population.new("X", X), Population.new("X", X[::-1] + 1)
    elim = DefaultDuplicateElimination(epsilon=1e-9)
    tracemalloc.start()
    elim.do(pop, other)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    estimate = memory.DUPLICATE_BYTES_PER_PAIR * n * n
    assert 0.5 * estimate < peak <= estimate, (peak, estimate)


def test_section_panels_sample_only_their_planes(monkeypatch):
    """report.section_panels never builds a full section-resolution grid: every grid it samples is one plane
    (one axis of size 1) or the coarse CENTROID_RESOLUTION^3 grid that locates the sections. (That the planes equal
    the slices of a full grid is tests/test_views.py::test_plane_sampling_equals_the_full_grid_slice.)"""
    from scalesynth import workspace_view
    from scalesynth.kernels import grid as kgrid
    from scalesynth.report import SECTION_RESOLUTION, section_panels

    shapes = []
    real = kgrid.sample_fields

    def recording(kernel, n_fields, p, lo, step, shape):
        shapes.append(tuple(int(n) for n in shape))
        return real(kernel, n_fields, p, lo, step, shape)

    monkeypatch.setattr(kgrid, "sample_fields", recording)
    cfg = config_from_dict(SMALL)
    panels = section_panels(cfg, cfg.resolved_design())
    assert len(panels) == 2 and all((np.asarray(p["values"]) >= 0).any() for p in panels)
    coarse = (workspace_view.CENTROID_RESOLUTION,) * 3
    planes = [s for s in shapes if s != coarse]
    assert len(planes) == 2 and all(sorted(s)[0] == 1 and max(s) >= SECTION_RESOLUTION for s in planes), shapes

