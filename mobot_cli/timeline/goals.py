"""Goal commands on the timeline: one driver per robot plays its goals and the twists after them.

A driver wakes only when something is due: a command's start, a twist's end, or, while a goal
runs, every control period (``CONTROL_RATE_HZ``, whole physics steps). On each control tick it
reads the robot once, turns the pose it trusts into a twist (timeline/pursuit.py) and commands it.
A goal ends ``reached``, ``timed_out`` (its ``timeout``), ``blocked`` (the robot's true pose
moved less than ``BLOCKED_DISTANCE`` and turned less than ``BLOCKED_TURN`` in
``BLOCKED_SECONDS``, or the goal's ``stuck_time``: it pushes against something) or ``cancelled``
(a live command or goal took over) or ``unreachable`` (``planner: astar`` found no way there, at
its start: the record says why); the robot is stopped and ``GoalEnded`` recorded. Progress is judged on the true
pose, so wheels spinning against a wall count as blocked even if the encoders say they move.
A goal driven on odometry that odometry says is reached is checked on the true pose as well:
farther than its tolerance plus ``faults.odom_tolerance`` from the goal, it ends
``reached_by_odometry_only`` (the record's ``error`` says how far it truly is).

A goal with ``local: dwb`` is driven by the dynamic-window controller (timeline/local.py) along
the pursuit's route, on the latest scan of each of the robot's lidars (the timeline hands them
over as they are read). It ends ``stuck`` instead of ``blocked`` when the robot stood still
because no rollout was free or standing was its best, or when it has not moved ``PROGRESS_DISTANCE`` in
``PROGRESS_SECONDS`` (nav2's SimpleProgressChecker defaults).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

from mobot_cli.common.polygon import DEFAULT_FOOTPRINT, footprint_radius
from mobot_cli.common.transforms import Planar
from mobot_cli.plan import GoalStep, TwistStep, WorldPlan
from mobot_cli.sim.bullet.world import World
from mobot_cli.sim.state import RobotState
from mobot_cli.timeline.pursuit import PlanarPose, Pursuit

CONTROL_RATE_HZ = 20  # nav2's controller_frequency default
BLOCKED_SECONDS = 1.0  # the default of a goal's stuck_time
BLOCKED_DISTANCE = 0.02  # m
BLOCKED_TURN = 0.05  # rad
PROGRESS_SECONDS = 10.0  # local: dwb: the robot must move PROGRESS_DISTANCE within this ...
PROGRESS_DISTANCE = 0.5  # m ... or the goal ends stuck
STILL_LINEAR = 0.01  # m/s: local: dwb commanding less (and turning less than BLOCKED_TURN rad/s) stands
HANDOVER = 0.25  # m: local: dwb hands a free last stretch to a stop vertex to the pursuit
STATUSES = ("reached", "reached_by_odometry_only", "timed_out", "blocked", "cancelled", "unreachable", "stuck")


@dataclass(frozen=True)
class GoalStarted:
    """Goal command ``index`` of ``robot`` started at ``step``."""

    step: int
    robot: str
    index: int
    kind: str
    # m: the optimal path length for SPL: the polyline from the true start through the goal's points
    # (a patrol: one lap back to its first point). A planner puts its planned path's length here.
    optimal: float | None = None


@dataclass(frozen=True)
class GoalEnded:
    """Goal command ``index`` of ``robot`` ended at ``step``: ``status`` is one of STATUSES."""

    step: int
    robot: str
    index: int
    kind: str
    status: str
    started: int  # its start step
    error: float  # m: the true distance from the goal's last point
    laps: int | None = None  # patrol: rounds completed
    reason: str = ""  # unreachable: why


def optimal_length(state: RobotState, goal: GoalStep) -> float:
    """The straight-line route's length from the robot's true position through ``goal``'s points
    (a patrol: one lap, back to its first point), m."""
    route = [(state.true_x, state.true_y), *goal.points]
    if goal.kind == "patrol":
        route.append(goal.points[0])
    return sum(math.dist(a, b) for a, b in zip(route, route[1:]))


class Driver:
    """Plays ``items`` (GoalSteps and TwistSteps, in order) for robot ``name``."""

    def __init__(self, name: str, items, world: World, rate_hz: int, emit: Callable[[object], None],
                 plan_world: WorldPlan | None = None,
                 footprint: tuple[float, float, float, float] | None = None):
        self.name, self.world, self.emit = name, world, emit
        self.plan_world = plan_world  # the static world a planned goal's map is drawn from
        self.floor: float | None = None  # the floor under the robot, found by its first planned goal
        self.items: list[GoalStep | TwistStep] = list(items)
        self.every = max(1, round(rate_hz / CONTROL_RATE_HZ))
        self.dt = self.every / rate_hz
        self.rate_hz = rate_hz
        self.blocked_steps = max(1, round(BLOCKED_SECONDS * rate_hz))
        self.current: GoalStep | TwistStep | None = None
        self.started = 0
        self.wake = self.items[0].step if self.items else -1  # the next step it has work at
        self.pursuit: Pursuit | None = None
        self.anchor: tuple[int, float, float, float] = (0, 0.0, 0.0, 0.0)  # blocked check: step, x, y, yaw
        self.lap_ends: list[int] = []  # patrol: route vertices that close a lap
        self.lap: list[tuple[float, float]] = []  # patrol: the points one more lap adds
        x, y, yaw = world.odom_origin(name)
        self.odom = Planar(x, y, yaw)
        self.odom_tolerance = world.physics.faults.odom_tolerance
        # local: dwb: the latest level scan of each lidar (world x, y points) and the controller
        self.footprint = footprint
        self.sees = any(isinstance(item, GoalStep) and item.control.local for item in self.items)
        self.scans: dict[str, object] = {}
        self.cloud = None  # the scans joined (local.Cloud of world points)
        self.local = None
        self.progress_steps = max(1, round(PROGRESS_SECONDS * rate_hz))
        self.progress: tuple[int, float, float] = (0, 0.0, 0.0)  # step, true x, y: the progress check
        self.stood = False  # the controller chose to stand (or found no free rollout) at the last tick

    @property
    def finished(self) -> bool:
        """Nothing left to do."""
        return self.current is None and not self.items

    def tick(self, step: int) -> None:
        """Do what is due at ``step`` (call when ``step >= wake``)."""
        if isinstance(self.current, GoalStep):
            self._control(step)
        elif isinstance(self.current, TwistStep):  # its hold is over
            self.world.set_command(self.name, 0.0, 0.0)
            self.current = None
        if self.current is None:
            self._next(step)

    def cancel(self, step: int) -> None:
        """A live command or goal takes over: a running goal ends ``cancelled``; the rest is dropped."""
        if isinstance(self.current, GoalStep):
            self._end(step, "cancelled", self.world.read(self.name), stop=False)
        self.current, self.items = None, []

    def _next(self, step: int) -> None:
        """Start the next item when its time has come; else sleep until it has."""
        if not self.items:
            self.wake = -1
            return
        if self.items[0].step > step:
            self.wake = self.items[0].step
            return
        item = self.items.pop(0)
        self.current, self.started = item, step
        if isinstance(item, TwistStep):
            self.world.set_command(self.name, item.linear, item.angular, item.linear_y)
            if item.hold is not None:
                self.wake = step + item.hold
            else:
                self.current = None
                self.wake = self.items[0].step if self.items else -1
            return
        self._start_goal(step, item)

    def _start_goal(self, step: int, goal: GoalStep) -> None:
        state = self.world.read(self.name)
        pose = self._pose(state, goal)
        route = [(pose.x, pose.y), *goal.points]
        self.lap = [*goal.points[1:], goal.points[0]]
        if goal.control.planner is not None:
            from mobot_cli.timeline.routes import plan_route  # the world's map: only for planned goals

            planned = plan_route(self.plan_world, (pose.x, pose.y, state.true_z), goal, self.floor)
            self.floor = planned.floor if not planned.reason else self.floor
            if planned.reason:
                self.current = goal
                self.emit(GoalStarted(step, self.name, goal.index, goal.kind))
                self._end(step, "unreachable", state, reason=planned.reason)
                return
            route = [(pose.x, pose.y), *planned.lead[1:], *planned.lap[1:]]
            self.lap = list(planned.lap[1:])
            # SPL's optimal length: the planned way (a patrol's first lap), from the true start
            way = [(state.true_x, state.true_y), *route[1:]]
            optimal = sum(math.dist(a, b) for a, b in zip(way, way[1:]))
        else:
            if goal.kind == "patrol":
                route.append(goal.points[0])
            optimal = optimal_length(state, goal)
        self.pursuit = Pursuit(route, goal.control, self.dt, yaw=goal.yaw)
        if goal.kind == "patrol":
            self.lap_ends = [len(self.pursuit.route) - 1]
        self.local = None
        if goal.control.local:
            from mobot_cli.timeline.local import Dwb  # numpy: only for goals that use it

            self.local = Dwb(goal.control, self.dt, footprint_radius(self.footprint or DEFAULT_FOOTPRINT))
            self.progress = (step, state.true_x, state.true_y)
        if goal.kind == "patrol" and goal.laps != 1:
            self._add_lap(goal)  # the route holds two laps ahead: one more each time one begins
        self.anchor = (step, state.true_x, state.true_y, state.true_yaw)
        self.blocked_steps = max(1, round(goal.control.stuck_time * self.rate_hz))
        self.emit(GoalStarted(step, self.name, goal.index, goal.kind, optimal))
        self._control(step, state)

    def _add_lap(self, goal: GoalStep) -> None:
        before = len(self.pursuit.route)
        self.pursuit.extend(self.lap)
        self.lap_ends.append(self.lap_ends[-1] + len(self.pursuit.route) - before)

    def _control(self, step: int, state: RobotState | None = None) -> None:
        """One control tick of the running goal."""
        goal = self.current
        state = state or self.world.read(self.name)
        pursuit = self.pursuit
        if goal.kind == "patrol" and len(self.lap_ends) > 1 and pursuit.passed >= self.lap_ends[-2] and \
                (goal.laps is None or len(self.lap_ends) < goal.laps):
            self._add_lap(goal)  # on its last lap ahead: one more
        pose = self._pose(state, goal)
        if self.local is not None and pursuit.follow(pose):
            linear, angular = self._avoid(pose, state)
        else:
            linear, angular = pursuit.update(pose)
        if pursuit.done:
            self._end(step, "reached", state)
        elif goal.control.timeout is not None and step - self.started >= goal.control.timeout:
            self._end(step, "timed_out", state)
        elif self.local is not None and self._no_progress(step, state):
            self._end(step, "stuck", state)
        elif self._blocked(step, state):
            self._end(step, "stuck" if self.local is not None and self.stood else "blocked", state)
        else:
            self.world.set_command(self.name, linear, angular)
            self.wake = step + self.every

    def see(self, sensor, data) -> None:
        """A lidar reading of this robot (the timeline hands every one over while ``sees``)."""
        if sensor.kind != "lidar":
            return
        from mobot_cli.timeline.scan_points import level_points

        self.scans[sensor.name] = level_points(data)
        self.cloud = None  # joined again at the next tick

    def _avoid(self, pose: PlanarPose, state: RobotState) -> tuple[float, float]:
        """The local controller's twist: lidar points and the route ahead in the robot's frame."""
        from mobot_cli.timeline.scan_points import Cloud, joined, path_in_frame
        from mobot_cli.timeline.wavefront import WAVE_REACH

        if self.cloud is None:
            self.cloud = Cloud(joined(list(self.scans.values())))
        path = path_in_frame(self.pursuit.ahead(pose, WAVE_REACH), pose.x, pose.y, pose.yaw)
        choice = self.local.command(self.cloud, path, (state.true_x, state.true_y, state.true_yaw))
        # It stands because nothing free is better, not because something holds it: stuck if it lasts.
        self.stood = not choice.admissible or (abs(choice.linear) < STILL_LINEAR and abs(choice.angular) < BLOCKED_TURN)
        stop = self.pursuit.route[self.pursuit.stop]
        if choice.admissible and not choice.blocked_path and math.dist((pose.x, pose.y), stop) < HANDOVER:
            return self.pursuit.update(pose)  # a free last stretch: the pursuit lands within the tolerance
        self.pursuit.v, self.pursuit.w = choice.linear, choice.angular  # the final turn starts from it
        return choice.linear, choice.angular

    def _no_progress(self, step: int, state: RobotState) -> bool:
        """local: dwb: whether the robot stayed within PROGRESS_DISTANCE for PROGRESS_SECONDS."""
        since, x, y = self.progress
        if math.hypot(state.true_x - x, state.true_y - y) >= PROGRESS_DISTANCE:
            self.progress = (step, state.true_x, state.true_y)
            return False
        return step - since >= self.progress_steps

    def _blocked(self, step: int, state: RobotState) -> bool:
        """Whether the robot stayed put for BLOCKED_SECONDS (checked once per such window)."""
        since, x, y, yaw = self.anchor
        if step - since < self.blocked_steps:
            return False
        self.anchor = (step, state.true_x, state.true_y, state.true_yaw)
        moved = math.hypot(state.true_x - x, state.true_y - y)
        turned = abs(math.remainder(state.true_yaw - yaw, math.tau))
        return moved < BLOCKED_DISTANCE and turned < BLOCKED_TURN

    def _end(self, step: int, status: str, state: RobotState, stop: bool = True, reason: str = "") -> None:
        goal = self.current
        if stop:
            self.world.set_command(self.name, 0.0, 0.0)
        target = goal.points[0] if goal.kind == "patrol" else goal.points[-1]
        error = math.hypot(state.true_x - target[0], state.true_y - target[1])
        if status == "reached" and goal.control.localization == "odometry" and \
                error > goal.control.tolerance + self.odom_tolerance:
            status = "reached_by_odometry_only"
        laps = None
        if goal.kind == "patrol":
            laps = sum(self.pursuit.passed >= end for end in self.lap_ends) if self.pursuit else 0
        self.emit(GoalEnded(step, self.name, goal.index, goal.kind, status, self.started, error, laps, reason))
        self.current, self.pursuit, self.lap_ends, self.local = None, None, [], None
        self.wake = step

    def _pose(self, state: RobotState, goal: GoalStep) -> PlanarPose:
        """The pose the goal's controller trusts: odometry mapped into the world, or the truth."""
        if goal.control.localization == "ground_truth":
            return PlanarPose(state.true_x, state.true_y, state.true_yaw)
        x, y = self.odom(state.odom_x, state.odom_y)
        return PlanarPose(x, y, self.odom.yaw + state.odom_yaw)
