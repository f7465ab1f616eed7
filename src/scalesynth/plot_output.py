"""Where the figure commands (``plot-front``, ``plot-bands``, ``plot-task``) write: staged and swapped whole through
``scalesynth.rundir``, like every other output directory.

Two kinds of target:

- **A run's own ``plots/``** (the default of ``plot-front`` and ``plot-bands``, or any ``--out`` that is
  ``RUN/plots`` of a directory with a run's ``manifest.json``): the figures belong to the run. The whole run
  directory is staged (its files hard-linked into ``.<run>.plotting`` beside it, the new figures written there)
  and swapped in at once, and the run's manifest lists the new files, so the next run on that directory replaces
  them like its own figures (a run without plots no longer keeps an older ``plot-front``'s ``front.svg``). The
  figures are added or replaced one by one: the run's other figures (another format, report.md's links) stay.
- **Any other directory**: a figures directory marked by ``plots.json``, which lists per command the files it
  wrote. The figure commands share it: each one replaces what it wrote there before and keeps the others' files
  and the user's. It must be new, empty or a figures directory; another is refused before any work (exit 2)
  unless ``--force``, which moves only the new figures in.

``plot-task --out FILE.png`` writes one file (atomically): the figure carries its writer in its metadata, and an
existing file without that mark is refused before any work unless ``--force``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from scalesynth import io as rio
from scalesynth import outpath, rundir
from scalesynth.errors import ConfigError
from scalesynth.results import MANIFEST as RUN_MANIFEST
from scalesynth.results import PLOTS

MANIFEST = "plots.json"
_STAGE = "plotting"  # not a run's "staging": an unfinished run there waits for --resume


@dataclass(frozen=True)
class FiguresOutput(rundir.Output):
    """A figures directory (``plots.json``): ``command`` replaces its own earlier files there, nothing else."""

    command: str = ""

    def owns(self, directory: Path) -> Callable[[str], bool]:
        entry = ((self.manifest_of(directory) or {}).get("commands") or {}).get(self.command)
        files = entry.get("files") if isinstance(entry, dict) else None
        mine = set(files) if isinstance(files, list) and all(isinstance(f, str) for f in files) else set()
        return lambda rel: rel in mine or rel == MANIFEST or rundir.is_temp(rel.rsplit("/", 1)[-1])


@dataclass(frozen=True)
class RunFiguresOutput(rundir.Output):
    """A run directory that figures are added to: nothing of it is dropped (the staged copy holds it all)."""

    def owns(self, directory: Path) -> Callable[[str], bool]:
        return lambda rel: rundir.is_temp(rel.rsplit("/", 1)[-1])


def figures_output(command: str) -> FiguresOutput:
    return FiguresOutput("figures", MANIFEST, ("commands",), owned=lambda name: False, command=command)


INTO_RUN = RunFiguresOutput("run", RUN_MANIFEST, rundir.RUN.keys, owned=lambda name: False)


class Figures:
    """A claimed figures target while the command writes: ``dir`` is where its figures go (the staging copy's
    ``plots/`` for a run, the staging directory itself otherwise), ``root`` the staging directory, ``target`` the
    directory swapped in at the end."""

    def __init__(self, staged: rundir.RunDir, into_run: bool):
        self.target = staged.target
        self.root = staged.work
        self.into_run = into_run
        self.dir = rio.ensure_dir(self.root / PLOTS) if into_run else self.root

    def final(self, written) -> Path:
        """Where a file written under ``root`` (absolute, or relative to ``root``) ends up after the swap."""
        path = Path(written)
        return self.target / (path.relative_to(self.root) if path.is_absolute() else path)


def _run_of(plots: Path) -> Path | None:
    """The run directory whose own ``plots/`` ``plots`` is, or None."""
    if plots.name == PLOTS and rundir.RUN.manifest_of(plots.parent) is not None:
        return plots.parent
    return None


@contextmanager
def figures(out: Path, command: str, force: bool = False, source: str | None = None) -> Iterator[Figures]:
    """Claim ``out`` for the figures of ``command`` (``--out`` checked, a foreign directory refused unless
    ``force``: ConfigError, exit 2) and yield a :class:`Figures` to write into; when the block ends the manifest
    (the run's, or plots.json) gets the files written and the target is swapped in whole. A block that raises
    leaves the target as it was."""
    real = outpath.check_dir(out, "--out")
    run = _run_of(real)
    if run is not None:
        with rundir.staged(run, INTO_RUN, force, stage=_STAGE) as staged:
            fig = Figures(staged, into_run=True)
            yield fig
            _update_run_manifest(fig)
        return
    output = figures_output(command)
    with rundir.staged(out, output, force, stage=_STAGE) as staged:  # the message shows the user's --out
        fig = Figures(staged, into_run=False)
        yield fig
        _write_figures_manifest(fig, output, source)


def _update_run_manifest(fig: Figures) -> None:
    """The run's manifest.json, its ``files`` joined by the new figures (a manifest without ``files``, of an older
    run, already owns plots/ whole: left as it is)."""
    manifest = rundir.RUN.manifest_of(fig.target)
    files = (manifest or {}).get("files")
    if not isinstance(files, list) or not all(isinstance(f, str) for f in files):
        return
    added = rundir.listing(fig.root)
    manifest["files"] = [*sorted({*files, *added} - {RUN_MANIFEST}), RUN_MANIFEST]
    rio.write_json(fig.root / RUN_MANIFEST, manifest)


def _write_figures_manifest(fig: Figures, output: FiguresOutput, source: str | None) -> None:
    """plots.json: the earlier commands' entries (their files still there) and this command's files."""
    old = (output.manifest_of(fig.target) or {}).get("commands") if fig.target.is_dir() else None
    commands = {k: v for k, v in (old or {}).items() if k != output.command and isinstance(v, dict)}
    commands[output.command] = {"source": source, "files": rundir.listing(fig.root)}
    files = sorted({f for v in commands.values() for f in v.get("files") or [] if isinstance(f, str)})
    rio.write_json(fig.root / MANIFEST, {"commands": dict(sorted(commands.items())), "files": [*files, MANIFEST]})


# ----- one figure file (plot-task --out FILE.png) --------------------------------------------------------------
_MARK_KEY = {"png": "Software", "svg": "Creator", "pdf": "Creator"}  # metadata keys each format writes as text
_MARK_SPAN = 1 << 16  # png and svg carry it in their header, pdf in its trailing info dictionary


def _mark(command: str) -> str:
    return f"scalesynth {command}"


def metadata(path: Path, command: str) -> dict[str, str]:
    """The savefig metadata that marks a figure file as written by ``command``."""
    return {_MARK_KEY.get(Path(path).suffix.lstrip(".").lower(), "Creator"): _mark(command)}


def check_file(path: Path, command: str, force: bool = False) -> Path:
    """The resolved figure file ``command`` may write (``outpath.check_file``); an existing file without its mark
    (the user's, or another program's) is refused (ConfigError naming --out) unless ``force``."""
    real, exists = outpath.check_file(path, "--out")
    if exists and not force and not _marked(real, path, command):
        raise ConfigError(f"--out: {outpath.shown(path)}: exists and was not written by {command}; give a new file "
                          "name, or --force to replace it")
    return real


def _marked(real: Path, given, command: str) -> bool:
    mark = _mark(command).encode()
    try:
        with open(real, "rb") as fh:
            head = fh.read(_MARK_SPAN)
            size = fh.seek(0, 2)
            fh.seek(max(size - _MARK_SPAN, 0))
            tail = fh.read(_MARK_SPAN)
    except OSError as err:
        raise ConfigError(f"--out: {outpath.shown(given)}: cannot read ({err.strerror or err})") from None
    return mark in head or mark in tail
