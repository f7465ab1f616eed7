"""Packaged example configs: ``configs/`` equals the package data, every example is a valid config, the
``example`` command, and the walk of a new user after a non-editable ``pip install .``."""

import json
import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest
from typer.testing import CliRunner

from scalesynth import examples
from scalesynth.cli import app
from scalesynth.config import load_config

from conftest import ROOT

PACKAGED = ROOT / "src" / "scalesynth" / "examples"
runner = CliRunner()


def test_configs_folder_is_a_byte_identical_copy_of_the_packaged_examples():
    shipped = {p.name: p.read_bytes() for p in PACKAGED.glob("*.yaml")}
    user = {p.name: p.read_bytes() for p in (ROOT / "configs").glob("*.yaml")}
    assert set(user) == set(shipped) and "quick.yaml" in shipped
    stale = [name for name in shipped if user[name] != shipped[name]]
    assert stale == [], f"{stale}: edit src/scalesynth/examples/, then cp src/scalesynth/examples/*.yaml configs/"


@pytest.mark.parametrize("name", examples.names())
def test_every_example_is_a_valid_config_with_a_description(name, tmp_path):
    path = tmp_path / f"{name}.yaml"
    path.write_text(examples.text(name))
    cfg = load_config(path)
    assert cfg.name and examples.description(name)


def test_example_list_names_every_example():
    res = runner.invoke(app, ["example", "--list"])
    assert res.exit_code == 0
    listed = [line.split()[0] for line in res.stdout.splitlines()]
    assert listed == examples.names() == sorted(p.stem for p in PACKAGED.glob("*.yaml"))


def test_example_writes_refuses_to_overwrite_and_forces(tmp_path):
    out = tmp_path / "q.yaml"
    res = runner.invoke(app, ["example", "quick", "--out", str(out)])
    assert res.exit_code == 0 and out.read_bytes() == (PACKAGED / "quick.yaml").read_bytes()
    out.write_text("mine")
    res = runner.invoke(app, ["example", "quick", "--out", str(out)])
    assert res.exit_code == 2 and out.read_text() == "mine"
    assert res.stderr.strip() == f"error: --out: {out} exists (use --force to overwrite it)"
    res = runner.invoke(app, ["example", "quick", "--out", str(out), "--force"])
    assert res.exit_code == 0 and out.read_bytes() == (PACKAGED / "quick.yaml").read_bytes()
    res = runner.invoke(app, ["example", "quick", "--out", "-"])
    assert res.exit_code == 0 and res.stdout == (PACKAGED / "quick.yaml").read_text()


def test_example_default_file_name_and_bad_names(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert runner.invoke(app, ["example", "rps_upu"]).exit_code == 0
    assert (tmp_path / "rps_upu.yaml").read_bytes() == (PACKAGED / "rps_upu.yaml").read_bytes()
    res = runner.invoke(app, ["example", "nope"])
    assert res.exit_code == 2 and len(res.stderr.strip().splitlines()) == 1
    assert res.stderr.startswith("error: example: unknown example 'nope' (available: delta, delta_picks, "
                                 "fivebar_described, "
                                 "fivebar_packing, ")
    res = runner.invoke(app, ["example"])
    assert res.exit_code == 2 and "give an example name" in res.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rps_upu.yaml"]  # nothing else written


@pytest.mark.slow
def test_non_editable_install_in_a_fresh_venv_runs_the_example_from_an_empty_directory(tmp_path):
    """`pip install .` (a wheel, not editable) into a new virtual environment, then in an empty directory
    `scalesynth example quick --out q.yaml && scalesynth optimize q.yaml --out r`. The dependencies come from this
    test environment (a .pth line) so that nothing is downloaded but the build backend."""
    src = tmp_path / "src"
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(".venv", ".git", "results", "build", "*.egg-info",
                                                             "__pycache__", ".pytest_cache", ".hypothesis"))
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True, timeout=120)
    vpy = venv / "bin" / "python"
    purelib = subprocess.run([str(vpy), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                             capture_output=True, text=True, check=True).stdout.strip()
    Path(purelib, "_test_deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env["NUMBA_NUM_THREADS"] = "1"
    subprocess.run([sys.executable, "-m", "pip", "--python", str(vpy), "install", "--quiet", "--no-deps", str(src)],
                   check=True, timeout=600, env=env)
    work = tmp_path / "empty"
    work.mkdir()
    where = subprocess.run([str(vpy), "-c", "import scalesynth.examples as e; print(e.__file__)"], cwd=work,
                           capture_output=True, text=True, env=env, check=True).stdout.strip()
    assert where.startswith(purelib) and "src/scalesynth" not in where  # the installed copy, not the checkout
    exe = str(venv / "bin" / "scalesynth")
    step1 = subprocess.run([exe, "example", "quick", "--out", "q.yaml"], cwd=work, env=env, capture_output=True,
                           text=True, timeout=120)
    assert step1.returncode == 0, step1.stderr
    step2 = subprocess.run([exe, "optimize", "q.yaml", "--out", "r", "-q"], cwd=work, env=env, capture_output=True,
                           text=True, timeout=600)
    assert step2.returncode == 0, step2.stderr
    manifest = json.loads((work / "r" / "manifest.json").read_text())
    assert manifest["status"] == "finished" and manifest["name"] == "quick"
    assert (work / "r" / "pareto.csv").stat().st_size > 0 and (work / "r" / "plots").is_dir()


def test_example_list_lines_are_whole_sentences():
    """Each `example --list` line is the name and the first whole sentence of the example's header comment: it ends
    with a full stop, its brackets close, and the header starts with it (nothing cut mid-sentence)."""
    res = runner.invoke(app, ["example", "--list"])
    assert res.exit_code == 0
    for line in res.stdout.splitlines():
        name, text = line.split(maxsplit=1)
        header = " ".join(x.lstrip("#").strip() for x in examples.text(name).splitlines() if x.startswith("#"))
        assert text.endswith("."), line
        assert text.count("(") == text.count(")") and text.count("[") == text.count("]"), line
        assert header.startswith(text), line
