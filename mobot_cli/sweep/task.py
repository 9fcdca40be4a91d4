"""One sweep run as a task: plain data in, plain data out, so any executor can carry it.

``run_task`` runs in a worker (a local process or a Ray task). It never raises: whatever
goes wrong becomes a failed TaskResult with the reason, and the sweep goes on.
"""

from __future__ import annotations

import shutil
import tempfile
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

from mobot_cli.errors import MobotError, SimulationFault

if TYPE_CHECKING:  # the sweep starts its workers before it imports these (executor_local.prestart)
    from mobot_cli.plan import Plan
    from mobot_cli.record.summary import RobotRecord

PASSED, FAILED = "passed", "failed"
# Of robots that drive to goals: their metrics over the run (summary.json's robots.NAME.metrics)
ROBOT_METRICS = ("success", "spl", "time", "path_length", "collision_first", "clearance_min", "clearance_mean",
                 "danger_time", "jerk_linear", "jerk_angular", "failure")


@dataclass(frozen=True)
class Task:
    """Run ``plan`` into ``out_dir`` (an absolute run folder)."""

    index: int
    plan: Plan
    resolved_yaml: str
    out_dir: str
    pictures: bool = True  # draw trajectory.png (`mobot sweep --pictures`)


@dataclass(frozen=True)
class TaskResult:
    """How one run went: what results.csv records of it."""

    index: int
    status: str  # "passed" | "failed"
    failure: str = ""  # "" | "expectation" | "fault" | "error" | "timeout" | "crash"
    reason: str = ""
    wall_time: float = 0.0
    robots: dict[str, dict[str, Any]] = field(default_factory=dict)  # final figures per robot
    expect_passed: int = 0
    expect_failed: int = 0
    files: dict[str, bytes] | None = None  # the run folder, when it was made on another machine


# What an executor calls for each task: run_task here, run_task_elsewhere on Ray, a test's stand-in.
RunTask = Callable[[Task], TaskResult]


def failed(index: int, failure: str, reason: str, wall_time: float = 0.0) -> TaskResult:
    """An outcome for a run that did not finish."""
    return TaskResult(index, FAILED, failure, reason, round(wall_time, 3))


def run_task(task: Task, watch: Callable[[Any], None] | None = None) -> TaskResult:
    """Run one task in this process and say how it went; never raises (but on Ctrl-C).
    ``watch`` is handed the timeline before the run starts (run.execute), to attach a consumer."""
    from mobot_cli.run import execute  # imported once per warm worker

    started = time.perf_counter()
    try:
        # summary.json is flushed to disk by the sweep (runner.Syncer): an fsync here would hold the run up.
        result = execute(task.plan, task.resolved_yaml, Path(task.out_dir), watch=watch, durable=False,
                         pictures=task.pictures)
    except MobotError as exc:
        kind = "fault" if isinstance(exc, SimulationFault) else "error"
        return failed(task.index, kind, str(exc), time.perf_counter() - started)
    except Exception as exc:  # noqa: BLE001 - a bug or a broken robot: this run fails, the sweep goes on
        return failed(task.index, "error", f"{type(exc).__name__}: {exc}", time.perf_counter() - started)
    wall = time.perf_counter() - started
    robots = {name: _figures(robot) for name, robot in result.record.robots.items()}
    bad = [r for r in result.expectations if not r.passed]
    reason = ""
    if bad:
        reason = f"robot '{bad[0].robot}' was expected to {bad[0].expected}; it {bad[0].happened}"
        reason += f" (and {len(bad) - 1} more)" if len(bad) > 1 else ""
    return TaskResult(task.index, FAILED if bad else PASSED, "expectation" if bad else "", reason,
                   round(wall, 3), robots, len(result.expectations) - len(bad), len(bad))


def run_task_elsewhere(task: Task) -> TaskResult:
    """Run a task into a scratch folder and return the folder's files with the outcome (Ray)."""
    scratch = Path(tempfile.mkdtemp(prefix="mobot-run-"))
    try:
        outcome = run_task(replace(task, out_dir=str(scratch)))
        files = {str(p.relative_to(scratch)): p.read_bytes() for p in sorted(scratch.rglob("*")) if p.is_file()}
        return replace(outcome, files=files)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def _figures(robot: RobotRecord) -> dict[str, Any]:
    pose = robot.final_pose
    figures = {"distance": robot.distance, "x": pose.x, "y": pose.y, "yaw": pose.yaw, "collisions": robot.collisions}
    if robot.metrics is not None:
        figures.update((k, getattr(robot.metrics, k)) for k in ROBOT_METRICS)
    return figures
