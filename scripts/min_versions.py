"""Print the runtime dependencies of pyproject.toml pinned to their declared lower bounds, one 'name==version' a
line, for the minimum-versions environment of scripts/test-min. Every dependency must declare a '>=' floor."""

from __future__ import annotations

import re
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
_REQ = re.compile(r"^\s*([A-Za-z0-9_.-]+)(\[[^\]]*\])?\s*(.*)$")


def floors(pyproject: Path = ROOT / "pyproject.toml") -> dict[str, str]:
    """{distribution name: lower bound} of [project].dependencies."""
    deps = tomllib.loads(pyproject.read_text())["project"]["dependencies"]
    out = {}
    for dep in deps:
        name, _extras, spec = _REQ.match(dep).groups()
        lows = [s.strip()[2:].strip() for s in spec.split(",") if s.strip().startswith(">=")]
        if len(lows) != 1:
            raise SystemExit(f"pyproject.toml: dependency {dep!r} needs exactly one '>=' lower bound")
        out[name] = lows[0]
    return out


if __name__ == "__main__":
    sys.stdout.write("".join(f"{name}=={low}\n" for name, low in floors().items()))
