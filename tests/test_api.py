"""The public Python API: ``import scalesynth`` is cheap, every public name resolves and is documented, the
wrappers give the same numbers as the modules they wrap, and ``python -m scalesynth`` is the CLI."""

import importlib
import inspect
import json
import pkgutil
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

import scalesynth
from scalesynth.errors import ScalesynthError

from conftest import EXACT_VOLUME, SMALL, TABLE4


def _python(code: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)


def test_import_is_cheap_no_numba_no_numpy():
    r = _python(
        "import sys, scalesynth; heavy = [m for m in ('numba', 'numpy', 'pymoo', 'pandas', 'matplotlib') "
        "if m in sys.modules]; print(heavy); print(len(scalesynth.__all__))"
    )
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0] == "[]" and int(lines[1]) >= 12


def test_every_public_name_resolves_and_functions_have_docstrings():
    assert "evaluate" in dir(scalesynth) and "__version__" in scalesynth.__all__
    assert set(scalesynth.__all__) - {"__version__"} == set(scalesynth._EXPORTS)
    for name in scalesynth.__all__:
        value = getattr(scalesynth, name)
        if callable(value):
            assert inspect.getdoc(value), name
    # public names that are also submodules are the functions, even after the submodules were imported
    for module in ("scalesynth.mechanisms.base", "scalesynth.evaluate", "scalesynth.optimize"):
        importlib.import_module(module)

    submodules = {m.name for m in pkgutil.iter_modules(scalesynth.__path__)}
    clashing = submodules & set(scalesynth.__all__)
    assert clashing == {"evaluate", "optimize", "mechanisms"}
    for name in clashing:
        value = getattr(scalesynth, name)
        func = getattr(importlib.import_module("scalesynth.api"), name)
        assert callable(value) and not inspect.ismodule(value) and inspect.signature(value) == inspect.signature(func)
        assert value.__doc__ == func.__doc__
    # ... and the submodules stay reachable through them, in every import form
    r = _python(
        "import scalesynth.mechanisms.rps_upu as m; import scalesynth.evaluate as ev; import scalesynth\n"
        "print(m.MECHANISM.name, ev.make_grid.__name__, len(scalesynth.mechanisms()) > 4)"
    )
    assert r.returncode == 0 and r.stdout.split() == ["rps-upu", "make_grid", "True"], r.stderr
    with pytest.raises(AttributeError):
        scalesynth.no_such_name  # noqa: B018


def test_mechanisms_and_get_mechanism():
    names = scalesynth.mechanisms()
    assert names == sorted(names) and {"2pauu-ppap", "planar-fivebar", "pprs-rprs", "rps-upu", "ups-sspr"} <= set(
        names
    )
    mech = scalesynth.get_mechanism("2pauu-ppap")
    assert isinstance(mech, scalesynth.Mechanism) and mech.task_axes == ("x", "y", "z")
    with pytest.raises(ScalesynthError, match="unknown mechanism 'nope'"):
        scalesynth.get_mechanism("nope")


def test_evaluate_by_name_object_and_config_agree_and_match_the_exact_volume(tmp_path):
    design = TABLE4[1]
    by_name = scalesynth.evaluate("2pauu-ppap", design, resolution=40, keep_grid=True)
    by_obj = scalesynth.evaluate(scalesynth.get_mechanism("2pauu-ppap"), design, resolution=40)
    assert by_name.metrics == by_obj.metrics
    cfg = dict(SMALL, grid={"resolution": 40})
    assert scalesynth.evaluate_config(cfg).metrics == by_name.metrics  # a mapping, the same design
    path = tmp_path / "c.yaml"
    path.write_text(json.dumps(cfg))  # JSON is YAML
    assert scalesynth.evaluate_config(path, design).metrics == by_name.metrics
    assert by_name.measure == pytest.approx(EXACT_VOLUME[1], rel=0.01)  # 40^3 cells, spec §1.9 exact volume


def test_per_voxel_arrays_reproduce_the_metrics():
    rep = scalesynth.evaluate("2pauu-ppap", TABLE4[1], resolution=24, keep_grid=True)
    lci, g = rep.lci_grid, rep.grid
    assert lci.shape == tuple(g.shape) == (24, 24, 24)
    reach = lci >= 0
    assert set(np.unique(lci[~reach])) == {-1.0}  # -1 marks unreachable cells
    assert lci[reach].max() <= 1.0
    assert int(reach.sum()) == rep.metrics["voxels"]
    assert reach.sum() * g.cell_measure == pytest.approx(rep.measure, rel=1e-12)
    assert lci[reach].mean() == pytest.approx(rep.gci, rel=1e-9)  # GCI = mean LCI over reachable cells
    assert lci[reach].min() == pytest.approx(rep.metrics["min_lci"], rel=1e-9)
    # cell centres in task units: the first and last centre of x are half a step inside the box
    x = g.axis(0)
    assert x[0] == pytest.approx(g.lo[0] + g.step[0] / 2) and len(x) == 24
    assert rep.lci_grid is not None and scalesynth.evaluate("2pauu-ppap", TABLE4[1], resolution=8).lci_grid is None


def test_optimize_and_load_result(tmp_path):
    result = scalesynth.optimize(SMALL, tmp_path / "run", plots=False)
    assert isinstance(result, scalesynth.RunResult) and result.manifest["status"] == "finished"
    assert len(result.history) == SMALL["algorithm"]["n_gen"]
    loaded = scalesynth.load_result(tmp_path / "run")
    pd.testing.assert_frame_equal(loaded.pareto, pd.read_csv(tmp_path / "run" / "pareto.csv"))
    assert loaded.manifest["config_digest"] == result.manifest["config_digest"]
    with pytest.raises(ScalesynthError, match="not a finished scalesynth run"):
        scalesynth.load_result(tmp_path)


def test_python_dash_m_is_the_cli():
    r = subprocess.run([sys.executable, "-m", "scalesynth", "mechanisms", "--json"], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    assert {m["name"] for m in json.loads(r.stdout)} == set(scalesynth.mechanisms())


def test_importing_main_and_walking_the_package_runs_nothing():
    r = _python(
        "import pkgutil, scalesynth, scalesynth.__main__\n"
        "mods = [m.name for m in pkgutil.walk_packages(scalesynth.__path__, 'scalesynth.')]\n"
        "print('scalesynth.__main__' in mods, len(mods))"
    )
    assert r.returncode == 0, r.stderr
    assert r.stdout.split()[0] == "True" and r.stderr == ""
