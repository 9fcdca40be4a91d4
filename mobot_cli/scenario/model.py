"""The typed scenario, version 1: what a user may write, validated at load.

Field names and defaults here are the scenario format; DESIGN.md shows an example.
Checks that need more than one field (pose forms, fleets, command order) live in validators
so that a scenario which constructs is one that can be resolved.
"""

from __future__ import annotations

import math
import re
from typing import Annotated, Literal, Optional, Union

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from mobot_cli.scenario.expect_model import ExpectSpec

NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
FLEET_NAME_RE = re.compile(r"^[A-Za-z_]([A-Za-z0-9_]|\{i\})*$")
NAMESPACE_RE = re.compile(r"^(/[A-Za-z_][A-Za-z0-9_]*)+$")

PositiveFloat = Annotated[float, Field(gt=0)]
NonNegativeFloat = Annotated[float, Field(ge=0)]
Vector3 = tuple[float, float, float]


class Strict(BaseModel):
    """Base: unknown keys and NaN/inf numbers are errors."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)


class PhysicsSpec(Strict):
    rate_hz: Annotated[int, Field(gt=0, le=10_000)] = 240
    gravity: Vector3 = (0.0, 0.0, -9.81)
    solver_iterations: Annotated[int, Field(gt=0, le=1000)] = 50


class LogSpec(Strict):
    # None: about 50 Hz, rounded down to a whole number of physics steps (48 Hz at 240 Hz).
    rate_hz: Optional[Annotated[float, Field(gt=0)]] = None
    formats: list[Literal["csv", "mcap"]] = Field(default_factory=lambda: ["csv"])  # mcap: DIR/bag/


class PoseSpec(Strict):
    """A spawn pose: {x, y, z, roll, pitch, yaw}, {xyz, rpy} or {xyz, quat: [x, y, z, w]}."""

    x: Optional[float] = None
    y: Optional[float] = None
    z: Union[float, Literal["auto"], None] = None
    roll: Optional[float] = None
    pitch: Optional[float] = None
    yaw: Optional[float] = None
    xyz: Optional[tuple[float, float, Union[float, Literal["auto"]]]] = None
    rpy: Optional[Vector3] = None
    quat: Optional[tuple[float, float, float, float]] = None

    @model_validator(mode="after")
    def _one_form(self) -> "PoseSpec":
        flat = [k for k in ("x", "y", "z", "roll", "pitch", "yaw") if getattr(self, k) is not None]
        if self.xyz is None and (self.rpy is not None or self.quat is not None):
            raise ValueError("'rpy' and 'quat' need 'xyz' beside them")
        if self.xyz is not None and flat:
            raise ValueError(f"mixes the xyz form with '{flat[0]}': use either x/y/z/roll/pitch/yaw or xyz with rpy or quat")
        if self.rpy is not None and self.quat is not None:
            raise ValueError("gives both 'rpy' and 'quat': use one")
        if self.quat is not None and math.sqrt(sum(q * q for q in self.quat)) < 1e-9:
            raise ValueError("quat has zero length: give [x, y, z, w], e.g. [0, 0, 0, 1]")
        return self


class DriveOverrides(Strict):
    """Anything detected from the URDF can be overridden here."""

    type: Literal["diff_drive"] = "diff_drive"
    odometry: Literal["encoder", "ground_truth"] = "encoder"
    left_joints: Optional[list[str]] = None
    right_joints: Optional[list[str]] = None
    wheel_radius: Optional[PositiveFloat] = None
    wheel_separation: Optional[PositiveFloat] = None
    wheel_separation_multiplier: Optional[PositiveFloat] = None
    wheel_radius_multiplier: Optional[PositiveFloat] = None
    max_wheel_torque: Optional[PositiveFloat] = None
    max_wheel_acceleration: Optional[PositiveFloat] = None


class CommandSpec(Strict):
    """From ``at`` on, drive with this twist; ``for`` ends it with a stop."""

    at: NonNegativeFloat
    linear: float = 0.0
    angular: float = 0.0
    for_: Optional[PositiveFloat] = Field(default=None, alias="for")

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True, populate_by_name=True)


class RobotSpec(Strict):
    name: str
    namespace: Optional[str] = None
    description: str = "mobot"
    args: dict[str, Union[str, bool, int, float]] = Field(default_factory=dict)
    pose: PoseSpec = Field(default_factory=PoseSpec)
    drive: Optional[DriveOverrides] = None
    commands: list[CommandSpec] = Field(default_factory=list)
    count: Optional[Annotated[int, Field(ge=1, le=1000)]] = None
    poses: Optional[list[Vector3]] = None

    @field_validator("name")
    @classmethod
    def _name(cls, v: str) -> str:
        if not FLEET_NAME_RE.match(v):
            raise ValueError(f"'{v}' is not a valid robot name: use letters, digits and '_', "
                             "not starting with a digit ('{i}' allowed in fleets)")
        return v

    @field_validator("namespace")
    @classmethod
    def _namespace(cls, v: Optional[str]) -> Optional[str]:
        if v is not None and not NAMESPACE_RE.match(v):
            raise ValueError(f"'{v}' is not a valid ROS namespace: it must start with '/' and "
                             "hold names of letters, digits and '_' separated by '/', e.g. /robot1")
        return v

    @model_validator(mode="after")
    def _fleet(self) -> "RobotSpec":
        templated = "{i}" in self.name
        if self.count is None:
            if templated:
                raise ValueError("name contains '{i}' but 'count' is missing")
            if self.poses is not None:
                raise ValueError("'poses' needs 'count' (a fleet); a single robot uses 'pose'")
            return self
        if not templated:
            raise ValueError(f"a fleet (count: {self.count}) needs '{{i}}' in its name, e.g. '{self.name}_{{i}}'")
        if self.namespace is not None:
            raise ValueError("a fleet cannot share one 'namespace': each robot gets /<name>")
        if self.poses is None or len(self.poses) != self.count:
            got = "none" if self.poses is None else len(self.poses)
            raise ValueError(f"a fleet of count {self.count} needs {self.count} 'poses' ([x, y, yaw] each), got {got}")
        return self


class Ros2Spec(Strict):
    """``ros2:``: join a ROS 2 domain as a node (as `--ros2` does), publishing what the bag records."""

    enabled: bool = True
    node: str = "mobot"
    namespace: str = "/"
    domain_id: Optional[int] = None  # default: ROS_DOMAIN_ID, else 0
    cmd_vel_timeout: Optional[PositiveFloat] = None  # s; none: a command holds until the next
    ignore_fastdds_type_information: bool = True
    world_frame: bool = True  # false: no world -> <prefix>odom (slam_toolbox or AMCL publish map -> odom)

    @field_validator("domain_id")
    @classmethod
    def _domain(cls, v: Optional[int]) -> Optional[int]:
        if v is not None and not 0 <= v <= 232:
            raise ValueError(f"{v} is not a ROS 2 domain id: use 0 to 232 (0 to 101 is safe on every system)")
        return v

    @field_validator("node")
    @classmethod
    def _node(cls, v: str) -> str:
        if not NAME_RE.match(v):
            raise ValueError(f"'{v}' is not a valid ROS 2 node name: use letters, digits and '_', "
                             "not starting with a digit")
        return v

    @field_validator("namespace")
    @classmethod
    def _namespace(cls, v: str) -> str:
        if v != "/" and not NAMESPACE_RE.match(v):
            raise ValueError(f"'{v}' is not a valid ROS 2 namespace: '/' or names of letters, digits "
                             "and '_' separated by '/', e.g. /sim")
        return v


class EventSpec(Strict):
    """At ``at`` seconds, spawn one robot or delete one by name."""

    at: NonNegativeFloat
    spawn: Optional[RobotSpec] = None
    delete: Optional[str] = None

    @model_validator(mode="after")
    def _one_action(self) -> "EventSpec":
        if (self.spawn is None) == (self.delete is None):
            raise ValueError("an event needs exactly one of 'spawn' or 'delete'")
        if self.spawn is not None and self.spawn.count is not None:
            raise ValueError("a spawn event spawns one robot: use one event per robot, not 'count'")
        return self


class Scenario(Strict):
    """A whole scenario file, version 1."""

    version: Literal[1]
    name: str = "scenario"
    world: str = "empty"
    # World models whose files are missing (Fuel includes, meshes) are left out with a warning.
    skip_missing: bool = False
    physics: PhysicsSpec = Field(default_factory=PhysicsSpec)
    duration: Annotated[float, Field(gt=0, le=1e6)]
    seed: Annotated[int, Field(ge=0, lt=2**32)] = 0
    settle: Annotated[float, Field(ge=0)] = 0.5
    log: LogSpec = Field(default_factory=LogSpec)
    robots: list[RobotSpec] = Field(default_factory=list)
    events: list[EventSpec] = Field(default_factory=list)
    expect: list[ExpectSpec] = Field(default_factory=list)
    ros2: Optional[Ros2Spec] = None

    @field_validator("name")
    @classmethod
    def _name(cls, v: str) -> str:
        if not re.match(r"^[A-Za-z0-9_.-]+$", v):
            raise ValueError(f"'{v}' is not a valid scenario name: use letters, digits, '_', '-' and '.'")
        return v
