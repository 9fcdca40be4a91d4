"""Expectations checked against a run: a consumer of the timeline's samples, like the sinks.

Every robot keeps running figures (distance, worst tilt, worst odometry drift, collisions);
an expectation at a time reads a snapshot taken on that log row, one at the end reads the
last figures. ``robot: all`` checks every robot on its own: ``within`` the robots in the
world at that moment, the other checks every robot seen until then. Checks over time
(reaches, visits, coverage, goal) follow each robot in trackers (timeline/expect_time.py); the
footprint sweeps that coverage needs (timeline/coverage.py) are kept here for trajectory.png too.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, Callable, Optional

from mobot_cli.common.transforms import Planar
from mobot_cli.plan import Expectation, Plan, RobotPlan
from mobot_cli.sim.clearance import REACH_MARGIN
from mobot_cli.sim.state import RobotState
from mobot_cli.timeline.expect_time import Tracker, coverage_areas, tracker
from mobot_cli.timeline.goals import GoalEnded
from mobot_cli.timeline.records import Sample, Sink

if TYPE_CHECKING:
    from mobot_cli.timeline.coverage import Sweep


@dataclass
class Figures:
    """What the checks need of one robot, up to one sample (updated in place: this runs at the
    log rate for every robot, so no new objects per sample)."""

    step: int
    first: RobotState  # its first sample: the odometry frame's origin in the world
    state: RobotState
    distance: float = 0.0
    tilt: tuple[float, int] = (0.0, 0)  # worst tilt (rad) and its step
    drift: tuple[float, int] = (0.0, 0)  # worst odometry position error (m) and its step
    yaw_drift: tuple[float, int] = (0.0, 0)  # worst odometry yaw error (rad) and its step
    closest: tuple[float, int, str] = (math.inf, 0, "")  # smallest clearance (m), its step, to what

    def advance(self, step: int, state: RobotState) -> None:
        """Carry the figures on by one more sample."""
        if state.clearance < self.closest[0]:
            self.closest = (state.clearance, step, state.nearest)
        prev = self.state
        self.distance += math.hypot(state.true_x - prev.true_x, state.true_y - prev.true_y)
        position, yaw = odom_error(self.first, state)
        self.step, self.state = step, state
        if (t := tilt(state)) > self.tilt[0]:
            self.tilt = (t, step)
        if position > self.drift[0]:
            self.drift = (position, step)
        if abs(yaw) > self.yaw_drift[0]:
            self.yaw_drift = (abs(yaw), step)


@dataclass(frozen=True)
class Result:
    """One expectation for one robot: what was expected, what happened, and whether they agree."""

    robot: str
    kind: str
    expected: str
    happened: str
    passed: bool

    def as_dict(self) -> dict[str, Any]:
        return {"robot": self.robot, "kind": self.kind, "expected": self.expected,
                "happened": self.happened, "passed": self.passed}


def tilt(state: RobotState) -> float:
    """Angle between the robot's z axis and the world's, in radians."""
    c = math.cos(state.true_roll) * math.cos(state.true_pitch)
    return math.acos(max(-1.0, min(1.0, c)))


def odom_error(first: RobotState, state: RobotState) -> tuple[float, float]:
    """Odometry position (m) and yaw (rad) error against the truth, the odom frame's origin
    being the first sample's true pose (the spawn pose, as on a real robot)."""
    x, y = Planar(first.true_x, first.true_y, first.true_yaw)(state.odom_x, state.odom_y)
    yaw = math.remainder(first.true_yaw + state.odom_yaw - state.true_yaw, math.tau)
    return math.hypot(x - state.true_x, y - state.true_y), yaw


class Checker(Sink):
    """Feed it the timeline's records; ``results()`` then evaluates the plan's expectations."""

    def __init__(self, plan: Plan):
        self.plan = plan
        self.rate = plan.physics.rate_hz
        self.figures: dict[str, Figures] = {}
        self.present: set[str] = set()
        self.last_step = 0
        self._wanted = {e.step for e in plan.expectations if e.step is not None and e.kind not in TRACKED}
        self._snapshots: dict[int, tuple[dict[str, Figures], frozenset[str]]] = {}
        self._tracked = [(i, e) for i, e in enumerate(plan.expectations) if e.kind in TRACKED]
        self.trackers: dict[tuple[int, str], Tracker] = {}  # (expectation index, robot) ->
        self._areas = coverage_areas(plan)
        self.sweeps: dict[tuple[str, tuple], Sweep] = {}  # (robot, area) -> its footprint's sweep
        self._robot_sweeps: dict[str, list[Sweep]] = {}
        # ``metric`` checks: (robot, goal command index or None, metric name) -> its value, None when
        # not measured; the run record's metrics, set by whoever keeps them (record/recording.py)
        self.metric_value: Optional[Callable[[str, Optional[int], str], Optional[float]]] = None

    def spawned(self, step: int, key: str, robot: RobotPlan) -> None:
        self.present.add(key)
        name, footprint = (robot.name, robot.footprint) if robot is not None else (key, None)
        for area in [*self._areas.get(name, ()), *self._areas.get("all", ())]:
            if (key, area) not in self.sweeps:
                from mobot_cli.timeline.coverage import Sweep  # numpy and the floor plan: only for coverage

                sweep = self.sweeps[(key, area)] = Sweep(area, self.plan.world, footprint)
                self._robot_sweeps.setdefault(key, []).append(sweep)
        for i, exp in self._tracked:
            if exp.robot in (name, "all") and (i, key) not in self.trackers:
                self.trackers[(i, key)] = tracker(exp, self.rate, self.sweeps.get((key, exp.points)))

    def goal_ended(self, key: str, record: GoalEnded) -> None:
        """A goal command of robot ``key`` ended (its outcome for ``goal:`` checks)."""
        for (_, name), track in self.trackers.items():
            if name == key:
                track.goal(record)

    def deleted(self, step: int, key: str) -> None:
        self.present.discard(key)

    def write(self, sample: Sample) -> None:
        """Take one sample (the sink interface, so it can sit beside the writers)."""
        if self.trackers or self.sweeps:
            self._track(sample)
        if not self.plan.expectations:
            return
        for name, state in sample.states.items():
            known = self.figures.get(name)
            if known is None:
                self.figures[name] = Figures(sample.step, state, state, tilt=(tilt(state), sample.step),
                                             closest=(state.clearance, sample.step, state.nearest))
            else:
                known.advance(sample.step, state)
        self.last_step = sample.step
        if sample.complete and sample.step in self._wanted:
            self._snapshots[sample.step] = ({n: replace(f) for n, f in self.figures.items()},
                                            frozenset(self.present))

    def _track(self, sample: Sample) -> None:
        """Feed the checks over time, then the sweeps (a coverage check reads its sweep as it
        was before a row past its deadline)."""
        for (_, name), track in self.trackers.items():
            state = sample.states.get(name)
            if state is not None:
                track.sample(sample.step, state)
        for name, sweeps in self._robot_sweeps.items():
            state = sample.states.get(name)
            if state is not None:
                for sweep in sweeps:
                    sweep.add(state.true_x, state.true_y, state.true_yaw)

    def results(self) -> list[Result]:
        """Every expectation, for every robot it names, in the scenario's order."""
        out = []
        for index, exp in enumerate(self.plan.expectations):
            if exp.kind == "metric":
                names = list(self.figures) if exp.robot == "all" else [exp.robot]
                out.extend(self._metric(exp, name) for name in names)
                continue
            if exp.kind in TRACKED:
                out.extend(self._tracked_results(index, exp))
                continue
            if exp.step is not None and exp.step not in self._snapshots:
                ended = f"was not checked: the run ended at {self.last_step / self.rate:g} s"
                names = list(self.figures) if exp.robot == "all" else [exp.robot]
                out.extend(Result(n, exp.kind, describe(exp, self.rate), ended, False) for n in names)
                continue
            figures, present = self._snapshots[exp.step] if exp.step is not None \
                else (self.figures, frozenset(self.present))
            names = [exp.robot] if exp.robot != "all" else \
                [n for n in figures if exp.kind != "within" or n in present]
            out.extend(self._check(exp, name, figures.get(name), name in present) for name in names)
        return out

    def _metric(self, exp: Expectation, name: str) -> Result:
        command = exp.limit("command")
        command = None if command is None else int(command)
        value = self.metric_value(name, command, exp.metric) if self.metric_value is not None else None
        expected = describe(exp, self.rate)
        if value is None:  # no goal, a goal that never started, nothing within the clearance's reach
            return Result(name, exp.kind, expected, f"had no {exp.metric} measured", False)
        low, high = exp.limit("min"), exp.limit("max")
        ok = (low is None or value >= low) and (high is None or value <= high)
        return Result(name, exp.kind, expected, f"had {exp.metric} {value:.6g}", ok)

    def _tracked_results(self, index: int, exp: Expectation) -> list[Result]:
        expected = describe(exp, self.rate)
        names = [exp.robot] if exp.robot != "all" else [n for (i, n) in self.trackers if i == index]
        out = []
        for name in names:
            track = self.trackers.get((index, name))
            if track is None:
                out.append(Result(name, exp.kind, expected, "was not in the world", False))
            else:
                passed, happened = track.result()
                out.append(Result(name, exp.kind, expected, happened, passed))
        return out

    def _check(self, exp: Expectation, name: str, fig: Optional[Figures], present: bool) -> Result:
        expected = describe(exp, self.rate)
        if fig is None:
            return Result(name, exp.kind, expected, "was not in the world yet", False)
        if exp.kind == "within" and not present:
            return Result(name, exp.kind, expected, f"was deleted (last seen at "
                                                    f"{fig.step / self.rate:g} s)", False)
        passed, happened = CHECKS[exp.kind](exp, fig, self.rate)
        return Result(name, exp.kind, expected, happened, passed)


def _within(exp: Expectation, fig: Figures, rate: int) -> tuple[bool, str]:
    x, y = fig.state.true_x, fig.state.true_y
    where = f"was at ({x:.3f}, {y:.3f})"
    if exp.limit("radius") is not None:
        off = math.hypot(x - exp.limit("x"), y - exp.limit("y"))
        return off <= exp.limit("radius"), f"{where}, {off:.3f} m from the centre"
    inside = exp.limit("xmin") <= x <= exp.limit("xmax") and exp.limit("ymin") <= y <= exp.limit("ymax")
    return inside, where


def _collisions(exp: Expectation, fig: Figures, rate: int) -> tuple[bool, str]:
    n = fig.state.collisions
    return n <= exp.limit("max"), f"had {n} collision{'s' if n != 1 else ''}"


def _distance(exp: Expectation, fig: Figures, rate: int) -> tuple[bool, str]:
    low, high, d = exp.limit("min"), exp.limit("max"), fig.distance
    ok = (low is None or d >= low) and (high is None or d <= high)
    return ok, f"travelled {d:.3f} m"


def _upright(exp: Expectation, fig: Figures, rate: int) -> tuple[bool, str]:
    worst, step = fig.tilt
    return worst <= exp.limit("max_tilt"), f"tilted at most {_angle(worst)}{_when(worst, step, rate)}"


def _odom(exp: Expectation, fig: Figures, rate: int) -> tuple[bool, str]:
    ok, parts = True, []
    if exp.limit("position") is not None:
        worst, step = fig.drift
        ok = ok and worst <= exp.limit("position")
        parts.append(f"drifted at most {worst:.3f} m{_when(worst, step, rate)}")
    if exp.limit("yaw") is not None:
        worst, step = fig.yaw_drift
        ok = ok and worst <= exp.limit("yaw")
        parts.append(f"was off in yaw by at most {_angle(worst)}{_when(worst, step, rate)}")
    return ok, ", ".join(parts)


def _clearance(exp: Expectation, fig: Figures, rate: int) -> tuple[bool, str]:
    closest, step, what = fig.closest
    if not math.isfinite(closest):
        return True, f"stayed more than {exp.limit('min') + REACH_MARGIN:g} m from everything"
    near = "touched" if closest <= 0.0 else f"came within {closest:.3f} m of"
    return closest >= exp.limit("min"), f"{near} {what}{_when(1.0, step, rate)}"


TRACKED = ("reaches", "visits", "coverage", "goal")
CHECKS = {"within": _within, "collisions": _collisions, "distance": _distance, "upright": _upright,
          "odom_error": _odom, "clearance": _clearance}


def describe(exp: Expectation, rate: int) -> str:
    """The expectation in words, e.g. 'within 0.3 m of (5, 1) at the end'."""
    when = "at the end" if exp.step is None else f"at {exp.step / rate:g} s"
    until = "until the end" if exp.step is None else f"until {exp.step / rate:g} s"
    by = "by the end" if exp.step is None else f"by {exp.step / rate:g} s"
    lim = exp.limit
    if exp.kind in TRACKED:
        return _describe_tracked(exp)
    if exp.kind == "metric":
        low, high, command = lim("min"), lim("max"), lim("command")
        span = f"{low:g}..{high:g}" if low is not None and high is not None else \
            f"at least {low:g}" if low is not None else f"at most {high:g}"
        of = "over its goals" if command is None else f"in goal command {int(command)}"
        return f"have {exp.metric} {span} {of}"
    if exp.kind == "within":
        if lim("radius") is not None:
            return f"be within {lim('radius'):g} m of ({lim('x'):g}, {lim('y'):g}) {when}"
        return f"be inside x {lim('xmin'):g}..{lim('xmax'):g}, y {lim('ymin'):g}..{lim('ymax'):g} {when}"
    if exp.kind == "collisions":
        return f"have at most {lim('max'):g} collision{'s' if lim('max') != 1 else ''} {by}"
    if exp.kind == "distance":
        low, high = lim("min"), lim("max")
        span = f"{low:g}..{high:g} m" if low is not None and high is not None else \
            f"at least {low:g} m" if low is not None else f"at most {high:g} m"
        return f"travel {span} {by}"
    if exp.kind == "clearance":
        return f"keep at least {lim('min'):g} m from world geometry and other robots {until}"
    if exp.kind == "upright":
        return f"stay upright, tilting at most {_angle(lim('max_tilt'))}, {until}"
    parts = []
    if lim("position") is not None:
        parts.append(f"{lim('position'):g} m")
    if lim("yaw") is not None:
        parts.append(f"{lim('yaw'):g} rad in yaw")
    return f"keep its odometry within {' and '.join(parts)} of the truth {until}"


def _describe_tracked(exp: Expectation) -> str:
    lim = exp.limit
    by = "by the end" if lim("within") is None else f"by {lim('within'):g} s"
    if exp.kind == "reaches":
        return f"come within {lim('radius'):g} m of ({lim('x'):g}, {lim('y'):g}) {by}"
    if exp.kind == "visits":
        points = ", ".join(f"({x:g}, {y:g})" for x, y in exp.points)
        return f"visit {points} in order, within {lim('radius'):g} m of each, {by}"
    if exp.kind == "coverage":
        return f"cover at least {100 * lim('min'):g} % of the area's free space {by}"
    return f"end goal command {int(lim('command'))} '{exp.status}'"


def _angle(rad: float) -> str:
    return f"{rad:.3f} rad ({math.degrees(rad):.1f} deg)"


def _when(value: float, step: int, rate: int) -> str:
    """' (at 8.5 s)': when a worst value happened, unless it rounds to nothing."""
    return f" (at {round(step / rate, 3):g} s)" if value >= 5e-4 else ""
