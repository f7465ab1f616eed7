"""Bad configs: one line on stderr naming the field, exit code 2, nothing written; a fuzzed loader never crashes.

Every CLI case runs ``python -m scalesynth`` in a subprocess (the real entry point, real exit code); the cases
run a few at a time because each process spends most of its time importing.
"""

import copy
import json
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from scalesynth.config import RunConfig, config_from_dict, load_config
from scalesynth.errors import ConfigError

ROOT = Path(__file__).resolve().parents[1]
QUICK = yaml.safe_load((ROOT / "configs" / "quick.yaml").read_text())


def _set(path, value):
    """A mutation setting the dotted ``path`` (list indices as ints) of a config dict to ``value``."""

    def mutate(data):
        *parents, last = path
        node = data
        for part in parents:
            node = node[part]
        node[last] = value

    return mutate


def _delete(path):
    def mutate(data):
        *parents, last = path
        node = data
        for part in parents:
            node = node[part]
        del node[last]

    return mutate


def _both(*mutations):
    def mutate(data):
        for m in mutations:
            m(data)

    return mutate


# (label, mutation of configs/quick.yaml, text the one-line message must contain)
CASES = [
    ("unknown top-level key", _set(["colour"], "red"), "colour: unknown key"),
    ("unknown nested key", _set(["algorithm", "popsize"], 10), "algorithm.popsize: unknown key"),
    ("wrong type (string for int)", _set(["algorithm", "pop_size"], "many"), "algorithm.pop_size:"),
    ("wrong type (list for int)", _set(["grid", "resolution"], [20]), "grid.resolution:"),
    ("wrong type (mapping for list)", _set(["objectives"], {"metric": "gci"}), "objectives:"),
    ("inverted bounds", _set(["bounds", "m"], [1.5, 0.5]), "bounds.m: lower bound 1.5 must be below"),
    ("empty bounds interval", _set(["bounds", "l1"], [1.0, 1.0]), "bounds.l1: lower bound 1.0 must be below"),
    ("bounds not a pair", _set(["bounds", "n"], [0.5]), "bounds.n.1: Field required"),
    ("negative design length", _set(["design", "l1"], -1.0), "design.l1: must be > 0"),
    ("negative length bound", _set(["bounds", "c"], [-0.1, 0.5]), "bounds.c: lower bound must be > 0"),
    ("unknown design parameter", _set(["design", "q"], 1.0), "design.q: unknown parameter"),
    ("unknown option", _set(["options", "speed"], 1.0), "options.speed: unknown option"),
    ("bad option value", _set(["options", "mode"], "+*"), "options.mode:"),
    ("unknown mechanism", _set(["mechanism"], "hexapod-9000"), "mechanism: unknown mechanism 'hexapod-9000'"),
    ("unknown objective", _set(["objectives", 0, "metric"], "speed"),
     "objectives[0].metric: unknown metric 'speed' for 2pauu-ppap (valid: volume, gci, "),
    ("band out of range", _set(["objectives", 0], {"metric": "band_share", "band": 3}),
     "objectives[0].band: 3 out of range (valid: 0..2)"),
    ("task metric without a task", _set(["constraints"], [{"metric": "task_coverage", "min": 1.0}]),
     "constraints[0].metric: task_coverage needs a task section"),
    ("path metric without a path",
     _both(_set(["task"], {"box": {"x": [0, 1], "y": [0, 1], "z": [0, 1]}}),
           _set(["constraints"], [{"metric": "path_min_lci", "min": 0.1}])),
     "constraints[0].metric: path_min_lci needs task.path"),
    ("unbounded metric minimised", _set(["objectives", 0], {"metric": "mean_sigma_max", "sense": "min"}),
     "objectives[0].sense: mean_sigma_max has no finite worst value"),
    ("unknown objective sense", _set(["objectives", 1, "sense"], "maximise"), "objectives.1.sense:"),
    ("band objective without band", _set(["objectives", 0], {"metric": "band_share"}), "objectives[0].band:"),
    ("unknown algorithm", _set(["algorithm", "name"], "cmaes"), "algorithm.name:"),
    ("missing name", _delete(["name"]), "name:"),
    ("name escaping the directory", _set(["name"], "../escape"), "name:"),
    ("name '..'", _set(["name"], ".."), "name:"),
    ("name with a separator", _set(["name"], "a/b"), "name:"),
    ("non-finite bound", _set(["bounds", "m"], [0.5, float("inf")]), "bounds.m:"),
]


def _cli(*args, cwd=None):
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.run(
        [sys.executable, "-m", "scalesynth", *args], capture_output=True, text=True, env=env, cwd=cwd, timeout=120
    )


def _parallel(calls):
    with ThreadPoolExecutor(max_workers=4) as pool:
        return list(pool.map(lambda c: _cli(*c), calls))


def _assert_one_line_error(r, expected):
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert len(lines) == 1, r.stderr
    assert lines[0].startswith("error: ") and expected in lines[0], lines[0]
    assert r.stdout == ""


def test_every_kind_of_config_error_via_the_cli(tmp_path):
    calls, outs = [], []
    for i, (_, mutate, _) in enumerate(CASES):
        data = copy.deepcopy(QUICK)
        mutate(data)
        path = tmp_path / f"bad{i}.yaml"
        path.write_text(yaml.safe_dump(data))
        out = tmp_path / f"out{i}"
        calls.append(("optimize", str(path), "--out", str(out), "-q"))
        outs.append(out)
    for (label, _, expected), r, out in zip(CASES, _parallel(calls), outs, strict=True):
        assert r.returncode == 2, (label, r.stderr)
        _assert_one_line_error(r, expected)
        assert not out.exists(), label


def test_yaml_is_loaded_safely_and_files_are_checked(tmp_path):
    marker = tmp_path / "MARKER"
    evil = tmp_path / "evil.yaml"
    evil.write_text(f"!!python/object/apply:os.system ['touch {marker}']\n")
    tagged = tmp_path / "tagged.yaml"
    tagged.write_text(yaml.safe_dump(QUICK) + "extra: !!python/object:pathlib.Path {}\n")
    broken = tmp_path / "broken.yaml"
    broken.write_text("name: [unclosed\n")
    listed = tmp_path / "list.yaml"
    listed.write_text("- name: quick\n")
    cases = [
        (evil, "evil.yaml: invalid YAML (line 1)"),
        (tagged, "tagged.yaml: invalid YAML"),
        (broken, "broken.yaml: invalid YAML"),
        (listed, "config: top level must be a mapping"),
        (tmp_path / "missing.yaml", "missing.yaml: no such config file"),
    ]
    calls = [("optimize", str(p), "--out", str(tmp_path / f"out{i}"), "-q") for i, (p, _) in enumerate(cases)]
    for i, ((_, expected), r) in enumerate(zip(cases, _parallel(calls), strict=True)):
        _assert_one_line_error(r, expected)
        assert not (tmp_path / f"out{i}").exists()
    assert not marker.exists(), "the YAML tag was executed"


def test_batch_rejects_bad_input_before_writing_anything(tmp_path):
    good = tmp_path / "good.yaml"
    good.write_text(yaml.safe_dump(QUICK))
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump({**QUICK, "bounds": {**QUICK["bounds"], "m": [2.0, 1.0]}}))
    twin = tmp_path / "twin.yaml"
    twin.write_text(yaml.safe_dump(QUICK))  # same name as good.yaml: its directories would collide
    out = tmp_path / "batch"
    cases = [
        (("batch", str(good), str(bad), "--out", str(out)), "bounds.m: lower bound 2.0 must be below"),
        (("batch", str(good), str(twin), "--out", str(out)), "name: 'quick' is also the name of"),
        (("batch", str(good), "--seeds", "0", "--out", str(out)), "--seeds: must be at least 1"),
        (("batch", str(good), "--set", "algorithm.seed=-1", "--out", str(out)), "algorithm.seed:"),
    ]
    for (_, expected), r in zip(cases, _parallel([c for c, _ in cases]), strict=True):
        _assert_one_line_error(r, expected)
    assert not out.exists()


@pytest.mark.parametrize("name", ["..", ".", "../x", "a/b", "/abs", ".hidden", "a\\b", ""])
def test_names_that_could_escape_the_output_directory_are_rejected(name):
    with pytest.raises(ConfigError, match=r"^name:"):
        config_from_dict({**QUICK, "name": name})


@pytest.mark.parametrize("name", ["quick", "run_2", "a..b", "v1.2-final"])
def test_plain_names_are_accepted(name):
    assert config_from_dict({**QUICK, "name": name}).name == name


# ----- fuzzing the loader ---------------------------------------------------------------------------------------

def _valid_bases():
    """Every shipped config that validates (so each mechanism's option checks are fuzzed too)."""
    out = []
    for path in sorted((ROOT / "configs").glob("*.yaml")):
        try:
            load_config(path)
        except ConfigError:
            continue
        out.append(yaml.safe_load(path.read_text()))
    return out


BASES = _valid_bases()
KEYS = st.sampled_from(["name", "m", "l1", "mode", "x", "band", "metric", "min", "lo", "0", "seed", "region"])
KEYS = KEYS | st.text(max_size=6)
SCALARS = (
    st.none()
    | st.booleans()
    | st.integers(-(2**40), 2**40)
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=8)
    | st.sampled_from(["max", "min", "++", "nsga2", "volume", "band_share", "x", "2pauu-ppap", "planar-fivebar"])
)
VALUES = st.recursive(
    SCALARS,
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(KEYS, inner, max_size=4),
    max_leaves=8,
)


def _paths(node, prefix=()):
    """Every path to a node of a nested dict/list config (the root included)."""
    yield prefix
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _paths(v, (*prefix, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _paths(v, (*prefix, i))


@st.composite
def mutated_configs(draw):
    data = copy.deepcopy(draw(st.sampled_from(BASES)))
    for _ in range(draw(st.integers(1, 4))):
        paths = list(_paths(data))
        path = draw(st.sampled_from(paths))
        action = draw(st.sampled_from(["set", "delete", "add", "wrap", "nest"]))
        if not path:  # the root itself
            if action == "set":
                data = draw(VALUES)
            continue
        parent = data
        for part in path[:-1]:
            parent = parent[part]
        last = path[-1]
        if action == "set":
            parent[last] = draw(VALUES)
        elif action == "delete":
            del parent[last]
        elif action == "add" and isinstance(parent[last], dict):
            parent[last][draw(KEYS)] = draw(VALUES)
        elif action == "wrap":
            parent[last] = [parent[last]]
        elif action == "nest":
            parent[last] = {draw(KEYS): parent[last]}
        if not isinstance(data, dict | list):
            break
    return data


@settings(max_examples=1200, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(mutated_configs())
def test_fuzzed_configs_either_load_or_raise_one_line_config_error(data):
    try:
        cfg = config_from_dict(copy.deepcopy(data))
    except ConfigError as err:
        msg = str(err)
        assert msg and len(msg.splitlines()) == 1, msg
        return
    assert isinstance(cfg, RunConfig)
    # what loads must survive its own round trip through YAML (config.yaml of a results directory)
    again = config_from_dict(yaml.safe_load(yaml.safe_dump(cfg.model_dump(mode="json"))))
    assert json.dumps(again.model_dump(mode="json"), sort_keys=True) == json.dumps(
        cfg.model_dump(mode="json"), sort_keys=True
    )
