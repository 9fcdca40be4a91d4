"""One robot's life in a run's record: what summary.json says of it (distance, odometry error,
readings, goals and their metrics), accumulated sample by sample (record/recording.py)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Optional

from mobot_cli.common.transforms import Planar
from mobot_cli.plan import GoalControl, GoalStep, RobotPlan
from mobot_cli.sim.state import RobotState
from mobot_cli.timeline import metrics
from mobot_cli.timeline.expect import odom_error
from mobot_cli.timeline.goals import GoalEnded, GoalStarted
from mobot_cli.timeline.metrics import Meter

if TYPE_CHECKING:  # the record's classes are made when it is written (record/outcome.py)
    from mobot_cli.record.summary import GoalRecord, RobotMetrics, RobotRecord, SensorRecord


@dataclass
class Life:
    """One robot's life in the record, accumulated sample by sample."""

    name: str
    plan: RobotPlan
    spawned_at: float
    deleted_at: Optional[float] = None
    first: Optional[RobotState] = None
    last: Optional[RobotState] = None
    distance: float = 0.0
    readings: dict[str, int] = field(default_factory=dict)  # sensor name -> readings recorded
    goals: list[dict] = field(default_factory=list)  # GoalRecord fields, and the distance at the start
    worst: tuple[float, int] = (0.0, 0)  # the largest odometry position error so far (m), its step
    rate: int = 1
    meter: Optional[Meter] = None  # its whole life's metrics, once it drives to goals
    running: list[dict] = field(default_factory=list)  # goals whose meter still runs (or waits for a row)
    _origin: Optional[Planar] = None  # the first sample's true pose: the odom frame odom_error measures in

    def add(self, state: RobotState, step: int) -> None:
        if self.meter is None and self.first is None and any(isinstance(c, GoalStep) for c in self.plan.commands):
            self.meter = Meter(state, step, self.rate, self._danger(0))
        elif self.meter is not None:
            self.meter.add(state, step)
        for goal in self.running:
            if goal["meter"] is None:
                goal["meter"] = Meter(state, step, self.rate, goal["danger"])
            else:
                goal["meter"].add(state, step)
        if self.first is None:
            self.first = state
            self._origin = Planar(state.true_x, state.true_y, state.true_yaw)  # odom_error's frame, made once
        else:
            if self.last is not None:
                self.distance += math.hypot(state.true_x - self.last.true_x, state.true_y - self.last.true_y)
            x, y = self._origin(state.odom_x, state.odom_y)  # odom_error's position, on every row
            position = math.hypot(x - state.true_x, y - state.true_y)
            if position > self.worst[0]:  # NaN never is: a broken state is not the worst
                self.worst = (position, step)
        self.last = state

    def failed(self, kind: str) -> None:
        """Its robot faulted: the goal it was driving to failed (tipped over: ``flipped``)."""
        for goal in self.goals:
            if goal["status"] == "unfinished":
                goal.update(status="failed", fault=kind)

    def started(self, record: GoalStarted, rate: int) -> None:
        danger = self._danger(record.index)
        if self.meter is None and self.last is not None:  # a goal a live request gave: from now on
            self.meter = Meter(self.last, record.step, rate, danger)
        goal = {"command": _command(record.index), "kind": record.kind, "status": "unfinished",
                "started_at": record.step / rate, "from": self.distance, "meter": None,
                "danger": danger, "optimal": record.optimal}
        self.goals.append(goal)
        self.running.append(goal)

    def ended(self, record: GoalEnded, rate: int) -> None:
        goal = next(g for g in reversed(self.goals) if g["command"] == _command(record.index))
        error = rounded(record.error) if math.isfinite(record.error) else None  # a robot whose state broke
        goal.update(status=record.status, ended_at=record.step / rate, error=error, laps=record.laps,
                    path_length=rounded(self.distance - goal["from"]), reason=record.reason or None)
        self.running = [g for g in self.running if g is not goal]

    def _danger(self, index: int) -> float:
        """The danger distance of goal command ``index`` (the default for a live goal)."""
        step = next((c for c in self.plan.commands if isinstance(c, GoalStep) and c.index == index), None)
        return (step.control if step is not None else GoalControl()).danger_distance

    def record(self, end: float, rate_hz: int) -> RobotRecord:
        from mobot_cli.record.summary import OdomError, OdomPose, Pose, RobotRecord

        goals = [self._goal(g, end) for g in self.goals]
        s = self.last
        position, yaw = odom_error(self.first, s)
        return RobotRecord(
            name=self.name, namespace=self.plan.namespace, source=self.plan.source,
            spawned_at=self.spawned_at, deleted_at=self.deleted_at,
            final_pose=Pose(x=rounded(s.true_x), y=rounded(s.true_y), z=rounded(s.true_z), roll=rounded(s.true_roll),
                            pitch=rounded(s.true_pitch), yaw=rounded(s.true_yaw)),
            final_odom=OdomPose(x=rounded(s.odom_x), y=rounded(s.odom_y), yaw=rounded(s.odom_yaw)),
            distance=rounded(self.distance), collisions=s.collisions,
            odom_error=OdomError(position=rounded(position), yaw=rounded(yaw), max_position=rounded(self.worst[0]),
                                 max_position_at=rounded(self.worst[1] / rate_hz)), goals=goals,
            sensors=[self._sensor(spec, rate_hz) for spec in self.plan.sensors], metrics=self._metrics(goals))

    def _goal(self, g: dict, end: float) -> GoalRecord:
        """One goal's record, its metrics from its meter."""
        from mobot_cli.record.summary import GoalRecord

        path_length = g["path_length"] if "path_length" in g else rounded(self.distance - g["from"])
        meter: Optional[Meter] = g["meter"]
        collisions = meter.collisions if meter is not None else 0
        success = g["status"] == "reached"
        fields = {k: v for k, v in g.items() if k not in ("from", "meter", "danger", "optimal", "fault", "path_length")}
        found = {}
        if meter is not None:
            found = dict(collision_first=_opt(meter.first_collision), collided_with=list(meter.hits),
                         clearance_min=_opt(meter.least_clearance), clearance_mean=_opt(meter.clearance_mean),
                         danger_time=rounded(meter.danger_time), jerk_linear=rounded(meter.jerk_linear),
                         jerk_angular=rounded(meter.jerk_angular), **_social(meter))
        return GoalRecord(**fields, time=rounded(g.get("ended_at", end) - g["started_at"]), path_length=path_length,
                          failure=metrics.failure(g["status"], collisions, g.get("fault")), success=success,
                          collisions=collisions, optimal_length=_opt(g["optimal"]),
                          spl=_opt(metrics.spl(success, g["optimal"], path_length)), **found)

    def _metrics(self, goals: list[GoalRecord]) -> Optional[RobotMetrics]:
        """The robot's metrics over its life, when it drove to goals."""
        from mobot_cli.record.summary import RobotMetrics

        meter = self.meter
        if meter is None or not goals:
            return None
        spls = [g.spl for g in goals if g.spl is not None]
        return RobotMetrics(
            success=all(g.success for g in goals), collisions=meter.collisions,
            collision_first=_opt(meter.first_collision), collided_with=list(meter.hits),
            time=rounded(sum(g.time for g in goals)), path_length=rounded(meter.path_length),
            spl=rounded(sum(spls) / len(spls)) if spls else None, clearance_min=_opt(meter.least_clearance),
            clearance_mean=_opt(meter.clearance_mean), danger_time=rounded(meter.danger_time),
            jerk_linear=rounded(meter.jerk_linear), jerk_angular=rounded(meter.jerk_angular),
            failure=next((g.failure for g in goals if g.failure is not None), None), **_social(meter))

    def _sensor(self, spec, rate_hz: int) -> SensorRecord:
        from mobot_cli.record.sensor_files import sensor_file
        from mobot_cli.record.summary import SensorRecord
        from mobot_cli.ros import sensor_topics

        return SensorRecord(name=spec.name, kind=spec.kind, topic=sensor_topics.topic(self.plan, spec),
                            frame_id=sensor_topics.sensor_frame(self.plan, spec).frame,
                            rate_hz=rounded(sensor_topics.rate_hz(spec, rate_hz)),
                            readings=self.readings.get(spec.name, 0), file=sensor_file(self.name, spec))


def _command(index: int) -> int | None:
    """A goal's command index in the record; None for a goal a live request gave (index < 0)."""
    return index if index >= 0 else None


def _social(meter: Meter) -> dict:
    """A meter's people_* figures, rounded as the record's numbers are."""
    return {k: (rounded(v) if isinstance(v, float) else v) for k, v in meter.social().items()}


def _opt(value: float | None) -> float | None:
    return None if value is None else rounded(value)


def rounded(value: float) -> float:
    """Six decimals and never -0.0, so that records compare as text."""
    return round(value, 6) + 0.0
