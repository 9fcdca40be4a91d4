"""The run record: what ``summary.json`` holds, as one typed record built in one place.

`mobot run` and `mobot serve --out` write it, `mobot check`, the terminal table and sweeps read
it back; nothing passes string-keyed summary dicts between packages.

The records are frozen dataclasses, not pydantic models: writing one needs nothing but the
standard library. Pydantic validates a summary.json that
is read back (``RunRecord.load``), from these same classes. Fields declared ``float`` or ``int``
hold exactly that type, as a pydantic model's would, so the file's numbers read the same
(``10.0``, not ``10``).
"""

from __future__ import annotations

import dataclasses
import functools
import json
from enum import Enum
from pathlib import Path
from typing import Optional

from mobot_cli.common.files import write_text_atomic
from mobot_cli.record.outcome import SUMMARY, Status  # noqa: F401 - the record's, re-exported


class _Record:
    """What every record shares: numbers of the declared type, and a JSON-ready form."""

    def __post_init__(self) -> None:
        for name, kind in _numbers(type(self)):
            value = getattr(self, name)
            if value is not None and type(value) is not kind:
                object.__setattr__(self, name, kind(value))  # frozen: set once, here

    def to_dict(self) -> dict:
        """The record as plain JSON values (an enum as its value), keys in declaration order."""
        return {f.name: _plain(getattr(self, f.name)) for f in dataclasses.fields(self)}


_NUMBERS = {"float": float, "Optional[float]": float, "int": int, "Optional[int]": int}


@functools.cache
def _numbers(cls: type) -> tuple[tuple[str, type], ...]:
    """The fields of ``cls`` declared a float or an int (annotations are strings here)."""
    return tuple((f.name, _NUMBERS[f.type]) for f in dataclasses.fields(cls) if f.type in _NUMBERS)


def _plain(value):
    if isinstance(value, _Record):
        return value.to_dict()
    if isinstance(value, Enum):
        return value.value
    if isinstance(value, list):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    return value


_record = dataclasses.dataclass(frozen=True, kw_only=True)  # every record class: keywords, fixed once made


@_record
class Pose(_Record):
    """A true pose in the world frame (m, rad)."""

    x: float
    y: float
    z: float
    roll: float
    pitch: float
    yaw: float


@_record
class OdomPose(_Record):
    """What the robot's odometry reports, in its odom frame (the spawn pose)."""

    x: float
    y: float
    yaw: float


@_record
class OdomError(_Record):
    """Odometry against the truth at the end of the robot's life."""

    position: float
    yaw: float
    max_position: Optional[float] = None  # m, the largest position error over the log rows
    max_position_at: Optional[float] = None  # s, when it was largest


@_record
class SensorRecord(_Record):
    """One sensor of a robot: what it is, where its readings went and how many there were."""

    name: str
    kind: str  # lidar | imu | contact
    topic: str  # in the bag, namespace included
    frame_id: str  # frame prefix included
    rate_hz: float
    readings: int
    file: str  # relative to the run folder


@_record
class GoalRecord(_Record):
    """How one goal command went: status, when, how long and how far the robot drove."""

    command: Optional[int]  # its index in the robot's commands list; None: a live goto request
    kind: str  # goto | path | patrol | coverage
    # reached | reached_by_odometry_only (odometry says so, the truth is farther than its tolerance
    # plus faults.odom_tolerance) | timed_out | blocked | stuck | cancelled | unreachable | unfinished
    # (the run ended first) | failed (its robot faulted: ``failure`` says how)
    status: str
    started_at: float
    ended_at: Optional[float] = None
    time: float  # s from start to end (or to the end of the record)
    path_length: float  # m the robot truly drove meanwhile (from the log rows)
    error: Optional[float] = None  # m from the goal's last point (a patrol's first) when it ended
    laps: Optional[int] = None  # patrol: rounds completed
    # Why it did not succeed (docs/metrics.md): timeout | collision | stuck | unreachable, or its robot's
    # fault (flipped | flying | runaway | non_finite | out_of_world | off_floor); None on success
    failure: Optional[str] = None
    reason: Optional[str] = None  # unreachable: why (planner: astar found no way there)
    # The metrics (timeline/metrics.py, docs/metrics.md), from the true states of the log rows
    success: Optional[bool] = None  # reached (on the truth)
    collisions: Optional[int] = None  # new collision events meanwhile
    collision_first: Optional[float] = None  # s, sim time of the first
    collided_with: list[str] = dataclasses.field(default_factory=list)  # what they were with, once each
    optimal_length: Optional[float] = None  # m: the straight-line route (or a planner's path)
    spl: Optional[float] = None  # success x optimal_length / max(path_length, optimal_length)
    clearance_min: Optional[float] = None  # m; None: nothing within timeline/metrics.py's REACH
    clearance_mean: Optional[float] = None  # m, of min(clearance, REACH)
    danger_time: Optional[float] = None  # s closer than the goal's danger_distance
    jerk_linear: Optional[float] = None  # m^2/s^5: the integral of the squared jerk of the forward speed
    jerk_angular: Optional[float] = None  # rad^2/s^5: ... of the yaw rate
    # With people in the world (docs/movers.md); left out of summary.json without them
    people_distance_min: Optional[float] = None  # m, robot to the nearest person's axis
    people_intimate_time: Optional[float] = None  # s within 0.5 m of a person
    people_personal_time: Optional[float] = None  # s within 1.2 m
    people_collisions: Optional[int] = None  # collision events with people (also in collisions)

    def to_dict(self) -> dict:
        """As every record, without the people_* figures of a world without people."""
        return _without_people(super().to_dict())


@_record
class RobotMetrics(_Record):
    """A robot's metrics over its life, kept for robots that drove to goals (docs/metrics.md)."""

    success: bool  # every goal succeeded
    collisions: int
    collision_first: Optional[float] = None
    collided_with: list[str] = dataclasses.field(default_factory=list)
    time: float  # s, its goals' time together
    path_length: float  # m over its life
    spl: Optional[float] = None  # the mean of its goals'
    clearance_min: Optional[float] = None
    clearance_mean: Optional[float] = None
    danger_time: float
    jerk_linear: float
    jerk_angular: float
    failure: Optional[str] = None  # its first failed goal's
    people_distance_min: Optional[float] = None  # as GoalRecord's, over its life
    people_intimate_time: Optional[float] = None
    people_personal_time: Optional[float] = None
    people_collisions: Optional[int] = None

    def to_dict(self) -> dict:
        """As every record, without the people_* figures of a world without people."""
        return _without_people(super().to_dict())


def _without_people(out: dict) -> dict:
    for key in ("people_distance_min", "people_intimate_time", "people_personal_time", "people_collisions"):
        if out.get(key) is None:
            out.pop(key, None)
    return out


@_record
class RobotRecord(_Record):
    """One robot's life: where it came from, where it ended, how far it went."""

    name: str
    namespace: str
    source: str
    spawned_at: float
    deleted_at: Optional[float] = None
    final_pose: Pose
    final_odom: OdomPose
    distance: float
    collisions: int
    odom_error: OdomError
    sensors: list[SensorRecord] = dataclasses.field(default_factory=list)
    goals: list[GoalRecord] = dataclasses.field(default_factory=list)
    metrics: Optional[RobotMetrics] = None  # robots that drove to goals

    def to_dict(self) -> dict:
        """As every record, without ``metrics`` when it has none (summaries without goals stay as they were)."""
        out = super().to_dict()
        if out["metrics"] is None:
            del out["metrics"]
        return out


@_record
class ExpectationResult(_Record):
    """One expectation for one robot."""

    robot: str
    kind: str
    expected: str
    happened: str
    passed: bool


@_record
class Expectations(_Record):
    """The expectations of a run that finished."""

    passed: int
    failed: int
    results: list[ExpectationResult]


@_record
class FaultRecord(_Record):
    """The fault that ended a run (status ``fault``): which robot, when, what happened."""

    robot: str
    step: int
    time: float
    kind: str  # non_finite | out_of_world | tipped_over | flying | runaway | off_floor


@_record
class Versions(_Record):
    mobot: str
    pybullet: Optional[str] = None
    python: str


@_record
class LiveInfo(_Record):
    """What a live world adds to its record."""

    endpoint: str
    pace: str
    requests: dict[str, int]


@_record
class RunRecord(_Record):
    """``summary.json``: written last, so a folder without it is a run that did not end."""

    status: Status
    error: Optional[str] = None
    scenario: str
    world: str
    seed: int
    versions: Versions
    steps: int
    sim_time: float
    wall_time: float
    real_time_factor: Optional[float] = None
    physics_rate_hz: int
    log_rate_hz: float
    notices: list[str] = dataclasses.field(default_factory=list)
    robots: dict[str, RobotRecord] = dataclasses.field(default_factory=dict)
    expectations: Optional[Expectations] = None
    live: Optional[LiveInfo] = None
    fault: Optional[FaultRecord] = None

    @property
    def failed_expectations(self) -> int:
        return self.expectations.failed if self.expectations else 0

    def to_json(self) -> str:
        """The file's text: two-space indents, keys in declaration order, no NaN."""
        return json.dumps(self.to_dict(), indent=2, allow_nan=False) + "\n"

    def save(self, folder: Path, durable: bool = True) -> None:
        """Write ``folder/summary.json`` atomically, flushed to disk unless not ``durable``."""
        write_text_atomic(folder / SUMMARY, self.to_json(), durable)

    @classmethod
    def load(cls, folder: Path) -> Optional["RunRecord"]:
        """The record in ``folder``, or None when it is missing or not a record mobot wrote."""
        try:
            return cls.parse((folder / SUMMARY).read_bytes())
        except OSError:
            return None

    @classmethod
    def parse(cls, data: bytes) -> Optional["RunRecord"]:
        """summary.json's bytes as a record, or None when they are not a record mobot wrote."""
        try:
            return _reader().validate_json(data)
        except (ValueError, RecursionError):  # pydantic's ValidationError is a ValueError
            return None


@functools.cache
def _reader():
    """Pydantic's validator of a RunRecord (unknown keys ignored), built at the first read."""
    from pydantic import TypeAdapter

    return TypeAdapter(RunRecord)
