"""Example configs shipped inside the package (``scalesynth example --list``).

These YAML files are the source of truth; ``configs/`` in the repository holds byte-identical copies for the
README's commands (tests/test_examples.py checks that they agree). Each file starts with comment lines that say
what it is; their first sentence is the one-line description shown by ``--list``.
"""

from __future__ import annotations

import re
from importlib import resources

from scalesynth.errors import ConfigError
from scalesynth.names import hint


def _files() -> dict[str, resources.abc.Traversable]:
    root = resources.files(__name__)
    return {p.name[: -len(".yaml")]: p for p in root.iterdir() if p.name.endswith(".yaml")}


def names() -> list[str]:
    """Names of the shipped examples (file names without .yaml), sorted."""
    return sorted(_files())


def text(name: str) -> str:
    """The YAML text of example ``name``; an unknown name raises ConfigError naming the available ones."""
    files = _files()
    if name not in files:
        raise ConfigError(f"example: unknown example {name!r} " + hint(name, sorted(files), "available"))
    return files[name].read_text(encoding="utf-8")


def description(name: str) -> str:
    """The first sentence of example ``name``'s leading comment block (its lines joined, without the '#'): a whole
    sentence, ending with its full stop."""
    header = []
    for line in text(name).splitlines():
        if not line.startswith("#"):
            break
        header.append(line.lstrip("#").strip())
    joined = " ".join(header)
    end = re.search(r"\.(\s|$)", joined)  # a full stop before a space or the end (not a decimal point)
    return joined[: end.start() + 1] if end else joined
