"""Run-directory integrity: an exclusive lock per target, a staging directory beside it, an atomic swap.

A results directory is always either the previous finished run, untouched, or the new run, whole:

- ``claim(target)`` takes an exclusive ``flock`` on ``.<name>.lock`` beside the target (released by the kernel
  when the process ends, even on SIGKILL); a second run on the same target fails at once with exit code 1 and a
  line naming the holder's pid.
- The run writes everything (checkpoints, CSVs, plots, manifest) into ``.<name>.staging`` beside the target.
  ``--resume`` continues the staged run from its checkpoint; a fresh run discards an abandoned staging directory.
- ``RunDir.commit()`` swaps the staging directory in: ``renameat2(RENAME_EXCHANGE)`` exchanges the two
  directories atomically (Linux), then the old run is deleted. Where the exchange is not supported it falls back
  to two renames through ``.<name>.old``; a claim finding that directory (a kill between the two renames) puts
  the old run back first. Files in the old directory that no run writes (notes, ``drives/``, ...) are hard-linked
  into the new one before the swap, so they survive it; the old run's own files (``RUN_OWNED``) do not.

The lock, staging and old directories are hidden (leading dot) and sit in the target's parent, on the same file
system, so the swap is a rename and ``results/*/`` globs never see them.

Every command that writes a directory (a run, ``batch``, ``cycle``, ``show``, ``compare``, ``drives``, the figure
commands through ``scalesynth.plot_output``) uses this module, with an
``Output`` saying which file marks a directory as its own (its manifest) and which entries its output owns. A
command writes only into a directory that is new, empty or its own (``claim`` checks the path with
``scalesynth.outpath`` and refuses anything else with exit code 2 before any work); with ``force`` it also writes
into another directory, but then moves its files in one by one and touches nothing else there. A manifest that
lists the files of its output (``"files"``) says exactly what the next output replaces; everything else (a user's
notes, a ``plots/my.png``) is carried over, down to single files.
"""

from __future__ import annotations

import ctypes
import errno
import fcntl
import json
import os
import re
import shutil
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from scalesynth import io as rio
from scalesynth import outpath
from scalesynth.errors import ConfigError, RunError

_TEMP = re.compile(r"^\..+\.tmp$")
_MANIFEST_LIMIT = 16 * 2**20  # a manifest larger than this is not one of ours (and is not read whole)


@dataclass(frozen=True)
class Output:
    """What one command writes into its output directory."""

    what: str  # the command, as messages name it
    manifest: str  # the JSON file that marks a directory as this command's output
    keys: tuple[str, ...]  # keys that manifest always has
    owned: Callable[[str], bool]  # top-level names the output owns when its manifest lists no "files" (older ones)
    always: Callable[[str], bool] = lambda rel: False  # paths the output owns whatever its manifest lists

    def manifest_of(self, directory: Path) -> dict | None:
        """The directory's manifest as this command writes it, or None if it has none."""
        path = Path(directory) / self.manifest
        try:
            if not path.is_file() or path.is_symlink() or path.stat().st_size > _MANIFEST_LIMIT:
                return None
            data = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None
        if not isinstance(data, dict) or any(k not in data for k in self.keys):
            return None
        return data

    def owns(self, directory: Path) -> Callable[[str], bool]:
        """Which paths (relative, '/'-separated) of the existing output in ``directory`` the next one replaces."""
        files = (self.manifest_of(directory) or {}).get("files")
        if isinstance(files, list) and all(isinstance(f, str) for f in files):
            listed = {*files, self.manifest}
            base = listed.__contains__
        else:
            base = lambda rel: self.owned(rel.split("/", 1)[0])  # noqa: E731
        return lambda rel: base(rel) or self.always(rel) or bool(_TEMP.match(rel.rsplit("/", 1)[-1]))


# entries of a results directory that belong to the run that wrote it (replaced by the next run, never carried)
RUN_OWNED = (*rio.RESULT_FILES, rio.CHECKPOINT, "plots", "bands", "report.html")
_SELECTED = re.compile(r"^selected_[a-z]+\.yaml$")  # `select` outputs: they name rows of the old front

RUN = Output("run", "manifest.json", ("config", "status"), owned=lambda name: name in RUN_OWNED,
             always=lambda rel: bool(_SELECTED.match(rel)) or rel == rio.CHECKPOINT)


def listing(directory: Path) -> list[str]:
    """Every file under ``directory`` (relative, '/'-separated, sorted), for a manifest's ``"files"``."""
    directory = Path(directory)
    return sorted(p.relative_to(directory).as_posix() for p in directory.rglob("*")
                  if not p.is_dir() and not _TEMP.match(p.name) and p.name != rio.CHECKPOINT)


def staging_path(target: Path) -> Path:
    """Where an unfinished run on ``target`` lives (its checkpoint is ``staging_path(target) / 'checkpoint.pkl'``)."""
    target = _absolute(target)
    return target.parent / f".{target.name}.staging"


def lock_path(target: Path) -> Path:
    target = _absolute(target)
    return target.parent / f".{target.name}.lock"


def _old_path(target: Path) -> Path:
    return target.parent / f".{target.name}.old"


def _absolute(target: Path) -> Path:
    return Path(os.path.abspath(Path(target).expanduser()))


class RunDir:
    """A claimed target: ``work`` is the staging directory to write into; ``commit()`` swaps it in.

    ``merge``: the target is another directory that ``force`` lets the command write into: ``commit()`` then moves
    the staged files in one by one instead of swapping the directory."""

    def __init__(self, target: Path, fd: int, output: Output = RUN, merge: bool = False):
        self.target = target
        self.work = staging_path(target)
        self.output = output
        self.merge = merge
        self.created: list[Path] = []  # directories claim made for the target's parent (removed by discard)
        self._fd = fd
        self.committed = False

    # --- staging ------------------------------------------------------------------------------------------------
    def fresh(self) -> Path:
        """An empty staging directory (an abandoned one, of a run that died, is discarded first)."""
        _remove_tree(self.work)
        rio.ensure_dir(self.work)
        return self.work

    def continued(self) -> Path | None:
        """The staging directory of an unfinished run, with a killed writer's temp files removed; None if none."""
        if not self.work.is_dir():
            legacy = self.target / rio.CHECKPOINT  # a checkpoint written inside the target (scalesynth < 0.2)
            if not legacy.is_file():
                return None
            rio.ensure_dir(self.work)
            os.link(legacy, self.work / rio.CHECKPOINT)
        rio.remove_stale_temps(self.work)
        return self.work

    def discard(self) -> None:
        """Forget a failed output: its staging directory, and the parent directories claim created for it."""
        _remove_tree(self.work)
        for path in reversed(self.created):
            try:
                path.rmdir()
            except OSError:
                break

    # --- swap ---------------------------------------------------------------------------------------------------
    def commit(self) -> None:
        """Make the staged output the target: atomically, the previous output (if any) deleted afterwards; or, in a
        directory that is not the command's own (``merge``), file by file."""
        target, work = self.target, self.work
        if self.merge:
            _merge(work, target)
        elif target.is_dir():
            _carry_foreign_entries(target, work, self.output.owns(target))
            if not _exchange(work, target):
                old = _old_path(target)
                _remove_tree(old)
                _rename(target, old)
                _rename(work, target)
                _remove_tree(old)
            else:
                _remove_tree(work)  # now holds the previous run
        else:
            _rename(work, target)
        self.committed = True

    def release(self) -> None:
        if self._fd < 0:
            return
        try:
            os.unlink(lock_path(self.target))  # safe: a waiter re-checks that its locked file is still the path
        except OSError:
            pass
        os.close(self._fd)
        self._fd = -1

    def __enter__(self) -> RunDir:
        return self

    def __exit__(self, *exc) -> None:
        self.release()


def claim(target: Path, output: Output = RUN, force: bool = False, option: str = "--out",
          resuming: bool = False) -> RunDir:
    """Check ``target`` (``outpath.check_dir``), lock it for this process (RunError naming the holder's pid if
    another run has it), repair a swap that a kill interrupted, and refuse (ConfigError naming ``option``) a
    directory that is neither empty nor ``output``'s own unless ``force``. ``resuming``: a target with an unfinished
    run's checkpoint (staged beside it, or inside it from scalesynth < 0.2) counts as the run's own too when the
    swap would drop nothing of it but temp files and that checkpoint. Use as ``with claim(target) as rd:``."""
    given = target
    target = outpath.check_dir(target, option)
    created = [p for p in reversed(target.parents) if not p.exists()]
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise RunError(f"{target}: cannot create output directory ({err.strerror or err})") from None
    path = lock_path(target)
    while True:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
        except OSError as err:
            raise RunError(f"{path}: cannot create the run lock ({err.strerror or err})") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as err:
            os.close(fd)
            if err.errno not in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                raise RunError(f"{path}: cannot lock ({err.strerror or err})") from None
            raise RunError(f"{target}: another scalesynth run (pid {_holder(path)}) is writing this directory; "
                           "wait for it to finish or stop it") from None
        try:
            same = os.fstat(fd).st_ino == os.stat(path).st_ino
        except FileNotFoundError:
            same = False
        if same:  # else the holder removed the file between our open and flock: lock the new one
            break
        os.close(fd)
    os.ftruncate(fd, 0)
    os.write(fd, f"{os.getpid()}\n".encode())
    rd = RunDir(target, fd, output)
    rd.created = created
    try:
        _repair(target)
        rd.merge = not _own(target, output, resuming)
        if rd.merge and not force:
            raise _refusal(given, output, option)
    except BaseException:
        rd.release()
        raise
    return rd


def check(target: Path, output: Output = RUN, force: bool = False, option: str = "--out",
          resuming: bool = False) -> Path:
    """``claim``'s checks of ``target`` without taking or creating anything (for a command that reads its inputs
    before claiming); returns the resolved path."""
    real = outpath.check_dir(target, option)
    if not force and not _own(real, output, resuming):
        raise _refusal(target, output, option)
    return real


def check_own(target: Path, output: Output = RUN, force: bool = False, option: str = "--out",
              resuming: bool = False) -> None:
    """Only the ownership part of :func:`check`: an existing, non-empty ``target`` that is not ``output``'s own is
    refused (ConfigError naming ``option``) unless ``force``; a path that cannot be a directory is left to the
    caller (``batch`` fails that task alone when it cannot make the directory)."""
    if not force and not _own(Path(target), output, resuming):
        raise _refusal(target, output, option)


def is_temp(name: str) -> bool:
    """Whether a file name is one of a killed writer's temp files (``io.write_atomic``)."""
    return bool(_TEMP.match(name))


def _own(target: Path, output: Output, resuming: bool) -> bool:
    """New, empty or ``output``'s own; ``resuming``: also a target whose unfinished run (a checkpoint staged beside
    it, or inside it from scalesynth < 0.2) would lose nothing of it but temp files and that checkpoint."""
    if _is_own(target, output):
        return True
    unfinished = resuming and any(p.is_file() for p in (staging_path(target) / rio.CHECKPOINT,
                                                         target / rio.CHECKPOINT))
    return unfinished and not _would_drop(target, output)


def _refusal(given, output: Output, option: str) -> ConfigError:
    return ConfigError(f"{option}: {outpath.shown(given)}: not empty and not a scalesynth {output.what} directory "
                       f"(no {output.manifest}); use a new or empty one, or --force")


def _is_own(target: Path, output: Output) -> bool:
    """New, empty, or holding ``output``'s manifest."""
    if not target.is_dir():
        return True
    try:
        if next(target.iterdir(), None) is None:
            return True
    except OSError as err:
        raise RunError(f"{target}: cannot read ({err.strerror or err})") from None
    return output.manifest_of(target) is not None


def _would_drop(target: Path, output: Output) -> bool:
    """Whether swapping a new output in would drop a file of ``target`` other than temp files and a checkpoint."""
    owned = output.owns(target)
    for path in target.rglob("*"):
        rel = path.relative_to(target).as_posix()
        if not path.is_dir() and owned(rel) and not _TEMP.match(path.name) and rel != rio.CHECKPOINT:
            return True
    return False


@contextmanager
def staged(target: Path, output: Output, force: bool = False, option: str = "--out",
           stage: str = "staging") -> Iterator[RunDir]:
    """Claim ``target`` and yield it with an empty staging directory (``.work``) to write into: swapped in when the
    block ends normally, discarded (the target untouched) when the block raises, an interrupt included.
    ``stage``: the staging directory's suffix, ``.<name>.<stage>`` (another than a run's ``staging`` where
    ``target`` is a run directory whose unfinished successor may wait there for ``--resume``)."""
    with claim(target, output, force, option) as rd:
        rd.work = rd.target.parent / f".{rd.target.name}.{stage}"
        rd.fresh()
        try:
            yield rd
            rd.commit()
        except BaseException:
            rd.discard()  # after a failed swap too: the next claim puts an interrupted fallback swap right
            raise


def _holder(path: Path) -> str:
    """The pid written in a lock file (its holder writes it right after locking: retry briefly)."""
    for _ in range(50):
        try:
            text = path.read_text().strip()
        except OSError:
            text = ""
        if text.isdigit():
            return text
        time.sleep(0.01)
    return "unknown"


def _repair(target: Path) -> None:
    """A kill between the two renames of the fallback swap leaves the old run in ``.<name>.old``: restore it."""
    old = _old_path(target)
    if old.is_dir():
        if target.exists():
            _remove_tree(old)
        else:
            _rename(old, target)


def _carry_foreign_entries(target: Path, work: Path, owned: Callable[[str], bool], rel: str = "") -> bool:
    """Hard-link (copy where links are not possible) into ``work`` what ``target`` holds besides the previous
    output's own files (``owned``) and what the new output replaces; returns whether ``target/rel`` held any
    owned entry. A directory holding nothing owned is carried whole; one that does is carried file by file, and
    left out when nothing of it remains."""
    any_owned = False
    source = target / rel if rel else target
    for entry in sorted(source.iterdir()):
        name = f"{rel}{entry.name}"
        dst = work / name
        if owned(name):
            any_owned = True
            continue
        try:
            if entry.is_dir() and not entry.is_symlink():
                if os.path.lexists(dst) and not (dst.is_dir() and not dst.is_symlink()):
                    continue  # the new output has a file of that name
                made = not os.path.lexists(dst)
                if made:
                    dst.mkdir()
                if _carry_foreign_entries(target, work, owned, name + "/"):
                    any_owned = True
                    if made and next(dst.iterdir(), None) is None:
                        dst.rmdir()  # held only the previous output's files
                        continue
                if made:
                    shutil.copystat(entry, dst)
            elif not os.path.lexists(dst):
                _link_or_copy(entry, dst)
        except OSError as err:
            raise RunError(f"{entry}: cannot carry over into the new output ({err.strerror or err})") from None
    return any_owned


def _merge(work: Path, target: Path) -> None:
    """Move every file of ``work`` to the same place under ``target`` (replacing a file of that name), creating
    directories as needed and touching nothing else; checked first, so a conflict moves nothing."""
    moves = []
    for src in sorted(work.rglob("*")):
        dst = target / src.relative_to(work)
        src_dir = src.is_dir() and not src.is_symlink()
        dst_dir = dst.is_dir() and not dst.is_symlink()
        if os.path.lexists(dst) and src_dir != dst_dir:
            raise RunError(f"{dst}: cannot replace a {'file' if src_dir else 'directory'} of that name with the "
                           f"new {'directory' if src_dir else 'file'} (nothing was moved)")
        if not src_dir:
            moves.append((src, dst))
    for src, dst in moves:
        try:
            dst.parent.mkdir(parents=True, exist_ok=True)
            os.replace(src, dst)
        except OSError as err:
            raise RunError(f"{dst}: cannot move the new file into place ({err.strerror or err})") from None
    _remove_tree(work)


def _link_or_copy(src, dst) -> None:
    if os.path.islink(src):
        os.symlink(os.readlink(src), dst)
        return
    try:
        os.link(src, dst)
    except OSError:
        shutil.copy2(src, dst)


_RENAME_EXCHANGE = 2
_AT_FDCWD = -100
_renameat2 = None


def _exchange(a: Path, b: Path) -> bool:
    """Atomically exchange two directories (Linux renameat2); False where the system cannot."""
    global _renameat2
    if _renameat2 is None:
        try:
            libc = ctypes.CDLL(None, use_errno=True)
            _renameat2 = libc.renameat2
            _renameat2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
        except (OSError, AttributeError):
            _renameat2 = False
    if not _renameat2:
        return False
    rc = _renameat2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE)
    if rc == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP, errno.ENOTSUP):
        return False
    raise RunError(f"{b}: cannot swap the new run in ({os.strerror(err)})")


def _rename(src: Path, dst: Path) -> None:
    try:
        os.rename(src, dst)
    except OSError as err:
        raise RunError(f"{dst}: cannot move the run into place ({err.strerror or err})") from None


def _remove_tree(path: Path) -> None:
    if not os.path.lexists(path):
        return
    try:
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path)
        else:
            path.unlink()
    except OSError as err:
        raise RunError(f"{path}: cannot remove ({err.strerror or err})") from None
