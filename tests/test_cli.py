"""CLI contract (DESIGN.md): --json prints one JSON object, nothing else; exit 0 or 2 with one-line errors."""

import json
import os
import subprocess
import sys

import pytest

PAPER = "configs/paper_2pauu_ppap.yaml"


def cli(*args, cwd=None):
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.run([sys.executable, "-m", "scalesynth", *args], capture_output=True, text=True, env=env,
                          cwd=cwd)


@pytest.fixture(autouse=True)
def _in_root(root, monkeypatch):
    monkeypatch.chdir(root)


def test_evaluate_json_group1_matches_spec():
    r = cli("evaluate", PAPER, "--json")
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)  # the whole stdout is one JSON object
    for key in ("volume_m3", "gci", "fci", "min_lci", "band0_share", "band1_share", "band2_share", "voxels",
                "resolution", "seconds"):
        assert key in out
    assert out["volume_m3"] == pytest.approx(61.183182, rel=0.005)  # spec §1.9 exact volume
    assert out["gci"] == pytest.approx(0.3438, abs=0.002)  # spec §1.10 (2-norm, mode ++)
    # the paper config's tolerance runs the uniform grid calibrated for it (Mechanism.uniform_plan)
    assert out["resolution"] == 72 and 0 < out["seconds"] < 60
    assert out["error_volume"] < 0.002 and out["error_gci"] < 5e-4  # its estimates: the change to N = 144


def test_evaluate_overrides_and_text_output():
    r = cli("evaluate", PAPER, "--set", "m=0.5", "--set", "n=0.506", "--set", "l1=1.5", "--resolution", "48")
    assert r.returncode == 0, r.stderr
    assert "volume_m3" in r.stdout and "band 2" in r.stdout
    r = cli("evaluate", PAPER, "--set", "mode=+-", "--json", "--resolution", "24")
    assert r.returncode == 0 and json.loads(r.stdout)["gci"] < 0.2  # asymmetric mode: GCI 0.0724 in spec §1.10


def test_design_outside_bounds_warns_but_evaluates():
    r = cli("evaluate", PAPER, "--set", "l1=2.0", "--json", "--resolution", "16")
    assert r.returncode == 0
    assert "warning: design.l1=2 is outside the optimisation bounds [0.5, 1.5]" in r.stderr
    assert json.loads(r.stdout)["volume_m3"] > 0


def test_unreachable_design_is_data():
    r = cli("evaluate", PAPER, "--set", "stroke_limits=[5, 6]", "--json", "--resolution", "16")
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["volume_m3"] == 0 and out["gci"] == 0 and out["voxels"] == 0


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["evaluate", PAPER, "--set", "l1=-1"], "design.l1: must be > 0"),
        (["evaluate", PAPER, "--set", "l1=nan"], "design.l1"),
        (["evaluate", PAPER, "--set", "foo=1"], "options.foo: unknown option"),
        (["evaluate", PAPER, "--set", "mode=+x"], "options.mode"),
        (["evaluate", PAPER, "--set", "grid.resolution=2"], "grid.resolution"),
        (["evaluate", PAPER, "--set", "theta1_limits=[1, 0]"], "options.theta1_limits"),
        (["evaluate", "missing.yaml"], "missing.yaml: no such config file"),
        (["ik", "nope", "--pose", "0,0,1"], "unknown mechanism 'nope'"),
        (["ik", "2pauu-ppap", "--pose", "0,0"], "--pose"),
        (["ik", "2pauu-ppap", "--pose", "a,b,c"], "--pose"),
        (["fk", "2pauu-ppap", "--inputs", "1,2"], "--inputs"),
        (["ik", "2pauu-ppap", "--set", "l2=0", "--pose", "0,0,1"], "design.l2"),
    ],
)
def test_bad_input_one_line_exit_2(args, needle):
    r = cli(*args)
    assert r.returncode == 2
    assert needle in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
    assert r.stdout == ""


def test_invalid_yaml_and_unknown_key(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: x\nmechanism: [unclosed\n")
    r = cli("evaluate", str(bad))
    assert r.returncode == 2 and "invalid YAML" in r.stderr
    bad.write_text("name: x\nmechanism: 2pauu-ppap\ngrid: {resolution: 16, colour: red}\n")
    r = cli("evaluate", str(bad))
    assert r.returncode == 2 and "grid.colour: unknown key" in r.stderr


def test_ik_fk_json_all_branches():
    r = cli("ik", "2pauu-ppap", "--set", "m=1", "--set", "n=0.5", "--set", "l1=0.6", "--set", "l2=1.2",
            "--pose=-0.9165,-0.5846,0.8792", "--json")
    assert r.returncode == 0, r.stderr
    sols = {s["branch"]: s for s in json.loads(r.stdout)["solutions"]}
    assert set(sols) == {"++", "+-", "-+", "--"}
    assert sols["++"]["values"][0] == pytest.approx(-2.285386, abs=1e-6)  # spec §1.8
    assert sols["++"]["lci"] == pytest.approx(0.227552, abs=1e-6)
    r = cli("fk", "2pauu-ppap", "--set", "m=1", "--set", "n=0.5", "--set", "l1=0.6", "--set", "l2=1.2",
            "--inputs=-3.1033,-2.6997,-0.5846", "--json")
    sols = json.loads(r.stdout)["solutions"]
    assert len(sols) == 2
    assert min(abs(s["values"][0] - 0.859400) for s in sols) < 1e-6  # spec Table 3 mode 2


def test_mechanisms_lists_registry():
    r = cli("mechanisms", "--json")
    assert r.returncode == 0
    names = [m["name"] for m in json.loads(r.stdout)]
    assert "2pauu-ppap" in names
