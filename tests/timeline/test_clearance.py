"""`clearance` expectations: measured from geometry (no sensors needed), floors excluded."""

from __future__ import annotations

import json
from dataclasses import astuple

import pytest

from mobot_cli.cli import invoke
from tests.sim.sensor_world import room_scenario

# mobot's chassis front is 0.10 m ahead of its axle; its wheels reach 0.05 m either way.
FRONT = 0.10

DRIVE_TO_WALL = """  - name: mobot
    description: mobot
    pose: {x: 2.0, y: 0.0, yaw: 0.0}
    commands:
      - {at: 0.0, linear: 0.25, for: 2.0}
"""


def _run(tmp_path, robots: str, expect: str, extra: str = ""):
    path = room_scenario(tmp_path, robots, duration=3.0, extra=extra)
    path.write_text(path.read_text() + f"expect:\n{expect}")
    code, out, err = astuple(invoke(["run", path, "--out", tmp_path / "out", "--quiet"]))
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    return code, err, summary


def test_clearance_to_a_wall_is_the_geometric_gap(tmp_path):
    code, err, summary = _run(tmp_path, DRIVE_TO_WALL, "  - {robot: mobot, clearance: {min: 0.25}}\n"
                                                       "  - {robot: mobot, clearance: {min: 0.5}}\n")
    assert code == 1, err
    final_x = summary["robots"]["mobot"]["final_pose"]["x"]
    gap = 3.0 - (final_x + FRONT)  # the east wall's inner face is at x = 3
    assert 0.3 < gap < 0.5
    passed, failed = summary["expectations"]["results"]
    assert passed["passed"] and passed["expected"] == \
        "keep at least 0.25 m from world geometry and other robots until the end"
    assert not failed["passed"]
    closest = float(failed["happened"].split("came within ")[1].split(" m")[0])
    assert closest == pytest.approx(gap, abs=0.01)
    assert "of world model 'walls'" in failed["happened"] and "(at 3 s)" in failed["happened"]
    assert err.startswith("mobot: expectation failed: robot 'mobot' was expected to keep at least 0.5 m")


def test_clearance_to_another_robot_and_at_a_time(tmp_path):
    robots = DRIVE_TO_WALL + "  - name: other\n    description: mobot\n    pose: {x: 2.0, y: 0.6, yaw: 0.0}\n"
    code, err, summary = _run(tmp_path, robots, "  - {robot: all, clearance: {min: 0.1}, at: 1.0}\n")
    assert code == 0, err
    results = {r["robot"]: r for r in summary["expectations"]["results"]}
    # side by side, 0.6 m apart between axles: wheel to wheel 0.6 - 2 * 0.1725 m
    for name in ("mobot", "other"):
        happened = results[name]["happened"]
        assert happened.startswith("came within 0.25") or happened.startswith("came within 0.26"), happened
        assert "robot '" in happened
        assert results[name]["expected"].endswith("until 1 s")


def test_clearance_far_from_everything_and_in_an_empty_world(tmp_path):
    robots = "  - name: mobot\n    description: mobot\n    pose: {x: 0.0, y: 0.0}\n"
    code, err, summary = _run(tmp_path, robots, "  - {robot: mobot, clearance: {min: 0.5}}\n")
    assert code == 0, err
    assert summary["expectations"]["results"][0]["happened"] == "stayed more than 1 m from everything"


@pytest.mark.parametrize("item, message", [
    ("{robot: mobot, clearance: {min: 0}}", "greater than 0"),
    ("{robot: mobot, clearance: {}}", "min"),
    ("{robot: mobot, clearance: 0.3}", "clearance"),
])
def test_bad_clearance_items_are_located_errors(tmp_path, item, message):
    path = room_scenario(tmp_path, DRIVE_TO_WALL)
    path.write_text(path.read_text() + f"expect:\n  - {item}\n")
    code, out, err = astuple(invoke(["check", path]))
    assert code == 2 and message in err and "scenario.yaml:" in err and "Traceback" not in err


def _tiles(cell: float = 0.25, half: float = 3.0) -> str:
    """A flat floor of triangles (OBJ), ``cell`` m squares from -half to +half, as a mesh floor is."""
    n = int(round(2 * half / cell))
    vertices = [f"v {-half + i * cell:g} {-half + j * cell:g} 0" for j in range(n + 1) for i in range(n + 1)]
    faces = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i + 1
            faces += [f"f {a} {a + 1} {a + n + 2}", f"f {a} {a + n + 2} {a + n + 1}"]
    return "\n".join(vertices + faces) + "\n"


@pytest.mark.parametrize("engine", ["bullet", "kinematic"])
def test_the_edges_of_a_mesh_floors_triangles_are_no_obstacle(tmp_path, engine):
    """AWS's hospital floor is a mesh: beside the triangle the caster stands on, PyBullet reports
    the neighbours' edges 1-2 cm away, normals tilted up to 50 deg. They are floor, not obstacles."""
    (tmp_path / "tiles.obj").write_text(_tiles())
    (tmp_path / "tiles.sdf").write_text(
        "<?xml version='1.0'?><sdf version='1.6'><world name='tiles'><model name='floor'><static>true</static>"
        "<link name='l'><collision name='c'><geometry><mesh><uri>tiles.obj</uri></mesh></geometry></collision>"
        "</link></model></world></sdf>")
    scenario = tmp_path / "s.yaml"
    scenario.write_text(f"version: 1\nworld: tiles.sdf\nduration: 4\nphysics: {{engine: {engine}}}\nrobots:\n"
                        "  - name: mobot\n    description: mobot\n    pose: {x: -1.0, y: 0.1, yaw: 0.3}\n"
                        "    commands:\n      - {at: 0.5, linear: 0.3, angular: 0.2, for: 3.0}\n"
                        "expect:\n  - {robot: mobot, clearance: {min: 0.5}}\n  - {robot: mobot, collisions: 0}\n")
    done = invoke(["run", scenario, "--out", tmp_path / "out", "--quiet"])
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert done.exit_code == 0, summary["expectations"]["results"]
    assert summary["robots"]["mobot"]["distance"] > 0.8  # it drove across many triangles' edges
    assert summary["expectations"]["results"][0]["happened"] == "stayed more than 1 m from everything"


@pytest.mark.parametrize("engine", ["bullet", "kinematic"])
def test_a_rug_and_a_carpet_under_the_floor_are_floor_not_obstacles(tmp_path, engine):
    """Bodies wholly below the robot's support band (0.02 m: where the map starts counting
    obstacles) are floor: a 1 cm rug beside the path, a carpet laid just under the floor's
    surface, as AWS's small house has its carpets (its clearance read 0.035 m to one), and the
    next floor slab, 1.5 cm higher than the one it stands on (a city's road tiles read 0.075 m).
    The wall
    beyond still counts."""
    box = ("<model name='{name}'><static>true</static><pose>{pose}</pose><link name='l'><collision name='c'>"
           "<geometry><box><size>{size}</size></box></geometry></collision></link></model>")
    models = "".join(box.format(name=n, pose=pose, size=size) for n, pose, size in (
        ("floor", "-1.85 0 -0.05 0 0 0", "4.3 8 0.1"),  # x -4 to 0.3: under the robot
        ("tiles", "2.15 0 -0.035 0 0 0", "3.7 8 0.1"),  # x 0.3 to 4, 1.5 cm higher, its edge 0.2 m ahead
        ("rug", "0.5 0.6 0.005 0 0 0", "1.5 0.6 0.01"),  # its edge 0.3 m beside the robot's side
        ("carpet", "0 0 -0.006 0 0 0", "4 4 0.004"),  # under the floor's top surface
        ("wall", "2.2 0 0.5 0 0 0", "0.2 4 1"),  # its face 2.1 m ahead of the axle
    ))
    (tmp_path / "rug.sdf").write_text(f"<?xml version='1.0'?><sdf version='1.6'><world name='w'>{models}"
                                      "</world></sdf>")
    scenario = tmp_path / "s.yaml"
    scenario.write_text(f"version: 1\nworld: rug.sdf\nduration: 1\nphysics: {{engine: {engine}}}\nrobots:\n"
                        "  - name: mobot\n    description: mobot\n    pose: {x: 0.0, y: 0.0, z: auto}\n"
                        "expect:\n  - {robot: mobot, clearance: {min: 3.0}}\n")
    done = invoke(["run", scenario, "--out", tmp_path / "out", "--quiet"])
    assert done.exit_code == 1, done.stderr
    happened = json.loads((tmp_path / "out" / "summary.json").read_text())["expectations"]["results"][0]["happened"]
    assert "of world model 'wall'" in happened, happened
    closest = float(happened.split("came within ")[1].split(" m")[0])
    assert closest == pytest.approx(2.1 - FRONT, abs=0.02)
