"""Users' own described mechanisms: a config's ``mechanism: {description: FILE or MAPPING}`` resolved against the
registry (a description may not take a built-in mechanism's name with other content). Above both the registry
(``scalesynth.mechanisms``) and the description system (``mechanisms.describe``), which import neither this module
nor each other in a circle."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from scalesynth.errors import ConfigError
from scalesynth.mechanisms import find
from scalesynth.mechanisms.describe import DescribedMechanism, from_description, load_description, parse_description
from scalesynth.mechanisms.describe.schema import Description

_USER: dict[str, DescribedMechanism] = {}  # canonical description JSON -> its mechanism (one object per content)


def user_mechanism(desc: Description, where: str = "mechanism.description") -> DescribedMechanism:
    """The mechanism of a user's description. One object per description content (so caches keyed by the
    mechanism hold across configs); a description equal to a built-in one gives the registered built-in; one that
    takes a registered mechanism's name but differs from it is refused (results and plans go by name)."""
    registered = find(desc.name)
    if registered is not None:
        if isinstance(registered, DescribedMechanism) and registered.description == desc:
            return registered
        raise ConfigError(f"{where}.name: {desc.name!r} is a built-in mechanism and this description differs from "
                          "it: give yours a name of its own")
    key = json.dumps(desc.model_dump(mode="json"), sort_keys=True)
    if key not in _USER:
        _USER[key] = from_description(desc)
    return _USER[key]


def resolve_source(source: Any, base_dir: Path | None, where: str = "mechanism") -> DescribedMechanism:
    """The mechanism of a config's ``mechanism: {description: PATH or MAPPING}``; a relative PATH is read from
    ``base_dir`` (the config file's directory; None: the working directory). ConfigError, one line, otherwise."""
    if not isinstance(source, dict) or set(source) != {"description"}:
        keys = sorted(set(source) - {"description"}) if isinstance(source, dict) else []
        if keys:
            raise ConfigError(f"{where}.{str(keys[0])[:40]}: unknown key (a described mechanism has only "
                              "'description: file or mapping')")
        raise ConfigError(f"{where}: expected a mechanism name or {{description: file or mapping}}")
    value = source["description"]
    inner = f"{where}.description"
    if isinstance(value, str):
        path = Path(value)
        if not path.is_absolute() and base_dir is not None:
            path = base_dir / path
        try:
            is_file = path.is_file()
        except OSError:  # e.g. a name too long for the file system
            is_file = False
        if not is_file:
            raise ConfigError(f"{inner}: no such description file {value[:120]!r}"
                              + (" (relative to the config's directory)" if base_dir is not None else ""))
        desc = load_description(path, f"{inner} ({path.name[:60]})")
    elif isinstance(value, dict):
        desc = parse_description(value, inner)
    else:
        raise ConfigError(f"{inner}: expected a description file name or a mapping, got {type(value).__name__}")
    return user_mechanism(desc, inner)
