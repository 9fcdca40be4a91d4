"""Lockstep control of a real `mobot serve` process: pause, resume, step, reset, get/set state,
features, through the CLI and the protocol, with simulation_interfaces' result codes."""

from __future__ import annotations

import json
import math
import time

import pytest

from mobot_cli.cli import invoke
from mobot_cli.live.client import Client
from tests.live.live_server import REPO, LiveProcess

QUICKSTART = str(REPO / "scenarios" / "quickstart.yaml")
PACED_STEP = 1000.0 / 240  # s: one step of a world paced at --rtf 0.001


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.getbasetemp() / "mobot-cache"


@pytest.fixture(scope="module")
def paused(cache):
    """quickstart (one robot, 240 Hz), started paused, stepping as fast as it can."""
    server = LiveProcess(QUICKSTART, "--paused", "--fast", cache_dir=cache)
    yield server
    server.kill()


def mobot(server, *args: str):
    done = invoke([*args, "--endpoint", server.endpoint])
    assert "Traceback" not in done.stderr
    return done.exit_code, done.stdout, done.stderr


def reply_of(server, *args: str) -> dict:
    code, out, err = mobot(server, *args, "--json")
    assert code == 0, err
    return json.loads(out)


def test_a_paused_world_takes_exactly_the_steps_asked_for_and_stands_still_between(paused):
    start = reply_of(paused, "reset")  # whatever ran before: t = 0 again
    assert (start["step"], start["t"], start["state"], start["state_code"]) == (0, 0.0, "paused", 2)
    first = reply_of(paused, "step", "240")
    assert (first["steps"], first["step"], first["t"]) == (240, 240, 1.0)  # exactly 1.000 s at 240 Hz
    [robot] = first["robots"]
    assert robot["name"] == "mobot" and 0.05 < robot["pose"]["x"] < 0.2  # the script drove it from t = 0.5
    read = reply_of(paused, "state", "mobot")
    time.sleep(0.5)  # wall time passes; simulated time does not
    again = reply_of(paused, "state", "mobot")
    assert (read["step"], read["pose"], read["twist"]) == (again["step"], again["pose"], again["twist"])
    assert read["pose"] == robot["pose"] and read["twist"] == robot["twist"]
    second = reply_of(paused, "step", "--seconds", "1.0")
    assert (second["steps"], second["step"], second["t"]) == (240, 480, 2.0)
    assert reply_of(paused, "step", "--seconds", "0.1")["step"] == 504  # 24.000000000000004 steps is 24
    code, out, err = mobot(paused, "step", "3")
    assert code == 0 and out.startswith("stepped 3 to t=2.112 s (step 507)\n  mobot in world: x=")


def test_pause_and_resume_are_idempotent_and_step_needs_a_paused_world(cache):
    server = LiveProcess("--fast", cache_dir=cache)
    try:
        assert reply_of(server, "resume")["changed"] is False
        code, out, err = mobot(server, "step", "10")
        assert (code, out) == (2, "") and err.startswith("mobot: error: INCORRECT_STATE: the world is playing")
        code, out, err = mobot(server, "step", "10", "--json")
        assert code == 2 and json.loads(out)["code"] == 3
        paused = reply_of(server, "pause")
        assert (paused["changed"], paused["state"], paused["state_code"]) == (True, "paused", 2)
        assert mobot(server, "pause")[1].startswith("paused (already) at t=")
        with server.client() as client:
            held = client.ping()
            time.sleep(0.3)
            assert client.ping()["step"] == held["step"] and held["state"] == "paused"
            assert client.request("step", steps=7)["step"] == held["step"] + 7
        resumed = reply_of(server, "resume")
        assert (resumed["changed"], resumed["state"], resumed["state_code"]) == (True, "playing", 1)
        time.sleep(0.2)
        with server.client() as client:
            assert client.ping()["step"] > held["step"] + 100
    finally:
        server.kill()


def test_serve_paused_starts_at_t_0_and_stays_there(cache):
    # Paced at a thousandth of real time, yet paused: a paced step would wait 1/240 s x 1000 = 4.2 s
    # of wall time, so the steps below would take 25 minutes paced. As fast as it can, they take a
    # fraction of a second, or a minute on a machine that gives this test almost no CPU.
    server = LiveProcess(QUICKSTART, "--paused", "--rtf", "0.001", cache_dir=cache)
    try:
        time.sleep(0.5)
        with server.client(timeout=60) as client:
            ping = client.ping()
            assert (ping["step"], ping["state"]) == (0, "paused")
            assert "240 Hz, paused." in server.output()
            started = time.perf_counter()
            assert client.request("step", steps=240, timeout=120)["t"] == 1.0  # paced: 1,000 s
            for _ in range(120):  # one step per request
                client.request("step", states=False)
            elapsed = time.perf_counter() - started
            assert client.ping()["step"] == 360 and elapsed < 120 * PACED_STEP, elapsed
    finally:
        server.kill()


def lockstep_session(client: Client) -> list[dict]:
    """The same requests for every session: steps, commands, a teleport, a reset, a spawn."""
    replies = [client.request("step", steps=100)]
    client.cmd("mobot", linear=0.3, angular=0.2)
    replies.append(client.request("step", steps=240))
    replies.append(client.request("set_state", name="mobot", pose={"x": 2.0, "y": 1.0, "yaw": 0.5}))
    replies.append(client.request("step", seconds=0.5))
    client.spawn("visitor", description="mobot", pose={"x": -2.0, "y": 0.0})
    replies.append(client.request("step", steps=60))
    replies.append(client.request("reset"))
    replies.append(client.request("step", steps=170))
    return [{k: v for k, v in r.items() if k != "id"} for r in replies]


def test_two_lockstep_sessions_write_byte_identical_records(tmp_path, cache):
    outs, sessions = [tmp_path / "a", tmp_path / "b"], []
    for out in outs:
        server = LiveProcess(QUICKSTART, "--paused", "--fast", cache_dir=cache, out=out)
        try:
            with server.client() as client:
                sessions.append(lockstep_session(client))
                client.stop()
            assert server.wait() == 0
        finally:
            server.kill()
    assert sessions[0] == sessions[1]
    files = sorted(p.relative_to(outs[0]) for p in outs[0].rglob("*") if p.is_file() and p.name != "summary.json"
                   and p.suffix != ".png")
    assert {str(f) for f in files} >= {"odom/mobot.csv", "odom/mobot__2.csv", "odom/visitor.csv", "history.jsonl"}
    for name in files:
        assert (outs[0] / name).read_bytes() == (outs[1] / name).read_bytes(), name


def test_reset_starts_the_scenario_over_and_the_record_says_so(tmp_path, cache):
    out = tmp_path / "rec"
    server = LiveProcess(QUICKSTART, "--paused", "--fast", cache_dir=cache, out=out)
    try:
        with server.client() as client:
            first = [client.request("step", steps=n)["robots"] for n in (120, 240, 600)]
            client.spawn("visitor", description="mobot", pose={"x": -2.0, "y": 0.0})
            client.request("set_state", name="mobot", pose={"x": 3.0, "y": 3.0})
            client.cmd("mobot", linear=-0.5)
            reset = client.request("reset")
            assert (reset["step"], reset["t"], reset["resets"], reset["robots"]) == (0, 0.0, 1, ["mobot"])
            assert client.request("get_state", name="mobot")["pose"]["x"] == pytest.approx(0.0, abs=1e-3)
            again = [client.request("step", steps=n)["robots"] for n in (120, 240, 600)]
            assert again == first  # the same steps give the same states, to the last bit
            client.stop()
        assert server.wait() == 0
    finally:
        server.kill()
    lines = [json.loads(line) for line in (out / "history.jsonl").read_text().splitlines()]
    at = next(i for i, line in enumerate(lines) if line["op"] == "reset")
    assert lines[at] == {"t": 4.0, "step": 960, "op": "reset", "result": "OK", "resets": 1}
    after = [(line["op"], line.get("name"), line.get("by"), line["step"]) for line in lines[at + 1:]]
    assert after == [("delete", "mobot", "reset", 960), ("delete", "visitor", "reset", 960),
                     ("spawn", "mobot", "reset", 0)]
    first_life = (out / "odom" / "mobot.csv").read_text().splitlines()
    second_life = (out / "odom" / "mobot__2.csv").read_text().splitlines()
    assert first_life[0] == second_life[0] and first_life[-1].startswith("4.000000,")
    assert second_life[1].startswith("0.000000,") and second_life[-1].startswith("4.000000,")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["robots"]["mobot"]["deleted_at"] == 4.0 and summary["robots"]["mobot__2"]["spawned_at"] == 0.0
    assert summary["steps"] == 960 and summary["live"]["requests"]["reset"] == 1


def test_get_state_in_another_robots_frame(paused):
    with paused.client() as client:
        client.request("reset")
        client.spawn("ref", description="mobot", pose={"x": 2.0, "y": 1.0, "yaw": math.pi / 2})
        client.request("set_state", name="mobot", pose={"x": 1.0, "y": 0.0, "yaw": 0.0},
                       twist={"linear": {"x": 0.5}, "angular": {"z": 0.25}})
        world = client.request("get_state", name="mobot")
        seen = client.request("get_state", name="mobot", reference_frame="ref")
        client.delete("ref")
    assert world["reference_frame"] == "world" and seen["reference_frame"] == "ref"
    assert world["twist"]["linear"]["x"] == pytest.approx(0.5) and world["twist"]["angular"]["z"] == pytest.approx(0.25)
    # mobot is 1 m west and 1 m south of ref, which faces +y: 1 m behind it and 1 m to its left.
    assert (seen["pose"]["x"], seen["pose"]["y"]) == pytest.approx((-1.0, 1.0), abs=2e-3)
    assert seen["pose"]["yaw"] == pytest.approx(-math.pi / 2, abs=1e-3)
    assert seen["twist"]["linear"]["x"] == pytest.approx(0.0, abs=1e-3)  # +x in the world is -y for ref
    assert seen["twist"]["linear"]["y"] == pytest.approx(-0.5, abs=1e-3)
    assert seen["pose"]["quat"][2] == pytest.approx(-math.sin(math.pi / 4), abs=1e-3)


def test_teleport_moves_the_robot_and_a_teleport_into_a_wall_is_invalid_pose(cache):
    server = LiveProcess("house", "--paused", "--fast", cache_dir=cache)
    try:
        assert mobot(server, "spawn", "r1", "--file", "mobot", "-x", "-3", "-y", "-2.5")[0] == 0
        moved = reply_of(server, "teleport", "r1", "-x", "2", "-y", "-4", "-Y", "0.5")
        assert (moved["pose"]["x"], moved["pose"]["y"], moved["pose"]["yaw"]) \
            == pytest.approx((2.0, -4.0, 0.5), abs=1e-6)
        assert moved["pose"]["z"] == pytest.approx(0.0, abs=2e-3)  # rested on the floor slab
        code, out, err = mobot(server, "teleport", "r1", "-x", "0", "-y", "-5")  # into wall_south
        assert (code, out) == (2, "")
        assert err.startswith("mobot: error: INVALID_POSE: ") and "house_walls" in err
        code, out, err = mobot(server, "teleport", "r1", "-x", "0", "-y", "-5", "--json")
        assert code == 2 and (json.loads(out)["result"], json.loads(out)["code"]) == ("INVALID_POSE", 109)
        still = reply_of(server, "state", "r1")  # a refused teleport leaves the robot where it was
        assert (still["pose"]["x"], still["pose"]["y"]) == pytest.approx((2.0, -4.0), abs=1e-6)
        assert mobot(server, "teleport", "r1", "-x", "0", "-y", "0")[2].startswith(
            "mobot: error: INVALID_POSE:")  # the coffee table
    finally:
        server.kill()


def test_features_names_and_numbers_as_simulation_interfaces(paused):
    reply = reply_of(paused, "features")
    features = {f["name"]: f["id"] for f in reply["features"]}
    assert features == {"SPAWNING": 0, "DELETING": 1, "SPAWNING_RESOURCE_STRING": 9, "ENTITY_STATE_GETTING": 10,
                        "ENTITY_STATE_SETTING": 11, "SIMULATION_RESET": 20, "SIMULATION_STATE_SETTING": 25,
                        "SIMULATION_STATE_PAUSE": 26, "STEP_SIMULATION_SINGLE": 31, "STEP_SIMULATION_MULTIPLE": 32}
    assert {"pause", "resume", "step", "reset", "get_state", "set_state", "features"} <= set(reply["ops"])
    code, out, err = mobot(paused, "features")
    assert code == 0 and " 10  ENTITY_STATE_GETTING\n" in out and "spawn formats: urdf, xacro" in out


BAD_REQUESTS = [
    ({"op": "step", "steps": 0}, "INVALID_REQUEST", "field 'steps': Input should be greater than or equal to 1"),
    ({"op": "step", "steps": -5}, "INVALID_REQUEST", "field 'steps'"),
    ({"op": "step", "steps": 10**12}, "INVALID_REQUEST", "less than or equal to 10000000"),
    ({"op": "step", "steps": 2.0}, "INVALID_REQUEST", "field 'steps': Input should be a valid integer"),
    ({"op": "step", "steps": True}, "INVALID_REQUEST", "field 'steps'"),
    ({"op": "step", "steps": "10"}, "INVALID_REQUEST", "field 'steps'"),
    ({"op": "step", "seconds": -1.0}, "INVALID_REQUEST", "field 'seconds'"),
    ({"op": "step", "seconds": 1.001}, "INVALID_REQUEST", "not a whole number: the nearest is 240 step(s) (1 s)"),
    ({"op": "step", "seconds": 0.001}, "INVALID_REQUEST", "the nearest is 1 step(s)"),
    ({"op": "step", "seconds": 1e300}, "INVALID_REQUEST", "less than or equal to 1000000"),
    ({"op": "step", "steps": 2, "seconds": 1.0}, "INVALID_REQUEST", "'steps' or 'seconds', not both"),
    ({"op": "reset", "scope": 1}, "FEATURE_UNSUPPORTED", "resets everything at once"),
    ({"op": "get_state", "name": "nobody"}, "NOT_FOUND", "no robot named 'nobody'"),
    ({"op": "get_state", "name": "mobot", "reference_frame": "nowhere"}, "NOT_FOUND",
     "reference frame 'nowhere' is not a robot"),
    ({"op": "get_state"}, "INVALID_REQUEST", "field 'name': Field required"),
    ({"op": "set_state", "name": "nobody", "pose": {"x": 1.0}}, "NOT_FOUND", "no robot named 'nobody'"),
    ({"op": "set_state", "name": "mobot", "pose": {"x": 1.0}, "reference_frame": "nowhere"}, "NOT_FOUND",
     "reference frame 'nowhere'"),
    ({"op": "set_state", "name": "mobot", "pose": {"xyz": [0, 0, 0], "quat": [0, 0, 0, 0]}}, "INVALID_POSE",
     "quat has zero length"),
    ({"op": "set_state", "name": "mobot", "pose": {"x": 1e9}}, "INVALID_POSE", "field 'pose.x'"),
    ({"op": "set_state", "name": "mobot", "pose": {"x": 0.0, "z": -0.5}}, "INVALID_POSE", "into the ground plane"),
    ({"op": "set_state", "name": "mobot", "pose": {}, "twist": {"linear": {"x": 1e6}}}, "INVALID_REQUEST",
     "field 'twist.linear.x'"),
    ({"op": "set_state", "name": "mobot"}, "INVALID_REQUEST", "field 'pose': Field required"),
    ({"op": "pause", "extra": 1}, "INVALID_REQUEST", "field 'extra': Extra inputs are not permitted"),
]


@pytest.mark.parametrize("request_, result, text", BAD_REQUESTS, ids=[str(r[0]) for r in BAD_REQUESTS])
def test_bad_requests_get_their_result_codes(paused, request_, result, text):
    with paused.client() as client:
        before = client.ping()["step"]
        reply = client.call(**request_)
        assert (reply["ok"], reply["result"]) == (False, result), reply
        assert text in reply["message"], reply["message"]
        assert client.ping()["step"] == before  # nothing moved


@pytest.mark.parametrize("raw", [b'{"op":"set_state","name":"mobot","pose":{"x":NaN}}',
                                 b'{"op":"set_state","name":"mobot","pose":{"x":1e999}}',
                                 b'{"op":"step","seconds":Infinity}',
                                 b'{"op":"set_state","name":"mobot","pose":{},"twist":{"angular":{"z":-Infinity}}}'])
def test_nan_and_infinity_are_invalid_requests(paused, raw):
    import zmq

    socket = zmq.Context.instance().socket(zmq.DEALER)
    socket.setsockopt(zmq.LINGER, 0)
    try:
        socket.connect(paused.endpoint)
        socket.send_multipart([b"", raw])
        assert socket.poll(10_000)
        reply = json.loads(socket.recv_multipart()[-1])
    finally:
        socket.close()
    assert (reply["result"], reply["code"]) == ("INVALID_REQUEST", 900)
    assert "not" in reply["message"] and ("finite" in reply["message"] or "JSON allows" in reply["message"])


@pytest.mark.parametrize("args, text", [
    (["teleport", "mobot", "-x", "nan"], "teleport takes finite numbers"),
    (["teleport", "mobot", "--linear", "inf", "0", "0"], "teleport takes finite numbers"),
    (["step", "--seconds", "nan"], "is not a finite number of seconds"),
    (["step", "4", "--seconds", "1"], "give N steps or --seconds S, not both"),
    (["step", "-5"], "INVALID_REQUEST: step request, field 'steps'"),
    (["step", "0"], "INVALID_REQUEST: step request, field 'steps'"),
    (["state", "nobody"], "NOT_FOUND: no robot named 'nobody'"),
    (["state", "mobot", "--reference-frame", "nowhere"], "NOT_FOUND: reference frame 'nowhere'"),
    (["teleport", "nobody", "-x", "1"], "NOT_FOUND: no robot named 'nobody'"),
    (["teleport", "mobot", "-Y", "1", "--quat", "0", "0", "0", "1"], "either as --quat or as -R -P -Y, not both"),
    (["spawn", "r2", "-f", "mobot", "-R", "1", "--quat", "0", "0", "0", "1"],
     "either as --quat or as -R -P -Y, not both"),
])
def test_bad_cli_input_exits_2_with_one_line(paused, args, text):
    code, out, err = mobot(paused, *args)
    assert (code, out) == (2, "") and err.startswith("mobot: error: ") and text in err, err


@pytest.mark.parametrize("verb", [["pause"], ["resume"], ["step"], ["reset"], ["state", "r"],
                                  ["teleport", "r", "-x", "1"], ["features"]])
def test_no_live_world_exits_4(tmp_path, verb):
    done = invoke([*verb, "--endpoint", f"ipc://{tmp_path}/none.sock", "--timeout", "0.5"])
    assert done.exit_code == 4 and done.stdout == "" and "no live world" in done.stderr


def test_the_docs_wall_follower_runs_in_lockstep(cache, monkeypatch):
    """docs/live-world.md's lockstep example, as written, against `mobot serve house --paused`."""
    import re

    page = (REPO / "docs" / "live-world.md").read_text()
    section = page[page.index("## Lockstep control"):]
    block = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    assert 'world.spawn("r1"' in block and "pose={\"x\": -3.0, \"y\": -4.3}" in block
    server = LiveProcess("house", "--paused", "--fast", cache_dir=cache)
    try:
        monkeypatch.setenv("MOBOT_ENDPOINT", server.endpoint)
        exec(compile(block, "docs/live-world.md", "exec"), {})  # spawns r1 at (-3, -4.3), then 100 steps
        with server.client() as client:
            end = client.get_state("r1")
    finally:
        server.kill()
    start = {"t": 0.0, "pose": {"x": -3.0}}
    assert end["t"] == start["t"] + 10.0  # 100 x 24 steps at 240 Hz
    assert end["pose"]["x"] - start["pose"]["x"] > 1.5  # along the south wall (y = -5), 0.5 m from it
    assert -4.6 < end["pose"]["y"] < -4.0, end["pose"]  # neither into the wall nor away from it
