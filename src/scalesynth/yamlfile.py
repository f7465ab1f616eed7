"""YAML as scalesynth reads it from users: the safe loader (no object construction), duplicate keys refused, YAML 1.2
floats, and limits a hostile document cannot get through (size, alias expansion, nesting). Configs and mechanism
descriptions are read with it; nothing here imports the rest of scalesynth's modules, so any module may."""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

import yaml

from scalesynth.errors import ConfigError

MAX_YAML_NODES = 100_000  # nodes after alias expansion (a config has a few hundred; an alias bomb billions)
MAX_YAML_BYTES = 1_000_000
MAX_QUOTED = 200  # characters of a key or value quoted in an error message

# YAML 1.2 floats: PyYAML (YAML 1.1) reads 2e-1 or 1E5 as strings; configs and --set take them as numbers
_FLOAT = re.compile(
    r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
    |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
    |\.[0-9_]+(?:[eE][-+]?[0-9]+)?
    |[-+]?\.(?:inf|Inf|INF)
    |\.(?:nan|NaN|NAN))$""",
    re.X,
)


class _ConfigLoader(yaml.SafeLoader):
    """SafeLoader (no object construction) that refuses duplicate keys and reads YAML 1.2 floats."""


_ConfigLoader.yaml_implicit_resolvers = {k: list(v) for k, v in yaml.SafeLoader.yaml_implicit_resolvers.items()}
_ConfigLoader.add_implicit_resolver("tag:yaml.org,2002:float", _FLOAT, list("-+0123456789."))


def _mapping_without_duplicates(loader: yaml.SafeLoader, node: yaml.MappingNode, deep: bool = False):
    seen = set()
    for key_node, _ in node.value:
        if key_node.tag == "tag:yaml.org,2002:merge":
            continue
        key = loader.construct_object(key_node, deep=True)
        try:
            duplicate = key in seen
        except TypeError:  # an unhashable key: SafeLoader refuses it below
            break
        if duplicate:
            raise ConfigError(f"line {key_node.start_mark.line + 1}: duplicate key {quoted(key)}")
        seen.add(key)
    return loader.construct_mapping(node, deep=deep)


_ConfigLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _mapping_without_duplicates)


def _expanded_size(node, memo: dict[int, int]) -> int:
    """Number of nodes once every alias is expanded (memoised on the node graph, so a bomb is counted fast)."""
    key = id(node)
    if key in memo:
        return memo[key]
    memo[key] = 1  # a recursive alias: SafeLoader refuses it later
    if isinstance(node, yaml.SequenceNode):
        size = 1 + sum(_expanded_size(child, memo) for child in node.value)
    elif isinstance(node, yaml.MappingNode):
        size = 1 + sum(_expanded_size(k, memo) + _expanded_size(v, memo) for k, v in node.value)
    else:
        size = 1
    memo[key] = size
    return size


def safe_yaml(text: str, what: str) -> Any:
    """Parse YAML text with the safe loader; ConfigError (one line, naming ``what``) for invalid YAML, duplicate
    keys, documents that expand beyond MAX_YAML_NODES nodes or nest too deep."""
    if len(text) > MAX_YAML_BYTES:
        raise ConfigError(f"{what}: {len(text)} characters, more than the {MAX_YAML_BYTES} a config may have")
    loader = _ConfigLoader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        size = _expanded_size(node, {})
        if size > MAX_YAML_NODES:
            raise ConfigError(f"{what}: the document expands to {size:.3g} nodes (aliases), more than the "
                              f"{MAX_YAML_NODES} a config may have")
        return loader.construct_document(node)
    except ConfigError as err:
        raise ConfigError(f"{what}: {err}" if str(err).startswith("line ") else str(err)) from None
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" (line {mark.line + 1})" if mark is not None else ""
        raise ConfigError(f"{what}: invalid YAML{where}") from None
    except RecursionError:
        raise ConfigError(f"{what}: nested too deeply") from None
    finally:
        loader.dispose()


def quoted(value: Any) -> str:
    """repr of a key or value for an error message, cut to MAX_QUOTED characters."""
    text = repr(value) if not isinstance(value, str) or len(value) <= MAX_QUOTED else repr(value[:MAX_QUOTED])
    return text if len(text) <= MAX_QUOTED + 2 else text[:MAX_QUOTED] + "..."


def read_limited(path: Path, limit: int) -> str:
    """The UTF-8 text of a file of at most ``limit`` bytes; ConfigError (one line) for a larger one, checked by its
    size before reading and by reading at most ``limit + 1`` bytes (a sparse or growing file is never read whole)."""
    def too_big(size: str) -> ConfigError:
        return ConfigError(f"{path}: {size} bytes, more than the {limit} a config may have")

    try:
        with open(path, "rb") as fh:
            size = os.fstat(fh.fileno()).st_size
            if size > limit:
                raise too_big(str(size))
            data = fh.read(limit + 1)
        if len(data) > limit:
            raise too_big(f"{limit + 1} or more")
        return data.decode("utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise ConfigError(f"{path}: cannot read ({err.__class__.__name__})") from None
