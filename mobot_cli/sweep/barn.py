"""`mobot barn`: BARN's worlds run through the sweep machinery, judged by BARN's rules.

The sweep runs one base scenario (barn_worlds.scenario_text) with ``world`` swept over the
chosen worlds. In each worker a Judge watches the robot's true pose and collision count on
every log row and writes the moments that decide BARN's outcome to the run folder
(``barn_events.json``); the parent turns them into outcomes and scores (barn_score.py).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mobot_cli.errors import Location, MobotError, UsageError
from mobot_cli.sweep.barn_score import ERROR, GOAL, GOAL_RADIUS, MOVED, START, Outcome, aggregate, judge
from mobot_cli.sweep.barn_worlds import ROBOT, BarnWorld, Driver, scenario_text
from mobot_cli.sweep.task import Task, TaskResult, run_task
from mobot_cli.timeline.records import Sample

EVENTS = "barn_events.json"  # in each run folder
SCENARIO, SWEEP, RESULTS_CSV, RESULTS_JSON = "scenario.yaml", "sweep", "barn.csv", "barn.json"
PASSED_THROUGH = ("planner", "local")  # goal settings a newer mobot's goals may take
CSV_COLUMNS = ("world", "status", "success", "collision", "timeout", "time", "score", "optimal_time", "reason")


class Judge:
    """Watches one robot's log rows for BARN's moments: moved 0.1 m, within 1 m of the goal,
    first collision (simulated seconds, at the log rate)."""

    def __init__(self, robot: str, rate_hz: int):
        self.robot, self.rate_hz = robot, rate_hz
        self.moved_at: float | None = None
        self.reached_at: float | None = None
        self.collided_at: float | None = None
        self.end = 0.0

    def __call__(self, record: Any) -> None:
        if not isinstance(record, Sample) or self.robot not in record.states:
            return
        state, t = record.states[self.robot], record.step / self.rate_hz
        self.end = max(self.end, t)
        if self.moved_at is None and math.hypot(state.true_x - START[0], state.true_y - START[1]) >= MOVED:
            self.moved_at = t
        if self.reached_at is None and math.hypot(state.true_x - GOAL[0], state.true_y - GOAL[1]) <= GOAL_RADIUS:
            self.reached_at = t
        if self.collided_at is None and state.collisions > 0:
            self.collided_at = t

    def events(self) -> dict[str, float | None]:
        return {"moved_at": self.moved_at, "reached_at": self.reached_at, "collided_at": self.collided_at,
                "end": self.end}


def run_barn_task(task: Task) -> TaskResult:
    """run_task with a Judge watching; its moments go to the run folder (a worker's runner)."""
    found: list[Judge] = []

    def watch(timeline) -> None:
        judge_ = Judge(ROBOT, timeline.plan.physics.rate_hz)
        found.append(judge_)
        timeline.attach(judge_)

    outcome = run_task(task, watch=watch)
    if found and Path(task.out_dir).is_dir():
        (Path(task.out_dir) / EVENTS).write_text(json.dumps(found[0].events()) + "\n", encoding="utf-8")
    return outcome


def check_passed_through(extra: dict[str, str | None]) -> tuple[tuple[str, str], ...]:
    """The goal settings given (--planner, --local), refused with a clear message when this
    mobot's goals do not take them."""
    from mobot_cli.scenario.model import CommandSpec

    given = tuple((k, v) for k, v in extra.items() if v is not None)
    for key, value in given:
        if key not in CommandSpec.model_fields:
            raise UsageError(f"--{key} {value}: this mobot's goals take no '{key}' setting",
                             location=Location(file=f"--{key}"),
                             hint="Goals drive by pure pursuit along straight segments here; drop the flag, "
                                  "or use a mobot whose goals take it (docs/goals.md lists the settings).")
    return given


@dataclass
class BarnReport:
    """The benchmark's outcomes, by world, and their aggregate."""

    outcomes: list[Outcome]
    summary: dict[str, Any]
    out_dir: Path
    failed_runs: int  # runs mobot could not finish (error, fault, crash)


# Where a key of the generated scenario came from: an error about it points at the flag.
FLAGS = (("commands[0].max_linear", "--max-linear"), ("commands[0].max_angular", "--max-angular"),
         ("commands[0].planner", "--planner"), ("commands[0].local", "--local"), ("sensors.scan", "--no-lidar"),
         ("description", "--robot"), ("physics.engine", "--engine"))


def prepare_sweep(out_dir: Path, worlds: list[BarnWorld], driver: Driver):
    """Write the base scenario into ``out_dir`` and prepare every run. Anything the scenario model
    refuses (a speed, a --planner value it does not know, a robot) is an error at its flag, exit 2,
    and leaves nothing behind."""
    from mobot_cli.sweep.expand import expand
    from mobot_cli.sweep.spec import Axis, SweepSpec

    made = not out_dir.exists()
    out_dir.mkdir(parents=True, exist_ok=True)
    scenario = out_dir / SCENARIO
    scenario.write_text(scenario_text(worlds[0], driver), encoding="utf-8")
    where = Location(file="--worlds")
    axis = Axis("grid", ("world",), (where,), rows=tuple((_text(str(w.file)),) for w in worlds))
    try:
        return expand(SweepSpec(scenario=scenario, axes=(axis,), name="barn"))
    except MobotError as exc:
        scenario.unlink()
        if made:
            out_dir.rmdir()
        raise _at_flag(exc) from None


def _text(path: str) -> str:
    """A path as --set text: as it is, unless YAML would read it as something else."""
    from mobot_cli.scenario.yamlsource import parse_value

    return path if parse_value(path) == path else json.dumps(path)


def _at_flag(exc: MobotError) -> MobotError:
    """An error about a key of the generated scenario, pointed at the flag that set it."""
    key = exc.location.key or ""
    for suffix, flag in FLAGS:
        if key.endswith(suffix) and flag == "--no-lidar":
            return UsageError("the robot has no 2D lidar on (a sensor on topic scan) to turn off",
                              location=Location(file=flag), hint="Drop --no-lidar.")
        if key.endswith(suffix):
            message = exc.message.removeprefix(f"robot '{ROBOT}': ")
            return UsageError(message, location=Location(file=flag), hint=exc.hint)
    return exc


def collect(out_dir: Path, sweep, worlds: list[BarnWorld], rows: dict[int, dict[str, str]]) -> BarnReport:
    """Each run's outcome from its events (an error when the run did not finish), the aggregate,
    and barn.csv / barn.json written into ``out_dir``."""
    from mobot_cli.sweep.results import folder

    outcomes, failed = [], 0
    for variant, world in zip(sweep.variants, worlds):
        run_dir = out_dir / SWEEP / folder(variant.index, len(sweep.variants))
        row = rows.get(variant.index, {})
        events = run_dir / EVENTS
        if row.get("failure") in ("", "expectation") and events.is_file():
            e = json.loads(events.read_text(encoding="utf-8"))
            outcomes.append(judge(world.number, world.optimal_time, e["moved_at"], e["reached_at"],
                                  e["collided_at"], e["end"]))
        else:
            failed += 1
            reason = row.get("reason") or "the run did not finish"
            outcomes.append(Outcome(world.number, ERROR, 0.0, 0.0, world.optimal_time, reason))
    summary = aggregate(outcomes)
    _write(out_dir, outcomes, summary)
    return BarnReport(outcomes, summary, out_dir, failed)


def _write(out_dir: Path, outcomes: list[Outcome], summary: dict[str, Any]) -> None:
    import csv
    import io

    from mobot_cli.common.files import write_json_atomic, write_text_atomic

    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=CSV_COLUMNS, lineterminator="\n", extrasaction="ignore")
    writer.writeheader()
    for o in outcomes:
        writer.writerow({k: (f"{v:.4f}" if isinstance(v, float) else v) for k, v in o.row().items()})
    write_text_atomic(out_dir / RESULTS_CSV, buffer.getvalue())
    write_json_atomic(out_dir / RESULTS_JSON, {"summary": summary, "worlds": [o.row() for o in outcomes]})
