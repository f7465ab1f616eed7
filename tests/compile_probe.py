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
first workspace-grid evaluation (``Mechanism.grid_stats``; None if the command made none).
Used by tests/test_compile_cache.py and by benchmarks/compile_once.py, which both run ``commands()``.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

T0, C0 = time.perf_counter(), time.process_time()

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


def _watch_grid_stats() -> None:
    """Record when the first Mechanism.grid_stats call of the process returns (every registered class)."""
    from scalesynth.mechanisms import available, get

    classes = {c for name in available() for c in type(get(name)).__mro__ if "grid_stats" in c.__dict__}
    for cls in classes:
        original = cls.__dict__.get("grid_stats")
        if original is None:
            continue

        def timed(self, *args, _original=original, **kwargs):
            out = _original(self, *args, **kwargs)
            if not FIRST_GRID:
                FIRST_GRID.update(wall=time.perf_counter() - T0, cpu=time.process_time() - C0)
            return out

        cls.grid_stats = timed


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
            _watch_grid_stats()

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
