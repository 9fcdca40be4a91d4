"""Typed live requests: every field checked before the world is touched.

Pose and xacro arguments reuse the scenario's own models, so a pose a scenario accepts is a
pose a spawn request accepts, with the same checks.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, Optional, Union

from pydantic import BaseModel, ConfigDict, Field, StrictInt, TypeAdapter, ValidationError

from mobot_cli.live.protocol import OPS, Refusal, Result
from mobot_cli.scenario.limits import (
    MAX_ANGULAR_SPEED,
    MAX_NAME_LENGTH,
    MAX_SECONDS,
    MAX_SPEED,
    AngularSpeed,
    Coordinate,
    at_most,
)
from mobot_cli.scenario.limits import Speed as LinearSpeed
from mobot_cli.scenario.model import NAME_RE, NAMESPACE_RE, HoldField, PoseSpec
from mobot_cli.scenario.mover_model import MoverSpec

MAX_NAME = 256
# A step request advances at most this many physics steps (11.5 h at 240 Hz); the world keeps
# answering other requests between them, so a big one delays its own reply only.
MAX_STEPS = 10_000_000
Name = Annotated[str, Field(min_length=1, max_length=MAX_NAME)]
# Request fields whose problems have their own result code (SpawnEntity's, SetEntityState's).
FIELD_RESULTS = {"spawn": {"name": Result.NAME_INVALID, "namespace": Result.NAMESPACE_INVALID,
                           "pose": Result.INVALID_POSE},
                 "set_state": {"pose": Result.INVALID_POSE}}


class Request(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)

    id: Any = None


class Ping(Request):
    op: Literal["ping"]


class ListRobots(Request):
    op: Literal["list"]


class Stop(Request):
    op: Literal["stop"]


class Delete(Request):
    op: Literal["delete"]
    name: Name


class Odom(Request):
    op: Literal["odom"]
    name: Name


class Scan(Request):
    op: Literal["scan"]
    name: Name
    sensor: Optional[Name] = None  # default: the robot's first lidar, else its first sensor


class Cmd(Request):
    op: Literal["cmd"]
    name: Name
    linear: LinearSpeed = 0.0  # the scenario's bounds (docs/errors.md "Limits")
    angular: AngularSpeed = 0.0
    for_: Optional[Annotated[float, Field(gt=0, le=1e6)]] = Field(default=None, alias="for")
    wait: bool = False  # with 'for': reply when the command has ended
    linear_y: LinearSpeed = 0.0  # sideways (+ left): holonomic drives only

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True, populate_by_name=True)


class Goto(Request):
    op: Literal["goto"]
    name: Name
    x: Coordinate  # the goal, in the world frame
    y: Coordinate
    yaw: Optional[float] = None  # turn to this heading once there
    tolerance: Optional[Annotated[float, Field(gt=0)]] = None  # m
    timeout: Optional[Annotated[float, Field(gt=0, le=1e6)]] = None  # simulated s
    localization: Optional[Literal["odometry", "ground_truth"]] = None
    max_linear: Optional[Annotated[float, Field(gt=0), at_most(MAX_SPEED, "m/s")]] = None
    max_angular: Optional[Annotated[float, Field(gt=0), at_most(MAX_ANGULAR_SPEED, "rad/s")]] = None
    wait: bool = False  # reply when the goal has ended
    planner: Optional[Literal["astar"]] = None  # plan around the world's obstacles (timeline/routes.py)
    inflation: Optional[Annotated[float, Field(ge=0, le=10)]] = None  # m; default: the robot's footprint radius


class Spawn(Request):
    op: Literal["spawn"]
    name: str
    description: Optional[Name] = None  # a bundled name, a path, or a package:// URI
    urdf: Optional[str] = None  # URDF or xacro text (mobot spawn --string / --stdin)
    args: dict[str, Union[str, bool, int, float]] = Field(default_factory=dict)
    pose: PoseSpec = Field(default_factory=PoseSpec)
    namespace: Optional[str] = None  # default /<final name>
    reference_frame: Optional[str] = None  # a robot's name; None, "" or "world": the world
    allow_renaming: bool = False
    base_dir: Optional[str] = None  # the client's folder: relative paths resolve against it
    hold: HoldField = None  # joints held as a scenario's robot holds them (docs/scenarios.md)


class Pause(Request):
    op: Literal["pause"]


class Resume(Request):
    op: Literal["resume"]


class Features(Request):
    op: Literal["features"]


class Reset(Request):
    op: Literal["reset"]
    scope: StrictInt = 0  # ResetSimulation's: 0 (default) and 255 (all) are the same, all this server does


class Step(Request):
    """StepSimulation: ``steps`` physics steps (default 1) or ``seconds`` of them, while paused."""

    op: Literal["step"]
    steps: Optional[Annotated[StrictInt, Field(ge=1, le=MAX_STEPS)]] = None
    seconds: Optional[Annotated[float, Field(gt=0, le=MAX_SECONDS)]] = None
    states: bool = True  # the reply carries every robot's pose and twist


# A teleport's twist: far past any wheeled robot, short of what makes PyBullet's state blow up.
Speed = Annotated[float, Field(ge=-1000.0, le=1000.0)]


class Vector(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)

    x: Speed = 0.0
    y: Speed = 0.0
    z: Speed = 0.0


class Twist(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)

    linear: Vector = Vector()  # m/s
    angular: Vector = Vector()  # rad/s


class GetState(Request):
    op: Literal["get_state"]
    name: Name
    reference_frame: Optional[str] = None  # a robot's name; None, "" or "world": the world


class SetState(Request):
    """SetEntityState: a teleport, checked like a spawn; the twist defaults to rest."""

    op: Literal["set_state"]
    name: Name
    pose: PoseSpec
    twist: Twist = Twist()
    reference_frame: Optional[str] = None


class SpawnMover(Request):
    """A mover enters now (docs/movers.md): ``mover`` as a scenario's ``movers:`` item, one mover, now."""

    op: Literal["spawn_mover"]
    mover: MoverSpec


class DeleteMover(Request):
    op: Literal["delete_mover"]
    name: Name


AnyRequest = Annotated[Union[Ping, ListRobots, Stop, Delete, Odom, Scan, Cmd, Goto, Spawn, Pause, Resume,
                             Features, Reset, Step, GetState, SetState, SpawnMover, DeleteMover],
                       Field(discriminator="op")]
_ADAPTER: TypeAdapter = TypeAdapter(AnyRequest)


def parse(document: dict[str, Any]) -> Request:
    """A decoded request to its typed form, or a Refusal saying which field is wrong."""
    op = document["op"]
    if op not in OPS:
        shown = op if len(op) <= 60 else op[:57] + "..."
        raise Refusal(Result.FEATURE_UNSUPPORTED, f"unknown request op '{shown}': this server knows "
                      + ", ".join(OPS))
    try:
        request = _ADAPTER.validate_python(document)
    except ValidationError as exc:
        err = exc.errors()[0]
        loc = [str(part) for part in err["loc"][1:]]  # [0] is the union tag
        field = ".".join("for" if part == "for_" else part for part in loc) or "request"
        message = err["msg"].removeprefix("Value error, ")
        result = Result.INVALID_REQUEST
        special = FIELD_RESULTS.get(document["op"], {})
        if loc and loc[0] in special and err["type"] != "missing":
            result = special[loc[0]]
        raise Refusal(result, f"{document['op']} request, field '{field}': {message}") from None
    if isinstance(request, Spawn):
        check_spawn(request)
    elif isinstance(request, Step) and request.steps is not None and request.seconds is not None:
        raise Refusal(Result.INVALID_REQUEST, "a step request gives 'steps' or 'seconds', not both")
    elif isinstance(request, Reset) and request.scope not in (0, 255):
        raise Refusal(Result.FEATURE_UNSUPPORTED, f"reset scope {request.scope}: this server resets "
                      "everything at once (scope 0 or 255, SCOPE_ALL)")
    return request


def check_spawn(request: Spawn) -> None:
    """What a spawn request must hold beyond its field types."""
    if not NAME_RE.match(request.name) or len(request.name) > MAX_NAME_LENGTH:
        shown = request.name if len(request.name) <= 60 else request.name[:57] + "..."
        raise Refusal(Result.NAME_INVALID, f"'{shown}' is not a valid robot name: use letters, "
                      f"digits and '_', not starting with a digit, at most {MAX_NAME_LENGTH} characters")
    if request.namespace is not None and not NAMESPACE_RE.match(normalize_namespace(request.namespace)):
        raise Refusal(Result.NAMESPACE_INVALID, f"'{request.namespace}' is not a valid ROS namespace: "
                      "names of letters, digits and '_' separated by '/', e.g. /robot1")
    if (request.description is None) == (request.urdf is None):
        raise Refusal(Result.INVALID_REQUEST, "a spawn request needs exactly one of 'description' "
                      "(a bundled name or a file) and 'urdf' (the text)")


def normalize_namespace(namespace: str) -> str:
    """'r1' and '/r1/' mean '/r1', as spawn_entity.py's -robot_namespace takes them."""
    return "/" + namespace.strip("/")
