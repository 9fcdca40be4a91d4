"""Scenario file to Plan plus the resolved document, shared by `run`, `check` and later `sweep`."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Iterable

from mobot_cli.scenario.document import resolved_document, to_yaml
from mobot_cli.scenario.load import load_scenario
from mobot_cli.scenario.model import Scenario
from mobot_cli.scenario.resolve import resolve
from mobot_cli.sim.plan import Plan


@dataclass(frozen=True)
class Prepared:
    """A scenario ready to run: its typed form, its plan and the resolved YAML to store."""

    scenario: Scenario
    plan: Plan
    resolved_yaml: str


def prepare(path: Path | str, overrides: Iterable[str] = ()) -> Prepared:
    """Load, validate and resolve a scenario; raises located MobotErrors."""
    scenario, source = load_scenario(path, overrides)
    plan = resolve(scenario, source)
    base_dir = Path(path).resolve().parent
    return Prepared(scenario, plan, to_yaml(resolved_document(scenario, plan, base_dir)))
