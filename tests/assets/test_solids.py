"""SDF <cone>, <ellipsoid> and <polyline> as meshes (assets/world/solids.py): closed solids of the
right size, seen by a lidar where the geometry says, mapped, and collided with."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import trimesh

from mobot_cli.assets.world import solids
from mobot_cli.cli import invoke

# Around a robot at the origin: an L-shaped polyline wall east (its inner corner at x = 2),
# a cone north at y = 2, an ellipsoid west at x = -2.5 (radii 0.5, 0.3, 0.4), all 0.1+ m high.
WORLD = """<?xml version="1.0"?>
<sdf version="1.10"><world name="solids">
  <model name="ground"><static>true</static><link name="l"><collision name="c"><geometry><plane>
    <normal>0 0 1</normal></plane></geometry></collision></link></model>
  <model name="ell_wall"><static>true</static><pose>0 0 0 0 0 0</pose><link name="l">
    <collision name="c"><geometry><polyline>
      <point>2 -1</point><point>2.2 -1</point><point>2.2 1</point><point>1.2 1</point><point>1.2 0.8</point>
      <point>2 0.8</point><point>2 -1</point><height>0.6</height></polyline></geometry></collision></link></model>
  <model name="cone"><static>true</static><pose>0 2.3 0.5 0 0 0</pose><link name="l">
    <collision name="c"><geometry><cone><radius>0.3</radius><length>1.0</length></cone></geometry></collision>
  </link></model>
  <model name="egg"><static>true</static><pose>-2.5 0 0.4 0 0 0</pose><link name="l">
    <collision name="c"><geometry><ellipsoid><radii>0.5 0.3 0.4</radii></ellipsoid></geometry></collision>
  </link></model>
</world></sdf>
"""


def test_the_solids_are_closed_and_of_their_volume():
    cone = trimesh.Trimesh(*solids.cone(0.3, 1.0))
    assert cone.is_watertight and cone.volume == pytest.approx(math.pi * 0.09 / 3, rel=0.01)
    assert cone.bounds.ravel().tolist() == pytest.approx([-0.3, -0.3, -0.5, 0.3, 0.3, 0.5], abs=1e-3)
    egg = trimesh.Trimesh(*solids.ellipsoid((0.5, 0.3, 0.4)))
    assert egg.is_watertight and egg.volume == pytest.approx(4 / 3 * math.pi * 0.5 * 0.3 * 0.4, rel=0.01)
    vertices, faces, nested = solids.polyline([[(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2), (0, 0)]], 0.5)
    ell = trimesh.Trimesh(vertices, faces)
    assert ell.is_watertight and ell.volume == pytest.approx(3 * 0.5) and not nested
    assert ell.bounds.tolist() == [[0, 0, 0], [2, 2, 0.5]]  # extruded from z = 0, as Gazebo does
    clockwise = trimesh.Trimesh(*solids.polyline([[(0, 0), (0, 2), (1, 2), (1, 1), (2, 1), (2, 0)]], 0.5)[:2])
    assert clockwise.is_watertight and clockwise.volume == pytest.approx(1.5)
    *_, nested = solids.polyline([[(0, 0), (4, 0), (4, 4), (0, 4)], [(1, 1), (2, 1), (2, 2)]], 1.0)
    assert nested


@pytest.fixture()
def world(tmp_path):
    path = tmp_path / "solids.sdf"
    path.write_text(WORLD)
    return path


def test_a_lidar_sees_them_where_they_are_and_a_robot_stops_at_the_wall(world, tmp_path):
    from mobot_cli.api import Simulation

    scenario = tmp_path / "s.yaml"
    scenario.write_text("version: 1\nworld: solids.sdf\nduration: 8\nrobots:\n  - name: r\n    description: mobot\n"
                        "    args: {lidar: 'true'}\n    sensors: {scan: {samples: 720, range_max: 6.0, "
                        "noise_stddev: 0, range_resolution: 0}}\n")
    done = invoke(["check", str(world)])
    assert done.exit_code == 0 and "geometry" not in done.stderr, done.stderr  # nothing left out
    with Simulation.open(scenario) as sim:
        sim.run_for(1.0)
        scan = sim.scan("r")
        lidar = sim.state("r")
        x0 = lidar.true_x
        ranges, angles = scan.ranges, scan.angles

        def at(angle):
            return float(ranges[np.argmin(np.abs(np.remainder(angles - angle + math.pi, 2 * math.pi) - math.pi))])

        offset = scan_offset(sim)
        assert at(0.0) == pytest.approx(2.0 - offset, abs=0.005)  # the wall's inner face at x = 2
        # the cone's surface at the lidar's height z: radius 0.3 (1 - z) about x = 0, y = 2.3 (its base
        # on the floor, its apex 1 m up); the beam north passes offset m east of its axis
        height = lidar_height(sim)
        radius = 0.3 * (1 - height)
        assert at(math.pi / 2) == pytest.approx(2.3 - math.sqrt(radius ** 2 - offset ** 2), abs=0.005)
        # the ellipsoid at height z: its x radius 0.5 sqrt(1 - ((z - 0.4) / 0.4)^2), centre x = -2.5
        half = 0.5 * math.sqrt(1 - ((height - 0.4) / 0.4) ** 2)
        assert at(math.pi) == pytest.approx(2.5 - half + offset, abs=0.005)
        sim.command("r", linear=0.5)
        sim.run_for(6.0)
        assert x0 + 1.0 < sim.state("r").true_x < 2.0  # it drove east and the wall stopped it


def lidar_height(sim) -> float:
    reading = sim.reading("r", "lidar")
    return float(reading.data.position[2])


def scan_offset(sim) -> float:
    """How far ahead of the robot's origin the lidar sits (x, in the world: the robot faces +x)."""
    reading = sim.reading("r", "lidar")
    return float(reading.data.position[0])


def test_mobot_map_fills_the_polyline_and_the_cone(world, tmp_path):
    done = invoke(["map", str(world), "--out", tmp_path / "m", "--resolution", "0.05"])
    assert done.exit_code == 0, done.stderr
    from tests.ros.nav2_map import load_map

    data, res, origin = load_map(tmp_path / "m" / "map.yaml")

    def cell(x, y):
        return int(data[int((y - origin[1]) // res), int((x - origin[0]) // res)])

    assert cell(2.1, 0.0) == 100 and cell(1.6, 0.9) == 100  # both legs of the L
    assert cell(1.6, 0.0) == 0  # inside the L's bend: the outline is concave
    assert cell(0.0, 2.3) == 100 and cell(-2.5, 0.0) == 100
    assert cell(0.0, 0.0) == 0
    summary = json.loads(invoke(["check", str(world), "--json"]).stdout)
    assert summary["models"] == 4


def test_a_cached_world_whose_made_mesh_was_deleted_is_read_again(world, tmp_path):
    from mobot_cli.assets.world.worldplan import load_world

    first = load_world(str(world), tmp_path)
    made = [Path(s.mesh) for b in first.plan.bodies for s in b.shapes if s.kind == "mesh"]
    assert len(made) == 3 and all(path.exists() for path in made)
    for path in made:
        path.unlink()  # someone cleared the cache's meshes/, not its world/
    again = load_world(str(world), tmp_path)
    assert all(Path(s.mesh).exists() for b in again.plan.bodies for s in b.shapes if s.kind == "mesh")
