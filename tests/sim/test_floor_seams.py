"""A floor meshed as a few huge triangles (as Gazebo worlds exported from CAD often are: Clearpath's
office) with a wall in the same mesh: a wheel running a millimetre beside a seam between two
floor triangles is no collision, on either engine; the wall still is one.

Beside the triangle a wheel stands on, PyBullet reports the neighbour's edge a fraction of a
millimetre away with a normal tilted anywhere between vertical and horizontal; the kinematic
engine counted that as touching an obstacle (sim/contacts.py's SEAM).
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest
import yaml

from mobot_cli.cli import invoke

SEAM_Y = 0.278  # the seam between the floor triangles, along x
WHEEL = 0.1072  # the bundled robot's y with its left wheel's outer edge 1 mm beside the seam


def floor_obj() -> str:
    """A 19 m floor of four triangles, two of them slivers along the seam, and a wall box
    (x 3.0-3.2, y -1..1, 1 m high) in the same mesh: the body reaches above the robot's support band."""
    vertices = [(3.7, -12.2, 0.0), (3.7, SEAM_Y, 0.0), (-15.0, SEAM_Y, 0.0), (-15.0, -12.2, 0.0),
                (3.2, 1.8, 0.0), (-15.0, 1.8, 0.0)]
    faces = [(1, 3, 4), (1, 2, 3), (3, 2, 5), (3, 5, 6)]
    base = len(vertices)
    vertices += [(x, y, z) for z in (0.0, 1.0) for y in (-1.0, 1.0) for x in (3.0, 3.2)]
    box = [(0, 2, 3), (0, 3, 1), (4, 5, 7), (4, 7, 6), (0, 1, 5), (0, 5, 4),
           (2, 6, 7), (2, 7, 3), (0, 4, 6), (0, 6, 2), (1, 3, 7), (1, 7, 5)]
    faces += [tuple(base + 1 + i for i in face) for face in box]
    return "".join(f"v {x} {y} {z}\n" for x, y, z in vertices) + "".join(f"f {a} {b} {c}\n" for a, b, c in faces)


WORLD = """<?xml version="1.0"?>
<sdf version="1.6">
  <world name="seams">
    <model name="office">
      <static>true</static>
      <link name="link">
        <collision name="c"><geometry><mesh><uri>floor.obj</uri></mesh></geometry></collision>
      </link>
    </model>
  </world>
</sdf>
"""


def drive(tmp_path: Path, engine: str, x: float) -> tuple[dict, list[dict[str, float]]]:
    """The bundled robot from (x, WHEEL) straight along +x at 0.5 m/s for 10 s: its summary and odometry rows."""
    (tmp_path / "floor.obj").write_text(floor_obj())
    (tmp_path / "seams.sdf").write_text(WORLD)
    doc = {"version": 1, "name": "seams", "world": str(tmp_path / "seams.sdf"), "duration": 10.5,
           "physics": {"engine": engine},
           "robots": [{"name": "r", "description": "mobot", "pose": {"x": x, "y": WHEEL, "yaw": 0.0},
                       "commands": [{"at": 0.5, "linear": 0.5, "angular": 0.0}]}]}
    scenario = tmp_path / f"{engine}.yaml"
    scenario.write_text(yaml.safe_dump(doc, sort_keys=False))
    out = tmp_path / f"run-{engine}-{x:g}"
    done = invoke(["run", str(scenario), "--out", str(out), "--quiet"])
    assert done.exit_code == 0, done.stderr
    with (out / "odom" / "r.csv").open() as f:
        rows = [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]
    return json.loads((out / "summary.json").read_text())["robots"]["r"], rows


@pytest.mark.parametrize("engine", ["kinematic", "bullet"])
def test_a_wheel_along_a_seam_of_the_floor_is_no_collision(tmp_path, engine):
    robot, rows = drive(tmp_path, engine, -8.0)
    assert robot["collisions"] == 0
    assert rows[-1]["true_x"] - rows[0]["true_x"] == pytest.approx(5.0, abs=0.1)  # it drove on, 5 m along the seam
    assert max(abs(row["true_y"] - WHEEL) for row in rows) < 0.01


@pytest.mark.parametrize("engine", ["kinematic", "bullet"])
def test_a_wall_of_the_same_mesh_still_counts(tmp_path, engine):
    robot, rows = drive(tmp_path, engine, 0.0)  # the wall is 3 m ahead: reached after about 6 s
    assert robot["collisions"] >= 1
    assert rows[-1]["true_x"] < 3.0  # stopped by it
