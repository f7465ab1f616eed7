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
"""

from __future__ import annotations

import ctypes
import errno
import fcntl
import os
import re
import shutil
import time
from pathlib import Path

from scalesynth import io as rio
from scalesynth.errors import RunError

# entries of a results directory that belong to the run that wrote it (replaced by the next run, never carried)
RUN_OWNED = (*rio.RESULT_FILES, rio.CHECKPOINT, "plots")
_RUN_OWNED_PATTERN = re.compile(r"^selected_[a-z]+\.yaml$|^\..+\.tmp$")  # `select` outputs, temp files


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
    """A claimed target: ``work`` is the staging directory to write into; ``commit()`` swaps it in."""

    def __init__(self, target: Path, fd: int):
        self.target = target
        self.work = staging_path(target)
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

    # --- swap ---------------------------------------------------------------------------------------------------
    def commit(self) -> None:
        """Make the staged run the target, atomically; the previous run (if any) is deleted afterwards."""
        target, work = self.target, self.work
        if target.is_dir():
            _carry_foreign_entries(target, work)
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


def claim(target: Path) -> RunDir:
    """Lock ``target`` for this process (RunError naming the holder's pid if another run has it) and repair a
    swap that a kill interrupted. Use as ``with claim(target) as rd: ...``."""
    target = _absolute(target)
    if target.exists() and not target.is_dir():
        raise RunError(f"{target}: cannot create output directory (a file of that name exists)")
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
    rd = RunDir(target, fd)
    try:
        _repair(target)
    except BaseException:
        rd.release()
        raise
    return rd


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


def _carry_foreign_entries(target: Path, work: Path) -> None:
    """Hard-link (copy where links are not possible) what the old directory holds besides the run's own files."""
    for entry in target.iterdir():
        if entry.name in RUN_OWNED or _RUN_OWNED_PATTERN.match(entry.name) or (work / entry.name).exists():
            continue
        try:
            if entry.is_dir() and not entry.is_symlink():
                shutil.copytree(entry, work / entry.name, symlinks=True, copy_function=_link_or_copy)
            else:
                _link_or_copy(entry, work / entry.name)
        except OSError as err:
            raise RunError(f"{entry}: cannot carry over into the new run ({err.strerror or err})") from None


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
