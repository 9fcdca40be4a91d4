"""Scenario file (plus --set overrides) to a validated ``Scenario``, or a located error."""

from __future__ import annotations

import typing
from pathlib import Path
from typing import Any, Iterable

from pydantic import BaseModel, ValidationError

from mobot_cli.errors import Location, ScenarioError, did_you_mean, shown
from mobot_cli.scenario.model import Scenario
from mobot_cli.scenario.sensor_model import HINTS as SENSOR_HINTS
from mobot_cli.scenario.yamlsafe import read_yaml_file
from mobot_cli.scenario.yamlsource import PathKey, Source, parse_value, parse_yaml


def load_scenario(path: Path | str, overrides: Iterable[str] = ()) -> tuple[Scenario, Source]:
    """Read, override and validate a scenario file."""
    path = Path(path)
    source = parse_yaml(read_yaml_file(path), path)
    return validate(source, overrides), source


def validate(source: Source, overrides: Iterable[str] = ()) -> Scenario:
    """Apply overrides to parsed data and validate it into a Scenario."""
    if source.data is None:
        raise ScenarioError("the scenario is empty", location=Location(file=source.file),
                            hint="Start from scenarios/quickstart.yaml.")
    if not isinstance(source.data, dict):
        raise ScenarioError("a scenario must be a mapping of keys (version, duration, robots, ...)",
                            location=source.locate(()))
    for item in overrides:
        apply_override(source, item)
    version = source.data.get("version")
    if version != 1 or isinstance(version, bool):  # True == 1 in Python
        raise ScenarioError(
            "missing 'version'" if version is None else f"unsupported version {shown(version)}",
            location=source.locate(("version",)), hint="This mobot reads 'version: 1' scenarios.")
    try:
        return Scenario.model_validate(source.data)
    except ValidationError as exc:
        raise _to_scenario_error(exc, source) from None


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


def _to_scenario_error(exc: ValidationError, source: Source) -> ScenarioError:
    # A mistyped key also makes the real one "missing": report the unknown key first.
    err = sorted(exc.errors(), key=lambda e: e["type"] != "extra_forbidden")[0]
    path = _data_path(err["loc"], source.data)
    kind = err["type"]
    message = err["msg"].removeprefix("Value error, ")
    hint = None
    if kind == "missing":
        path = path + (err["loc"][len(path)],)
        message = f"'{path[-1]}' is required"
    elif kind == "extra_forbidden":
        word = str(path[-1])
        message = f"unknown key {shown(word)}"
        hint = did_you_mean(word, _fields_at(path[:-1]))
    elif kind not in ("value_error", "assertion_error"):
        message += f", got {shown(err.get('input'))}"
    if kind != "extra_forbidden" and len(path) > 3 and path[2] == "sensors":
        hint = SENSOR_HINTS.get(str(path[-1]))
    more = len({_data_path(e["loc"], source.data) for e in exc.errors()}) - 1
    if more:
        message += f" (and {more} more problem{'s' if more > 1 else ''})"
    return ScenarioError(message, location=source.locate_key(path), hint=hint)


def _data_path(loc: tuple, data: Any) -> PathKey:
    """The longest prefix of a pydantic error location that exists in the user's data."""
    path: PathKey = ()
    node = data
    for part in loc:
        key = "for" if part == "for_" else part
        if isinstance(node, dict) and key in node:
            node = node[key]
        elif isinstance(node, list) and isinstance(key, int) and key < len(node):
            node = node[key]
        else:
            break
        path += (key,)
    return path


def _fields_at(path: PathKey) -> list[str]:
    """Names of the keys allowed by the model found at a data path."""
    model: type[BaseModel] | None = Scenario
    keyed = False  # the part after a mapping field (robots.NAME.sensors.KEY) is a user's key
    for part in path:
        if isinstance(part, int) or model is None or keyed:
            keyed = False
            continue
        field = model.model_fields.get(str(part)) or model.model_fields.get(f"{part}_")
        model = _model_in(field.annotation) if field else None
        keyed = field is not None and typing.get_origin(field.annotation) is dict
    if model is None:
        return []
    return [f.alias or name for name, f in model.model_fields.items()]


def _model_in(annotation: Any) -> type[BaseModel] | None:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in typing.get_args(annotation):
        found = _model_in(arg)
        if found:
            return found
    return None
