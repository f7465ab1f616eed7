import sys
from pathlib import Path

import pytest
from hypothesis import settings

# reproducible property tests: the same examples on every run (CI included)
settings.register_profile("repro", derandomize=True, deadline=None, print_blob=True)
settings.load_profile("repro")

sys.path.insert(0, str(Path(__file__).parent))
from refdata import seed000_exact_volumes, seed000_table4  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]

# Table 4 of seed 000 (m, n, l1, l2, c), the exact volumes of spec §1.9 (m^3, no joint limits, from
# tests/data/cases/ref000_004.txt) and the GCI of spec §1.10 ("correct J, sym mode, 2-norm", grid error about
# +-5e-4); provenance: tests/data/README.md
TABLE4 = seed000_table4()["designs"]
EXACT_VOLUME = seed000_exact_volumes()
SPEC_GCI = seed000_table4()["gci"]


@pytest.fixture(scope="session")
def root():
    return ROOT


# a seed-000 synthesis small enough for tests (16 designs x 6 generations on a 12^3 grid), shared by the
# optimisation, reliability and batch tests
SMALL = {
    "name": "small",
    "mechanism": "2pauu-ppap",
    "design": {"m": 0.857, "n": 0.706, "l1": 1.499, "l2": 1.5, "c": 0.1},
    "bounds": {"m": [0.5, 1.5], "n": [0.2, 1.0], "l1": [0.5, 1.5], "l2": [0.5, 1.5], "c": [0.1, 0.5]},
    "grid": {"resolution": 12},
    "algorithm": {"pop_size": 16, "n_gen": 6, "seed": 3},
    "output": {"checkpoint_every": 2},
}


@pytest.fixture
def no_browser(tmp_path, monkeypatch):
    """PATH without any browser and no $SCALESYNTH_CHROMIUM (scalesynth.html_print finds no Chromium)."""
    from scalesynth import html_print

    empty = tmp_path / "empty-bin"
    empty.mkdir()
    monkeypatch.setenv("PATH", str(empty))
    monkeypatch.delenv(html_print.BROWSER_ENV, raising=False)
