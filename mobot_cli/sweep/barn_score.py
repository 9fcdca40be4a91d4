"""The BARN challenge's rules and score, as its run.py and report_test.py compute them.

Pure functions, no simulation: the reference path's length (grid cells to metres), the
optimal time, one episode's outcome from the moments that decide it, the score, and the
aggregate over worlds. Source: github.com/Daffan/the-barn-challenge (run.py, report_test.py).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Iterable, Sequence

# run.py, static worlds 0-299: the start, the goal 10 m ahead, the cylinders and their grid
from mobot_cli.assets.world.generate.barn_grid import CELL, CYLINDER_RADIUS, GOAL, START  # noqa: F401

GOAL_RADIUS = 1.0  # m: the episode succeeds once the robot is this close to the goal
TIMEOUT = 100.0  # s after the robot starts moving
MOVED = 0.1  # m from the start: the clock starts when the robot has moved this far
OPTIMAL_SPEED = 2.0  # m/s: optimal time = reference path length / this
WORLDS = 300  # static BARN worlds, numbered 0..299

# path_coord_to_gazebo_coord: the path files hold cells of BARN's grid of cylinders
X_SHIFT = -CYLINDER_RADIUS - 30 * CELL
Y_SHIFT = CYLINDER_RADIUS + 5

SUCCEEDED, COLLIDED, TIMED_OUT, ERROR = "succeeded", "collided", "timeout", "error"


def cell_to_world(row: float, col: float) -> tuple[float, float]:
    """A path file's (first, second) cell index in the world frame, metres (run.py's conversion)."""
    return row * CELL + X_SHIFT, col * CELL + Y_SHIFT


def reference_length(cells: Iterable[Sequence[float]], start: Sequence[float] = START,
                     goal: Sequence[float] = GOAL) -> float:
    """The reference path's length in metres: start, every cell converted, goal, joined straight."""
    points = [(start[0], start[1]), *(cell_to_world(c[0], c[1]) for c in cells), (goal[0], goal[1])]
    return sum(math.dist(a, b) for a, b in zip(points, points[1:]))


def optimal_time(length: float) -> float:
    """The time to drive the reference path at BARN's optimal speed, 2 m/s."""
    return length / OPTIMAL_SPEED


def score(success: bool, time: float, t_opt: float) -> float:
    """BARN's navigation metric: success * t_opt / clip(time, 2 t_opt, 8 t_opt)."""
    if not success:
        return 0.0
    return t_opt / min(max(time, 2 * t_opt), 8 * t_opt)


@dataclass(frozen=True)
class Outcome:
    """One episode as BARN reports it (a line of its out.txt, with the reason spelled out)."""

    world: int
    status: str  # succeeded | collided | timeout | error
    time: float  # s from the start of motion to the end of the episode
    score: float
    optimal_time: float
    reason: str = ""

    @property
    def success(self) -> bool:
        return self.status == SUCCEEDED

    def row(self) -> dict:
        return {**asdict(self), "success": int(self.success), "collision": int(self.status == COLLIDED),
                "timeout": int(self.status == TIMED_OUT)}


def judge(world: int, t_opt: float, moved_at: float | None, reached_at: float | None,
          collided_at: float | None, end: float) -> Outcome:
    """The episode's outcome from when the robot first moved 0.1 m, first came within 1 m of the
    goal and first collided (None: never), the simulation having run to ``end`` (s).

    As run.py's loop: the clock starts at the move; the episode ends at the first of the goal,
    a collision, or 100 s; a collision in the same moment as the goal is a collision."""
    if moved_at is None:
        return Outcome(world, TIMED_OUT, TIMEOUT, 0.0, t_opt, "never moved 0.1 m from the start")
    deadline = moved_at + TIMEOUT
    if collided_at is not None and collided_at < deadline and (reached_at is None or collided_at <= reached_at):
        return Outcome(world, COLLIDED, round(collided_at - moved_at, 6), 0.0, t_opt)
    if reached_at is not None and reached_at < deadline:
        time = round(reached_at - moved_at, 6)
        return Outcome(world, SUCCEEDED, time, score(True, time, t_opt), t_opt)
    reason = "" if end >= deadline else f"the run ended {deadline - end:.1f} s before the 100 s were up"
    return Outcome(world, TIMED_OUT, TIMEOUT, 0.0, t_opt, reason)


def aggregate(outcomes: Iterable[Outcome]) -> dict:
    """report_test.py's averages: per world first (the mean of its runs), then over worlds; the
    mean time is over successful runs only."""
    by_world: dict[int, list[Outcome]] = {}
    for o in outcomes:
        by_world.setdefault(o.world, []).append(o)
    if not by_world:
        return {"worlds": 0, "runs": 0}

    def mean(values: list[float]) -> float:
        return sum(values) / len(values)

    def rate(status: str) -> float:
        return mean([mean([float(o.status == status) for o in runs]) for runs in by_world.values()])

    times = [mean([o.time for o in runs if o.success]) for runs in by_world.values() if any(o.success for o in runs)]
    return {
        "worlds": len(by_world),
        "runs": sum(len(r) for r in by_world.values()),
        "success_rate": rate(SUCCEEDED),
        "collision_rate": rate(COLLIDED),
        "timeout_rate": rate(TIMED_OUT),
        "error_rate": rate(ERROR),
        "mean_time": mean(times) if times else None,
        "mean_score": mean([mean([o.score for o in runs]) for runs in by_world.values()]),
    }
