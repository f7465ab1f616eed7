"""Results directory I/O: atomic writes (temp file in the same directory + fsync + rename) and path safety.

A reader never sees a half-written file: either the previous version or the new one. Errors writing (disk full,
read-only directory) become RunError (exit code 1) and leave the earlier file untouched.
"""

from __future__ import annotations

import json
import os
import pickle
import re
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

from scalesynth.errors import RunError

RESULT_FILES = ("pareto.csv", "population.csv", "history.csv", "manifest.json", "config.yaml", "report.md")
CHECKPOINT = "checkpoint.pkl"


def safe_child(directory: Path, name: str) -> Path:
    """``directory / name``, refusing names that would escape the directory (absolute, '..', separators)."""
    if not name or Path(name).is_absolute() or any(part in ("..", "") for part in Path(name).parts):
        raise RunError(f"{name!r}: output names must stay inside {directory}")
    path = (directory / name).resolve()
    if directory.resolve() not in path.parents:
        raise RunError(f"{name!r}: output names must stay inside {directory}")
    return path


def ensure_dir(path: Path) -> Path:
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise RunError(f"{path}: cannot create output directory ({err.strerror or err})") from None
    if not os.access(path, os.W_OK):
        raise RunError(f"{path}: output directory is not writable")
    return path


def write_atomic(path: Path, writer: Callable[[Any], None], mode: str = "w") -> None:
    """Call ``writer(fileobj)`` on a temp file next to ``path``, fsync, then rename over ``path``."""
    path = Path(path)
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
        text_args = {} if "b" in mode else {"encoding": "utf-8", "newline": ""}
        with os.fdopen(fd, mode, **text_args) as fh:
            writer(fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
        tmp = None
    except OSError as err:
        raise RunError(f"{path}: cannot write ({err.strerror or err})") from None
    finally:
        if tmp is not None and os.path.exists(tmp):
            os.unlink(tmp)


# write_atomic's temp names: '.' + target name + '.' + mkstemp's 8 random characters + '.tmp'
_TEMP_NAME = re.compile(r"^\..+\.[a-z0-9_]{8}\.tmp$")


def remove_stale_temps(directory: Path) -> list[Path]:
    """Delete temp files that a killed writer (SIGKILL mid-write) left in ``directory`` and its subdirectories
    one level down; returns them. Only names made by ``write_atomic`` are touched."""
    stale = []
    for pattern in (".*.tmp", "*/.*.tmp"):
        for path in Path(directory).glob(pattern):
            if _TEMP_NAME.match(path.name) and path.is_file():
                try:
                    path.unlink()
                except FileNotFoundError:
                    continue
                stale.append(path)
    return stale


def write_text(path: Path, text: str) -> None:
    write_atomic(path, lambda fh: fh.write(text))


def write_json(path: Path, obj: Any) -> None:
    write_text(path, json.dumps(obj, indent=2, sort_keys=False) + "\n")


def write_pickle(path: Path, obj: Any) -> None:
    write_atomic(path, lambda fh: pickle.dump(obj, fh, protocol=pickle.HIGHEST_PROTOCOL), mode="wb")


def read_pickle(path: Path) -> Any:
    with open(path, "rb") as fh:
        return pickle.load(fh)


def write_csv(path: Path, frame) -> None:
    """CSV with a fixed float format so equal numbers always give equal bytes."""
    write_text(path, frame.to_csv(index=False, float_format="%.12g", lineterminator="\n"))


FIGURE_FORMATS = ("png", "svg", "pdf")


def save_figure(fig, path: Path, dpi: int = 130) -> None:
    """Write a matplotlib figure atomically in the format of the file's suffix (png, svg or pdf)."""
    fmt = Path(path).suffix.lstrip(".").lower() or "png"
    write_atomic(path, lambda fh: fig.savefig(fh, format=fmt, dpi=dpi, bbox_inches="tight"), mode="wb")
