"""A scenario file read and made ready for validation: the checks that need no model (empty, not a
mapping, its version) and the --set overrides applied, located like any error.

This is the YAML side of loading a scenario (PyYAML parses the file and each --set value);
scenario/load.py validates the result with pydantic.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Iterable

from mobot_cli.errors import Location, ScenarioError, did_you_mean, shown
from mobot_cli.scenario.source import PathKey, Source
from mobot_cli.scenario.yamlsource import parse_value, read_source


def read_ready(path: Path | str, overrides: Iterable[str] = ()) -> Source:
    """Read a scenario file and make it ready (``ready``)."""
    return ready(read_source(path), overrides)


# Keys only a scenario has at its top: a YAML file with none of them is something else (an RMF
# .building.yaml, a ROS parameter file), and "missing 'version'" would mislead.
SCENARIO_KEYS = {"version", "name", "world", "skip_missing", "physics", "duration", "seed", "settle", "log",
                 "faults", "robots", "events", "expect", "ros2", "movers"}


def ready(source: Source, overrides: Iterable[str] = ()) -> Source:
    """Check what needs no model and apply the overrides to ``source`` (changed in place); returns it."""
    if source.data is None:
        raise ScenarioError("the scenario is empty", location=Location(file=source.file),
                            hint="Start from scenarios/quickstart.yaml.")
    if not isinstance(source.data, dict):
        raise ScenarioError("a scenario must be a mapping of keys (version, duration, robots, ...)",
                            location=source.locate(()))
    for item in overrides:
        apply_override(source, item)
    version = source.data.get("version")
    if version is None and source.data and not SCENARIO_KEYS & set(source.data):
        keys = ", ".join(str(k) for k in list(source.data)[:4])
        raise ScenarioError(f"this is not a mobot scenario: none of its keys ({keys}) is a scenario's "
                            "(version, robots, world, duration, ...)", location=source.locate(()),
                            hint="Give mobot a scenario (scenarios/quickstart.yaml shows one); a world goes "
                                 "under its world: key, as a Gazebo .world or .sdf file.")
    if version != 1 or isinstance(version, bool):  # True == 1 in Python
        raise ScenarioError(
            "missing 'version'" if version is None else f"unsupported version {shown(version)}",
            location=source.locate(("version",)), hint="This mobot reads 'version: 1' scenarios.")
    return source


def apply_override(source: Source, item: str) -> None:
    """Apply one ``KEY=VALUE``; list items are addressed by their ``name`` (or index)."""
    key, sep, raw = item.partition("=")
    if not sep or not key.strip():
        raise ScenarioError(f"--set '{item}' is not KEY=VALUE", hint="e.g. --set robots.mobot.pose.x=2.0")
    parts = key.strip().split(".")
    node: Any = source.data
    path: PathKey = ()
    for i, part in enumerate(parts):
        last = i == len(parts) - 1
        if isinstance(node, list):
            index = _list_index(node, part, item, path, source)
            path += (index,)
            if last:
                node[index] = parse_value(raw, Location(file="--set " + item))
            else:
                node = node[index]
            continue
        if not isinstance(node, dict):
            raise ScenarioError(f"--set {key}: '{'.'.join(parts[:i])}' is a value, not a mapping",
                                location=source.locate(path))
        path += (part,)
        if last:
            node[part] = parse_value(raw, Location(file="--set " + item))
        else:
            node = node.setdefault(part, [] if part == "robots" else {})
    source.overrides[path] = item


def _list_index(items: list, part: str, item: str, path: PathKey, source: Source) -> int:
    names = [x.get("name") for x in items if isinstance(x, dict)]
    for index, x in enumerate(items):
        if isinstance(x, dict) and x.get("name") == part:
            return index
    if part.isdigit() and int(part) < len(items):
        return int(part)
    raise ScenarioError(f"--set {item.partition('=')[0]}: no item named '{part}' in '{source.key_text(path)}'",
                        location=source.locate(path), hint=did_you_mean(part, [str(n) for n in names if n]))
