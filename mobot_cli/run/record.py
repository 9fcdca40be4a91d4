"""The run record: what ``summary.json`` holds, as one typed model built in one place.

`mobot run` and `mobot serve --out` write it, `mobot check`, the terminal table and sweeps read
it back; nothing passes string-keyed summary dicts between packages.
"""

from __future__ import annotations

import json
from enum import Enum
from pathlib import Path
from typing import Optional

from pydantic import BaseModel, ConfigDict, ValidationError

from mobot_cli.common.files import write_text_atomic

SUMMARY = "summary.json"


class Status(str, Enum):
    """How a run (or a live world) ended."""

    OK = "ok"
    FAULT = "fault"  # the simulation broke: a NaN state, a robot left the world
    ERROR = "error"  # a bug or an unexpected failure inside mobot
    INTERRUPTED = "interrupted"  # Ctrl-C or SIGTERM before the end


class _Model(BaseModel):
    model_config = ConfigDict(extra="ignore", frozen=True, defer_build=True)


class Pose(_Model):
    """A true pose in the world frame (m, rad)."""

    x: float
    y: float
    z: float
    roll: float
    pitch: float
    yaw: float


class OdomPose(_Model):
    """What the robot's odometry reports, in its odom frame (the spawn pose)."""

    x: float
    y: float
    yaw: float


class OdomError(_Model):
    """Odometry against the truth at the end of the robot's life."""

    position: float
    yaw: float


class SensorRecord(_Model):
    """One sensor of a robot: what it is, where its readings went and how many there were."""

    name: str
    kind: str  # lidar | imu | contact
    topic: str  # in the bag, namespace included
    frame_id: str  # frame prefix included
    rate_hz: float
    readings: int
    file: str  # relative to the run folder


class GoalRecord(_Model):
    """How one goal command went: status, when, how long and how far the robot drove."""

    command: Optional[int]  # its index in the robot's commands list; None: a live goto request
    kind: str  # goto | path | patrol | coverage
    status: str  # reached | timed_out | blocked | cancelled | unfinished (the run ended first)
    started_at: float
    ended_at: Optional[float] = None
    time: float  # s from start to end (or to the end of the record)
    path_length: float  # m the robot truly drove meanwhile (from the log rows)
    error: Optional[float] = None  # m from the goal's last point (a patrol's first) when it ended
    laps: Optional[int] = None  # patrol: rounds completed


class RobotRecord(_Model):
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
    sensors: list[SensorRecord] = []
    goals: list[GoalRecord] = []


class ExpectationResult(_Model):
    """One expectation for one robot."""

    robot: str
    kind: str
    expected: str
    happened: str
    passed: bool


class Expectations(_Model):
    """The expectations of a run that finished."""

    passed: int
    failed: int
    results: list[ExpectationResult]


class Versions(_Model):
    mobot: str
    pybullet: Optional[str] = None
    python: str


class LiveInfo(_Model):
    """What a live world adds to its record."""

    endpoint: str
    pace: str
    requests: dict[str, int]


class RunRecord(_Model):
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
    notices: list[str] = []
    robots: dict[str, RobotRecord] = {}
    expectations: Optional[Expectations] = None
    live: Optional[LiveInfo] = None

    @property
    def failed_expectations(self) -> int:
        return self.expectations.failed if self.expectations else 0

    def to_json(self) -> str:
        """The file's text: two-space indents, keys in declaration order, no NaN."""
        return json.dumps(self.model_dump(mode="json"), indent=2, allow_nan=False) + "\n"

    def save(self, folder: Path, durable: bool = True) -> None:
        """Write ``folder/summary.json`` atomically, flushed to disk unless not ``durable``."""
        write_text_atomic(folder / SUMMARY, self.to_json(), durable)

    @classmethod
    def load(cls, folder: Path) -> Optional["RunRecord"]:
        """The record in ``folder``, or None when it is missing or not a record mobot wrote."""
        try:
            return cls.model_validate_json((folder / SUMMARY).read_bytes())
        except (OSError, ValueError, ValidationError):
            return None


def build_models() -> None:
    """Build the record models' validators now rather than at their first use (defer_build): a
    run does it while its helper process draws the picture (~20 ms the first time in a process)."""
    for model in (Pose, OdomPose, OdomError, SensorRecord, GoalRecord, RobotRecord, ExpectationResult,
                  Expectations, Versions, LiveInfo, RunRecord):
        model.model_rebuild()
