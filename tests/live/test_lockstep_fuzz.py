"""Property: random requests to the lockstep ops never crash a real server, never hit an internal
error, and always get a reply with a known simulation_interfaces result code.

The server starts paused with one robot ("fz"); requests are pause, resume, step, reset,
get_state, set_state and features with fields drawn plausible (right types, edge values) or
random (any JSON), so both valid requests that move the world and refusals are exercised.
"""

from __future__ import annotations

import json
from collections import Counter
from typing import Any

import zmq
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mobot_cli.live.lockstep import steps_of
from mobot_cli.live.protocol import Refusal, Result, decode
from mobot_cli.live.schema import Step, parse
from tests.live.live_server import LiveProcess
from tests.live.test_fuzz import VALUES, dump

EXAMPLES = 150
REPLY_MS = 60_000
MOST_STEPS = 2_000  # a valid step asks for at most this many, so the sample stays quick

NUMBERS = (st.floats(allow_nan=False, allow_infinity=False) | st.integers(min_value=-10**6, max_value=10**6)
           | st.sampled_from([0, -0.0, 1e-9, 1e6, 1e7, 1e300]))
NAMES = st.sampled_from(["fz", "fz", "nobody", "", "world", "x" * 300])
VECTOR = st.fixed_dictionaries({}, optional={"x": NUMBERS, "y": NUMBERS, "z": NUMBERS})
PLAUSIBLE: dict[str, Any] = {
    "steps": st.integers(min_value=-3, max_value=300) | st.sampled_from([10**7 + 1, 10**30, 2.0, True, "5"]),
    "seconds": st.sampled_from([0.5, 1.0, 1 / 240, 1.001, 0.0, -1.0, 1e300, 0.1]) | NUMBERS,
    "states": st.booleans(),
    "scope": st.sampled_from([0, 255, 1, 2, 4, -1, 256]),
    "name": NAMES,
    "reference_frame": NAMES | st.none(),
    "pose": st.fixed_dictionaries({}, optional={"x": NUMBERS, "y": NUMBERS, "z": NUMBERS | st.just("auto"),
                                                "yaw": NUMBERS, "roll": NUMBERS, "pitch": NUMBERS})
    | st.fixed_dictionaries({"xyz": st.tuples(NUMBERS, NUMBERS, NUMBERS | st.just("auto")).map(list)},
                            optional={"quat": st.tuples(NUMBERS, NUMBERS, NUMBERS, NUMBERS).map(list)}),
    "twist": st.fixed_dictionaries({}, optional={"linear": VECTOR, "angular": VECTOR}),
}
OPS = {"pause": [], "resume": [], "features": [], "reset": ["scope"], "step": ["steps", "seconds", "states"],
       "get_state": ["name", "reference_frame"], "set_state": ["name", "pose", "twist", "reference_frame"]}


@st.composite
def lockstep_requests(draw) -> bytes:
    op = draw(st.sampled_from(sorted(OPS)))
    document: dict[str, Any] = {"op": op, "id": draw(st.integers(min_value=0, max_value=10**6))}
    for key in OPS[op]:
        if draw(st.integers(min_value=0, max_value=3)):  # mostly given
            document[key] = draw(PLAUSIBLE[key]) if draw(st.integers(min_value=0, max_value=5)) else draw(VALUES)
    if draw(st.integers(min_value=0, max_value=9)) == 0:
        document[draw(st.text(max_size=6))] = draw(VALUES)
    return _bounded(dump(document).encode())


def _bounded(frame: bytes) -> bytes:
    """A valid step request for more than MOST_STEPS asks for fewer (its other fields kept)."""
    try:
        request = parse(decode(frame))
        if isinstance(request, Step) and steps_of(request.steps, request.seconds, 240) > MOST_STEPS:
            document = json.loads(frame)
            document.pop("seconds", None)
            document["steps"] = MOST_STEPS
            return json.dumps(document).encode()
    except (Refusal, ValueError):
        pass
    return frame


def test_random_lockstep_requests_always_get_a_known_result(tmp_path_factory):
    server = LiveProcess("--paused", "--fast", cache_dir=tmp_path_factory.getbasetemp() / "mobot-cache")
    results: Counter[str] = Counter()
    failures: list[str] = []
    socket = zmq.Context.instance().socket(zmq.DEALER)
    socket.setsockopt(zmq.LINGER, 0)
    try:
        with server.client() as client:
            client.spawn("fz", description="mobot")
        socket.connect(server.endpoint)
        known = {r.name: int(r) for r in Result}

        @settings(max_examples=EXAMPLES, derandomize=True, database=None, deadline=None,
                  suppress_health_check=list(HealthCheck))
        @given(lockstep_requests())
        def one(frame: bytes) -> None:
            assert server.process.poll() is None, f"the server died: {server.output()}"
            socket.send_multipart([b"", frame])
            assert socket.poll(REPLY_MS), f"no reply to {frame!r:.300}"
            reply = json.loads(socket.recv_multipart()[-1])
            results[reply["result"]] += 1
            if known.get(reply["result"]) != reply["code"] or reply["ok"] != (reply["result"] == "OK"):
                failures.append(f"odd reply {reply!r:.300} to {frame!r:.300}")
            if "internal error" in reply["message"]:
                failures.append(f"{reply['message']:.300} for {frame!r:.300}")

        one()
        with server.client(timeout=30) as client:
            assert client.call("ping")["ok"]
    finally:
        socket.close()
        print(f"\nlockstep fuzz: {sum(results.values())} replies; "
              + ", ".join(f"{k} {v}" for k, v in results.most_common()))
        server.kill()
    assert not failures, failures[:5]
    assert sum(results.values()) == EXAMPLES
    assert {"OK", "INVALID_REQUEST", "NOT_FOUND", "INCORRECT_STATE"} <= set(results), results
