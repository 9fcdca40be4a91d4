"""The typed scenario, version 1: what a user may write, validated at load.

Field names and defaults here are the scenario format; DESIGN.md shows an example.
Checks that need more than one field (pose forms, fleets, command order) live in validators
so that a scenario which constructs is one that can be resolved.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal, Optional, Union

from pydantic import AfterValidator, BaseModel, ConfigDict, Discriminator, Field, Tag, field_validator, model_validator

from mobot_cli.errors import shown
from mobot_cli.scenario.expect_model import ExpectSpec
from mobot_cli.scenario.goal_model import GoalFields
from mobot_cli.scenario.limits import (
    FLEET_NAME_RE,
    MAX_COORDINATE,
    MAX_MULTIPLIER,
    MAX_NAMESPACE_LENGTH,
    MAX_RATE_HZ,
    MAX_SPEED,
    MAX_WHEEL_ACCELERATION,
    MAX_WHEEL_RADIUS,
    MAX_WHEEL_SEPARATION,
    MAX_WHEEL_TORQUE,
    MIN_LOG_RATE_HZ,
    NAME_RE,  # noqa: F401 - live/schema.py imports the name rule from here
    NAMESPACE_RE,
    SCENARIO_NAME_RE,
    AngularSpeed,
    Coordinate,
    Duration,
    Float,
    Int,
    PositiveFloat,
    Reference,
    Seconds,
    Speed,
    Vector3,
    at_most,
    check_engine,
    check_name,
    gravity_length,
)
from mobot_cli.scenario.mover_model import MoverSpec
from mobot_cli.scenario.sensor_model import SensorEntry, SensorKey
from mobot_cli.scenario.world_model import GeneratedWorld

# ``world:`` is a name or path, or a mapping ``{generate: ...}``; the tags never reach a message
# (scenario/load.py drops them from error locations).
WORLD_TAGS = ("world_file", "world_generate")


def _world_form(value: object) -> str:
    return WORLD_TAGS[1] if isinstance(value, (dict, GeneratedWorld)) else WORLD_TAGS[0]


WorldField = Annotated[Union[Annotated[Reference, Tag(WORLD_TAGS[0])], Annotated[GeneratedWorld, Tag(WORLD_TAGS[1])]],
                       Discriminator(_world_form)]


class Strict(BaseModel):
    """Base: unknown keys and NaN/inf numbers are errors."""

    # defer_build: the validators are built once, for the whole Scenario, when the first scenario
    # is validated, not model by model at import (a process that never validates never builds).
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True, defer_build=True)


class PhysicsSpec(Strict):
    rate_hz: Annotated[Int, Field(gt=0, le=MAX_RATE_HZ)] = 240
    gravity: Annotated[Vector3, AfterValidator(gravity_length)] = (0.0, 0.0, -9.81)
    solver_iterations: Annotated[Int, Field(gt=0, le=1000)] = 50
    engine: Annotated[str, AfterValidator(check_engine)] = "bullet"
    renderer: Literal["auto", "tiny", "egl"] = "auto"  # cameras (docs/cameras.md)


class FaultsSpec(Strict):
    """``faults:``: when a robot's motion ends the run as a fault, and the odometry tolerance
    (docs/faults.md); the defaults suit ground robots."""

    max_tilt: Annotated[Float, Field(gt=0, le=180)] = 60.0  # degrees of roll or pitch: tipped over
    flying_time: Duration = 1.0  # s touching nothing while above its last support: flying
    max_speed: Annotated[Float, Field(gt=0, le=MAX_SPEED * 10)] = 20.0  # m/s: runaway speed
    odom_tolerance: Annotated[Float, Field(gt=0, le=MAX_COORDINATE)] = 0.25  # m, odometry vs truth


class LogSpec(Strict):
    # None: about 50 Hz, rounded down to a whole number of physics steps (48 Hz at 240 Hz).
    rate_hz: Optional[Annotated[Float, Field(ge=MIN_LOG_RATE_HZ, le=MAX_RATE_HZ)]] = None
    formats: list[Literal["csv", "mcap"]] = ["csv"]  # mcap: DIR/bag/
    # the bag's camera images: raw (sensor_msgs/Image), or compressed on image_raw/compressed
    images: Literal["raw", "png", "jpeg"] = "raw"


class PoseSpec(Strict):
    """A spawn pose: {x, y, z, roll, pitch, yaw}, {xyz, rpy} or {xyz, quat: [x, y, z, w]}."""

    x: Optional[Coordinate] = None
    y: Optional[Coordinate] = None
    z: Union[Coordinate, Literal["auto"], None] = None
    roll: Optional[Float] = None
    pitch: Optional[Float] = None
    yaw: Optional[Float] = None
    xyz: Optional[tuple[Coordinate, Coordinate, Union[Coordinate, Literal["auto"]]]] = None
    rpy: Optional[Vector3] = None
    quat: Optional[tuple[Float, Float, Float, Float]] = None

    @model_validator(mode="after")
    def _one_form(self) -> "PoseSpec":
        flat = [k for k in ("x", "y", "z", "roll", "pitch", "yaw") if getattr(self, k) is not None]
        if self.xyz is None and (self.rpy is not None or self.quat is not None):
            raise ValueError("'rpy' and 'quat' need 'xyz' beside them")
        if self.xyz is not None and flat:
            raise ValueError(f"mixes the xyz form with '{flat[0]}': "
                             "use either x/y/z/roll/pitch/yaw or xyz with rpy or quat")
        if self.rpy is not None and self.quat is not None:
            raise ValueError("gives both 'rpy' and 'quat': use one")
        if self.quat is not None and math.sqrt(sum(q * q for q in self.quat)) < 1e-9:
            raise ValueError("quat has zero length: give [x, y, z, w], e.g. [0, 0, 0, 1]")
        return self


class DriveOverrides(Strict):
    """Anything detected from the URDF can be overridden here."""

    # None: as detected. "diff_drive" is the older spelling of "diff"; "holonomic" is mecanum or
    # omni (scenario/robots.py, drive_kind); "ackermann" must be what is detected.
    type: Optional[Literal["diff", "diff_drive", "holonomic", "ackermann"]] = None
    odometry: Optional[Literal["encoder", "ground_truth"]] = None  # None: as detected (encoder for most)
    left_joints: Optional[list[str]] = None
    right_joints: Optional[list[str]] = None
    wheel_radius: Optional[Annotated[PositiveFloat, at_most(MAX_WHEEL_RADIUS, "m")]] = None
    wheel_separation: Optional[Annotated[PositiveFloat, at_most(MAX_WHEEL_SEPARATION, "m")]] = None
    wheel_separation_multiplier: Optional[
        Annotated[PositiveFloat, at_most(MAX_MULTIPLIER, "", 1 / MAX_MULTIPLIER)]] = None
    wheel_radius_multiplier: Optional[Annotated[PositiveFloat, at_most(MAX_MULTIPLIER, "", 1 / MAX_MULTIPLIER)]] = None
    max_wheel_torque: Optional[Annotated[PositiveFloat, at_most(MAX_WHEEL_TORQUE, "N m")]] = None
    max_wheel_acceleration: Optional[Annotated[PositiveFloat, at_most(MAX_WHEEL_ACCELERATION, "rad/s^2")]] = None
    twist_feedback: Optional[bool] = None
    # holonomic and ackermann: metres between the axles; ackermann: the bicycle model's largest
    # steering angle (rad)
    wheelbase: Optional[Annotated[PositiveFloat, at_most(MAX_WHEEL_SEPARATION, "m")]] = None
    max_steering_angle: Optional[Annotated[PositiveFloat, Field(lt=math.pi / 2)]] = None


class CommandSpec(GoalFields):
    """From ``at`` on, drive with this twist (``for`` ends it with a stop) or toward one goal.

    Without ``at`` a command starts when the one before it ends (a goal, or a twist's ``for``);
    a command after a goal starts at ``at`` or when the goal ends, whichever is later.
    """

    at: Optional[Seconds] = None
    linear: Speed = 0.0
    angular: AngularSpeed = 0.0
    # a car's steering angle (rad, + left) instead of angular: angular = linear tan(it) / wheelbase
    steering_angle: Optional[Annotated[Float, Field(gt=-math.pi / 2, lt=math.pi / 2)]] = None
    linear_y: Speed = 0.0  # sideways, m/s (+ left): holonomic drives only
    for_: Optional[Duration] = Field(default=None, alias="for")

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True, populate_by_name=True, defer_build=True)

    @model_validator(mode="after")
    def _twist_or_goal(self) -> "CommandSpec":
        given = self.model_fields_set
        self.check_goal([k.rstrip("_") for k in ("linear", "angular", "steering_angle", "linear_y", "for_")
                         if k in given])
        if "angular" in given and self.steering_angle is not None:
            raise ValueError("gives both 'angular' and 'steering_angle': a car turns by one of them")
        return self


# Joints a position controller holds, as a vendor's plugin does in Gazebo (an arm): "all" holds every
# joint the description leaves free where it starts (0), {joint: position} the ones named. A
# scenario's robot, a live spawn and the Python API's spawn take it.
HoldField = Union[Literal["all"], dict[str, Annotated[Float, Field(ge=-1000, le=1000)]], None]


class RobotSpec(Strict):
    name: str
    namespace: Optional[str] = None
    description: Reference = "mobot"
    # Empty defaults are values, not default_factory=list/dict: pydantic copies a default for each
    # model, and a builtin factory costs it a parse of the builtin's text signature.
    args: dict[str, Union[str, bool, int, float]] = {}
    pose: PoseSpec = PoseSpec.model_construct()  # all defaults (see Scenario.physics)
    drive: Optional[DriveOverrides] = None
    hold: HoldField = None  # see HoldField
    sensors: dict[SensorKey, SensorEntry] = {}  # see sensor_model.py
    commands: list[CommandSpec] = []
    count: Optional[Annotated[Int, Field(ge=1, le=1000)]] = None
    poses: Optional[list[tuple[Coordinate, Coordinate, Float]]] = None

    @field_validator("name")
    @classmethod
    def _name(cls, v: str) -> str:
        # '{i}' becomes at most 3 digits (count <= 1000): a fleet's names are no longer than its template.
        return check_name(v, "robot", FLEET_NAME_RE, "use letters, digits and '_', not starting with a "
                                                    "digit ('{i}' allowed in fleets)")

    @field_validator("namespace")
    @classmethod
    def _namespace(cls, v: Optional[str]) -> Optional[str]:
        if v is not None and len(v) > MAX_NAMESPACE_LENGTH:
            raise ValueError(f"{shown(v, 40)} is not a valid ROS namespace: it is {len(v)} characters long, "
                             f"the limit is {MAX_NAMESPACE_LENGTH}")
        if v is not None and not NAMESPACE_RE.match(v):
            raise ValueError(f"{shown(v, 40)} is not a valid ROS namespace: it must start with '/' and "
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
    map: bool = False  # true: the world's occupancy grid on /map (as `mobot map` makes it), transient local

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

    at: Seconds
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
    world: WorldField = "empty"  # a bundled name, a file, or {generate: ...} (world_model.py)
    # World models whose files are missing (Fuel includes, meshes) are left out with a warning.
    skip_missing: bool = False
    # All defaults, made once without validating them (frozen: one serves every scenario).
    # default_factory=PhysicsSpec made the first scenario without ``physics:`` build PhysicsSpec's
    # own validator (defer_build) apart from the Scenario's.
    physics: PhysicsSpec = PhysicsSpec.model_construct()
    duration: Duration
    seed: Annotated[Int, Field(ge=0, lt=2**32)] = 0
    settle: Seconds = 0.5
    log: LogSpec = LogSpec.model_construct()  # all defaults (see physics)
    faults: FaultsSpec = FaultsSpec.model_construct()  # all defaults (see physics)
    robots: list[RobotSpec] = []
    events: list[EventSpec] = []
    expect: list[ExpectSpec] = []
    ros2: Optional[Ros2Spec] = None
    movers: list[MoverSpec] = []  # docs/movers.md

    @field_validator("name")
    @classmethod
    def _name(cls, v: str) -> str:
        return check_name(v, "scenario", SCENARIO_NAME_RE, "use letters, digits, '_', '-' and '.'")
