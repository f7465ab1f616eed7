"""Progress reporting for long runs: a rich progress bar on a terminal, plain periodic lines otherwise (CI)."""

from __future__ import annotations

import sys
import time
from typing import Any


class PlainProgress:
    """One line every ``every_seconds`` (and at the last generation) on stderr."""

    def __init__(self, every_seconds: float = 10.0, stream=None):
        self.every = every_seconds
        self.stream = stream or sys.stderr
        self._last = -1e9

    def __call__(self, row: dict[str, Any]) -> None:
        now = time.monotonic()
        last = row["generation"] >= row["n_gen"]
        if not last and now - self._last < self.every:
            return
        self._last = now
        left = _eta(row)
        self.stream.write(
            f"gen {row['generation']}/{row['n_gen']}  evals {row['evaluations']}  HV {row['hypervolume']:.6g}  "
            f"front {row['n_nondominated']}  {row['seconds']:.1f} s  ~{left:.0f} s left\n"
        )
        self.stream.flush()

    def close(self) -> None:
        pass


class RichProgress:
    """A rich progress bar: generation, evaluations, hypervolume, time left."""

    def __init__(self, total: int, description: str = "NSGA-II"):
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

        self.progress = Progress(
            TextColumn("[bold]{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("evals {task.fields[evals]}  HV {task.fields[hv]}"),
            TimeRemainingColumn(),
            transient=False,
        )
        self.task = self.progress.add_task(description, total=total, evals=0, hv="-")
        self.progress.start()

    def __call__(self, row: dict[str, Any]) -> None:
        self.progress.update(
            self.task, completed=row["generation"], evals=row["evaluations"], hv=f"{row['hypervolume']:.5g}"
        )

    def close(self) -> None:
        self.progress.stop()


def _eta(row: dict[str, Any]) -> float:
    done = max(row["generation"], 1)
    return row["seconds"] / done * max(row["n_gen"] - row["generation"], 0)


def make_progress(total: int, quiet: bool = False):
    if quiet:
        return None
    if sys.stderr.isatty():
        return RichProgress(total)
    return PlainProgress()
