"""The live server survives bad peers: malformed, oversized and unknown requests, vanishing and
slow clients, floods of requests; it keeps stepping and keeps answering everyone else."""

from __future__ import annotations

import json
import threading
import time

import pytest
import zmq

from mobot_cli.cli import invoke
from mobot_cli.live.client import Client
from mobot_cli.live.protocol import HARD_LIMIT_BYTES, MAX_REQUEST_BYTES
from tests.live.live_server import fast_world, wait_for_step


@pytest.fixture(scope="module")
def live(tmp_path_factory):
    with fast_world(tmp_path_factory) as server:
        yield server


@pytest.fixture
def raw(live):
    """A bare DEALER socket, to send what no well-behaved client would."""
    socket = zmq.Context.instance().socket(zmq.DEALER)
    socket.setsockopt(zmq.LINGER, 0)
    socket.setsockopt(zmq.RCVTIMEO, 10_000)
    socket.connect(live.endpoint)
    yield socket
    socket.close()


def exchange(socket, *frames: bytes) -> dict:
    socket.send_multipart([b"", *frames])
    return json.loads(socket.recv_multipart()[-1])


def still_serving(live) -> None:
    with live.client(timeout=10) as client:
        assert client.ping()["ok"]


@pytest.mark.parametrize("frame, text", [
    (b"not json", "request is not UTF-8 JSON"),
    (b"\xff\xfe\x00", "request is not UTF-8 JSON"),
    (b"", "request is not UTF-8 JSON"),
    (b"[1, 2, 3]", "a request must be a JSON object"),
    (b'{"id": 1}', "a request needs 'op'"),
    (b'{"op": 5}', "a request needs 'op'"),
    (b'{"op": "cmd", "name": "x", "linear": NaN}', "NaN is not a number JSON allows"),
    (b'{"op": "list", "verbose": true}', "field 'verbose': Extra inputs are not permitted"),
    (b'{"op": "spawn"}', "field 'name': Field required"),
    (b'{"op": "cmd", "name": "x", "linear": "fast"}', "field 'linear': Input should be a valid number"),
    (b'{"op": "cmd", "name": "x", "for": -1}', "field 'for': Input should be greater than 0"),
    (b'{"op": "spawn", "name": "x", "description": "mobot", "urdf": "<robot/>"}', "exactly one of"),
])
def test_malformed_requests_get_invalid_request(live, raw, frame, text):
    reply = exchange(raw, frame)
    assert (reply["ok"], reply["result"], reply["code"]) == (False, "INVALID_REQUEST", 900)
    assert text in reply["message"], reply["message"]
    still_serving(live)


def test_unknown_op_is_feature_unsupported(live, raw):
    reply = exchange(raw, b'{"op": "teleport", "id": "t1"}')
    assert (reply["id"], reply["result"], reply["code"]) == ("t1", "FEATURE_UNSUPPORTED", 0)
    assert reply["message"] == ("unknown request op 'teleport': this server knows ping, spawn, delete, "
                                "list, cmd, odom, scan, stop, goto, pause, resume, step, reset, get_state, "
                                "set_state, features, spawn_mover, delete_mover")


def test_more_than_one_frame_or_no_delimiter(live, raw):
    reply = exchange(raw, b'{"op": "ping"}', b"extra")
    assert reply["result"] == "INVALID_REQUEST" and "one JSON frame, got 2" in reply["message"]
    raw.send_multipart([b'{"op": "ping", "id": 7}'])  # a DEALER without the empty delimiter
    reply = json.loads(raw.recv_multipart()[-1])
    assert reply["ok"] and reply["id"] == 7


def test_oversized_requests(live, raw):
    big = b'{"op": "ping", "pad": "' + b"x" * MAX_REQUEST_BYTES + b'"}'
    reply = exchange(raw, big)
    assert reply["result"] == "INVALID_REQUEST" and "larger than the limit" in reply["message"]
    # Past the hard limit ZeroMQ drops the peer before Python sees the message; no reply.
    huge = zmq.Context.instance().socket(zmq.DEALER)
    huge.setsockopt(zmq.LINGER, 0)
    huge.connect(live.endpoint)
    huge.send_multipart([b"", b"x" * (HARD_LIMIT_BYTES + 1)])
    assert huge.poll(1000) == 0
    huge.close()
    still_serving(live)


def test_the_client_refuses_an_oversized_request_as_the_world_would(live):
    """The world cannot read the id of a request it will not parse, so its refusal would never
    match: the client answers it with the same INVALID_REQUEST instead of waiting in vain."""
    with live.client(timeout=5) as client:
        # Waiting in vain would end in LiveWorldError after the timeout: a reply is the answer.
        reply = client.call("spawn", name="big", urdf="x" * (MAX_REQUEST_BYTES + 1))
        assert (reply["ok"], reply["result"], reply["code"]) == (False, "INVALID_REQUEST", 900)
        assert f"larger than the limit of {MAX_REQUEST_BYTES} bytes" in reply["message"]
    still_serving(live)


@pytest.mark.parametrize("value", [float("nan"), float("inf"), -float("inf")])
def test_the_client_refuses_a_number_json_has_not_as_the_world_would(live, value):
    """NaN and infinity cannot be sent as JSON: the client answers with the world's own refusal of
    one (what a raw peer gets for 1e999) instead of failing with a traceback."""
    with live.client(timeout=5) as client:
        reply = client.call("cmd", name="nobody", linear=0.1, pose={"xyz": [0.0, value, 0.0]})
        assert (reply["ok"], reply["result"], reply["code"]) == (False, "INVALID_REQUEST", 900)
        assert reply["message"] == (f"request has the number {value!r}, which is not finite as a float: "
                                    "numbers must be finite")
    still_serving(live)
    done = invoke(["cmd", "nobody", "--linear", "nan", "--endpoint", live.endpoint])
    assert (done.exit_code, done.stdout) == (2, "")
    assert done.stderr == ("mobot: error: INVALID_REQUEST: request has the number nan, which is not finite as a "
                           "float: numbers must be finite\n")


def test_clients_that_vanish_mid_request(live):
    for request in (b'{"op": "spawn", "name": "orphan", "description": "mobot", "pose": {"x": 30}}',
                    b'{"op": "cmd", "name": "orphan", "linear": 0.1, "for": 5, "wait": true}',
                    b'{"op": "list"}'):
        socket = zmq.Context.instance().socket(zmq.DEALER)
        socket.setsockopt(zmq.LINGER, 5000)  # deliver the request, then the peer is gone
        socket.connect(live.endpoint)
        socket.send_multipart([b"", request])
        socket.close()  # gone before the reply
    with live.client() as client:
        # The spawn still happens (as with Gazebo's spawn service); the world goes on.
        deadline = time.monotonic() + 60  # a cold first load expands xacro: a few seconds
        while "orphan" not in [robot["name"] for robot in client.list()]:
            assert time.monotonic() < deadline, "the orphan's spawn never happened"
            time.sleep(0.02)


def test_a_thousand_rapid_lists_from_several_clients(live):
    answers: list[int] = []
    failures: list[str] = []

    def worker(n: int) -> None:
        try:
            with Client(live.endpoint, timeout=30) as client:
                for _ in range(n):
                    reply = client.request("list")
                    answers.append(len(reply["robots"]) >= 0)
        except Exception as exc:  # noqa: BLE001 - collected and asserted below
            failures.append(repr(exc))

    with live.client() as client:
        before = client.ping()["step"]
    threads = [threading.Thread(target=worker, args=(250,)) for _ in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(120)
    assert failures == []
    assert len(answers) == 1000 and all(answers)
    with live.client() as client:
        assert client.ping()["step"] > before  # the world kept stepping through the flood


def test_a_slow_client_never_blocks_the_world(live):
    """A peer that sends thousands of requests and never reads a reply costs the world nothing."""
    slow = zmq.Context.instance().socket(zmq.DEALER)
    slow.setsockopt(zmq.LINGER, 0)
    slow.setsockopt(zmq.RCVHWM, 1)
    slow.setsockopt(zmq.SNDHWM, 100_000)
    slow.connect(live.endpoint)
    for i in range(5000):
        slow.send_multipart([b"", json.dumps({"op": "list", "id": i}).encode()])
    try:
        with live.client(timeout=30) as client:
            first = client.ping()["step"]
            second = wait_for_step(client, first + 240)["step"]
            assert second >= first + 240
    finally:
        slow.close()


def test_request_ids_are_echoed_and_replies_are_plain_json(live, raw):
    reply = exchange(raw, json.dumps({"op": "ping", "id": {"any": ["json", 1]}}).encode())
    assert reply["id"] == {"any": ["json", 1]}
    assert reply["protocol"] == 1 and reply["world"] == "empty" and reply["pace"] == "fast"
