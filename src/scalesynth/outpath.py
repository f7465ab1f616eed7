"""Checks of an output path before any work: ``check_dir`` for a command's output directory, ``check_file`` for one
output file (``select``). Each returns the absolute path with its symbolic links resolved, or raises ConfigError
(exit code 2) with one line naming the option and the problem: a dangling link or a link loop anywhere on the
path, a file where a directory belongs (or the reverse), a pseudo file system (/proc, /sys, ...), a place this
user cannot write. Nothing is created or changed."""

from __future__ import annotations

import ctypes
import errno
import os
import stat
from pathlib import Path

from scalesynth.errors import ConfigError

# statfs f_type of kernel pseudo file systems (linux/magic.h): nothing written there is a file on a disk
PSEUDO_FILE_SYSTEMS = {
    0x9FA0: "proc", 0x62656572: "sysfs", 0x1CD1: "devpts", 0x27E0EB: "cgroup", 0x63677270: "cgroup2",
    0x64626720: "debugfs", 0x74726163: "tracefs", 0x73636673: "securityfs", 0xCAFE4A11: "bpf",
    0x6165676C: "pstore", 0x62656570: "configfs", 0x65735543: "fusectl", 0x42494E4D: "binfmt_misc",
    0xDE5E81E4: "efivarfs", 0x19800202: "mqueue", 0x1373: "devtmpfs",
}


def shown(path, limit: int = 80) -> str:
    """A path as a message shows it: the user's text, its start cut when long, so the line stays short."""
    text = str(path)
    return text if len(text) <= limit else "..." + text[3 - limit:]


def _fail(option: str, path, problem: str) -> ConfigError:
    return ConfigError(f"{option}: {shown(path)}: {problem}")


def _existing_part(path: Path, option: str, given) -> tuple[Path, list[str]]:
    """(the longest existing leading part of ``path``, the names below it that do not exist yet)."""
    missing: list[str] = []
    cur = path
    while True:
        try:
            os.stat(cur)
            return cur, missing
        except FileNotFoundError:
            if os.path.lexists(cur):
                raise _fail(option, given, f"{shown(cur, 50)} is a dangling symbolic link") from None
        except OSError as err:
            if err.errno == errno.ELOOP:
                raise _fail(option, given, f"symbolic link loop at {shown(cur, 50)}") from None
            if err.errno == errno.ENOTDIR:
                raise _fail(option, given, "cannot create output directory (a part of the path is a file)") from None
            if err.errno == errno.ENAMETOOLONG:
                raise _fail(option, given, "path too long") from None
            raise _fail(option, given, f"cannot use it ({err.strerror or err})") from None
        if cur.parent == cur:
            return cur, missing
        missing.append(cur.name)
        cur = cur.parent


def file_system(path: Path) -> str | None:
    """The name of the pseudo file system ``path`` is on, or None (a disk, tmpfs, NFS, ... or unknown)."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        buf = ctypes.create_string_buffer(256)  # struct statfs is 120 bytes on x86-64; f_type is its first word
        if libc.statfs(os.fsencode(path), buf) != 0:
            return None
    except (OSError, AttributeError):
        return None
    f_type = ctypes.c_long.from_buffer(buf).value & 0xFFFFFFFF
    return PSEUDO_FILE_SYSTEMS.get(f_type)


def _resolved(target, option: str) -> tuple[Path, bool]:
    """(absolute path with links resolved, whether it exists), after the checks common to files and directories."""
    given = target
    path = Path(os.path.abspath(Path(target).expanduser()))
    existing, missing = _existing_part(path, option, given)
    real = Path(os.path.realpath(existing))
    kind = file_system(real)
    if kind is not None:
        raise _fail(option, given, f"is on the {kind} pseudo file system; choose a directory on a disk")
    if missing and not real.is_dir():
        raise _fail(option, given, "cannot create output directory (a part of the path is a file)")
    for name in reversed(missing):
        real = real / name
    return real, not missing


def check_dir(target, option: str = "--out") -> Path:
    """The output directory ``target`` resolved; ConfigError if it cannot be one (see the module docstring)."""
    real, exists = _resolved(target, option)
    if real.parent == real:
        raise _fail(option, target, "the root directory cannot be an output directory")
    if exists:
        if not stat.S_ISDIR(os.stat(real).st_mode):
            raise _fail(option, target, "cannot create output directory (a file of that name exists)")
        if not os.access(real, os.R_OK | os.W_OK | os.X_OK):
            raise _fail(option, target, "the directory is not writable")
    _check_writable_ancestor(real.parent, option, target)  # the staging directory and the lock go beside it
    return real


def check_file(target, option: str = "--out") -> tuple[Path, bool]:
    """(the output file ``target`` resolved, whether it exists); ConfigError if it cannot be written."""
    real, exists = _resolved(target, option)
    if exists and stat.S_ISDIR(os.stat(real).st_mode):
        raise _fail(option, target, "is a directory (give a file name)")
    _check_writable_ancestor(real.parent, option, target)
    return real, exists


def _check_writable_ancestor(directory: Path, option: str, given) -> None:
    """The nearest existing directory at or above ``directory`` must let this user create entries."""
    cur = directory
    while not cur.exists() and cur.parent != cur:
        cur = cur.parent
    if not os.access(cur, os.W_OK | os.X_OK):
        raise _fail(option, given, f"cannot create output directory ({shown(cur, 50)} is not writable)")
