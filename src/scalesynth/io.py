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
        os.fchmod(fd, 0o666 & ~current_umask())  # mkstemp makes 0600; results are shared like any other file
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


def current_umask() -> int:
    """The process umask (read without changing it where /proc allows; else set and restored at once)."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


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


def null_nan(obj: Any) -> Any:
    """``obj`` with every float NaN (a statistic over an empty set) replaced by None, so JSON gets null, never the
    non-JSON NaN; dicts, lists and tuples are walked, NumPy floats included."""
    if isinstance(obj, float):  # numpy.float64 is a float too
        return None if obj != obj else obj
    if isinstance(obj, dict):
        return {k: null_nan(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [null_nan(v) for v in obj]
    return obj


def write_json(path: Path, obj: Any) -> None:
    write_text(path, json.dumps(null_nan(obj), indent=2, sort_keys=False) + "\n")


def write_pickle(path: Path, obj: Any) -> None:
    write_atomic(path, lambda fh: pickle.dump(obj, fh, protocol=pickle.HIGHEST_PROTOCOL), mode="wb")


def read_pickle(path: Path) -> Any:
    with open(path, "rb") as fh:
        return pickle.load(fh)


CHECKPOINT_KEYS = ("algorithm", "history", "elapsed", "digest", "started")


def read_checkpoint(path: Path) -> dict[str, Any]:
    """A checkpoint written by ``optimize.run``; ConfigError (one line) if it is empty, truncated or foreign.

    Checkpoints are pickles: resume only checkpoints you wrote yourself (unpickling runs code)."""
    from scalesynth.errors import ConfigError

    hint = "start without --resume to discard it"
    try:
        with open(path, "rb") as fh:
            state = pickle.load(fh)
    except OSError as err:
        raise RunError(f"{path}: cannot read ({err.strerror or err})") from None
    except EOFError:
        raise ConfigError(f"{path}: empty or truncated checkpoint ({hint})") from None
    except Exception as err:  # UnpicklingError, AttributeError/ImportError of a foreign class, ...
        raise ConfigError(f"{path}: not a scalesynth checkpoint ({err.__class__.__name__}; {hint})") from None
    if not isinstance(state, dict) or any(k not in state for k in CHECKPOINT_KEYS):
        raise ConfigError(f"{path}: not a scalesynth checkpoint (unexpected content; {hint})")
    from pymoo.algorithms.moo.nsga2 import NSGA2

    if not isinstance(state["algorithm"], NSGA2) or not isinstance(state["history"], list):
        raise ConfigError(f"{path}: not a scalesynth checkpoint (no NSGA-II state; {hint})")
    return state


def write_csv(path: Path, frame) -> None:
    """CSV with a fixed float format so equal numbers always give equal bytes; every number must be finite or NaN
    (a statistic over an empty set, written as an empty cell); infinities are refused."""
    import numpy as np

    numeric = frame.select_dtypes(include="number")
    bad = [c for c in numeric.columns if np.isinf(numeric[c].to_numpy(dtype=float)).any()]
    if bad:
        raise RunError(f"{path}: column {bad[0]} has a non-finite value (not written); please report it")
    write_text(path, frame.to_csv(index=False, float_format="%.12g", lineterminator="\n"))


FIGURE_FORMATS = ("png", "svg", "pdf")


def save_figure(fig, path: Path, dpi: int = 130, metadata: dict[str, str] | None = None) -> None:
    """Write a matplotlib figure atomically in the format of the file's suffix (png, svg or pdf); ``metadata``:
    matplotlib's savefig metadata (the keys that format knows)."""
    fmt = Path(path).suffix.lstrip(".").lower() or "png"
    write_atomic(path, lambda fh: fig.savefig(fh, format=fmt, dpi=dpi, bbox_inches="tight", metadata=metadata),
                 mode="wb")


# ----- reading a results directory that may have been damaged: one-line ConfigError, never a traceback ----------

def read_results_csv(path: Path, required: tuple[str, ...] | list[str] = (), nullable=frozenset()):
    """A results CSV as a DataFrame; ConfigError naming the file if it is empty, not CSV, lacks a ``required``
    column or has a non-numeric or non-finite value in one (an empty cell is allowed in ``nullable`` columns: a
    statistic over an empty set)."""
    import numpy as np
    import pandas as pd

    from scalesynth.errors import ConfigError

    try:
        frame = pd.read_csv(path)
    except OSError as err:
        raise RunError(f"{path}: cannot read ({err.strerror or err})") from None
    except (pd.errors.EmptyDataError, pd.errors.ParserError, UnicodeDecodeError, ValueError) as err:
        raise ConfigError(f"{path}: not a scalesynth results table ({err.__class__.__name__})") from None
    for col in required:
        if col not in frame.columns:
            raise ConfigError(f"{path}: column {col!r} is missing (damaged or not written by this version)")
        values = pd.to_numeric(frame[col], errors="coerce").to_numpy(dtype=float)
        if col in nullable:
            ok = np.isfinite(values) | (frame[col].isna().to_numpy() & np.isnan(values))
        else:
            ok = np.isfinite(values)
        if not ok.all():
            row = int(np.nonzero(~ok)[0][0])
            raise ConfigError(f"{path}: column {col!r}, row {row + 1}: not a finite number")
        frame[col] = values
    return frame


def read_csv_columns(path: Path, columns: tuple[str, ...] | list[str]):
    """``columns`` of a results CSV as float arrays (dict name -> (n_rows,)), read without pandas (whose import a
    command can then put after its first evaluation); None if the file is missing, not CSV, lacks a column or
    holds a value that is not a finite number: the caller then reads it with :func:`read_results_csv`, which says
    what is wrong."""
    import csv

    import numpy as np

    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = list(csv.reader(fh))
        header = rows[0]
        idx = [header.index(c) for c in columns]
        values = np.array([[float(r[i]) for i in idx] for r in rows[1:]], dtype=float).reshape(-1, len(idx))
    except (OSError, UnicodeDecodeError, csv.Error, ValueError, IndexError):
        return None
    if not np.isfinite(values).all():
        return None
    return {c: values[:, k] for k, c in enumerate(columns)}


def csv_rows_conform(path: Path, required, nullable=frozenset()) -> int | None:
    """The number of data rows of a results CSV whose ``required`` columns each hold a finite number in every row
    (in ``nullable`` columns also an empty cell or nan), read without pandas; None where the file is missing, not
    CSV, lacks a column or holds another value: :func:`read_results_csv` then says what is wrong (this check only
    ever accepts less than it does)."""
    import csv
    import math

    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = [r for r in csv.reader(fh) if r]
        header = rows[0]
        idx = [(header.index(c), c in nullable) for c in required]
        for r in rows[1:]:
            if len(r) != len(header):
                return None
            for i, can_be_null in idx:
                if r[i] == "" and can_be_null:
                    continue
                v = float(r[i])
                if not (math.isfinite(v) or (can_be_null and math.isnan(v))):
                    return None
    except (OSError, UnicodeDecodeError, csv.Error, ValueError, IndexError):
        return None
    return len(rows) - 1


def read_manifest(path: Path) -> dict[str, Any]:
    """manifest.json as a dict with its resolved config; ConfigError naming the file if damaged."""
    from scalesynth.errors import ConfigError

    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as err:
        raise RunError(f"{path}: cannot read ({err.strerror or err})") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as err:
        raise ConfigError(f"{path}: not valid JSON ({err.__class__.__name__})") from None
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a JSON object, got {type(data).__name__}")
    for key, kind in (("config", dict), ("status", str), ("hypervolume", (int, float)), ("wall_seconds", (int, float))):
        if not isinstance(data.get(key), kind):
            raise ConfigError(f"{path}: field {key!r} is missing or of the wrong type")
    return data

