"""What the timeline hands its consumers: samples, spawns, deletes and sensor readings, in order.

The run folder's writers, the expectations, the ROS 2 node and the view all take these records;
none of them drives the loop.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple, Protocol, Union

from mobot_cli.plan import RobotPlan, SensorSpec
from mobot_cli.sim.state import RobotState
from mobot_cli.timeline.goals import GoalEnded, GoalStarted


class Sample(NamedTuple):
    """Robot states after ``step`` physics steps: every robot on a log row (``complete``), or only
    the robot that arrived or left between two rows (so that even a short life leaves rows)."""

    # A named tuple, not a frozen dataclass: one is made per log row, and it is made in a third
    # of the time (measured), as immutable.
    step: int
    states: dict[str, RobotState]
    complete: bool = True
    movers: dict | None = None  # name -> (x, y, yaw) of every mover, on complete rows after they moved


@dataclass(frozen=True)
class Spawned:
    """A robot entered the world at ``step``; ``by`` says how (scenario, request)."""

    step: int
    robot: RobotPlan
    by: str
    state: RobotState  # where it was placed


@dataclass(frozen=True)
class Deleted:
    """A robot left the world at ``step`` (its last row was recorded just before)."""

    step: int
    name: str
    by: str
    message: str | None = None


@dataclass(frozen=True)
class Reading:
    """A sensor's reading after ``step`` physics steps (data: sim.sensors ScanData, ImuData or
    ContactData)."""

    step: int
    robot: str
    sensor: SensorSpec
    data: object


Record = Union[Sample, Spawned, Deleted, Reading, GoalStarted, GoalEnded]


class Consumer(Protocol):
    """Whatever takes the timeline's records, in order."""

    def __call__(self, record: Record) -> None: ...


class Sink:
    """Something that records the timeline into the run folder."""

    def spawned(self, step: int, key: str, robot: RobotPlan) -> None:
        """Robot ``key`` entered the world at ``step``; its first sample follows."""

    def deleted(self, step: int, key: str) -> None:
        """Robot ``key`` left the world at ``step``, after its last sample."""

    def write(self, sample: Sample) -> None:
        """Record one sample."""

    def reading(self, key: str, reading: Reading) -> None:
        """Record one sensor reading of robot ``key`` (after its first sample)."""

    def close(self) -> None:
        """Finish every file."""
