"""Goals with ``local: dwb``: the dynamic-window controller on the robot's own lidar.

Real runs of the bundled robot with its lidar (args: lidar) on PyBullet (and the kinematic
engine): a box in the way of a straight goto (a world of tests/data), a box put in the way by a
scenario event at run time, a goal walled in, and the controller's maths on its own.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from mobot_cli.cli import invoke
from mobot_cli.common.polygon import footprint_radius
from mobot_cli.plan import GoalControl
from mobot_cli.timeline.local import Dwb

DATA = Path(__file__).resolve().parents[1] / "data"
GOAL = (4.0, 0.0)


def run(tmp_path: Path, name: str, *, world: str = "empty", local: bool = True, events=(), engine: str = "bullet",
        duration: float = 25.0) -> Path:
    goal = {"at": 0.5, "goto": {"x": GOAL[0], "y": GOAL[1]}, "timeout": duration - 1.0}
    if local:
        goal["local"] = "dwb"
    doc = {"version": 1, "name": name, "world": world, "duration": duration, "seed": 3,
           "physics": {"engine": engine},
           "robots": [{"name": "r", "description": "mobot", "args": {"lidar": "true"},
                       "pose": {"x": 0.0, "y": 0.0, "yaw": 0.0},
                       "sensors": {"scan": {"rate_hz": 10, "samples": 180, "range_max": 8.0}},
                       "commands": [goal]}],
           "events": list(events)}
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    out = tmp_path / name
    done = invoke(["run", str(path), "--out", str(out), "--quiet"])
    assert done.exit_code == 0, done.stderr
    return out


def outcome(out: Path) -> tuple[dict, dict, list[dict[str, float]]]:
    summary = json.loads((out / "summary.json").read_text())
    robot = summary["robots"]["r"]
    with (out / "odom" / "r.csv").open() as f:
        rows = [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]
    return robot, robot["goals"][0], rows


BOX_WORLD = str(DATA / "box_in_the_way.sdf")
CHAIR = [{"at": 2.0, "spawn": {"name": "chair", "description": str(DATA / "box.urdf"),
                               "pose": {"x": 2.0, "y": 0.0, "yaw": 0.0}}}]


@pytest.mark.parametrize("case", ["static box", "box put there by an event"])
def test_pursuit_hits_what_dwb_goes_round(case, tmp_path):
    where = {"world": BOX_WORLD} if case == "static box" else {"events": CHAIR}
    robot, goal, _ = outcome(run(tmp_path, "pursuit", local=False, **where))
    assert robot["collisions"] >= 1  # it drives into the box (and pushes the 20 kg one aside)
    if case == "static box":
        assert goal["status"] == "blocked"
    robot, goal, rows = outcome(run(tmp_path, "dwb", **where))
    assert robot["collisions"] == 0
    assert goal["status"] == "reached" and goal["error"] <= 0.05  # the true distance, the default tolerance
    assert 4.0 < goal["path_length"] <= 1.3 * 4.0  # round a 0.4 m box: measured 4.31 m
    passing = [row for row in rows if 1.6 <= row["true_x"] <= 2.4]  # beside the box
    assert min(abs(row["true_y"]) for row in passing) >= 0.2 + 0.17  # its half width and the robot's


def test_dwb_run_is_deterministic(tmp_path):
    first = run(tmp_path, "a", world=BOX_WORLD)
    second = run(tmp_path, "b", world=BOX_WORLD)
    assert (first / "odom" / "r.csv").read_bytes() == (second / "odom" / "r.csv").read_bytes()


def test_dwb_on_the_kinematic_engine(tmp_path):
    robot, goal, _ = outcome(run(tmp_path, "kinematic", world=BOX_WORLD, engine="kinematic"))
    assert robot["collisions"] == 0 and goal["status"] == "reached" and goal["error"] <= 0.05
    assert goal["path_length"] <= 1.3 * 4.0


WALLED = """<?xml version="1.0"?>
<sdf version="1.6">
  <world name="walled_in">
    <include><uri>model://ground_plane</uri></include>
    <model name="room">
      <static>true</static>
      <link name="link">
{walls}
      </link>
    </model>
  </world>
</sdf>
"""


def test_a_walled_in_goal_ends_stuck_never_reached(tmp_path):
    walls = [((3.0, 0.0), (0.1, 2.0)), ((5.0, 0.0), (0.1, 2.0)), ((4.0, 1.0), (2.1, 0.1)), ((4.0, -1.0), (2.1, 0.1))]
    shapes = "\n".join(
        f'<collision name="w{i}"><pose>{x} {y} 0.3 0 0 0</pose><geometry><box><size>{sx} {sy} 0.6</size></box>'
        f'</geometry></collision>' for i, ((x, y), (sx, sy)) in enumerate(walls))
    world = tmp_path / "walled_in.sdf"
    world.write_text(WALLED.format(walls=shapes))
    robot, goal, _ = outcome(run(tmp_path, "walled", world=str(world), duration=40.0))
    assert goal["status"] in ("stuck", "timed_out")
    assert goal["error"] > 0.9  # never inside
    assert robot["collisions"] == 0


# -- the controller's maths on its own -------------------------------------------------------------


def drive(dwb: Dwb, obstacles: np.ndarray, path: np.ndarray, ticks: int):
    return [dwb.command(obstacles, path) for _ in range(ticks)]


def test_open_floor_speeds_up_along_the_path():
    dwb = Dwb(GoalControl(), 0.05, 0.25)
    choices = drive(dwb, np.zeros((0, 2)), np.array([[0.0, 0.0], [1.5, 0.0]]), 40)
    assert choices[-1].linear == pytest.approx(0.3) and abs(choices[-1].angular) < 1e-9
    assert all(c.admissible and not c.blocked_path for c in choices)


def test_a_wall_ahead_stops_forward_motion():
    wall = np.array([[0.35, y] for y in np.linspace(-1.0, 1.0, 41)])
    dwb = Dwb(GoalControl(), 0.05, 0.25)
    dwb.v = 0.2
    choice = dwb.command(wall, np.array([[0.0, 0.0], [1.5, 0.0]]))
    assert choice.blocked_path and choice.linear < 0.2  # it brakes: no forward rollout is free


def test_a_point_on_the_path_steers_aside_the_same_way_each_time():
    box = np.array([[0.9 + dx, dy] for dx in (-0.1, 0.0, 0.1) for dy in (-0.1, 0.0, 0.1)])
    turns = []
    for _ in range(2):
        dwb = Dwb(GoalControl(), 0.05, 0.25)
        dwb.v = 0.3
        turns.append([c.angular for c in drive(dwb, box, np.array([[0.0, 0.0], [2.0, 0.0]]), 10)])
    assert turns[0] == turns[1] and max(abs(w) for w in turns[0]) > 0.1


def test_radius_of_a_footprint():
    assert footprint_radius((-0.2, 0.1, -0.17, 0.17)) == pytest.approx(math.hypot(0.2, 0.17))


# -- the bundled house: a patrol of the four rooms' centres, straight segments past furniture ------

ROOMS = [[-2.5, -2.5], [-2.5, 3.0], [3.5, 3.0], [3.5, -2.5]]  # living room, bedroom, study, kitchen


def patrol(tmp_path: Path, name: str, local: bool, events=()) -> dict:
    command = {"at": 0.5, "patrol": ROOMS, "laps": 1, "timeout": 119}
    if local:
        command["local"] = "dwb"
    doc = {"version": 1, "name": name, "world": "house", "duration": 120, "seed": 11,
           "robots": [{"name": "r", "description": "mobot", "args": {"lidar": "true"},
                       "pose": {"x": -2.5, "y": -2.5, "yaw": 1.5708},
                       "sensors": {"scan": {"rate_hz": 10, "samples": 180, "range_max": 8.0}},
                       "commands": [command]}],
           "events": list(events)}
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    done = invoke(["run", str(path), "--out", str(tmp_path / name), "--quiet"])
    assert done.exit_code == 0, done.stderr
    return json.loads((tmp_path / name / "summary.json").read_text())["robots"]["r"]


def test_house_patrol_of_the_rooms_goes_round_the_furniture(tmp_path):
    robot = patrol(tmp_path, "pursuit", local=False)
    assert robot["collisions"] >= 1 and robot["goals"][0]["status"] == "blocked"  # the armchair
    robot = patrol(tmp_path, "dwb", local=True)
    (goal,) = robot["goals"]
    assert robot["collisions"] == 0 and (goal["status"], goal["laps"]) == ("reached", 1)
    assert 23.0 < goal["path_length"] < 1.1 * 23.0  # measured 23.3 m in 82.9 s
    box = [{"at": 10.0, "spawn": {"name": "chair", "description": str(DATA / "box.urdf"),
                                  "pose": {"x": -0.5, "y": 3.0, "yaw": 0.3}}}]  # on the bedroom-study leg
    robot = patrol(tmp_path, "dwb_box", local=True, events=box)
    (detour,) = robot["goals"]
    assert robot["collisions"] == 0 and (detour["status"], detour["laps"]) == ("reached", 1)
    assert detour["path_length"] > goal["path_length"] + 0.2  # round the box: measured +0.4 m


def test_the_python_api_goto_takes_local():
    from mobot_cli.api import Simulation
    from mobot_cli.errors import UsageError

    with Simulation.open(BOX_WORLD) as sim:
        sim.spawn("r", "mobot", args={"lidar": "true"})
        sim.spawn("blind", "mobot", y=2.0)
        with pytest.raises(UsageError, match="goto 'blind': local: dwb avoids what the robot's lidar sees"):
            sim.goto("blind", 4.0, 2.0, local="dwb")
        sim.run_for(0.5)
        sim.goto("r", *GOAL, local="dwb")
        while sim.goal_status("r") == "running" and sim.t < 30:
            sim.run_for(0.5)
        assert sim.goal_status("r") == "reached"
        s = sim.state("r")
        assert math.hypot(s.true_x - GOAL[0], s.true_y - GOAL[1]) < 0.05 and s.collisions == 0
