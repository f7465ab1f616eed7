"""Users' own described mechanisms (issue 28): ``mechanism: {description: FILE or MAPPING}`` in a config, FILE read
from the config's directory; ``scalesynth mechanisms NAME --description`` prints the description a user starts from;
a wrong description is one line naming the leg and the field, exit 2; a config dumped with a user's description
(results/config.yaml) reloads the same mechanism. Cheap: uniform 16^3 grids of the Delta."""

import json
import os
import subprocess
import sys

import pytest
import yaml
from typer.testing import CliRunner

import scalesynth
from scalesynth.cli import app
from scalesynth.config import config_from_dict, dump_config, load_config
from scalesynth.errors import ConfigError
from scalesynth.evaluate import evaluate_config
from scalesynth.mechanisms import get

from conftest import ROOT

GRID = ["grid.resolution=16"]
CONFIG = yaml.safe_load((ROOT / "configs" / "delta.yaml").read_text())


def _printed(name: str) -> str:
    res = CliRunner().invoke(app, ["mechanisms", name, "--description"])
    assert res.exit_code == 0, res.output
    return res.stdout


def _project(tmp_path, description_text: str, file_name: str = "my_robot.yaml"):
    """A user's project directory: the description file and a copy of configs/delta.yaml that names it."""
    folder = tmp_path / "project"
    folder.mkdir(exist_ok=True)
    (folder / file_name).write_text(description_text)
    cfg = folder / "robot.yaml"
    cfg.write_text(yaml.safe_dump({**CONFIG, "name": "robot", "mechanism": {"description": file_name}},
                                  sort_keys=False))
    return cfg


def test_the_printed_description_is_the_builtin_file_and_loads_back_as_the_delta(tmp_path):
    text = _printed("delta")
    assert text == (ROOT / "src" / "scalesynth" / "mechanisms" / "delta.yaml").read_text()
    cfg = load_config(_project(tmp_path, text))
    assert cfg.mechanism == "delta" and cfg.mech is get("delta")  # equal to the built-in: the built-in itself
    assert yaml.safe_load(dump_config(cfg))["mechanism"] == "delta"


def test_an_edited_copy_of_the_printed_delta_evaluates_as_the_builtin_through_the_cli(tmp_path):
    """The printed description renamed 'my-delta' (a separate mechanism object, its own packing) gives the built-in
    Delta's metrics on the same grid: the CLI reads the file from the config's directory, not the working one."""
    cfg_path = _project(tmp_path, _printed("delta").replace("\nname: delta\n", "\nname: my-delta\n"))
    res = CliRunner().invoke(app, ["evaluate", str(cfg_path), "--json", "--set", GRID[0]])
    assert res.exit_code == 0, res.output
    mine = json.loads(res.stdout)
    assert mine["mechanism"] == "my-delta"
    builtin = evaluate_config(load_config(ROOT / "configs" / "delta.yaml", GRID)).metrics
    assert mine["volume_m3"] > 0.5  # the Briot-Arakelian-Glazunov design: about 1.48 m^3
    for key, value in builtin.items():
        assert mine[key] == pytest.approx(value, rel=1e-12, abs=1e-15), key


def test_an_inline_description_and_the_python_api(tmp_path):
    """The same mapping inline works from Python (scalesynth.evaluate_config with a dict config); a dumped config
    (what results/config.yaml holds) carries the description inline and reloads the same mechanism anywhere."""
    data = yaml.safe_load(_printed("delta"))
    data["name"] = "inline-delta"
    cfg = scalesynth.load_config(_project(tmp_path, yaml.safe_dump(data), "inline.yaml"), GRID)
    inline = {**CONFIG, "mechanism": {"description": data}, "grid": {**CONFIG["grid"], "resolution": 16}}
    report = scalesynth.evaluate_config(inline)
    assert report.mechanism == "inline-delta"
    assert report.metrics == pytest.approx(scalesynth.evaluate_config(cfg).metrics, rel=1e-12)
    dumped = yaml.safe_load(dump_config(cfg))
    assert dumped["mechanism"]["description"]["name"] == "inline-delta"
    again = config_from_dict(dumped)
    assert again.mech is cfg.mech and again.mechanism == "inline-delta"


DELTA_TEXT = (ROOT / "src" / "scalesynth" / "mechanisms" / "delta.yaml").read_text().replace(
    "\nname: delta\n", "\nname: my-delta\n")


@pytest.mark.parametrize(("edit", "message"), [
    (("type: R-Pa", "type: R-Px"),
     "error: mechanism.description (my_robot.yaml): legs[0] (arm).type: unknown leg type 'R-Px' (did you mean "
     "'R-Pa'?; library: R-Pa, P-Pa, RUS, R-SS, UPS, SPS, RR, PR)"),
    (("platform: [platform_radius, 0, 0]", "platform: [platform_radus, 0, 0]"),
     "error: mechanism.description (my_robot.yaml): legs[0] (arm).platform.x: unknown parameter "
     "'platform_radus' (did you mean 'platform_radius'?; known: base_radius, platform_radius, upper_arm, forearm)"),
    (("    branch: out\n", "    branch: out\n    colour: red\n"),
     "error: mechanism.description (my_robot.yaml): legs[0].colour: unknown key"),
    (("limits: theta_limits", "limits: cone_limit"),
     "error: mechanism.description (my_robot.yaml): legs[0] (arm).limits: option 'cone_limit' is of kind angle, "
     "limits needs one of kind range"),
    (("name: my-delta", "name: delta"),
     "error: mechanism.description.name: 'delta' is a built-in mechanism and this description differs from it: "
     "give yours a name of its own"),
])
def test_a_wrong_description_is_one_line_exit_2(tmp_path, edit, message):
    old, new = edit
    text = DELTA_TEXT.replace(old, new, 1)
    if edit[1] == "name: delta":  # a real difference from the built-in as well as its name
        text = text.replace("default: 0.95", "default: 0.9")
    assert text != DELTA_TEXT
    res = CliRunner().invoke(app, ["evaluate", str(_project(tmp_path, text)), "--set", GRID[0]])
    assert res.exit_code == 2
    lines = res.output.strip().splitlines()
    assert lines == [message] and len(message) <= 200 + len("error: ")


@pytest.mark.parametrize(("mechanism", "message"), [
    ({"description": "missing.yaml"},
     "mechanism.description: no such description file 'missing.yaml' (relative to the config's directory)"),
    ({"description": "my_robot.yaml", "seed": 1},
     "mechanism.seed: unknown key (a described mechanism has only 'description: file or mapping')"),
    ({"description": 3}, "mechanism.description: expected a description file name or a mapping, got int"),
    ({"description": {"name": "x", "title": "t", "motion": "3T", "parameters": {}, "legs": []}},
     "mechanism.description: legs: List should have at least 1 item after validation, not 0"),
])
def test_a_wrong_mechanism_entry_is_one_line_exit_2(tmp_path, mechanism, message):
    cfg = _project(tmp_path, DELTA_TEXT)
    cfg.write_text(yaml.safe_dump({**CONFIG, "mechanism": mechanism}, sort_keys=False))
    res = CliRunner().invoke(app, ["evaluate", str(cfg)])
    assert res.exit_code == 2 and res.output.strip().splitlines() == [f"error: {message}"]
    with pytest.raises(ConfigError) as err:  # the Python API raises scalesynth's error with the same line
        scalesynth.load_config(cfg)
    assert str(err.value) == message


@pytest.mark.parametrize(("args", "message"), [
    (["mechanisms", "planar-fivebar", "--description"],
     "error: --description: planar-fivebar is a hand-written mechanism (seed 004), not a described one: start from a "
     "described one (scalesynth mechanisms lists them)"),
    (["mechanisms", "--description"], "error: --description: name the mechanism (scalesynth mechanisms NAME "
     "--description)"),
])
def test_description_of_what_has_none_is_refused(args, message):
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 2 and res.output.strip().splitlines() == [message]


def test_mechanisms_name_lists_one():
    res = CliRunner().invoke(app, ["mechanisms", "delta", "--json"])
    assert res.exit_code == 0 and [r["name"] for r in json.loads(res.stdout)] == ["delta"]


def test_a_users_description_loads_no_other_mechanism(tmp_path):
    """Checking the user's name against the built-ins reads only what that name suggests (no module imported for
    'my-delta'): a config of one's own costs no other mechanism's import."""
    cfg = _project(tmp_path, DELTA_TEXT)
    code = ("import json, sys\nfrom scalesynth.config import load_config\ncfg = load_config(sys.argv[1])\n"
            "print(json.dumps([cfg.mechanism, sorted(m for m in sys.modules if m.startswith('scalesynth.mechanisms.')"
            " and not m.startswith('scalesynth.mechanisms.describe'))]))")
    proc = subprocess.run([sys.executable, "-c", code, str(cfg)], capture_output=True, text=True, timeout=600,
                          env=dict(os.environ, NUMBA_NUM_THREADS="1"))
    assert proc.returncode == 0, proc.stderr[-2000:]
    name, modules = json.loads(proc.stdout.strip().splitlines()[-1])
    assert name == "my-delta" and set(modules) <= {"scalesynth.mechanisms.base", "scalesynth.mechanisms.links"}
