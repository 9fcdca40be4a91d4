"""`mobot goto` against a real `mobot serve` in the house: a goal reached, one refused, one blocked,
one taken over by a cmd; the record keeps them all."""

from __future__ import annotations

import json
import math

import pytest

from mobot_cli.cli import invoke
from tests.live.live_server import LiveProcess


@pytest.fixture(scope="module")
def house(tmp_path_factory):
    out = tmp_path_factory.mktemp("goto") / "record"
    server = LiveProcess("house", "--fast", cache_dir=tmp_path_factory.getbasetemp() / "mobot-cache", out=out)
    yield server
    server.kill()


def mobot(server, *args: str):
    done = invoke([*args, "--endpoint", server.endpoint])
    assert "Traceback" not in done.stderr
    return done.exit_code, done.stdout, done.stderr


def test_goto_drives_through_the_doorway_and_waits_for_the_goal(house):
    assert mobot(house, "spawn", "r", "--file", "mobot", "-x", "-2", "-y", "-2.5")[0] == 0
    code, out, err = mobot(house, "goto", "r", "2.5", "-2.5", "--yaw", "-1.57", "--wait", "--json")
    assert code == 0, err
    reply = json.loads(out)
    assert reply["status"] == "reached" and reply["error"] < 0.05 and 10 < reply["time"] < 30
    assert math.hypot(reply["pose"]["x"] - 2.5, reply["pose"]["y"] + 2.5) < 0.05
    assert abs(reply["pose"]["yaw"] + 1.57) < 0.06
    code, out, err = mobot(house, "goto", "r", "0", "0")  # the coffee table
    assert (code, out) == (2, "")
    assert err == ("mobot: error: INVALID_REQUEST: goto request: goto (0, 0) is inside world model "
                   "'coffee_table' at (0.00, 0.00, 0.00), its collision 'coffee_table::mobot_coffee_table::link::"
                   "body', a 1.00 x 0.60 x 0.40 m box centred at (0.00, 0.00, 0.20)\n")


def test_a_goal_into_a_wall_ends_blocked_and_exits_1(house):
    assert mobot(house, "spawn", "b", "--file", "mobot", "-x", "-4", "-y", "-4")[0] == 0
    code, out, err = mobot(house, "goto", "b", "-4", "-7", "--wait")  # beyond the south wall
    assert code == 1, err
    assert out.startswith("t=") and ": blocked after " in out


def test_a_planned_goal_goes_through_the_doorway_or_says_why_it_cannot(house):
    assert mobot(house, "spawn", "p", "--file", "mobot", "-x", "-4", "-y", "-2")[0] == 0
    # Straight north runs into the wall at y = 1; the doorway is at x = -3..-2.
    code, out, err = mobot(house, "goto", "p", "-3.2", "2.2", "--planner", "astar", "--ground-truth", "--wait",
                           "--json")
    assert code == 0, err
    reply = json.loads(out)
    assert reply["status"] == "reached" and "reason" not in reply
    code, out, err = mobot(house, "goto", "p", "-4", "-2", "--planner", "astar", "--inflation", "0.55", "--wait")
    assert code == 1, err
    assert ": unreachable after 0.000 s" in out
    assert "(no path from the start (-3.2" in out  # where its odometry says it stopped, within the tolerance
    assert out.rstrip().endswith(") to the goal (-4, -2) at this inflation (0.55 m from obstacles))")
    code, _, err = mobot(house, "goto", "p", "-4", "-2", "--planner", "dijkstra")
    assert code == 2 and "planner" in err and "'astar'" in err


def test_a_cmd_takes_over_from_a_goal_and_the_record_says_so(house):
    assert mobot(house, "spawn", "c", "--file", "mobot", "-x", "-2.5", "-y", "3")[0] == 0
    code, out, _ = mobot(house, "goto", "c", "-1", "3")
    assert code == 0 and out.startswith("'c': driving to (-1, 3) from step ")
    assert mobot(house, "cmd", "c", "--linear", "0")[0] == 0
    assert mobot(house, "stop")[0] == 0
    house.process.wait(timeout=30)
    robots = json.loads((house.out / "summary.json").read_text())["robots"]
    assert [(g["command"], g["kind"], g["status"]) for g in robots["r"]["goals"]] == [(None, "goto", "reached")]
    assert robots["b"]["goals"][0]["status"] == "blocked"
    assert robots["c"]["goals"][0]["status"] == "cancelled"
    assert [g["status"] for g in robots["p"]["goals"]] == ["reached", "unreachable"]
    assert robots["p"]["goals"][1]["reason"].startswith("no path from the start")
