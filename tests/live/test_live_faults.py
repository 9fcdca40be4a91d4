"""A fault in a live world takes the robot it names out; the world and the other robots go on."""

from __future__ import annotations

import json

from tests.live.live_server import LiveProcess


def test_a_robot_thrown_up_in_a_live_world_is_taken_out_and_the_world_goes_on(tmp_path):
    out = tmp_path / "rec"
    server = LiveProcess("empty", "--paused", "--fast", cache_dir=tmp_path / "cache", out=out)
    try:
        with server.client(timeout=90) as client:  # a cold load on a busy machine
            client.spawn("thrown", description="mobot")
            client.spawn("calm", description="mobot", pose={"x": 2.0})
            client.request("set_state", name="thrown", pose={"x": 0.0, "y": 0.0},
                           twist={"linear": {"z": 40.0}})  # beyond the 20 m/s runaway limit
            client.step(seconds=0.5)
            names = [robot["name"] for robot in client.list()]
            assert client.ping()["step"] == 120
        assert names == ["calm"]
        assert server.signal() == 0
    finally:
        server.kill()
    deleted = [json.loads(line) for line in (out / "history.jsonl").read_text().splitlines()
               if '"delete"' in line]
    assert [(d["name"], d["by"]) for d in deleted] == [("thrown", "fault")]
    assert "robot 'thrown' ran away at step 24" in deleted[0]["message"]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "ok" and summary["robots"]["thrown"]["deleted_at"] == 0.1
    assert any(n.startswith("robot 'thrown' was taken out of the live world: robot 'thrown' ran away at step 24")
               for n in summary["notices"])
