"""Scenario file (or a bare world) to Plan plus the resolved document: every door starts here."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Iterable

from mobot_cli.errors import MobotError
from mobot_cli.plan import Plan
from mobot_cli.scenario.document import resolved_document
from mobot_cli.scenario.load import validate, validate_ready
from mobot_cli.scenario.model import Scenario
from mobot_cli.scenario.resolve import resolve
from mobot_cli.scenario.source import Source

SCENARIO_SUFFIXES = (".yaml", ".yml")
DEFAULT_WORLD = "empty"
# A bare world has no script; its duration only bounds scripted commands, so one second will do.
BARE_WORLD_SECONDS = 1.0


@dataclass(frozen=True)
class Prepared:
    """A scenario ready to run: its typed form, its plan and the resolved YAML to store."""

    scenario: Scenario
    plan: Plan
    resolved_yaml: str


def prepare(path: Path | str, overrides: Iterable[str] = ()) -> Prepared:
    """Load, validate and resolve a scenario; raises located MobotErrors."""
    from mobot_cli.scenario.overrides import read_ready
    from mobot_cli.scenario.yamlsource import to_yaml

    source = read_ready(path, overrides)
    scenario = validate_ready(source)
    plan = resolve(scenario, source)
    document = resolved_document(scenario, plan, Path(source.file).resolve().parent)
    return Prepared(scenario, plan, to_yaml(document))


def prepare_target(target: str | None, overrides: Iterable[str] = ()) -> Prepared:
    """A scenario file is prepared as `mobot run` would; a world (bundled name or file) becomes a
    scenario without robots."""
    target = target or DEFAULT_WORLD
    if target.endswith(SCENARIO_SUFFIXES):
        return prepare(target, overrides)
    name = Path(target).name.split(".")[0] or DEFAULT_WORLD
    data = {"version": 1, "name": _safe(name), "world": target, "duration": BARE_WORLD_SECONDS}
    source = Source(data=data, file=None)  # relative world paths: the current folder
    try:
        scenario = validate(source, overrides)
        plan = resolve(scenario, source)
    except MobotError as exc:  # the generated document has no file or line worth naming
        raise type(exc)(exc.message, location=None if exc.location.file is None else exc.location,
                        hint=exc.hint) from None
    from mobot_cli.scenario.yamlsource import to_yaml

    return Prepared(scenario, plan, to_yaml(resolved_document(scenario, plan, Path.cwd())))


def _safe(name: str) -> str:
    text = "".join(c if c.isalnum() or c in "_-." else "_" for c in name)
    return text or DEFAULT_WORLD
