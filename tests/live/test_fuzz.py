"""Property: whatever a client sends, a real `mobot serve` answers it (or drops it) and lives.

Valid requests of every op get fields replaced by random JSON (huge numbers, NaN and Infinity
tokens, deep nesting, long strings, wrong types), or become random bytes, or come as several
frames. Every message gets a reply that is JSON with a known result code, except a valid
`cmd` with `wait` (its reply comes when the command ends), and the server still answers a ping
at the end. The fast suite sends a seeded sample; `pytest -m slow -s tests/live/test_fuzz.py`
sends MOBOT_FUZZ_REQUESTS (default 5,000) and prints the counts.
"""

from __future__ import annotations

import json
import os
from collections import Counter
from typing import Any

import pytest
import zmq
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mobot_cli.live.protocol import Refusal, Result, decode
from mobot_cli.live.schema import Cmd, parse
from tests.live.live_server import LiveProcess

FAST_SAMPLE = 200
SLOW_SAMPLE = int(os.environ.get("MOBOT_FUZZ_REQUESTS", "5000"))
REPLY_MS = 30_000  # a spawn is loaded by a worker process; everything else answers in milliseconds
WAIT_MS = 300  # a valid `cmd --wait` answers when its command ends: not waited for

TEMPLATES: dict[str, dict[str, Any]] = {
    "ping": {"op": "ping"},
    "list": {"op": "list"},
    "odom": {"op": "odom", "name": "fz"},
    "delete": {"op": "delete", "name": "fz_gone"},
    "cmd": {"op": "cmd", "name": "fz", "linear": 0.1, "angular": 0.2, "for": 0.5, "wait": False},
    "spawn": {"op": "spawn", "name": "fz_new", "description": "mobot", "pose": {"x": 40.0, "y": 40.0},
              "args": {}, "namespace": "/fz_new", "allow_renaming": False},
    "spawn_text": {"op": "spawn", "name": "fz_text", "urdf": '<robot name="t"><link name="b"/></robot>'},
    "stop": {"op": "stop", "never": "valid"},  # a valid stop would end the world under test
}


class Raw:
    """A token written into the JSON text as is (NaN, 1e999, a 5,000-digit integer, ...)."""

    def __init__(self, text: str):
        self.text = text


def dump(value: Any) -> str:
    """JSON text of ``value`` with Raw tokens spliced in."""
    if isinstance(value, Raw):
        return value.text
    if isinstance(value, dict):
        return "{" + ",".join(f"{json.dumps(str(k))}:{dump(v)}" for k, v in value.items()) + "}"
    if isinstance(value, list):
        return "[" + ",".join(dump(v) for v in value) + "]"
    return json.dumps(value)


RAW = st.sampled_from(["NaN", "Infinity", "-Infinity", "1e999", "-1e999", "1e-999", "-0", "1" * 5000,
                       "123456789012345678901234567890", "1.7976931348623157e308"]).map(Raw)
DEEP = st.integers(min_value=30, max_value=100_000).map(lambda n: Raw("[" * n + "]" * n))
LONG = st.integers(min_value=300, max_value=300_000).map(lambda n: "x" * n)
SCALARS = (st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False, allow_infinity=False)
           | st.text(max_size=30) | LONG | RAW | DEEP)
VALUES = st.recursive(SCALARS, lambda inner: st.lists(inner, max_size=4)
                      | st.dictionaries(st.text(max_size=8), inner, max_size=4), max_leaves=12)
# Values of the right type, so that many mutated requests stay valid and reach the world.
NUMBERS = st.floats(allow_nan=False, allow_infinity=False) | st.integers(min_value=-10**6, max_value=10**6)
NAMES = st.from_regex(r"[A-Za-z_][A-Za-z0-9_]{0,12}", fullmatch=True) | st.sampled_from(["fz", "fz_new"])
PLAUSIBLE = {
    "name": NAMES, "linear": NUMBERS, "angular": NUMBERS, "for": NUMBERS, "wait": st.booleans(),
    "allow_renaming": st.booleans(), "namespace": NAMES.map(lambda n: "/" + n),
    "pose": st.fixed_dictionaries({}, optional={"x": NUMBERS, "y": NUMBERS, "z": NUMBERS | st.just("auto"),
                                                "yaw": NUMBERS, "roll": NUMBERS}),
    "args": st.dictionaries(NAMES, st.text(max_size=10) | st.booleans() | NUMBERS, max_size=3),
    "reference_frame": NAMES | st.just("world"),
}


@st.composite
def requests(draw) -> bytes:
    """A template with some fields replaced, removed or added."""
    document: dict[str, Any] = dict(TEMPLATES[draw(st.sampled_from(sorted(TEMPLATES)))])
    for _ in range(draw(st.integers(min_value=0, max_value=3))):
        action = draw(st.sampled_from(["plausible", "plausible", "replace", "remove", "add", "id"]))
        keys = sorted(document)
        if action == "plausible":
            key = draw(st.sampled_from(sorted(PLAUSIBLE)))
            document[key] = draw(PLAUSIBLE[key])
        elif not keys or action == "add":
            document[draw(st.text(max_size=10))] = draw(VALUES)
        elif action == "replace":
            document[draw(st.sampled_from(keys))] = draw(VALUES)
        elif action == "remove":
            document.pop(draw(st.sampled_from(keys)))
        else:
            document["id"] = draw(VALUES)
    if document.get("op") == "stop":
        document["never"] = "valid"  # a valid stop would end the world under test
    return dump(document).encode()


FRAMES = (requests() | st.binary(max_size=200)
          | st.binary(max_size=12).map(lambda b: b'{"op": "ping", "id": ' + b + b"}"))
SINGLE = requests().map(lambda frame: [frame])
MESSAGES = st.tuples(st.booleans(), st.one_of(SINGLE, SINGLE, SINGLE, st.lists(FRAMES, min_size=1, max_size=3)))


def expects_no_reply(frames: list[bytes]) -> bool:
    """A valid `cmd` with `wait` and `for` answers only when its command ends."""
    if len(frames) != 1:
        return False
    try:
        request = parse(decode(frames[0]))
    except Refusal:
        return False
    return isinstance(request, Cmd) and request.wait and request.for_ is not None


class Tally:
    """What the fuzz saw."""

    def __init__(self):
        self.sent, self.replied, self.unanswered_waits = 0, 0, 0
        self.results: Counter[str] = Counter()
        self.failures: list[str] = []


def exchange(endpoint: str, delimiter: bool, frames: list[bytes], tally: Tally) -> None:
    socket = zmq.Context.instance().socket(zmq.DEALER)  # one per message: a late reply cannot mislead
    socket.setsockopt(zmq.LINGER, 0)
    socket.connect(endpoint)
    try:
        socket.send_multipart(([b""] if delimiter else []) + frames)
        tally.sent += 1
        waiting = expects_no_reply(frames)
        if not socket.poll(WAIT_MS if waiting else REPLY_MS):
            if waiting:
                tally.unanswered_waits += 1
            else:
                tally.failures.append(f"no reply to {frames!r:.300}")
            return
        reply = json.loads(socket.recv_multipart()[-1])
        tally.replied += 1
        tally.results[reply["result"]] += 1
        known = {r.name: int(r) for r in Result}
        if known.get(reply["result"]) != reply["code"] or reply["ok"] != (reply["result"] == "OK"):
            tally.failures.append(f"odd reply {reply!r:.300}")
    finally:
        socket.close()


def fuzz(tmp_path_factory, examples: int, seed_note: str) -> Tally:
    server = LiveProcess("--fast", cache_dir=tmp_path_factory.getbasetemp() / "mobot-cache")
    tally = Tally()
    try:
        with server.client() as client:
            client.spawn("fz", description="mobot")

        @settings(max_examples=examples, derandomize=True, database=None, deadline=None,
                  suppress_health_check=list(HealthCheck))
        @given(MESSAGES)
        def one(message) -> None:
            delimiter, frames = message
            assert server.process.poll() is None, f"the server died: {server.output()}"
            exchange(server.endpoint, delimiter, frames, tally)

        one()
        alive = server.process.poll() is None
        with server.client(timeout=30) as client:
            pong = client.call("ping")
        assert pong["ok"], pong
    finally:
        deaths = 0 if server.process.poll() is None else 1
        print(f"\nfuzz ({seed_note}): sent {tally.sent}, replied {tally.replied}, cmd --wait left waiting "
              f"{tally.unanswered_waits}, failures {len(tally.failures)}, server deaths {deaths}; by result: "
              + ", ".join(f"{name} {count}" for name, count in tally.results.most_common()))
        server.kill()
    assert alive and not tally.failures, tally.failures[:5]
    assert tally.sent == tally.replied + tally.unanswered_waits
    return tally


def test_a_seeded_sample_of_mutated_requests(tmp_path_factory):
    tally = fuzz(tmp_path_factory, FAST_SAMPLE, "seeded sample")
    assert tally.sent >= FAST_SAMPLE * 0.9
    assert tally.results["INVALID_REQUEST"] > 0 and tally.results["OK"] > 0


@pytest.mark.slow
def test_thousands_of_mutated_requests(tmp_path_factory):
    tally = fuzz(tmp_path_factory, SLOW_SAMPLE, f"{SLOW_SAMPLE} examples")
    assert tally.sent >= SLOW_SAMPLE * 0.9
