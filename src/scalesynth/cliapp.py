"""The typer application and the helpers every command module shares (error mapping, --set/--json options).

Command modules (``scalesynth.commands.*``, and ``scalesynth.cli`` itself) import ``app`` from here and register
their commands on it; ``scalesynth.cli`` loads them. Importing this module loads no command, so no command
module imports the module that loads it (no import cycle).

Exit codes: 0 ok, 1 run failed, 2 bad input (one line on stderr naming what is wrong).
"""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from functools import wraps
from typing import Annotated, Any

import typer

from scalesynth.errors import InvalidPose, ScalesynthError

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    help="Multi-objective dimensional synthesis of parallel mechanisms.",
    pretty_exceptions_enable=False,
)

SetOpt = Annotated[
    list[str] | None,
    typer.Option("--set", "-s", help="override: design parameter, option or dotted config path, as key=value"),
]
JsonOpt = Annotated[bool, typer.Option("--json", help="print one JSON object on stdout and nothing else")]
ForceOpt = Annotated[bool, typer.Option(
    "--force", help="write into an --out directory that is not this command's own (replacing only files it writes)")]

DesignOpt = Annotated[
    str | None,
    typer.Option("--design", help="of a results directory: knee (default), best-<metric> (e.g. best-gci) or a row "
                 "of pareto.csv"),
]

SourceArg = Annotated[
    str,
    typer.Argument(metavar="MECHANISM|CONFIG|RUN_DIR", help="mechanism name (its default design; see `scalesynth "
                   "mechanisms`), run config (YAML), or a results directory (with --design)"),
]

MAX_ERROR_LINE = 200  # characters of an error line, "error: " included (the project's promise)


def error_line(message: str) -> str:
    """The one line every error is printed as: 'error: ' and the message, line breaks escaped, at most
    MAX_ERROR_LINE characters: a long word (a path, a value or name quoted from the user) is shortened in its
    middle first, so the sentence around it stays whole; only then is the line cut, ending in '...'."""
    import re

    from scalesynth.config import _one_line

    line = f"error: {_one_line(str(message))}"
    words = re.split(r"(\s+)", line)
    while len("".join(words)) > MAX_ERROR_LINE:
        k = max(range(len(words)), key=lambda i: len(words[i]))
        if len(words[k]) <= 40:
            break
        words[k] = words[k][:20] + "..." + words[k][-17:]
    line = "".join(words)
    return line if len(line) <= MAX_ERROR_LINE else line[: MAX_ERROR_LINE - 3] + "..."


def _fail(message: str, code: int) -> None:
    typer.echo(error_line(message), err=True)
    raise typer.Exit(code)


def handles_errors(func: Callable) -> Callable:
    """Map library errors to a one-line message and the contract's exit codes."""

    @wraps(func)
    def wrapper(*args, **kwargs):
        try:
            return func(*args, **kwargs)
        except ScalesynthError as err:
            _fail(str(err), err.exit_code)
        except KeyboardInterrupt:
            _fail("interrupted", 1)
        except OSError as err:
            _fail(f"{getattr(err, 'filename', '') or ''}: {err.strerror or err}", 1)

    return wrapper


def _warn(message: str) -> None:
    typer.echo(f"warning: {message}", err=True)


def _parse_vector(what: str, text: str, n: int) -> list[float]:
    try:
        values = [float(t) for t in text.split(",")]
    except ValueError:
        raise InvalidPose(f"{what}: expected {n} comma-separated numbers, got {_quote(text)}") from None
    if len(values) != n or any(v != v or v in (float("inf"), float("-inf")) for v in values):
        raise InvalidPose(f"{what}: expected {n} finite comma-separated numbers, got {_quote(text)}")
    from scalesynth.mechanisms.base import MAX_MAGNITUDE

    if any(abs(v) > MAX_MAGNITUDE for v in values):
        raise InvalidPose(f"{what}: values beyond +-{MAX_MAGNITUDE:g} (the largest magnitude scalesynth computes "
                          f"with), got {_quote(text)}")
    return values


def _quote(text: str, limit: int = 80) -> str:
    """repr of a user's text, cut to ``limit`` characters so that an error message stays one short line."""
    return repr(text if len(text) <= limit else text[:limit] + "...")


def _design_inputs(source: str, design: str | None, sets: list[str] | None):
    """(mechanism, design, options) of a pose-level command's MECHANISM|CONFIG|RUN_DIR (selection.load_design)."""
    from scalesynth.selection import load_design

    chosen = load_design(source, design, sets, mechanism_ok=True)
    return chosen.mech, chosen.design, chosen.options


def _print_json(obj: Any) -> None:
    """One JSON object on stdout; strict JSON (a non-finite number is a bug: exit 1 instead of printing NaN)."""
    try:
        from scalesynth.io import null_nan  # a statistic over an empty set (NaN) is printed as null

        text = json.dumps(null_nan(obj), indent=None, sort_keys=False, allow_nan=False)
    except ValueError:
        from scalesynth.errors import RunError

        raise RunError("internal error: a result is not a finite number (nothing printed); please report it") from None
    sys.stdout.write(text + "\n")

