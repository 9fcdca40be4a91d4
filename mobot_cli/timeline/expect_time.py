"""Expectations over time: ``reaches``, ``visits``, ``coverage`` and ``goal``.

Each is a tracker for one robot, fed with that robot's samples (the log rows, true pose) and
goal records as they come; ``result`` says whether it passed and what happened, with times.
A deadline (``within: SECONDS``) is checked on the log rows: a row after it no longer counts,
but what happened later is still told ("1.3 s after the deadline").
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from mobot_cli.plan import Expectation, GoalStep, Plan
from mobot_cli.sim.state import RobotState
from mobot_cli.timeline.goals import GoalEnded

if TYPE_CHECKING:
    from mobot_cli.timeline.coverage import Sweep

Area = tuple[tuple[float, float], ...]


def _t(step: int, rate: int) -> str:
    return f"{round(step / rate, 3):g} s"


def _xy(x: float, y: float) -> str:
    return f"({x:.2f}, {y:.2f})"


class Tracker:
    """One expectation over time for one robot."""

    def __init__(self, exp: Expectation, rate: int):
        self.exp, self.rate = exp, rate
        within = exp.limit("within")
        self.deadline = None if within is None else round(within * rate)

    def sample(self, step: int, state: RobotState) -> None:
        """One log row of the robot."""

    def goal(self, record: GoalEnded) -> None:
        """One of the robot's goal commands ended."""

    def result(self) -> tuple[bool, str]:
        """Passed, and what happened."""
        raise NotImplementedError

    def late(self, step: int) -> str:
        """', 1.3 s after the deadline' when ``step`` is past it."""
        return f", {round((step - self.deadline) / self.rate, 3):g} s after the deadline" \
            if self.deadline is not None and step > self.deadline else ""


class Reaches(Tracker):
    """The first row inside the circle, and the closest approach in case there is none."""

    def __init__(self, exp: Expectation, rate: int):
        super().__init__(exp, rate)
        self.x, self.y, self.radius = exp.limit("x"), exp.limit("y"), exp.limit("radius")
        self.first: tuple[int, float, float] | None = None
        self.closest: tuple[float, int, float, float] = (math.inf, 0, 0.0, 0.0)

    def sample(self, step: int, state: RobotState) -> None:
        if self.first is not None:
            return
        off = math.hypot(state.true_x - self.x, state.true_y - self.y)
        if off <= self.radius:
            self.first = (step, state.true_x, state.true_y)
        elif off < self.closest[0]:
            self.closest = (off, step, state.true_x, state.true_y)

    def result(self) -> tuple[bool, str]:
        if self.first is None:
            off, step, x, y = self.closest
            if math.isinf(off):
                return False, "was never seen"
            return False, f"never reached it: closest {off:.2f} m away, at {_xy(x, y)} at {_t(step, self.rate)}"
        step, x, y = self.first
        late = self.late(step)
        return not late, f"reached {_xy(x, y)} at {_t(step, self.rate)}{late}"


class Visits(Tracker):
    """The checkpoints in order: when each was first within ``radius`` after the one before."""

    def __init__(self, exp: Expectation, rate: int):
        super().__init__(exp, rate)
        self.radius = exp.limit("radius")
        self.times: list[int] = []
        self.closest: tuple[float, int] = (math.inf, 0)  # to the next checkpoint

    def sample(self, step: int, state: RobotState) -> None:
        points = self.exp.points
        if len(self.times) == len(points):
            return
        x, y = points[len(self.times)]
        off = math.hypot(state.true_x - x, state.true_y - y)
        if off <= self.radius:
            self.times.append(step)
            self.closest = (math.inf, 0)
        elif off < self.closest[0]:
            self.closest = (off, step)

    def result(self) -> tuple[bool, str]:
        points, rate = self.exp.points, self.rate
        done = ", ".join(f"{_xy(*points[i])} at {_t(step, rate)}" for i, step in enumerate(self.times))
        if len(self.times) == len(points):
            late = self.late(self.times[-1])
            return not late, f"visited all {len(points)} in order: {done}{late}"
        missing = points[len(self.times)]
        off, step = self.closest
        closest = f" (closest {off:.2f} m, at {_t(step, rate)})" if not math.isinf(off) else ""
        visited = f"visited {len(self.times)} of {len(points)}" + (f" ({done})" if done else "")
        after = " after that" if self.times else ""
        return False, f"{visited}; never came within {self.radius:g} m of {_xy(*missing)}{after}{closest}"


class Coverage(Tracker):
    """The robot's footprint swept over the area, the fraction read at the deadline."""

    def __init__(self, exp: Expectation, rate: int, sweep: "Sweep"):
        super().__init__(exp, rate)
        self.sweep = sweep
        self.frozen: tuple[float, int] | None = None  # the fraction at the last row before the deadline

    def sample(self, step: int, state: RobotState) -> None:
        # Called before the sweep takes this row: at the first row past the deadline, the
        # sweep holds exactly the rows up to it.
        if self.frozen is None and self.deadline is not None and step > self.deadline:
            self.frozen = (self.sweep.fraction, step)

    def result(self) -> tuple[bool, str]:
        fraction = self.frozen[0] if self.frozen is not None else self.sweep.fraction
        by = f" by {_t(self.deadline, self.rate)}" if self.deadline is not None else ""
        text = (f"covered {100 * fraction:.1f} % of {self.sweep.free_area:.2f} m^2 of free space{by}")
        return fraction >= self.exp.limit("min"), text


class GoalOutcome(Tracker):
    """How the robot's goal command ``command`` ended."""

    def __init__(self, exp: Expectation, rate: int):
        super().__init__(exp, rate)
        self.index = int(exp.limit("command"))
        self.ended: GoalEnded | None = None

    def goal(self, record: GoalEnded) -> None:
        if record.index == self.index and self.ended is None:
            self.ended = record

    def result(self) -> tuple[bool, str]:
        rate, e = self.rate, self.ended
        if e is None:
            return self.exp.status == "unfinished", "was still on it when the run ended"
        laps = f", {e.laps} lap{'s' if e.laps != 1 else ''} done" if e.laps is not None else ""
        where = f", {e.error:.3f} m from its goal" if math.isfinite(e.error) else ""
        return e.status == self.exp.status, (f"ended '{e.status}' at {_t(e.step, rate)}, "
                                             f"{_t(e.step - e.started, rate)} after it started{laps}{where}")


def tracker(exp: Expectation, rate: int, sweep: "Sweep | None" = None) -> Tracker:
    """The tracker of one expectation over time (``sweep``: coverage's, for that robot and area)."""
    if exp.kind == "coverage":
        return Coverage(exp, rate, sweep)
    return {"reaches": Reaches, "visits": Visits, "goal": GoalOutcome}[exp.kind](exp, rate)


def coverage_areas(plan: Plan) -> dict[str, list[Area]]:
    """Robot name (or "all") -> the areas its coverage goals and coverage expectations name."""
    out: dict[str, list[Area]] = {}
    robots = [*plan.robots, *(event.spawn for event in plan.events if event.spawn is not None)]
    for robot in robots:
        for cmd in robot.commands:
            if isinstance(cmd, GoalStep) and cmd.kind == "coverage" and cmd.area not in out.get(robot.name, []):
                out.setdefault(robot.name, []).append(cmd.area)
    for exp in plan.expectations:
        if exp.kind == "coverage" and exp.points not in out.get(exp.robot, []):
            out.setdefault(exp.robot, []).append(exp.points)
    return out
