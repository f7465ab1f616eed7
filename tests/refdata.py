"""Reference data of the tests, read from tests/data/ only (provenance of every file: tests/data/README.md)."""

import json
import re
from functools import cache
from pathlib import Path

DATA = Path(__file__).resolve().parent / "data"
CASES = DATA / "cases"
_NUM = r"-?\d+(?:\.\d+)?(?:e[-+]?\d+)?"


def load_case(name: str):
    """A JSON case file of tests/data/cases/ (ref001.json, ref002.json, ref003.json), parsed."""
    return json.loads((CASES / name).read_text())


def numbers(text: str) -> list[float]:
    return [float(v) for v in re.findall(_NUM, text)]


@cache
def ref000_004_sections() -> dict[str, list[str]]:
    """cases/ref000_004.txt split at its '=== title ===' lines: {title: [lines]}."""
    sections: dict[str, list[str]] = {}
    current = None
    for line in (CASES / "ref000_004.txt").read_text().splitlines():
        head = re.fullmatch(r"=== (.*?) ===", line.strip())
        if head:
            current = head.group(1)
            sections[current] = []
        elif current is not None and line.strip():
            sections[current].append(line)
    return sections


def _section(prefix: str) -> list[str]:
    (lines,) = [v for k, v in ref000_004_sections().items() if k.startswith(prefix)]
    return lines


def seed000_modes() -> dict[str, tuple]:
    """Seed 000 at the Table-2 point, per working mode: (other FK pose (x, y, z) m, det Jx, diag Jq[:2], LCI 2-norm,
    J rows 3x3)."""
    lines = _section("000: Table-2 point")
    out = {}
    for i, line in enumerate(lines):
        head = re.match(r"\s*mode (\S\S): th=", line)
        if not head:
            continue
        fk = [numbers(p) for p in re.findall(r"'\(([^)]*)\)'", line)]
        jac, lci = lines[i + 1], lines[i + 2]
        det = float(re.search(rf"det Jx=({_NUM})", jac).group(1))
        diag = numbers(re.search(r"diag Jq=\(([^)]*)\)", jac).group(1))[:2]
        rows = [numbers(r) for r in re.findall(r"\(([^)]*)\)", jac.split("J rows=")[1])]
        out[head.group(1)] = (fk, det, tuple(diag), float(re.search(rf"LCI\(2-norm\)=({_NUM})", lci).group(1)), rows)
    return out


def seed000_table2_roots() -> dict[str, tuple[float, float]]:
    """IK roots at the Table-2 point: {'e=2c': (theta1 (+, -), theta2 (+, -)), 'e=c': ...}, rad."""
    first, text = _section("000: Table-2 point")[:2]
    t1 = numbers(re.search(r"theta1 \(\+,-\): \(([^)]*)\)", first).group(1))
    t2 = numbers(re.search(r"theta2 \(\+,-\): \(([^)]*)\)", first).group(1))
    c1 = numbers(re.search(r"theta1: \(([^)]*)\)", text).group(1))
    c2 = numbers(re.search(r"theta2: \(([^)]*)\)", text).group(1))
    return {"e=2c": (tuple(t1), tuple(t2)), "e=c": (tuple(c1), tuple(c2))}


def seed000_exact_volumes() -> dict[int, float]:
    """Exact reachable volume (m^3, no joint limits) of the six Table-4 groups."""
    out = {}
    for line in _section("000: exact volumes"):
        m = re.match(rf"group (\d): V_full=({_NUM})", line)
        if m:
            out[int(m.group(1))] = float(m.group(2))
    return out


def seed004_points() -> dict[str, tuple]:
    """Seed 004 reference points (illustrative r = 200, l1 = 475, l2 = 875 mm), per name a..o:
    ((x, y) mm, (alpha1, alpha2, beta1, beta2) rad of the elbow-out branch, J rows 2x2 mm, LCI, other FK pose)."""
    lines = _section("004")
    out = {}
    for i in range(0, len(lines), 2):
        a, b = lines[i], lines[i + 1]
        name, x, y = re.match(rf"(\w)=\(({_NUM}),({_NUM})\)", a).groups()
        a1 = numbers(re.search(r"alpha1\(\+,-\)=\(([^)]*)\)", a).group(1))
        a2 = numbers(re.search(r"alpha2\(\+,-\)=\(([^)]*)\)", a).group(1))
        beta = numbers(re.search(r"beta=\(([^)]*)\)", a).group(1))
        fk = [numbers(p) for p in re.findall(r"'\(([^)]*)\)'", b)]
        rows = [numbers(r) for r in re.findall(r"\(([^)]*)\)", b.split("J=")[1].split(" LCI")[0])]
        lci = float(re.search(rf"LCI=({_NUM})", b).group(1))
        # elbow out = (alpha1[+], alpha2[-]) (the file's own note)
        out[name] = ((float(x), float(y)), (a1[0], a2[1], beta[0], beta[1]), rows, lci, fk[1])
    return out


@cache
def seed000_table4() -> dict:
    """tests/data/seed000_table4.json with integer group keys."""
    raw = json.loads((DATA / "seed000_table4.json").read_text())
    return {k: {int(g): v for g, v in raw[k].items()} for k in raw if not k.startswith("_")}


def seed000_table3() -> list[tuple]:
    """Seed 000, FK of the paper's rounded Table-3 inputs (theta1, theta2, d): [(q, [pose mode 1, pose mode 2])]."""
    out = []
    for line in _section("000: Table 3"):
        q, rest = line.split("->")
        out.append((tuple(numbers(q)), [tuple(numbers(p)) for p in re.findall(r"'\(([^)]*)\)'", rest)]))
    return out
