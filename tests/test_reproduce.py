"""`reproduce` compares the dependency versions recorded in the manifest with the installed ones and warns (one
line, before the re-run) when they differ; byte-identical results are only promised for identical versions."""

import json
import os
import shutil
import subprocess
import sys

import pytest

from scalesynth.config import config_from_dict
from scalesynth.optimize import run
from scalesynth.versions import installed_versions, version_differences

from conftest import SMALL


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    return run(config_from_dict(SMALL), tmp_path_factory.mktemp("r") / "run", plots=False).out_dir


def _reproduce(run_dir, out):
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.run([sys.executable, "-m", "scalesynth", "reproduce", str(run_dir), "--out", str(out)],
                          capture_output=True, text=True, env=env, timeout=600)


def test_version_differences():
    now = installed_versions()
    assert version_differences(now) == []
    assert version_differences(dict(now, numpy="0.0.1")) == [f"numpy 0.0.1 -> {now['numpy']}"]
    assert version_differences(dict(now, nosuchpkg="1.0")) == ["nosuchpkg 1.0 -> not installed"]
    assert version_differences({}) == ["the manifest records no versions"]


def test_same_versions_no_warning(finished, tmp_path):
    r = _reproduce(finished, tmp_path / "again")
    assert r.returncode == 0 and "pareto.csv identical" in r.stdout
    assert r.stderr == ""


def test_other_versions_warn_in_one_line(finished, tmp_path):
    other = tmp_path / "other"
    shutil.copytree(finished, other)
    manifest = json.loads((other / "manifest.json").read_text())
    real = manifest["versions"]["numba"]
    manifest["versions"]["numba"] = "0.1.0"
    (other / "manifest.json").write_text(json.dumps(manifest))
    r = _reproduce(other, tmp_path / "again")
    assert r.returncode == 0, r.stderr  # the same installed versions still give the same front
    (line,) = r.stderr.strip().splitlines()
    assert line.startswith(f"warning: dependency versions differ from the recorded run (numba 0.1.0 -> {real}):")
    assert "same versions and machine type" in line
