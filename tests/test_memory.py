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
from scalesynth.kernels.grid import sample_grid
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


def test_section_planes_equal_the_slices_of_the_full_grid():
    """report.section_panels samples only the two planes it draws; they equal the same slices of the full grid."""
    from scalesynth.evaluate import make_grid
    from scalesynth.report import section_panels

    cfg = config_from_dict(SMALL)
    design = cfg.resolved_design()
    panels = section_panels(cfg, design)
    mech, options = cfg.mech, cfg.resolved_options()
    g = make_grid(mech, design, options, 129, None)  # max(12, 128) + 1 cells: the sections' grid
    full = sample_grid(mech.point_kernel, mech.pack(design, options), g.lo, g.step, g.shape)
    j, k = 129 // 2, 129 // 2
    for panel, ref in zip(panels, (full[:, j, :], full[:, :, k]), strict=True):
        assert panel["lci"].shape == ref.shape
        np.testing.assert_allclose(panel["lci"], ref, rtol=0, atol=1e-12)
