"""simulation_interfaces requests to live requests and back (ros2/sim_requests.py), without rclpy,
and TwistStamped's CDR to the Twist inside it (what nav2 from Kilted on sends on cmd_vel)."""

from __future__ import annotations

import math
import re
import struct
from types import SimpleNamespace as NS

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.live.protocol import Refusal, Result
from mobot_cli.ros2 import sim_requests as sr
from mobot_cli.ros2.publisher import planar_twist, unstamped


def pose(x=0.0, y=0.0, z=0.0, q=(0.0, 0.0, 0.0, 1.0)):
    return NS(position=NS(x=x, y=y, z=z), orientation=NS(x=q[0], y=q[1], z=q[2], w=q[3]))


def spawn_request(**fields):
    base = dict(name="r", allow_renaming=False, uri="", resource_string="<robot/>", entity_namespace="",
                initial_pose=NS(header=NS(frame_id=""), pose=pose()))
    return NS(**{**base, **fields})


def filters(pattern="", categories=(), tags=(), bounds_type=0):
    return NS(filter=pattern, categories=[NS(category=c) for c in categories], tags=NS(tags=list(tags)),
              bounds=NS(type=bounds_type, points=[]))


def test_spawn_fields():
    fields = sr.spawn(spawn_request(uri="file:///tmp/a.urdf", entity_namespace="/ns",
                                    initial_pose=NS(header=NS(frame_id="base"), pose=pose(1.0, 2.0, 0.3))))
    assert fields == {"name": "r", "allow_renaming": False, "description": "/tmp/a.urdf", "namespace": "/ns",
                      "reference_frame": "base", "pose": {"xyz": [1.0, 2.0, 0.3], "quat": [0.0, 0.0, 0.0, 1.0]}}
    text = sr.spawn(spawn_request())
    assert text["urdf"] == "<robot/>" and "description" not in text and "reference_frame" not in text
    assert text["pose"]["xyz"][2] == "auto"  # z = 0: on the floor
    assert sr.spawn(spawn_request(name="", allow_renaming=True))["name"] == "entity"
    with pytest.raises(Refusal) as empty:
        sr.spawn(spawn_request(resource_string=""))
    assert empty.value.result == Result.NO_RESOURCE


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=7, max_size=7))
def test_a_pose_is_finite_or_refused_as_invalid_pose(values):
    request = pose(*values[:3], q=tuple(values[3:]))
    try:
        fields = sr.pose_fields(request)
    except Refusal as exc:
        assert exc.result == Result.INVALID_POSE and not all(math.isfinite(v) for v in values)
        return
    numbers = [v for v in fields["xyz"] + fields["quat"] if v != "auto"]
    assert all(math.isfinite(v) for v in numbers)


@pytest.mark.parametrize("service, live, expected", [
    ("spawn_entity", ("NAME_NOT_UNIQUE", 101), 101),
    ("spawn_entity", ("LIMIT_EXCEEDED", 901), 4),
    ("delete_entity", ("NOT_FOUND", 2), 2),
    ("set_entity_state", ("INVALID_POSE", 109), 101),
    ("step_simulation", ("INCORRECT_STATE", 3), 3),
    ("step_simulation", ("INVALID_REQUEST", 900), 4),
    ("get_entities", ("NAME_INVALID", 102), 4),
])
def test_result_codes_as_each_service_defines_them(service, live, expected):
    code, message = sr.result_code({"ok": False, "result": live[0], "code": live[1], "message": "why"}, service)
    assert code == expected
    assert message == ("why" if expected == live[1] or live[1] == 109 else f"{live[0]}: why")


def test_entity_filters():
    assert sr.entity_filter(filters("^r[0-9]$"))("r1") and not sr.entity_filter(filters("^r[0-9]$"))("r10")
    assert sr.entity_filter(filters(categories=[1]))("r1")  # CATEGORY_ROBOT
    assert not sr.entity_filter(filters(categories=[0, 4]))("r1")
    for bad, result in ((filters(tags=["a"]), Result.FEATURE_UNSUPPORTED),
                        (filters(bounds_type=3), Result.FEATURE_UNSUPPORTED),
                        (filters("(a+)+$"), Result.OPERATION_FAILED), (filters("(a|aa)*b"), Result.OPERATION_FAILED),
                        (filters("(x{1,9}){2}"), Result.OPERATION_FAILED),
                        (filters("[unclosed"), Result.OPERATION_FAILED),
                        (filters("a" * 300), Result.OPERATION_FAILED)):
        with pytest.raises(Refusal) as refused:
            sr.entity_filter(bad)
        assert refused.value.result == result


@settings(max_examples=300, deadline=None)
@given(st.text(max_size=40))
def test_any_name_filter_is_taken_or_refused_never_raised(pattern):
    try:
        accept = sr.entity_filter(filters(pattern))
    except Refusal as exc:
        assert exc.result == Result.OPERATION_FAILED
        return
    assert accept("r1") == (re.search(pattern, "r1") is not None)


def test_simulation_state_transitions():
    assert sr.set_simulation_state(1, "paused") == [("resume", {})]
    assert sr.set_simulation_state(1, "playing") == sr.ALREADY_IN_TARGET_STATE
    assert sr.set_simulation_state(2, "playing") == [("pause", {})]
    assert sr.set_simulation_state(0, "playing") == [("pause", {}), ("reset", {})]
    with pytest.raises(Refusal):
        sr.set_simulation_state(3, "playing")  # QUITTING: `mobot stop` ends a world, not any peer
    sr.reset_scope(0), sr.reset_scope(255)
    with pytest.raises(Refusal):
        sr.reset_scope(2)
    assert sr.stamp(7, 240) == (0, 29166666)


def stamped_cdr(frame: str, twist: tuple[float, ...], sec: int = 3, nanosec: int = 4) -> bytes:
    """A TwistStamped as rmw writes it: CDR little endian, the twist aligned to 8 after the header."""
    text = frame.encode() + b"\0"
    body = struct.pack("<iII", sec, nanosec, len(text)) + text
    body += b"\0" * (-len(body) % 8)
    return b"\x00\x01\x00\x00" + body + struct.pack("<6d", *twist)


@settings(max_examples=200, deadline=None)
@given(st.text(alphabet="abcxyz_/0123456789", max_size=30),
       st.lists(st.floats(-100, 100), min_size=6, max_size=6))
def test_the_twist_inside_a_twist_stamped(frame, twist):
    assert planar_twist(unstamped(stamped_cdr(frame, tuple(twist)))) == (twist[0], twist[1], twist[5])


@given(st.binary(max_size=120))
def test_bytes_that_are_no_twist_stamped_give_nothing_the_bridge_takes(data):
    out = unstamped(data)
    if out:
        assert len(out) == 52 and out[1] == 1  # a Twist's size: the bridge's checks take it from here
