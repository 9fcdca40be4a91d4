"""Planned goals keep off the floor's edges: a robot on a raised platform is not routed off its
side (the goal beyond is unreachable at once) but down its ramp when it has one; cells with no
floor at all (a slab without a ground plane) are never a route or a drawn spawn."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from mobot_cli.assets.world import occupancy
from mobot_cli.assets.world.worldplan import load_world
from mobot_cli.cli import invoke
from mobot_cli.common.raster import Grid

HEIGHT = 0.15  # m: the platform's top, 3 x 3 m round the origin
SLOPE = math.radians(10.0)
RUN = HEIGHT / math.tan(SLOPE)  # m: the ramp's length on the ground, from the platform's edge at x = 1.5


def ramp_pose() -> str:
    """A 1.2 m wide, 0.1 m thick plank pitched down +x, its top from (1.5, HEIGHT) to (1.5 + RUN, 0)."""
    mid_x, mid_z = 1.5 + RUN / 2, HEIGHT / 2
    x, z = mid_x - 0.05 * math.sin(SLOPE), mid_z - 0.05 * math.cos(SLOPE)
    return f"{x:.6f} 0 {z:.6f} 0 {SLOPE:.6f} 0"


def world(ramp: bool, ground: bool = True) -> str:
    plank = (f"<model name='ramp'><static>true</static><pose>{ramp_pose()}</pose><link name='l'><collision name='c'>"
             f"<geometry><box><size>{RUN / math.cos(SLOPE) + 0.1:.4f} 1.2 0.1</size></box></geometry></collision>"
             "</link></model>") if ramp else ""
    plane = ("<model name='ground'><static>true</static><link name='l'><collision name='c'><geometry><plane>"
             "<normal>0 0 1</normal></plane></geometry></collision></link></model>") if ground else ""
    return (f"<?xml version='1.0'?><sdf version='1.6'><world name='stage'>{plane}"
            f"<model name='platform'><static>true</static><pose>0 0 {HEIGHT / 2} 0 0 0</pose><link name='l'>"
            f"<collision name='c'><geometry><box><size>3 3 {HEIGHT}</size></box></geometry></collision></link>"
            f"</model>{plank}</world></sdf>")


def goto(tmp_path: Path, name: str, text: str, goal: tuple[float, float], engine: str = "kinematic") -> dict:
    (tmp_path / f"{name}.sdf").write_text(text)
    doc = {"version": 1, "name": name, "world": str(tmp_path / f"{name}.sdf"), "duration": 20.0,
           "physics": {"engine": engine},
           "robots": [{"name": "r", "description": "mobot", "pose": {"x": 0.0, "y": 0.0, "z": "auto"},
                       "commands": [{"at": 0.5, "goto": {"x": goal[0], "y": goal[1]}, "planner": "astar",
                                     "timeout": 19}]}]}
    scenario = tmp_path / f"{name}.yaml"
    scenario.write_text(yaml.safe_dump(doc, sort_keys=False))
    out = tmp_path / f"out-{name}"
    done = invoke(["run", str(scenario), "--out", str(out), "--quiet"])
    assert done.exit_code in (0, 1), done.stderr
    return json.loads((out / "summary.json").read_text())["robots"]["r"]


def test_a_goal_off_the_platform_without_a_ramp_is_unreachable_at_once(tmp_path):
    robot = goto(tmp_path, "stage", world(ramp=False), (3.0, 0.0))
    (goal,) = robot["goals"]
    assert goal["status"] == "unreachable" and goal["time"] == 0.0
    assert "no path" in goal["reason"]
    assert robot["final_pose"]["z"] == pytest.approx(HEIGHT, abs=0.01)  # still up there


def test_a_point_at_the_foot_of_the_drop_is_named_as_off_the_edge(tmp_path):
    robot = goto(tmp_path, "foot", world(ramp=False), (1.52, 0.0))  # the cell just beyond the edge
    (goal,) = robot["goals"]
    assert goal["status"] == "unreachable"
    assert "off the floor's edge" in goal["reason"]


@pytest.mark.parametrize("engine", ["kinematic", "bullet"])
def test_the_route_off_the_platform_goes_down_its_ramp(tmp_path, engine):
    robot = goto(tmp_path, f"ramp-{engine}", world(ramp=True), (3.0, 2.0), engine)
    (goal,) = robot["goals"]
    assert goal["status"] == "reached", goal
    assert robot["collisions"] == 0
    assert robot["final_pose"]["z"] == pytest.approx(0.0, abs=0.02)  # down on the ground
    # down the ramp (about 4.45 m), not straight off the side (3.6 m, over the edge at y = 1)
    assert goal["path_length"] > 4.0


def test_edges_are_the_foot_of_the_drop_and_the_void_not_the_ramp():
    loaded = load_world(_write(world(ramp=True)), Path.cwd()).plan
    grid = Grid.covering(-2.5, 4.5, -2.5, 2.5, 0.05)
    occ = occupancy.drivable(loaded, grid, HEIGHT)
    edges = occ.edges

    def at(x, y):
        ix, iy = grid.cell_of(x, y)
        return bool(edges[iy, ix])

    assert at(1.52, -1.0) and at(-1.52, 0.0) and at(0.0, 1.52)  # the platform's sides: the foot of the drop
    assert not at(1.4, 0.0) and not at(0.0, 0.0)  # the platform
    assert not any(at(1.5 + f * RUN, 0.0) for f in np.linspace(0.05, 0.95, 10))  # along the ramp
    assert at(1.5 + RUN / 2, 0.62)  # beside the ramp: its side drops to the ground
    assert not at(3.5, 0.0)  # the ground beyond


def test_no_ground_plane_no_floor_beyond_the_slab():
    loaded = load_world(_write(world(ramp=False, ground=False)), Path.cwd()).plan
    grid = Grid.covering(-2.5, 2.5, -2.5, 2.5, 0.05)
    occ = occupancy.drivable(loaded, grid, HEIGHT)
    ix, iy = grid.cell_of(2.2, 0.0)
    assert occ.occupied[iy, ix] and occ.edges[iy, ix]  # nothing to stand on
    ix, iy = grid.cell_of(1.0, 0.0)
    assert not occ.occupied[iy, ix]
    plain = occupancy.occupancy(loaded, grid, HEIGHT)  # the map itself: what rises into the band
    assert not plain.occupied[iy, ix] and not plain.occupied[grid.cell_of(2.2, 0.0)[1], grid.cell_of(2.2, 0.0)[0]]


def _write(text: str) -> str:
    import tempfile

    path = Path(tempfile.mkdtemp(prefix="mobot-dropoffs-")) / "stage.sdf"
    path.write_text(text)
    return str(path)


def test_poses_drawn_for_a_sweep_stand_on_the_floor():
    from mobot_cli.errors import Location
    from mobot_cli.sweep.freedraw import FreeDraw, draw

    loaded = load_world(_write(world(ramp=False, ground=False)), Path.cwd()).plan
    where = Location(file="sweep.yaml", line=1, key="random.robots.r.pose")
    # a region four times the slab's area: three quarters of it has nothing to stand on
    pose = FreeDraw("robots.r.pose", where, (-3.0, 3.0, -3.0, 3.0), 0.3)
    for seed in range(40):
        got = dict(draw((pose,), loaded, {}, np.random.default_rng(seed), "test"))
        x, y = float(got["robots.r.pose.x"]), float(got["robots.r.pose.y"])
        assert max(abs(x), abs(y)) <= 1.5 - 0.3 + 0.05, (seed, x, y)  # on the slab, 0.3 m clear of its edge
