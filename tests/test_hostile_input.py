"""Hostile input of issue 27 ("Crashes and hangs", "Bounded network waits", API validation): each case was accepted
or crashed before, and is now refused with one line naming the field (ConfigError / InvalidParameter, exit 2 on the
command line), or degrades as documented (a read-only Numba cache); scheduler waits end within the stated timeout.
Configs are the cheap ones (planar-fivebar, quick); most cases are refused before any kernel runs."""

import copy
import json
import math
import os
import socket
import subprocess
import sys
import textwrap
import threading
from pathlib import Path

import numpy as np
import pytest
import yaml

import scalesynth as ss
from cli_main import run_main as _run_main
from scalesynth.config import config_from_dict, load_config
from scalesynth.errors import ConfigError, InvalidParameter, RunError
from scalesynth.yamlfile import MAX_YAML_BYTES

from conftest import SMALL

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"
QUICK = ROOT / "configs" / "quick.yaml"
FIVEBAR = yaml.safe_load((ROOT / "configs" / "fivebar_packing.yaml").read_text())
CYCLE = yaml.safe_load((ROOT / "configs" / "fivebar_pnp_cycle.yaml").read_text())
DENORMAL = 5e-324  # the smallest positive float



def _one_error_line(err: str, needle: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("error: ") and needle in lines[0], lines[0]
    assert len(lines[0]) <= 200 + len("error: "), lines[0]
    return lines[0]


def _python(code: str, env: dict[str, str], timeout: float = 300, cwd=None) -> subprocess.CompletedProcess:
    """A fresh interpreter (Numba reads its environment once per process) with this checkout's sources first."""
    full = {**os.environ, "PYTHONPATH": str(SRC), "MPLBACKEND": "Agg", **env}
    return subprocess.run([sys.executable, "-c", code], env=full, capture_output=True, text=True, timeout=timeout,
                          stdin=subprocess.DEVNULL, cwd=cwd)


# ----- the Python API validates as a config does ------------------------------------------------------------------

API_CASES = [
    # the case: volume 0 and GCI 0 were returned; 1024 is grid.resolution's limit in a config
    ("2pauu-ppap", {"resolution": 65536}, "resolution: 65536 cells per axis is outside 4..1024"),
    ("planar-fivebar", {"resolution": 0}, "resolution: 0 cells per axis is outside 4..1024"),
    ("planar-fivebar", {"resolution": -3}, "resolution: -3 cells per axis"),
    ("planar-fivebar", {"resolution": True}, "resolution: expected an integer"),
    ("planar-fivebar", {"resolution": 8.5}, "resolution:"),
    ("planar-fivebar", {"region": {"x": [1.0, 0.0]}}, "region.x: need finite lo < hi"),
    ("planar-fivebar", {"region": {"x": [math.nan, 1.0]}}, "region.x: need finite lo < hi"),
    ("planar-fivebar", {"region": {"x": [0.0, math.inf]}}, "region.x: need finite lo < hi"),
    ("planar-fivebar", {"region": {"q": [0.0, 1.0]}}, "region.q: not a task axis of planar-fivebar (x, y)"),
    ("planar-fivebar", {"region": {"x": [1.0, 1.0 + 2**-52]}}, "region.x: the range"),
    ("planar-fivebar", {"region": [0, 1]}, "region: expected {task axis: [lo, hi]}"),
    ("planar-fivebar", {"band_edges": [0.0, 0.5]}, "band_edges: must start at 0 and end at 1"),
    ("planar-fivebar", {"band_edges": [0.0, 0.5, 0.4, 1.0]}, "band_edges: must be strictly increasing"),
    ("planar-fivebar", {"length_unit": "furlong"}, "length_unit: must be one of m, mm, cm, dm"),
]


@pytest.mark.parametrize(("mech", "kwargs", "needle"), API_CASES, ids=[str(c[1]) for c in API_CASES])
def test_api_evaluate_refuses_what_a_config_refuses(mech, kwargs, needle):
    with pytest.raises(ConfigError) as exc:
        ss.evaluate(mech, {}, **kwargs)
    message = str(exc.value)
    assert needle in message and "\n" not in message, message


def test_api_evaluate_refuses_a_mechanism_that_is_neither_a_name_nor_a_mechanism():
    with pytest.raises(ConfigError, match="^mechanism: expected a name or a Mechanism, got int$"):
        ss.evaluate(3)


def test_api_keep_grid_is_refused_above_the_memory_limit(monkeypatch):
    """keep_grid keeps (n^3, n_fields) float64: at 128 cells per axis 2pauu-ppap's fields are far above 1 MiB."""
    from scalesynth.memory import MemoryLimitError

    monkeypatch.setenv("SCALESYNTH_MEMORY_LIMIT", "1M")
    with pytest.raises(MemoryLimitError, match="^keep_grid: the per-voxel fields of a 128-cell grid needs about"):
        ss.evaluate("2pauu-ppap", {}, resolution=128, keep_grid=True)


# ----- numbers checked for the arithmetic they enter -----------------------------------------------------------------

def _fivebar(**options) -> dict:
    data = copy.deepcopy(FIVEBAR)
    data["options"].update(options)
    return data


STIFFNESS_CASES = [
    ({"actuator_stiffness": DENORMAL}, "options.actuator_stiffness: 4.94066e-324 is outside [1e-12, 1e+12]"),
    ({"actuator_stiffness": 1e-300}, "options.actuator_stiffness: 1e-300 is outside"),
    ({"tube": [1e-300, 1e-301]}, "options.tube[0]: 1e-300 is outside"),
    ({"tube": [40.0, 1e-15]}, "options.tube[1]: 1e-15 is outside"),
    ({"tube": [1e6, 1e-4]}, "options.tube: wall 0.0001 is below 1e-09 of the outer diameter"),
    ({"sections": {"arm": [1e-300, 1e-301]}}, "options.sections.arm[0]: 1e-300 is outside"),
    ({"youngs_modulus": 1e-320}, "options.youngs_modulus: 9.99989e-321 is outside"),
    ({"load": [0.0, DENORMAL]}, "options.load[1]: 4.94066e-324 is subnormal"),
    ({"parallelogram_spacing": DENORMAL}, "options.parallelogram_spacing: 4.94066e-324 is subnormal"),
]


@pytest.mark.parametrize(("options", "needle"), STIFFNESS_CASES, ids=[str(c[0]) for c in STIFFNESS_CASES])
def test_tiny_stiffness_options_are_refused_by_config_and_api(options, needle):
    """Before: accepted, then a ZeroDivisionError inside the point kernel (`stiffness`, `evaluate`)."""
    with pytest.raises(ConfigError) as exc:
        config_from_dict(_fivebar(**options))
    assert needle in str(exc.value), str(exc.value)
    with pytest.raises(InvalidParameter) as exc:
        ss.evaluate("planar-fivebar", {}, options, resolution=4)
    assert needle in str(exc.value), str(exc.value)


@pytest.mark.parametrize(("mech", "option"), [("2pauu-ppap", "stroke_stiffness"), ("pprs-rprs", "beta_stiffness")])
def test_each_mechanisms_own_stiffness_option_is_checked_too(mech, option):
    with pytest.raises(InvalidParameter, match=rf"^options.{option}: 4.94066e-324 is outside \[1e-12, 1e\+12\]"):
        ss.get_mechanism(mech).resolve_options({option: DENORMAL})


def test_stiffness_options_at_their_limits_give_finite_fields_and_reports():
    """The accepted range is safe: planar-fivebar (whose kernel always computes stiffness and deflection) at every
    corner of [1e-12, 1e12] for E, the tube and the actuator stiffness gives finite metrics, and the `stiffness`
    report at a pose is strict JSON."""
    from scalesynth.stiffness.report import pose_stiffness

    mech = ss.get_mechanism("planar-fivebar")
    design = mech.resolve_design({})
    for e in (1e-12, 1e12):
        for tube in ([2e-12, 1e-12], [1e12, 1e4]):
            for k in (1e-12, 1e12):
                options = {"youngs_modulus": e, "tube": tube, "actuator_stiffness": k}
                report = ss.evaluate(mech, {}, options, resolution=6)
                assert all(math.isfinite(v) for v in report.metrics.values()), options
                out = pose_stiffness(mech, design, mech.resolve_options(options), np.array([0.0, -700.0]), "ideal")
                json.dumps(out, allow_nan=False)


SUBNORMAL_CASES = [
    ({"design": {**SMALL["design"], "c": DENORMAL}}, "design.c: 4.94066e-324 is subnormal"),
    ({"bounds": {**SMALL["bounds"], "c": [DENORMAL, 0.5]}}, "bounds.c: 4.94066e-324 is subnormal"),
    ({"grid": {"resolution": 12, "region": {"x": [-1.0, -DENORMAL]}}}, "grid.region.x: -4.94066e-324 is subnormal"),
]


@pytest.mark.parametrize(("change", "needle"), SUBNORMAL_CASES, ids=[c[1].split(":")[0] for c in SUBNORMAL_CASES])
def test_subnormal_numbers_are_refused(change, needle):
    with pytest.raises(ConfigError) as exc:
        config_from_dict({**copy.deepcopy(SMALL), **change})
    assert needle in str(exc.value), str(exc.value)


def test_a_bound_range_holding_one_float_is_refused():
    """[1, 1 + 2^-52] holds two floats; pymoo's SBX divided by its width (a crash inside pymoo). At least 64 float
    steps (config.MIN_RANGE_ULPS) are required, in bounds, grid.region and task.box alike."""
    data = copy.deepcopy(SMALL)
    data["bounds"]["l1"] = [1.0, 1.0 + 2**-52]
    with pytest.raises(ConfigError, match=r"^bounds.l1: the range \[1.0, 1.0000000000000002\] is too narrow"):
        config_from_dict(data)
    data["bounds"]["l1"] = [1.0, 1.0 + 64 * 2**-52]  # exactly the limit: accepted
    assert config_from_dict(data).bounds["l1"] == (1.0, 1.0 + 64 * 2**-52)
    box = copy.deepcopy(FIVEBAR)
    box["task"]["box"]["x"] = [-500.0, np.nextafter(-500.0, 0.0)]
    with pytest.raises(ConfigError, match=r"^task.box.x: the range"):
        config_from_dict(box)


def _cycle_path(path) -> dict:
    data = copy.deepcopy(CYCLE)
    data["cycle"] = {k: v for k, v in data["cycle"].items() if k not in ("preset", "start", "direction")}
    data["cycle"]["path"] = path
    return data


def test_a_closed_path_whose_points_differ_by_a_denormal_is_refused():
    """Before: accepted (the points differ), the segment's squared length underflowed to 0, the trajectory dropped
    every segment and the plot divided by zero (exit 1, internal error)."""
    with pytest.raises(ConfigError, match=r"^cycle.path.1: point 1 is only 4.94e-324 from point 0"):
        config_from_dict(_cycle_path([[0.0, -700.0], [DENORMAL, -700.0]]))
    with pytest.raises(ConfigError, match=r"^task.path.2: point 2 is only 1e-170 from point 1"):
        data = copy.deepcopy(FIVEBAR)
        data["task"]["path"] = [[0.0, -700.0], [100.0, 0.0], [100.0, 1e-170]]
        config_from_dict(data)
    # equal points stay allowed (a pause); points 1e-150 apart have a normal squared length
    config_from_dict(_cycle_path([[0.0, -700.0], [100.0, -700.0], [100.0, -700.0]]))
    config_from_dict(_cycle_path([[0.0, -700.0], [1e-150, -700.0]]))


def test_cycle_with_a_denormal_path_exits_2_before_writing(tmp_path, capsys, monkeypatch):
    cfg = tmp_path / "c.yaml"
    cfg.write_text(yaml.safe_dump(_cycle_path([[0.0, -700.0], [DENORMAL, -700.0]])))
    monkeypatch.chdir(tmp_path)
    code, out, err = _run_main(["cycle", cfg, "--out", tmp_path / "out"], capsys)
    assert code == 2 and out == ""
    _one_error_line(err, "cycle.path.1: point 1 is only")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.yaml"]


# ----- NUMBA_* variables and the disk cache -------------------------------------------------------------------------

BAD_NUMBA = [
    ("NUMBA_NUM_THREADS", "0"),  # Numba's import raised ValueError
    ("NUMBA_NUM_THREADS", "-1"),
    ("NUMBA_NUM_THREADS", "abc"),  # a warning and Numba's default
    ("NUMBA_NUM_THREADS", "1e20"),
    ("NUMBA_NUM_THREADS", "99999"),  # 99999 threads at the first parallel kernel
    ("NUMBA_DISABLE_JIT", "abc"),
    ("NUMBA_THREADING_LAYER", "nope"),
]


@pytest.mark.parametrize(("name", "value"), BAD_NUMBA, ids=[f"{n}={v}" for n, v in BAD_NUMBA])
def test_a_bad_numba_variable_is_one_line_exit_2_from_the_cli(name, value):
    r = _python("from scalesynth.cli import main; main(['ik', 'planar-fivebar', '--pose', '0,-700'])",
                {name: value})
    assert r.returncode == 2, (r.returncode, r.stderr[-2000:])
    assert r.stdout == ""
    _one_error_line(r.stderr, f"{name}: expected")


def test_a_bad_numba_variable_raises_config_error_from_the_api():
    code = textwrap.dedent("""
        import scalesynth as ss
        try:
            ss.evaluate("planar-fivebar", {}, resolution=4)
        except ss.ScalesynthError as err:
            print(type(err).__name__, err)
    """)
    r = _python(code, {"NUMBA_NUM_THREADS": "0"})
    assert r.returncode == 0, r.stderr[-2000:]
    assert r.stdout.startswith("ConfigError NUMBA_NUM_THREADS: expected the threads per process, an integer from 1 to"
                               " 1024, got '0'"), r.stdout
    assert "Traceback" not in r.stderr


def test_environment_check_accepts_good_values():
    from scalesynth import environment

    environment.check({"NUMBA_NUM_THREADS": " 4 ", "NUMBA_DISABLE_JIT": "0", "NUMBA_THREADING_LAYER": "workqueue",
                       "NUMBA_CACHE_DIR": "/tmp/x"})
    environment.check({"NUMBA_NUM_THREADS": ""})  # empty: unset, Numba's default
    with pytest.raises(ConfigError, match="^NUMBA_NUM_THREADS: .* got '1025'$"):
        environment.check({"NUMBA_NUM_THREADS": "1025"})


def test_every_cache_location_unwritable_compiles_in_memory_with_one_warning(tmp_path):
    """NUMBA_CACHE_DIR, the module's __pycache__ and the user cache all unusable (a regular file stands where each
    directory would be: running as root, permissions would not stop a write). Before: Numba raised 'cannot cache
    function ...: no locator available' when a cache=True function was defined, so nothing ran."""
    blocker = tmp_path / "blocker"
    blocker.write_text("")
    (tmp_path / "__pycache__").write_text("")  # the in-tree location of kernel_mod.py
    (tmp_path / "kernel_mod.py").write_text(textwrap.dedent("""
        from numba import njit

        @njit(cache=True)
        def twice(x):
            return 2 * x
    """))
    code = "import scalesynth.kernels, kernel_mod; print(kernel_mod.twice(21))"
    env = {"PYTHONPATH": f"{SRC}{os.pathsep}{tmp_path}", "NUMBA_CACHE_DIR": str(blocker / "numba"),
           "XDG_CACHE_HOME": str(blocker / "xdg"), "HOME": str(blocker)}
    r = _python(code, env, cwd=tmp_path)
    assert r.returncode == 0, r.stderr[-2000:]
    assert r.stdout.strip() == "42"
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("warning: no writable Numba cache location"), r.stderr


# ----- files and grids too large -------------------------------------------------------------------------------------

def test_a_sparse_20_gb_config_is_refused_by_its_size_without_reading_it(tmp_path):
    """In a process limited to 2 GiB of address space: reading the file whole (as before) fails with MemoryError;
    the size check refuses it first, naming the file and the limit."""
    big = tmp_path / "big.yaml"
    with open(big, "wb") as fh:
        fh.truncate(20 * 1024**3)  # sparse: no disk used
    code = textwrap.dedent(f"""
        import resource
        resource.setrlimit(resource.RLIMIT_AS, (2 * 1024**3, 2 * 1024**3))
        from scalesynth.config import load_config
        from scalesynth.errors import ConfigError
        try:
            load_config({str(big)!r})
        except ConfigError as err:
            print(err)
    """)
    r = _python(code, {"OPENBLAS_NUM_THREADS": "1"})
    assert r.returncode == 0, r.stderr[-2000:]
    assert r.stdout.strip() == f"{big}: {20 * 1024**3} bytes, more than the {MAX_YAML_BYTES} a config may have"


def test_a_config_one_byte_over_the_limit_is_refused(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("#" * MAX_YAML_BYTES + "\n")
    with pytest.raises(ConfigError, match=f"{MAX_YAML_BYTES + 1} bytes, more than the {MAX_YAML_BYTES} a config"):
        load_config(path)


def test_show_applies_the_memory_limit_to_its_grids(tmp_path, capsys, monkeypatch):
    """Before: `show --resolution 512` sampled 512^3 cells regardless (15.5 GB); here 64^3 cells of quick.yaml's
    2pauu-ppap against a 1 MiB limit are refused before anything is computed or written."""
    monkeypatch.setenv("SCALESYNTH_MEMORY_LIMIT", "1M")
    monkeypatch.chdir(tmp_path)
    code, out, err = _run_main(["show", QUICK, "--resolution", "64", "--out", tmp_path / "show"], capsys)
    assert code == 2 and out == ""
    _one_error_line(err, "--resolution: the fields of a 64-cell grid (2.62e+05 cells) needs about")
    assert list(tmp_path.iterdir()) == []


# ----- scheduler connections ----------------------------------------------------------------------------------------

class _SilentServer:
    """A loopback TCP port that accepts connections and never answers; stopped (every socket closed) on exit."""

    def __enter__(self):
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(16)
        self.sock.settimeout(0.1)
        self.port = self.sock.getsockname()[1]
        self.stop = threading.Event()
        self.accepted: list[socket.socket] = []
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()
        return self

    def _serve(self):
        while not self.stop.is_set():
            try:
                conn, _ = self.sock.accept()
            except (TimeoutError, OSError):
                continue
            self.accepted.append(conn)

    def __exit__(self, *exc):
        self.stop.set()
        self.thread.join(10)
        for conn in self.accepted:
            conn.close()
        self.sock.close()


def test_a_scheduler_that_accepts_and_never_answers_ends_within_the_timeout(tmp_path):
    """Before: `batch --scheduler` waited for ever on such a port. The batch runs in a child process (killed after
    240 s if it still hangs) with CONNECT_SECONDS = 2 s; it must exit 1 with one line, and have connected."""
    pytest.importorskip("distributed")
    code = textwrap.dedent("""
        import sys
        from scalesynth import cluster
        cluster.CONNECT_SECONDS = 2.0
        from scalesynth.cli import main
        main(sys.argv[1:])
    """)
    with _SilentServer() as server:
        out = tmp_path / "out"
        args = ["batch", str(QUICK), "--scheduler", f"tcp://127.0.0.1:{server.port}", "--out", str(out)]
        full = {**os.environ, "PYTHONPATH": str(SRC), "MPLBACKEND": "Agg"}
        r = subprocess.run([sys.executable, "-c", code, *args], env=full, capture_output=True, text=True,
                           timeout=240, stdin=subprocess.DEVNULL)
        assert server.accepted, "the batch never connected"
    assert r.returncode == 1, (r.returncode, r.stderr[-2000:])
    _one_error_line(r.stderr, f"--scheduler tcp://127.0.0.1:{server.port}: no answer within 2 s")
    assert not out.exists()


def test_probe_scheduler_raises_run_error_for_a_silent_port():
    pytest.importorskip("distributed")
    from scalesynth.cluster import probe_scheduler

    with _SilentServer() as server, pytest.raises(RunError, match=r"no answer within 0.5 s"):
        probe_scheduler(f"tcp://127.0.0.1:{server.port}", 0.5)


@pytest.mark.parametrize("address", ["tls://127.0.0.1:1", "wss://127.0.0.1:1", "ucx://127.0.0.1:1"])
def test_unavailable_scheduler_protocols_are_refused_at_the_start(address, tmp_path, capsys, monkeypatch):
    """Before: tls:// raised TypeError (no SSL context) and ucx:// dask's removal warning, each with a traceback."""
    pytest.importorskip("distributed")
    monkeypatch.chdir(tmp_path)
    code, out, err = _run_main(["batch", QUICK, "--scheduler", address, "--out", tmp_path / "out"], capsys)
    assert code == 2 and out == ""
    scheme = address.split(":")[0]
    line = _one_error_line(err, f"--scheduler {address}: the {scheme} protocol")
    assert "Traceback" not in err, line
    assert list(tmp_path.iterdir()) == []

