"""Messages about unknown names (metrics, mechanisms, fields, design selectors, choices): a "did you mean"
suggestion (difflib) and a list of the valid names cut to a width, so that an error stays one short line."""

from __future__ import annotations

import difflib
from collections.abc import Iterable

LIST_WIDTH = 80  # characters of the valid names quoted in a message; the rest are counted, not listed


def close_matches(name: str, choices: Iterable[str], n: int = 2) -> list[str]:
    """Up to ``n`` of ``choices`` close to ``name`` (difflib ratio >= 0.6, case-insensitive), best first."""
    choices = list(dict.fromkeys(str(c) for c in choices))
    lowered = {c.lower(): c for c in choices}
    return [lowered[c] for c in difflib.get_close_matches(str(name).lower(), list(lowered), n=n, cutoff=0.6)]


def did_you_mean(name: str, choices: Iterable[str]) -> str:
    """"did you mean 'x'?" (or "'x' or 'y'"), or '' when nothing is close."""
    close = close_matches(name, choices)
    return f"did you mean {' or '.join(repr(c) for c in close)}?" if close else ""


def short_list(choices: Iterable[str], width: int = LIST_WIDTH) -> str:
    """The names joined by ', ' up to ``width`` characters; beyond, ', ... (N in all)'."""
    choices = list(dict.fromkeys(str(c) for c in choices))
    shown: list[str] = []
    for c in choices:
        if len(", ".join([*shown, c])) > width:
            break
        shown.append(c)
    text = ", ".join(shown)
    return text if len(shown) == len(choices) else f"{text}, ... ({len(choices)} in all)"


def hint(name: str, choices: Iterable[str], label: str = "known", more: str = "", also: Iterable[str] = ()) -> str:
    """'(did you mean 'x'?; known: a, b, c)': the parenthesis an unknown-name message ends with. A list longer than
    LIST_WIDTH is cut (or only counted beside a suggestion); ``more`` says where the whole list is (e.g. "see
    `scalesynth metrics MECH`"); ``also``: more names to suggest that are not listed (design parameters beside an
    unknown option)."""
    choices = list(dict.fromkeys(str(c) for c in choices))
    tip = did_you_mean(name, [*choices, *also])
    full = ", ".join(choices)
    if len(full) <= LIST_WIDTH:
        listed = f"{label}: {full or 'none'}"
    elif tip:
        listed = f"{len(choices)} {label}"
    else:
        listed = f"{label}: {short_list(choices, LIST_WIDTH - 20)}"
    if more and len(full) > LIST_WIDTH:
        listed += f", {more}" if tip else f"; {more}"
    return f"({'; '.join(p for p in (tip, listed) if p)})"
