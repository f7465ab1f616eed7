import sys
from pathlib import Path

import pytest
from hypothesis import settings

# reproducible property tests: the same examples on every run (CI included)
settings.register_profile("repro", derandomize=True, deadline=None, print_blob=True)
settings.load_profile("repro")

sys.path.insert(0, str(Path(__file__).parent))

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared"

# Table 4 of seed 000 (m, n, l1, l2, c) and the exact volumes of spec §1.9 (m^3, no joint limits)
TABLE4 = {
    1: dict(m=0.857, n=0.706, l1=1.499, l2=1.5, c=0.1),
    2: dict(m=0.719, n=0.579, l1=1.499, l2=1.5, c=0.1),
    3: dict(m=0.516, n=0.342, l1=1.5, l2=1.5, c=0.1),
    4: dict(m=0.500, n=0.506, l1=1.5, l2=1.5, c=0.1),
    5: dict(m=0.509, n=0.339, l1=1.5, l2=1.5, c=0.1),
    6: dict(m=0.506, n=0.330, l1=1.5, l2=1.5, c=0.1),
}
EXACT_VOLUME = {1: 61.183182, 2: 61.572038, 3: 60.413342, 4: 66.403843, 5: 60.554123, 6: 60.342992}
# spec §1.10, "correct J, sym mode, 2-norm" (grid error about +-5e-4)
SPEC_GCI = {1: 0.3438, 2: 0.3438, 3: 0.3439, 4: 0.3380, 5: 0.3438, 6: 0.3440}


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
