"""Run scalesynth CLI commands in this process and record every Numba compilation they trigger.

    python tests/compile_probe.py REPORT.json scalesynth-arguments... [-- more-arguments...]

Commands separated by ``--`` run one after the other in the same process. Numba emits a ``numba:compile`` event
only when it really compiles a function (a dispatcher that finds its signature in the disk cache loads it without
the event), so a process whose cache is complete records none.

REPORT.json gets one entry per command: ``compiled`` (qualified names, in order, nested callees included),
``compile_s`` (wall seconds inside outermost compilations), ``jit_s`` (wall seconds inside outermost
``Dispatcher.compile`` calls: compilations and disk-cache loads, what JIT costs the command), ``wall_s`` /
``cpu_s`` of the command (the first command's include the process start and the imports), ``exit_code``, and
``first_grid_s`` / ``first_grid_cpu_s``: wall and CPU seconds from the process start to the end of the process's
first evaluation: a workspace grid (``Mechanism.grid_stats``, or the adaptive evaluator for configs with
``grid.tolerance``), a field or LCI grid (``kernels.grid.sample_fields`` / ``sample_grid``), a cycle
(``cycle.analysis.analyse``) or a pose's stiffness (``stiffness.report.pose_stiffness``), whichever comes first;
None if the command made none. The probe imports no scalesynth module the command would not.
Used by tests/test_compile_cache.py and by benchmarks/compile_once.py, which both run ``commands()``.
"""

from __future__ import annotations

import functools
import importlib.abc
import json
import sys
import time
from pathlib import Path

T0, C0 = time.perf_counter(), time.process_time()

if __name__ == "__main__":  # the CLI module first, as the `scalesynth` command does: it sets OPENBLAS_NUM_THREADS
    importlib.import_module("scalesynth.cli")  # before NumPy loads (not when tests import commands() from here)
from numba.core import dispatcher, event  # noqa: E402

JIT = {"s": 0.0, "depth": 0}
_compile = dispatcher.Dispatcher.compile


def _timed_compile(self, sig):
    """Dispatcher.compile (cache load or compilation), timed at the outermost call."""
    JIT["depth"] += 1
    t = time.perf_counter()
    try:
        return _compile(self, sig)
    finally:
        JIT["depth"] -= 1
        if JIT["depth"] == 0:
            JIT["s"] += time.perf_counter() - t


dispatcher.Dispatcher.compile = _timed_compile
FIRST_GRID: dict[str, float] = {}


def _first_evaluation(func):
    """``func`` that records when the process's first workspace evaluation (any wrapped call) returns."""

    @functools.wraps(func)
    def timed(*args, **kwargs):
        out = func(*args, **kwargs)
        if not FIRST_GRID:
            FIRST_GRID.update(wall=time.perf_counter() - T0, cpu=time.process_time() - C0)
        return out

    return timed


def _patch_mechanisms(module) -> None:
    """Wrap ``grid_stats`` of every mechanism class as the registry registers it (importing no mechanism)."""
    register, patched = module.register, set()

    def watch(mech):
        for cls in type(mech).__mro__:
            if "grid_stats" in cls.__dict__ and cls not in patched:
                patched.add(cls)
                cls.grid_stats = _first_evaluation(cls.__dict__["grid_stats"])

    def register_and_watch(mech):
        watch(mech)
        return register(mech)

    for mech in list(module._REGISTRY.values()):
        watch(mech)
    module.register = register_and_watch


def _patch_functions(*names: str):
    """A hook that wraps these module-level functions of a module (callers that import them by name, after the
    hook ran, get the wrapped ones)."""

    def hook(module) -> None:
        for name in names:
            setattr(module, name, _first_evaluation(getattr(module, name)))

    return hook


class _AfterImport(importlib.abc.MetaPathFinder):
    """Runs a hook on a module right after it is first imported, wherever and whenever that happens, so the
    probe imports nothing the command would not (the mechanism registry loads only the modules it needs)."""

    # the evaluations of the commands: workspace grid (uniform or adaptive: evaluate, optimize, plot-front),
    # field and LCI grids (show, plot-bands, plot-task), the cycle (cycle, drives), a pose's stiffness
    hooks = {"scalesynth.mechanisms": _patch_mechanisms,
             "scalesynth.evaluation.adaptive": _patch_functions("adaptive_population_stats"),
             "scalesynth.kernels.grid": _patch_functions("sample_fields", "sample_grid"),
             "scalesynth.cycle.analysis": _patch_functions("analyse"),
             "scalesynth.stiffness.report": _patch_functions("pose_stiffness")}

    def find_spec(self, name, path, target=None):
        hook = self.hooks.get(name)
        if hook is None:
            return None
        spec = next((s for f in sys.meta_path if f is not self and hasattr(f, "find_spec")
                     for s in [f.find_spec(name, path, target)] if s is not None), None)
        if spec is None or spec.loader is None:
            return spec
        exec_module = spec.loader.exec_module

        def exec_and_hook(module):
            exec_module(module)
            hook(module)

        spec.loader.exec_module = exec_and_hook
        return spec


def _watch_first_evaluation() -> None:
    """Record when the process's first evaluation returns (``_AfterImport.hooks``). Modules already imported are
    patched now."""
    for name, hook in _AfterImport.hooks.items():
        if name in sys.modules:
            hook(sys.modules[name])
    sys.meta_path.insert(0, _AfterImport())


class CompileRecorder(event.Listener):
    def __init__(self) -> None:
        self.compiled: list[str] = []
        self.compile_s = 0.0
        self._starts: list[float] = []

    def on_start(self, ev) -> None:
        disp = ev.data["dispatcher"]
        py = getattr(disp, "py_func", None)
        self.compiled.append(f"{getattr(py, '__module__', '?')}.{getattr(py, '__qualname__', repr(disp))}")
        self._starts.append(time.perf_counter())

    def on_end(self, ev) -> None:
        t = self._starts.pop()
        if not self._starts:
            self.compile_s += time.perf_counter() - t


# a reachable pose of the mechanism's default design for `scalesynth stiffness` (task coordinates, those of
# tests/test_stiffness*.py); a mechanism not listed gets its config design's best-LCI cell of a coarse grid
STIFFNESS_POSE = {"planar-fivebar": "0,-725", "ups-sspr": "0.5,0.25,47.6", "rps-upu-tool": "0.19,0,4"}


def commands(config: Path, out: Path, small: bool = False) -> list[tuple[str, list[str]]]:
    """(label, CLI arguments) of every command that evaluates or draws something for this config: evaluate,
    a short optimize with plots and report, show, plot-front, plot-bands, and where the config or mechanism has
    them cycle, stiffness, plot-task (planar with a task box), drives (pprs-rprs). ``small``: coarse grids
    (the same kernels and argument types, less work: for tests)."""
    from scalesynth.config import load_config
    from scalesynth.stiffness.report import modelled

    cfg = load_config(config)
    name = cfg.mechanism
    path, run = str(config), str(out / "run")
    grid = ["--set", "grid.resolution=8"] if small else []
    cmds = [("evaluate", ["evaluate", path, "--json", *grid]),
            ("optimize", ["optimize", path, "--out", run, "-q", "--set", "algorithm.pop_size=8", "--set",
                          "algorithm.n_gen=2", *grid]),
            ("show", ["show", path, "--out", str(out / "show"), "--json", *(["--resolution", "12"] if small else [])]),
            ("plot-front", ["plot-front", run]),
            ("plot-bands", ["plot-bands", run])]
    if cfg.cycle is not None:
        cmds.append(("cycle", ["cycle", path, "--out", str(out / "cycle"), "--json", *grid]))
    if modelled(cfg.mech):
        pose = STIFFNESS_POSE.get(name) or _reachable_pose(cfg)
        cmds.append(("stiffness", ["stiffness", name, f"--pose={pose}", "--json"]))
    if len(cfg.mech.task_axes) == 2 and cfg.task is not None:
        cmds.append(("plot-task", ["plot-task", path, "--out", str(out / "task"), "--json",
                                   *(["--resolution", "16"] if small else [])]))
    if name == "pprs-rprs":
        cmds.append(("drives", ["drives", path, "--out", str(out / "drives"), "--json"]))
    return cmds


def _reachable_pose(cfg) -> str:
    import numpy as np

    from scalesynth.workspace_view import sample_fields

    fg = sample_fields(cfg, cfg.resolved_design(), 12)
    idx = np.unravel_index(int(np.argmax(fg.lci)), fg.lci.shape)
    return ",".join(f"{float(fg.grid.axis(a)[idx[a]]):.6g}" for a in range(len(cfg.mech.task_axes)))


def main(argv: list[str]) -> None:
    report, rest = argv[0], argv[1:]
    commands: list[list[str]] = [[]]
    for a in rest:
        if a == "--":
            commands.append([])
        else:
            commands[-1].append(a)
    results = []
    t0, c0 = T0, C0
    for args in commands:
        rec = CompileRecorder()
        JIT["s"] = 0.0
        event.register("numba:compile", rec)
        from scalesynth.cli import main as cli_main  # the first command's record includes the imports

        if not results:
            _watch_first_evaluation()

        code = 0
        try:
            cli_main(args)
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
        event.unregister("numba:compile", rec)
        t1, c1 = time.perf_counter(), time.process_time()
        results.append({"args": args, "exit_code": code, "compiled": rec.compiled, "compile_s": rec.compile_s,
                        "jit_s": JIT["s"], "wall_s": t1 - t0, "cpu_s": c1 - c0,
                        "first_grid_s": FIRST_GRID.get("wall"), "first_grid_cpu_s": FIRST_GRID.get("cpu")})
        t0, c0 = t1, c1
    with open(report, "w", encoding="utf-8") as fh:
        json.dump(results, fh, indent=1)


if __name__ == "__main__":
    main(sys.argv[1:])
