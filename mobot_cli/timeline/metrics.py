"""Navigation metrics of a goal (or of a robot's whole life), from the true states of the log rows.

The names follow DESIGN.md; docs/metrics.md gives each one's definition and its name in the nav2
controller benchmark and arena-evaluation. A ``Meter`` takes one robot's samples in order and
is read at the end; it makes no new objects per sample but the running sums.

- path_length: the true x, y path, row to row (m).
- clearance: the smallest distance from the robot's collision shapes to anything but its floor
  (sim/clearance.py), measured up to ``REACH`` m on each log row: ``clearance_min`` is the least
  (None when nothing came within reach), ``clearance_mean`` the mean of min(clearance, REACH).
- danger_time: the log periods in which the clearance was below the danger distance (s).
- jerk_linear, jerk_angular: the integral of the squared jerk of the true forward speed and yaw
  rate (m^2/s^5, rad^2/s^5), jerk taken as the second difference of the speeds on log rows at
  least ``JERK_PERIOD`` apart (nav2's controller rate: the commands change no faster), so that
  the figure does not grow with the log rate; 0 at constant speed.
- collisions: new collision events (sim/contacts.py) meanwhile, the time of the first and what
  each was with.
- people_*: with people in the world (movers of shape person and actors, docs/movers.md), from
  the distance in the plane between the robot's root link and each person's axis on each log
  row: ``people_distance_min`` the least, ``people_intimate_time`` and ``people_personal_time``
  the log periods closer than ``INTIMATE`` and ``PERSONAL`` (Hall's proxemic zones, as
  hunav_evaluator's space intrusions), ``people_collisions`` the collision events with people
  (also counted in ``collisions``: Francis et al. 2023's human collisions). None without people.
"""

from __future__ import annotations

import math
from typing import Iterable

from mobot_cli.sim.state import RobotState

NAMES = ("success", "collisions", "time", "path_length", "spl", "clearance_min", "clearance_mean",
         "danger_time", "jerk_linear", "jerk_angular", "failure")
NUMERIC = ("collisions", "time", "path_length", "spl", "clearance_min", "clearance_mean", "danger_time",
           "jerk_linear", "jerk_angular", "success")
REACH = 2.0  # m: clearance is measured this far while a robot drives to goals
JERK_PERIOD = 0.05  # s: 20 Hz, nav2's controller_frequency default (timeline/goals.py CONTROL_RATE_HZ)
FAILURES = ("timeout", "collision", "stuck", "flipped", "unreachable")
SOCIAL = ("people_distance_min", "people_intimate_time", "people_personal_time", "people_collisions")
INTIMATE = 0.5  # m: intimate space around a person
PERSONAL = 1.2  # m: personal space
# How a goal's status (timeline/goals.py) reads as a failure; faults say their own kind.
_BY_STATUS = {"timed_out": "timeout", "blocked": "stuck", "unreachable": "unreachable"}


def polyline_length(points: Iterable[tuple[float, float]]) -> float:
    """The length of the polyline through ``points`` (m)."""
    points = list(points)
    return sum(math.dist(a, b) for a, b in zip(points, points[1:]))


def failure(status: str, collisions: int, fault: str | None = None) -> str | None:
    """Why a goal failed: its fault (tipped over is ``flipped``), ``unreachable``, ``collision``
    (it touched something and did not arrive), ``stuck``, ``timeout``; None when it succeeded
    or was cancelled or unfinished without a collision."""
    if status in ("reached", "reached_by_odometry_only") and fault is None:
        return None  # reached_by_odometry_only is no success, and its status says why
    if fault is not None:
        return "flipped" if fault == "tipped_over" else fault
    if status == "unreachable":
        return "unreachable"
    if collisions:
        return "collision"
    return _BY_STATUS.get(status)


def spl(success: bool, optimal: float | None, actual: float) -> float | None:
    """Success weighted by path length (Anderson et al. 2018): success x l / max(p, l), with
    l the optimal length and p the length driven; None without an optimal length."""
    if optimal is None:
        return None
    if not success:
        return 0.0
    if optimal <= 0.0:
        return 1.0
    return optimal / max(actual, optimal)


class Meter:
    """Running figures of one robot from ``first`` on; ``danger`` is the danger distance (m)."""

    def __init__(self, first: RobotState, step: int, rate_hz: int, danger: float):
        self.rate, self.danger = rate_hz, danger
        self.jerk_steps = max(1, round(JERK_PERIOD * rate_hz))
        self.start_step = step
        self.collisions_before = first.collisions
        self.collisions = 0
        self.first_collision: float | None = None  # s, sim time
        self.hits: list[str] = []  # what it collided with, in order, once each
        self.path_length = 0.0
        self.clearance_min = math.inf
        self.clearance_sum = 0.0
        self.rows = 0
        self.danger_steps = 0
        self.jerk_linear = self.jerk_angular = 0.0
        self.people_before = first.people_collisions
        self.people_min = math.inf
        self.people_seen = False  # a person was in the world on some row
        self.intimate_steps = self.personal_steps = 0
        self._last = first
        self._step = step
        self._speeds: list[tuple[int, float, float]] = [(step, first.true_vx, first.true_wz)]  # last three rows
        self._clearance(first, 0)

    def add(self, state: RobotState, step: int) -> None:
        """One more sample of the robot, at ``step``."""
        period = step - self._step
        if period <= 0:
            return
        last = self._last
        self.path_length += math.hypot(state.true_x - last.true_x, state.true_y - last.true_y)
        if state.collisions > last.collisions:
            if self.first_collision is None:
                self.first_collision = step / self.rate
            if state.hit and state.hit not in self.hits:
                self.hits.append(state.hit)
        self.collisions = state.collisions - self.collisions_before
        self._clearance(state, period)
        self._people(state, period)
        self._jerk(step, state)
        self._last, self._step = state, step

    def _clearance(self, state: RobotState, period: int) -> None:
        c = state.clearance
        if c < self.clearance_min:
            self.clearance_min = c
        self.clearance_sum += min(c, REACH)
        self.rows += 1
        if c < self.danger:
            self.danger_steps += period

    def _people(self, state: RobotState, period: int) -> None:
        d = state.people_distance
        if d == math.inf:
            return
        self.people_seen = True
        if d < self.people_min:
            self.people_min = d
        if d < PERSONAL:
            self.personal_steps += period
            if d < INTIMATE:
                self.intimate_steps += period

    def social(self) -> dict[str, float | int | None]:
        """The people_* figures (SOCIAL), all None when no person was ever in the world."""
        collisions = self._last.people_collisions - self.people_before
        if not self.people_seen and not collisions:
            return dict.fromkeys(SOCIAL)
        return {"people_distance_min": self.people_min if math.isfinite(self.people_min) else None,
                "people_intimate_time": self.intimate_steps / self.rate,
                "people_personal_time": self.personal_steps / self.rate, "people_collisions": collisions}

    def _jerk(self, step: int, state: RobotState) -> None:
        speeds = self._speeds
        if step - speeds[-1][0] < self.jerk_steps:
            return
        speeds.append((step, state.true_vx, state.true_wz))
        if len(speeds) > 3:
            del speeds[0]
        if len(speeds) < 3:
            return
        (s0, v0, w0), (s1, v1, w1), (s2, v2, w2) = speeds
        h1, h2 = (s1 - s0) / self.rate, (s2 - s1) / self.rate
        h = (h1 + h2) / 2.0
        jv = ((v2 - v1) / h2 - (v1 - v0) / h1) / h  # m/s^3 at the middle row
        jw = ((w2 - w1) / h2 - (w1 - w0) / h1) / h
        self.jerk_linear += jv * jv * h
        self.jerk_angular += jw * jw * h

    @property
    def time(self) -> float:
        """Seconds from the first sample to the last."""
        return (self._step - self.start_step) / self.rate

    @property
    def danger_time(self) -> float:
        return self.danger_steps / self.rate

    @property
    def clearance_mean(self) -> float | None:
        return self.clearance_sum / self.rows if self.rows and math.isfinite(self.clearance_min) else None

    @property
    def least_clearance(self) -> float | None:
        return self.clearance_min if math.isfinite(self.clearance_min) else None
