"""Scenario file (plus --set overrides) to a validated ``Scenario``, or a located error.

Reading the file and applying --set is scenario/overrides.py (PyYAML); validating is here
(pydantic), importing the reading side only when it is asked to read."""

from __future__ import annotations

import typing
from pathlib import Path
from typing import Any, Iterable

from pydantic import BaseModel, ValidationError

from mobot_cli.errors import ScenarioError, did_you_mean, shown
from mobot_cli.scenario.model import WORLD_TAGS, Scenario
from mobot_cli.scenario.sensor_model import HINTS as SENSOR_HINTS
from mobot_cli.scenario.source import PathKey, Source


def load_scenario(path: Path | str, overrides: Iterable[str] = ()) -> tuple[Scenario, Source]:
    """Read, override and validate a scenario file."""
    from mobot_cli.scenario.overrides import read_ready  # PyYAML: imported when a file is read

    source = read_ready(path, overrides)
    return validate_ready(source), source


def validate(source: Source, overrides: Iterable[str] = ()) -> Scenario:
    """Apply overrides to parsed data and validate it into a Scenario."""
    from mobot_cli.scenario.overrides import ready

    return validate_ready(ready(source, overrides))


def validate_ready(source: Source) -> Scenario:
    """Validate a document made ready by scenario/overrides.py."""
    try:
        return Scenario.model_validate(source.data)
    except ValidationError as exc:
        raise _to_scenario_error(exc, source) from None


def _to_scenario_error(exc: ValidationError, source: Source) -> ScenarioError:
    # A mistyped key also makes the real one "missing": report the unknown key first.
    err = sorted(exc.errors(), key=lambda e: e["type"] != "extra_forbidden")[0]
    err = {**err, "loc": _untagged(err["loc"])}
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
    more = len({_data_path(_untagged(e["loc"]), source.data) for e in exc.errors()}) - 1
    if more:
        message += f" (and {more} more problem{'s' if more > 1 else ''})"
    return ScenarioError(message, location=source.locate_key(path), hint=hint)


def _untagged(loc: tuple) -> tuple:
    """An error location without the tags of ``world:``'s two forms (pydantic puts them in)."""
    return tuple(part for part in loc if part not in WORLD_TAGS)


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
