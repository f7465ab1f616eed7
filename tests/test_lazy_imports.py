"""A fresh process imports what its command needs, and its first evaluation waits for nothing else (issue 15:
time to the first evaluation). Checked in subprocesses through ``sys.modules``, never by timing: the mechanism
registry loads only the mechanism asked for; ``evaluate`` and ``show`` of a config import neither pandas, pymoo
nor (before drawing) matplotlib; ``optimize`` evaluates its first population before pandas or matplotlib;
``plot-bands`` evaluates its sections before pandas or matplotlib."""

import json
import os
import subprocess
import sys

import pytest

from scalesynth.mechanisms import _HERE, _module_name, available, get

# not needed to evaluate a design (pandas: result tables; pymoo: the search; matplotlib, plotly: drawing; rich:
# progress bars; scipy.ndimage: show's band regions)
HEAVY = ("pandas", "pymoo", "matplotlib", "plotly", "rich", "scipy.ndimage")

RUN_CLI = """
import json, sys
from scalesynth.cli import main
try:
    main(sys.argv[1:])
except SystemExit as exc:
    code = exc.code
print(json.dumps({"code": code, "modules": sorted(sys.modules)}), file=sys.stderr)
"""


def _python(code: str, *args: str, cwd=None) -> dict:
    env = dict(os.environ, NUMBA_NUM_THREADS="1", MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, env=env, cwd=cwd,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stderr.strip().splitlines()[-1])


def _mechanism_modules(modules: list[str]) -> set[str]:
    # describe/ is the description machinery the described mechanisms share, not a mechanism
    return {m.rsplit(".", 1)[1] for m in modules if m.startswith("scalesynth.mechanisms.")
            and not m.startswith("scalesynth.mechanisms.describe")} - {"base", "links"}


def _described(names) -> set[str]:
    """The built-in described mechanisms: a description file mechanisms/NAME.yaml each, no module."""
    return {n for n in names if (_HERE / f"{n}.yaml").is_file()}


def test_every_mechanism_lives_in_the_module_its_name_suggests():
    """get(name) imports only _module_name(name) (or reads only NAME.yaml, for a described one); a mechanism
    elsewhere still works, through the fallback that imports every module, but costs each process the others'
    imports."""
    for name in available():
        assert type(get(name)).__module__.startswith("scalesynth.mechanisms."), name
        if name in _described([name]):
            assert get(name).description is not None and get(name).name == name
            assert f"scalesynth.mechanisms.{_module_name(name)}" not in sys.modules, name
            continue
        module = sys.modules[f"scalesynth.mechanisms.{_module_name(name)}"]
        assert module.MECHANISM is get(name), f"{name}: expected in scalesynth/mechanisms/{_module_name(name)}.py"


def test_get_loads_one_mechanism_and_available_all():
    out = _python("""
import json, sys
from scalesynth.errors import UnknownMechanism
from scalesynth.mechanisms import available, get
mods = lambda: sorted(m for m in sys.modules if m.startswith("scalesynth.mechanisms."))
get("planar-fivebar")
one = mods()
try:
    get("no-such-mechanism")
except UnknownMechanism as err:
    msg = str(err)
print(json.dumps({"one": one, "all": mods(), "names": available(), "msg": msg}), file=sys.stderr)
""")
    assert _mechanism_modules(out["one"]) == {"planar_fivebar"}
    assert _described(out["names"]) >= {"delta"}
    assert _mechanism_modules(out["all"]) == {_module_name(n) for n in out["names"]} - {
        _module_name(n) for n in _described(out["names"])}
    # an unknown name lists the mechanisms, or (more than fit a line) the first ones, their count and where to see all
    assert all(n in out["msg"] for n in out["names"]) or (
        f"({len(out['names'])} in all)" in out["msg"] and "`scalesynth mechanisms` lists them" in out["msg"])


@pytest.mark.parametrize(("config", "module"), [("fivebar_packing.yaml", "planar_fivebar"),
                                                ("ups_sspr.yaml", "ups_sspr")])  # uniform grid, adaptive
def test_evaluate_imports_one_mechanism_and_nothing_heavy(root, config, module):
    out = _python(RUN_CLI, "evaluate", str(root / "configs" / config), "--json", "--set", "grid.resolution=8")
    assert out["code"] in (0, None)
    assert [m for m in HEAVY if m in out["modules"]] == []
    assert _mechanism_modules(out["modules"]) == {module}


def test_show_of_a_config_imports_no_results_machinery(root, tmp_path):
    out = _python(RUN_CLI, "show", str(root / "configs" / "fivebar_packing.yaml"), "--resolution", "12", "--out",
                  str(tmp_path), "--json")
    assert out["code"] in (0, None)
    assert [m for m in ("pandas", "pymoo") if m in out["modules"]] == []


FIRST_CALL = """
import importlib, json, sys
module = importlib.import_module(sys.argv.pop(1))  # before the modules that import its functions by name
seen = {}
def watch(func):
    def first(*args, **kwargs):
        seen.setdefault("modules", sorted(sys.modules))
        return func(*args, **kwargs)
    return first
for name in sys.argv.pop(1).split(","):
    setattr(module, name, watch(getattr(module, name)))
from scalesynth.cli import main
try:
    main(sys.argv[1:])
except SystemExit as exc:
    code = exc.code
print(json.dumps({"code": code, "modules": seen.get("modules", [])}), file=sys.stderr)
"""


def test_optimize_evaluates_its_first_population_before_pandas_and_matplotlib(root, tmp_path):
    out = _python(FIRST_CALL, "scalesynth.evaluate", "evaluate_config_population", "optimize",
                  str(root / "configs" / "fivebar_packing.yaml"), "--out", str(tmp_path / "run"), "-q", "--set",
                  "grid.resolution=8", "--set", "algorithm.pop_size=4", "--set", "algorithm.n_gen=1")
    assert out["code"] in (0, None)
    assert "pymoo" in out["modules"]  # the hook saw the search's first evaluation
    assert [m for m in ("pandas", "matplotlib") if m in out["modules"]] == []
    assert (tmp_path / "run" / "pareto.csv").exists()


@pytest.mark.parametrize("config", ["fivebar_packing.yaml", "ups_sspr.yaml"])  # planar: one map; 3-D, stiffness
def test_plot_bands_evaluates_its_sections_before_reading_tables_and_drawing(root, tmp_path, config):
    """plot-bands' first evaluation (a section's field grid, kernels.grid) comes before pandas (the results tables)
    and matplotlib (the figures); ups-sspr: 3-D sections and stiffness maps."""
    run = tmp_path / "run"
    opt = _python(RUN_CLI, "optimize", str(root / "configs" / config), "--out", str(run), "-q", "--no-plots",
                  "--set", "grid.resolution=8", "--set", "algorithm.pop_size=4", "--set", "algorithm.n_gen=1")
    assert opt["code"] in (0, None)
    out = _python(FIRST_CALL, "scalesynth.kernels.grid", "sample_fields,sample_grid", "plot-bands", str(run))
    assert out["code"] in (0, None)
    assert "scalesynth.report" in out["modules"]  # the hook saw plot-bands' first evaluation
    assert [m for m in HEAVY if m != "pymoo" and m in out["modules"]] == []  # pymoo: the run's problem (columns)
    assert (run / "plots" / "bands_front.png").is_file() and (run / "bands" / "pareto_band0.csv").is_file()


def test_cli_runs_openblas_single_threaded_unless_told_otherwise():
    """scalesynth.cli sets OPENBLAS_NUM_THREADS=1 before NumPy loads (OpenBLAS's thread pools cost a short command
    about 0.1 s of wall and 0.25 s of CPU time at start; scalesynth's parallel work is Numba's); an explicit setting
    is kept."""
    code = ("import json, os, sys; import scalesynth.cli; "
            "print(json.dumps(os.environ.get('OPENBLAS_NUM_THREADS')), file=sys.stderr)")
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    for given, expected in ((None, "1"), ("3", "3")):
        run_env = env if given is None else dict(env, OPENBLAS_NUM_THREADS=given)
        proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=run_env, timeout=120)
        assert proc.returncode == 0, proc.stderr[-2000:]
        assert json.loads(proc.stderr.strip().splitlines()[-1]) == expected
