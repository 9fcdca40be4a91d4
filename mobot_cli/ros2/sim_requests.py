"""simulation_interfaces requests as live-protocol requests, and live replies as their results.

mobot speaks the Jazzy layout of ros-simulation/simulation_interfaces (1.5.x: SpawnEntity with
``uri`` and ``resource_string`` fields of its own, ``Result.result`` a uint8). Every service is
one or a few requests of the live protocol (live/protocol.py), so a spawn through ROS 2 is the
spawn `mobot spawn` makes: the same checks, loader sandbox, limits and history. Nothing here
imports rclpy: the request objects only need the fields the .srv files name (tests pass
SimpleNamespaces), and the replies are plain values that ros2/sim_services.py puts into messages.
"""

from __future__ import annotations

import math
import re
from typing import Any

from mobot_cli.live.protocol import Refusal, Result

# simulation_interfaces/msg/SimulatorFeatures: what works here, no more.
FEATURES = {
    "SPAWNING": 0, "DELETING": 1, "SPAWNING_RESOURCE_STRING": 9, "ENTITY_STATE_GETTING": 10,
    "ENTITY_BOUNDS": 5, "ENTITY_STATE_SETTING": 11, "ENTITY_INFO_GETTING": 12, "SPAWNABLES": 14, "SIMULATION_RESET": 20,
    "SIMULATION_STATE_GETTING": 24,
    "SIMULATION_STATE_SETTING": 25, "SIMULATION_STATE_PAUSE": 26, "STEP_SIMULATION_SINGLE": 31,
    "STEP_SIMULATION_MULTIPLE": 32, "STEP_SIMULATION_ACTION": 33,
}
SPAWN_FORMATS = ("urdf", "xacro", "sdf")
CUSTOM_INFO = ("mobot live world (simulation_interfaces 1.5 Jazzy layout); ResetSimulation: SCOPE_ALL only; "
               "entities are robots; see docs/ros2.md")
# Result codes (msg/Result.msg) and the extra codes of the services that have them.
OK, NOT_FOUND, OPERATION_FAILED, FEATURE_UNSUPPORTED = 1, 2, 4, 0
SPAWN_CODES = range(101, 110)  # SpawnEntity's NAME_NOT_UNIQUE .. INVALID_POSE, numbered as the live Result
SET_STATE_INVALID_POSE = 101  # SetEntityState's INVALID_POSE
ALREADY_IN_TARGET_STATE = 101  # SetSimulationState's
STATE_STOPPED, STATE_PLAYING, STATE_PAUSED, STATE_QUITTING = 0, 1, 2, 3
SCOPE_DEFAULT, SCOPE_ALL = 0, 255
CATEGORY_ROBOT = 1
BOUNDS_EMPTY, BOUNDS_BOX = 0, 1
MAX_FILTER = 256  # characters of a GetEntities name filter
# Matching can take exponential time when a quantified group holds a quantifier or an alternation
# ((a+)+, (a|aa)*, ((a+))+); a name filter comes from anyone on the domain, so a pattern with a
# quantified group and any other quantifier or '|' is refused.
_QUANTIFIED_GROUP = re.compile(r"\)[*+?{]")
_QUANTIFIER = re.compile(r"(?<!\\)[*+?{|]")
DEFAULT_NAME = "entity"  # SpawnEntity with no name and allow_renaming: entity, entity_0, ...


def result_code(reply: dict[str, Any], service: str) -> tuple[int, str]:
    """(Result.result, Result.error_message) of a live reply for ``service``: the live codes that
    the standard has pass through; mobot's own (INVALID_REQUEST, LIMIT_EXCEEDED) become
    OPERATION_FAILED with their name in front of the message."""
    code, message = int(reply.get("code", OPERATION_FAILED)), str(reply.get("message", ""))
    if code <= OPERATION_FAILED:
        return code, message
    if service == "spawn_entity" and code in SPAWN_CODES:
        return code, message
    if service == "set_simulation_state" and code == ALREADY_IN_TARGET_STATE:  # made here, not by the world
        return code, message
    if service == "set_entity_state" and code == int(Result.INVALID_POSE):
        return SET_STATE_INVALID_POSE, message
    return OPERATION_FAILED, f"{reply.get('result', code)}: {message}"


def spawnables(sources: Any) -> tuple[list[tuple[str, str]], dict[str, Any]]:
    """GetSpawnables: (uri, description) of each bundled robot, and the reply. A client's
    ``sources`` are not searched (a live spawn reads only the folders it is allowed, and a path or
    URI names any other description); they are named in the message, which does not fail the call."""
    from mobot_cli.assets.description.describe import bundled_robot_names

    found = [(name, f"mobot's bundled robot '{name}' (xacro; its arguments are spawn's NAME:=VALUE)")
             for name in bundled_robot_names()]
    unsearched = [str(source) for source in sources or ()]
    message = ("sources not searched (spawn any other description by its path, file://, package:// or "
               f"model:// URI): {', '.join(unsearched)}") if unsearched else ""
    return found, {"ok": True, "code": OK, "message": message}


def refused(result: Result | int, message: str) -> dict[str, Any]:
    """A reply-shaped refusal made before anything is sent to the world."""
    code = int(result)
    return {"ok": False, "code": code, "result": getattr(result, "name", str(code)), "message": message}


def _finite(*values: float) -> bool:
    return all(math.isfinite(v) for v in values)


def pose_fields(pose: Any) -> dict[str, Any]:
    """A geometry_msgs/Pose as a live pose; z = 0 means 'on the floor' (mobot's z: auto).
    Refusal(INVALID_POSE) for a number that is not finite."""
    p, q = pose.position, pose.orientation
    if not _finite(p.x, p.y, p.z, q.x, q.y, q.z, q.w):
        raise Refusal(Result.INVALID_POSE, "the pose holds a number that is not finite (NaN or infinity)")
    return {"xyz": [p.x, p.y, "auto" if p.z == 0.0 else p.z], "quat": [q.x, q.y, q.z, q.w]}


def frame(header: Any) -> str | None:
    """A header's frame as the live reference frame: '' and 'world' are the world, else a robot."""
    return header.frame_id or None


def spawn(request: Any) -> dict[str, Any]:
    """SpawnEntity as live spawn fields (``uri`` wins over ``resource_string``, as the .srv says)."""
    if not request.uri and not request.resource_string:
        raise Refusal(Result.NO_RESOURCE, "SpawnEntity needs 'uri' or 'resource_string'; both are empty")
    name, renaming = request.name, bool(request.allow_renaming)
    if not name and renaming:
        name = DEFAULT_NAME
    fields: dict[str, Any] = {"name": name, "allow_renaming": renaming,
                              "pose": pose_fields(request.initial_pose.pose)}
    if request.uri:
        uri = request.uri
        fields["description"] = uri[len("file://"):] if uri.startswith("file://") else uri
    else:
        fields["urdf"] = request.resource_string
    if request.entity_namespace:
        fields["namespace"] = request.entity_namespace
    reference = frame(request.initial_pose.header)
    if reference is not None:
        fields["reference_frame"] = reference
    return fields


def set_state(request: Any) -> dict[str, Any]:
    """SetEntityState as live set_state fields (the acceleration is not simulated: ignored)."""
    state = request.state
    lin, ang = state.twist.linear, state.twist.angular
    if not _finite(lin.x, lin.y, lin.z, ang.x, ang.y, ang.z):
        raise Refusal(Result.INVALID_REQUEST, "the twist holds a number that is not finite")
    fields: dict[str, Any] = {"name": request.entity, "pose": pose_fields(state.pose),
                              "twist": {"linear": {"x": lin.x, "y": lin.y, "z": lin.z},
                                        "angular": {"x": ang.x, "y": ang.y, "z": ang.z}}}
    reference = frame(state.header)
    if reference is not None:
        fields["reference_frame"] = reference
    return fields


def entity_filter(filters: Any):
    """A function name -> bool for GetEntities' and GetEntitiesStates' EntityFilters; Refusal for
    what mobot cannot filter by (tags, bounds) or a pattern it will not run."""
    if list(filters.tags.tags):
        raise Refusal(Result.FEATURE_UNSUPPORTED, "mobot's entities have no tags: filter by name or category")
    if filters.bounds.type != BOUNDS_EMPTY or list(filters.bounds.points):
        raise Refusal(Result.FEATURE_UNSUPPORTED, "mobot does not filter entities by bounds")
    categories = [c.category for c in filters.categories]
    robots = not categories or CATEGORY_ROBOT in categories  # every entity mobot lists is a robot
    pattern = filters.filter
    if len(pattern) > MAX_FILTER:
        raise Refusal(Result.OPERATION_FAILED, f"the name filter has {len(pattern)} characters; at most {MAX_FILTER}")
    if _QUANTIFIED_GROUP.search(pattern) and len(_QUANTIFIER.findall(pattern)) > 1:
        raise Refusal(Result.OPERATION_FAILED, f"the name filter '{pattern}' nests quantifiers, which can take "
                      "exponential time to match: write it without a quantified group that holds a quantifier")
    try:
        compiled = re.compile(pattern)
    except re.error as exc:
        raise Refusal(Result.OPERATION_FAILED, f"the name filter '{pattern}' is not a regular expression: {exc}")
    return lambda name: robots and compiled.search(name) is not None


def set_simulation_state(state: int, now: str) -> list[tuple[str, dict[str, Any]]] | int:
    """The live requests that take the world from ``now`` ('playing'/'paused') to ``state``, or the
    result code when there is nothing to do (ALREADY_IN_TARGET_STATE)."""
    if state == STATE_PLAYING:
        return ALREADY_IN_TARGET_STATE if now == "playing" else [("resume", {})]
    if state == STATE_PAUSED:
        return ALREADY_IN_TARGET_STATE if now == "paused" else [("pause", {})]
    if state == STATE_STOPPED:  # "equivalent to pausing and resetting"
        return [("pause", {}), ("reset", {})]
    raise Refusal(Result.FEATURE_UNSUPPORTED, f"state {state}: mobot takes STATE_PLAYING (1), STATE_PAUSED (2) "
                  "and STATE_STOPPED (0, a pause and a reset); stop the world with `mobot stop`")


def state_code(reply: dict[str, Any]) -> int:
    """The SimulationState number of a live reply's state."""
    return int(reply.get("state_code", STATE_PLAYING))


def reset_scope(scope: int) -> None:
    """Refusal(FEATURE_UNSUPPORTED) for a scope other than everything (0 or 255)."""
    if scope not in (SCOPE_DEFAULT, SCOPE_ALL):
        raise Refusal(Result.FEATURE_UNSUPPORTED, f"reset scope {scope}: mobot resets everything at once "
                      "(SCOPE_DEFAULT 0 or SCOPE_ALL 255)")


def stamp(step: int, rate_hz: int) -> tuple[int, int]:
    """A step's sim time as (sec, nanosec), without float drift."""
    return divmod(step * 1_000_000_000 // rate_hz, 1_000_000_000)
