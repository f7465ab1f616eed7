"""The repository is self-contained: nothing in src/, tests/, benchmarks/, scripts/ or .ci/ reads the reference
material beside the checkout (the developers' spec folder), and the test data has its provenance written down."""

import re

from conftest import ROOT
from refdata import CASES, DATA

# written in pieces so that this file does not match itself
DOTS, NAME = "..", "shared"
FORBIDDEN = re.compile(
    re.escape(DOTS + "/" + NAME) + "|" + r"/\s*[\"']" + NAME + r"[\"']" + "|" + re.escape("/work/" + NAME)
)


def test_no_file_refers_to_the_reference_folder_beside_the_checkout():
    hits = []
    for top in ("src", "tests", "benchmarks", "scripts", ".ci"):
        for path in sorted((ROOT / top).rglob("*")):
            skip = any(part == "__pycache__" or part.endswith(".egg-info") for part in path.parts)
            if skip or not path.is_file() or path.suffix in {".png", ".pyc"}:
                continue
            for n, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
                if FORBIDDEN.search(line):
                    hits.append(f"{path.relative_to(ROOT)}:{n}: {line.strip()}")
    assert hits == []


def test_the_pattern_catches_the_forms_it_is_meant_to():
    for text in (DOTS + "/" + NAME + "/spec", 'ROOT.parent / "' + NAME + '" / "spec"', "/work/" + NAME + "/spec"):
        assert FORBIDDEN.search(text), text
    assert not FORBIDDEN.search("a shared filesystem") and not FORBIDDEN.search("helpers shared by the CLI")


def test_every_data_file_has_its_provenance_in_the_readme():
    readme = (DATA / "README.md").read_text()
    files = sorted(p.relative_to(DATA).as_posix() for p in DATA.rglob("*") if p.is_file() and p.name != "README.md")
    assert "cases/ref000_004.txt" in files and len(list(CASES.iterdir())) == 4
    missing = [f for f in files if f"`{f}`" not in readme]
    assert missing == []
