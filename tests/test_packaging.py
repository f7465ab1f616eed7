"""pyproject.toml: every runtime dependency declares a floor that scripts/test-min can pin (CI installs them all
together and runs a test subset there), the known-bad typer versions are excluded, the licence is SPDX, and the
installed versions of this environment satisfy the declared ranges."""

import importlib.util
import tomllib
from importlib import metadata

from packaging.requirements import Requirement
from packaging.version import Version

from conftest import ROOT

PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())


def _min_versions():
    spec = importlib.util.spec_from_file_location("min_versions", ROOT / "scripts" / "min_versions.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_dependency_has_a_floor_that_the_min_environment_pins():
    deps = [Requirement(d) for d in PYPROJECT["project"]["dependencies"]]
    floors = _min_versions().floors()
    assert list(floors) == [d.name for d in deps]
    for dep in deps:
        low = Version(floors[dep.name])
        assert low in dep.specifier, f"{dep}: the floor {low} is not inside its own range"


def test_typer_floor_excludes_the_versions_that_break_the_cli():
    typer = next(Requirement(d) for d in PYPROJECT["project"]["dependencies"] if d.startswith("typer"))
    # 0.12.0-0.12.3 reject `list[str] | None` options, 0.12.4-0.12.5 mis-parse --out; 0.13.1 is tested by test-min
    assert not any(Version(v) in typer.specifier for v in ("0.12.0", "0.12.3", "0.12.5", "0.13.0"))
    assert Version("0.13.1") in typer.specifier


def test_spdx_licence_and_a_build_backend_that_understands_it():
    assert PYPROJECT["project"]["license"] == "MIT"
    assert (ROOT / "LICENSE").read_text().startswith("MIT License")
    (backend,) = [Requirement(r) for r in PYPROJECT["build-system"]["requires"] if r.startswith("setuptools")]
    assert Version("76.9") not in backend.specifier and Version("77.0") in backend.specifier  # PEP 639 support


def test_installed_versions_satisfy_the_declared_ranges():
    bad = []
    for text in PYPROJECT["project"]["dependencies"]:
        dep = Requirement(text)
        got = metadata.version(dep.name)
        if not dep.specifier.contains(got, prereleases=True):
            bad.append(f"{dep.name} {got} not in {dep.specifier}")
    assert bad == []
