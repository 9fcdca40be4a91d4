"""Narrow unit tests of the live world's pieces: endpoints, result codes, naming, frames."""

from __future__ import annotations

import math
import os
import stat

import pytest

from mobot_cli.common.transforms import quat_from_rpy
from mobot_cli.errors import DescriptionError, ResourceError, ScenarioError, SpawnError, UsageError
from mobot_cli.live import endpoint, protocol, spawning
from mobot_cli.live.clock import Clock
from mobot_cli.live.protocol import Refusal, Result
from mobot_cli.live.schema import Spawn, normalize_namespace, parse
from mobot_cli.plan import SpawnPose
from mobot_cli.sim.state import RobotState


@pytest.mark.parametrize("text", ["tcp://127.0.0.1:5555", "tcp://127.0.0.2:1", "tcp://[::1]:5555",
                                  "tcp://localhost:5555", "tcp://127.0.0.1:*", "ipc:///tmp/m.sock"])
def test_local_endpoints_are_accepted(text):
    assert endpoint.check(text) == text


@pytest.mark.parametrize("text, message", [
    ("tcp://0.0.0.0:5555", "not a loopback address"),
    ("tcp://*:5555", "not a loopback address"),
    ("tcp://192.168.1.4:5555", "not a loopback address"),
    ("tcp://127.0.0.1", "is not tcp://HOST:PORT"),
    ("udp://127.0.0.1:5", "neither ipc:// nor tcp://"),
    ("inproc://x", "neither ipc:// nor tcp://"),
    ("ipc://" + "/x" * 60, "longer than 107 bytes"),
])
def test_other_endpoints_are_refused(text, message):
    with pytest.raises(UsageError, match=message):
        endpoint.check(text)


def test_bind_any_allows_every_interface():
    assert endpoint.check("tcp://0.0.0.0:5555", bind_any=True) == "tcp://0.0.0.0:5555"


def test_default_endpoint_and_private_runtime_folder(monkeypatch, tmp_path):
    monkeypatch.delenv("MOBOT_ENDPOINT", raising=False)
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    assert endpoint.default_endpoint() == f"ipc://{tmp_path}/mobot/mobot.sock"
    folder = endpoint.runtime_dir(create=True)
    assert stat.S_IMODE(folder.stat().st_mode) == 0o700
    monkeypatch.setenv("MOBOT_ENDPOINT", "tcp://127.0.0.1:7000")
    assert endpoint.default_endpoint() == "tcp://127.0.0.1:7000"
    monkeypatch.delenv("XDG_RUNTIME_DIR")
    assert endpoint.runtime_dir().name == f"mobot-{os.getuid()}"


def test_a_folder_others_can_write_is_refused(tmp_path):
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    with pytest.raises(UsageError, match="writable by other users"):
        endpoint.private_dir(shared)


def test_decode_limits_and_encode_refuses_nan():
    with pytest.raises(Refusal) as err:
        protocol.decode(b" " * (protocol.MAX_REQUEST_BYTES + 1))
    assert err.value.result == Result.INVALID_REQUEST
    assert protocol.decode(b'{"op": "ping"}') == {"op": "ping"}
    with pytest.raises(ValueError):
        protocol.encode({"x": math.nan})
    assert protocol.reply(3, Result.NOT_FOUND, "no") == {
        "id": 3, "ok": False, "result": "NOT_FOUND", "code": 2, "message": "no"}


def test_result_codes_match_simulation_interfaces():
    assert [(r.name, int(r)) for r in Result if 100 < r < 200] == [
        ("NAME_NOT_UNIQUE", 101), ("NAME_INVALID", 102), ("UNSUPPORTED_FORMAT", 103), ("NO_RESOURCE", 104),
        ("NAMESPACE_INVALID", 105), ("RESOURCE_PARSE_ERROR", 106), ("MISSING_ASSETS", 107),
        ("UNSUPPORTED_ASSETS", 108), ("INVALID_POSE", 109)]


@pytest.mark.parametrize("error, result", [
    (ResourceError("package 'x' not found"), Result.MISSING_ASSETS),
    (DescriptionError("the collision mesh 'package://a/b.stl' of link 'base' cannot be found: nope"),
     Result.MISSING_ASSETS),
    (DescriptionError("included file 'a.xacro' cannot be read: No such file"), Result.MISSING_ASSETS),
    (DescriptionError("XML syntax error: mismatched tag"), Result.RESOURCE_PARSE_ERROR),
    (SpawnError("robot 'r' reaches 3 cm into robot 'q'"), Result.INVALID_POSE),
    (ScenarioError("something else"), Result.OPERATION_FAILED),
])
def test_errors_map_to_result_codes(error, result):
    assert spawning.classify(error) == result


def request(**fields) -> Spawn:
    return parse({"op": "spawn", "name": "r", "description": "mobot", **fields})


def test_renaming_takes_the_first_free_suffix():
    assert spawning.final_name(request(), {"q"}) == "r"
    assert spawning.final_name(request(allow_renaming=True), {"r", "r_0", "r_2"}) == "r_1"
    with pytest.raises(Refusal) as err:
        spawning.final_name(request(), {"r"})
    assert err.value.result == Result.NAME_NOT_UNIQUE


@pytest.mark.parametrize("fields, result", [
    ({"name": "9r"}, Result.NAME_INVALID),
    ({"name": "a b"}, Result.NAME_INVALID),
    ({"name": "r" * 65}, Result.NAME_INVALID),  # longer than a scenario name may be (odom/<name>.csv)
    ({"namespace": "/"}, Result.NAMESPACE_INVALID),
    ({"namespace": "/a//b"}, Result.NAMESPACE_INVALID),
    ({"pose": {"x": 1, "xyz": [0, 0, 0]}}, Result.INVALID_POSE),
    ({"pose": {"xyz": [0, 0, 0], "quat": [0, 0, 0, 0]}}, Result.INVALID_POSE),
    ({"urdf": "<robot/>"}, Result.INVALID_REQUEST),
])
def test_spawn_request_checks(fields, result):
    with pytest.raises(Refusal) as err:
        request(**fields)
    assert err.value.result == result


def test_namespaces_normalize_like_spawn_entity():
    assert normalize_namespace("r1") == normalize_namespace("/r1/") == "/r1"
    assert request(namespace="fleet/r1").namespace == "fleet/r1"


def state(x, y, z, yaw) -> RobotState:
    return RobotState(0, 0, 0, 0, 0, 0, 0, x, y, z, 0.0, 0.0, yaw, 0, 0)


def test_a_pose_in_a_robots_frame():
    local = SpawnPose(xyz=(1.0, 0.5, 0.2), quat=quat_from_rpy(0, 0, 0.3))
    world = spawning.in_frame(local, state(2.0, 3.0, 0.1, math.pi / 2))
    assert world.xyz == pytest.approx((2.0 - 0.5, 3.0 + 1.0, 0.3))
    assert world.quat == pytest.approx(quat_from_rpy(0, 0, math.pi / 2 + 0.3))
    auto = spawning.in_frame(SpawnPose(xyz=(1.0, 0.0, 0.0), z_auto=True), state(0, 0, 0.5, 0))
    assert auto.z_auto and auto.xyz[:2] == pytest.approx((1.0, 0.0))


def test_clock_paces_and_drops_time_it_cannot_make_up():
    clock = Clock(dt=0.01, rtf=2.0, start=100.0)
    assert clock.due() == pytest.approx(100.005)
    assert Clock(dt=0.01, rtf=None).due() is None
    late = Clock(dt=0.01, rtf=1.0, start=0.0)  # monotonic() is far past 0: hopelessly behind
    late.stepped()
    assert late.lags == 1 and late.due() > late.start


def test_a_huge_name_is_refused_and_shortened_in_the_message():
    with pytest.raises(Refusal) as err:
        request(name="r" * 10_000)
    assert err.value.result == Result.NAME_INVALID and len(err.value.message) < 200
