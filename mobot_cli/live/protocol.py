"""The live world's wire format: one JSON object per message, result codes as in ROS.

A request is ``{"op": OP, "id": ANY, ...fields}``; the reply echoes ``id`` and carries
``ok``, ``result`` (a name below) and ``message``, plus the op's own fields. Result names
and numbers follow ROS 2's simulation_interfaces (``msg/Result`` and ``srv/SpawnEntity``),
with ``INVALID_REQUEST`` added for messages that are not a valid request at all and
``LIMIT_EXCEEDED`` for a spawn beyond a bound the server sets (``mobot serve --max-...``).
This module stays light (no pydantic, no zmq) so the CLI client imports it cheaply.
"""

from __future__ import annotations

import json
import math
from enum import IntEnum
from typing import Any

from mobot_cli.common.files import json_default

PROTOCOL_VERSION = 1
# A request larger than this is refused with INVALID_REQUEST (robot descriptions sent with
# --string are the only big ones; 4 MiB holds any URDF in the corpus many times over).
MAX_REQUEST_BYTES = 4 * 1024 * 1024
# Larger frames are dropped by ZeroMQ itself before they reach Python (memory safety).
HARD_LIMIT_BYTES = 64 * 1024 * 1024
# JSON nested deeper than this is refused (no request needs more than a few levels).
MAX_DEPTH = 32

OPS = ("ping", "spawn", "delete", "list", "cmd", "odom", "scan", "stop", "goto",
       "pause", "resume", "step", "reset", "get_state", "set_state", "features", "spawn_mover", "delete_mover")


class SimulationState(IntEnum):
    """The world's state, as simulation_interfaces' ``msg/SimulationState``."""

    STOPPED = 0
    PLAYING = 1
    PAUSED = 2
    QUITTING = 3


class Feature(IntEnum):
    """What this server supports, as simulation_interfaces' ``msg/SimulatorFeatures`` numbers them."""

    SPAWNING = 0  # spawn
    DELETING = 1  # delete
    SPAWNING_RESOURCE_STRING = 9  # spawn with 'urdf' text
    ENTITY_STATE_GETTING = 10  # get_state
    ENTITY_STATE_SETTING = 11  # set_state
    SIMULATION_RESET = 20  # reset (the whole scope only: SCOPE_ALL)
    SIMULATION_STATE_SETTING = 25  # pause, resume
    SIMULATION_STATE_PAUSE = 26
    STEP_SIMULATION_SINGLE = 31  # step with steps = 1
    STEP_SIMULATION_MULTIPLE = 32  # step with steps > 1 (or seconds)


class Result(IntEnum):
    """Outcome of a request; names and numbers as in simulation_interfaces."""

    FEATURE_UNSUPPORTED = 0  # an op the server does not know
    OK = 1
    NOT_FOUND = 2  # no robot (or reference frame) of that name
    INCORRECT_STATE = 3  # the world is in the wrong state for it (step while playing, shutting down)
    OPERATION_FAILED = 4  # anything else that went wrong
    NAME_NOT_UNIQUE = 101
    NAME_INVALID = 102
    UNSUPPORTED_FORMAT = 103
    NO_RESOURCE = 104
    NAMESPACE_INVALID = 105
    RESOURCE_PARSE_ERROR = 106
    MISSING_ASSETS = 107
    UNSUPPORTED_ASSETS = 108
    INVALID_POSE = 109
    INVALID_REQUEST = 900  # not in simulation_interfaces: malformed, oversized, bad fields
    LIMIT_EXCEEDED = 901  # not in simulation_interfaces: beyond a bound of `mobot serve` (faces, links, robots)


class Refusal(Exception):
    """A request the server refuses; becomes a reply with ``ok: false``."""

    def __init__(self, result: Result, message: str):
        super().__init__(message)
        self.result = result
        self.message = message


def encode(document: dict[str, Any]) -> bytes:
    """One message: compact UTF-8 JSON; NaN and infinity are not JSON and never sent (ValueError)."""
    return json.dumps(document, separators=(",", ":"), allow_nan=False, default=json_default).encode()


def encode_reply(answer: dict[str, Any]) -> bytes:
    """A reply's bytes; never raises: a reply that cannot be encoded becomes OPERATION_FAILED."""
    try:
        return encode(answer)
    except Exception as exc:  # noqa: BLE001 - whatever a reply holds, the peer gets an answer
        problem = f"the reply could not be encoded as JSON: {exc!r}"[:300]
    for request_id in (answer.get("id"), None):
        try:
            return encode(reply(request_id, Result.OPERATION_FAILED, problem))
        except Exception:  # noqa: BLE001 - the id itself cannot be encoded: answer without it
            continue
    return encode(reply(None, Result.OPERATION_FAILED, "the reply could not be encoded as JSON"))


def encode_request(document: dict[str, Any]) -> bytes:
    """A request's bytes; Refusal(INVALID_REQUEST), as the server would refuse it, for a number that
    is not finite (JSON has none: it could not be sent) or a request over MAX_REQUEST_BYTES."""
    try:
        frame = encode(document)
    except ValueError:
        bad = _non_finite(document)
        if bad is None:
            raise
        raise Refusal(Result.INVALID_REQUEST, _not_finite(repr(bad))) from None
    check_size(frame)
    return frame


def check_size(frame: bytes) -> None:
    """Refusal(INVALID_REQUEST) for a request larger than MAX_REQUEST_BYTES (the server's check,
    which a client makes too: the server cannot read the id of a request it will not parse)."""
    if len(frame) > MAX_REQUEST_BYTES:
        raise Refusal(Result.INVALID_REQUEST, f"request of {len(frame)} bytes is larger than the "
                      f"limit of {MAX_REQUEST_BYTES} bytes")


def decode(frame: bytes) -> dict[str, Any]:
    """Parse one request; Refusal(INVALID_REQUEST) for anything but a JSON object with an op."""
    check_size(frame)
    try:
        document = json.loads(frame.decode("utf-8"), parse_constant=_no_constant, parse_float=_finite)
    except _NotFinite as exc:
        raise Refusal(Result.INVALID_REQUEST, str(exc)) from None
    except (UnicodeDecodeError, ValueError) as exc:
        raise Refusal(Result.INVALID_REQUEST, f"request is not UTF-8 JSON: {str(exc)[:200]}") from None
    except RecursionError:
        raise Refusal(Result.INVALID_REQUEST, f"request nests deeper than {MAX_DEPTH} levels") from None
    if not _shallow(document):
        raise Refusal(Result.INVALID_REQUEST, f"request nests deeper than {MAX_DEPTH} levels")
    if not isinstance(document, dict):
        raise Refusal(Result.INVALID_REQUEST, "a request must be a JSON object with an 'op'")
    op = document.get("op")
    if not isinstance(op, str):
        raise Refusal(Result.INVALID_REQUEST, "a request needs 'op', a string: one of " + ", ".join(OPS))
    return document


def decode_reply(frame: bytes) -> dict[str, Any] | None:
    """A reply document, or None for a frame that is not one (the client skips it)."""
    try:
        document = json.loads(frame.decode("utf-8"))
    except (UnicodeDecodeError, ValueError):
        return None
    return document if isinstance(document, dict) else None


def reply(request_id: Any, result: Result = Result.OK, message: str = "", **fields: Any) -> dict[str, Any]:
    """A reply document; ``ok`` is true only for Result.OK."""
    return {"id": request_id, "ok": result == Result.OK, "result": result.name, "code": int(result),
            "message": message, **fields}


def _no_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a number JSON allows")


class _NotFinite(ValueError):
    pass


def _finite(text: str) -> float:
    """json's float parsing, refusing what overflows to infinity (1e999)."""
    value = float(text)
    if not math.isfinite(value):
        raise _NotFinite(_not_finite(text))
    return value


def _not_finite(text: str) -> str:
    shown = text if len(text) <= 40 else text[:37] + "..."
    return f"request has the number {shown}, which is not finite as a float: numbers must be finite"


def _non_finite(document: Any) -> float | None:
    """The first number in ``document`` that is not finite, if any."""
    stack = [document]
    while stack:
        value = stack.pop()
        if isinstance(value, float) and not math.isfinite(value):
            return value
        if isinstance(value, dict):
            stack.extend(value.values())
        elif isinstance(value, (list, tuple)):
            stack.extend(value)
    return None


def _shallow(document: Any) -> bool:
    """True when no list or object nests deeper than MAX_DEPTH."""
    stack = [(document, 1)]
    while stack:
        value, depth = stack.pop()
        if isinstance(value, (dict, list)):
            if depth > MAX_DEPTH:
                return False
            stack.extend((item, depth + 1) for item in (value.values() if isinstance(value, dict) else value))
    return True
