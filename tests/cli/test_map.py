"""`mobot map WORLD`: map_server files that nav2's rules load to the floor plan of trajectory.png.

The maps are read back with tests/ros/nav2_map.py (map_io.cpp's rules, no mobot code) and
compared pixel by pixel with the trajectory.png of a real run in the same world: every map cell
whose centre falls on a plainly drawn pixel (obstacle grey, or floor white) must agree with it,
or be on an edge (a cell within one cell of it agrees).
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
import yaml
from PIL import Image

from mobot_cli.assets.world.floorplan import floor_plan
from mobot_cli.assets.world.worldplan import load_world
from mobot_cli.cli import invoke
from mobot_cli.record.render import placement
from tests.ros.nav2_map import load_map

REPO = Path(__file__).resolve().parents[2]
MARKER = 0.3  # m around the robot's path: its line and markers are drawn there
SMALL_HOUSE = "aws-robomaker-small-house-world/worlds/small_house.world"


def mapped(world: str, out: Path, *options: str) -> tuple[np.ndarray, float, tuple]:
    done = invoke(["map", world, "--out", out, *options])
    assert done.exit_code == 0, done.stderr
    assert done.stdout.startswith(f"{out / 'map.yaml'}: ")
    return load_map(out / "map.yaml")


def track_of(run: Path, robot: str) -> list[tuple[float, float, float]]:
    with (run / "odom" / f"{robot}.csv").open() as f:
        return [(float(row["true_x"]), float(row["true_y"]), float(row["true_z"])) for row in csv.DictReader(f)]


def agreement(data: np.ndarray, resolution: float, origin, picture: Path, floor, track) -> tuple[int, int, int]:
    """(cells compared, cells agreeing, cells disagreeing beyond one cell of an edge); cells under
    the robot's track and its start and end markers (within MARKER of it) are left out."""
    image = np.asarray(Image.open(picture).convert("RGB")).astype(int)
    to_pixel = placement([], floor)
    ny, nx = data.shape
    iy, ix = np.mgrid[0:ny, 0:nx]
    xs, ys = origin[0] + (ix + 0.5) * resolution, origin[1] + (iy + 0.5) * resolution
    px = np.empty((ny, nx), dtype=int)
    py = np.empty((ny, nx), dtype=int)
    for j in range(ny):
        for i in range(nx):
            u, v = to_pixel((xs[j, i], ys[j, i]))
            px[j, i], py[j, i] = int(u), int(v)
    rgb = image[py, px]
    grey = (rgb[..., 0] == rgb[..., 1]) & (rgb[..., 1] == rgb[..., 2])
    value = rgb[..., 0]
    drawn = grey & (value <= 200)  # FLOOR 178 and its edges 120: an obstacle
    clear = grey & (value >= 220)  # white, or a grid line (226)
    occupied = data == 100
    near_track = np.zeros((ny, nx), dtype=bool)
    for x, y, _ in track:
        near_track |= np.hypot(xs - x, ys - y) < MARKER
    compared = (drawn | clear) & ~near_track
    agree = compared & (occupied == drawn)
    # One cell of tolerance: a disagreeing cell with a neighbour that the map gives the picture's class.
    padded_occ = np.pad(occupied, 1, constant_values=False)
    padded_free = np.pad(~occupied, 1, constant_values=False)
    near_occ = np.zeros_like(occupied)
    near_free = np.zeros_like(occupied)
    for dy in (0, 1, 2):
        for dx in (0, 1, 2):
            near_occ |= padded_occ[dy:dy + ny, dx:dx + nx]
            near_free |= padded_free[dy:dy + ny, dx:dx + nx]
    excused = (drawn & near_occ) | (clear & near_free)
    return int(compared.sum()), int(agree.sum()), int((compared & ~agree & ~excused).sum())


def check_against_run(world: str, plan_world, scenario: Path, tmp_path: Path, robot: str) -> tuple[int, int]:
    run = tmp_path / "run"
    done = invoke(["run", scenario, "--out", run, "--quiet", "--duration", "0.5"])
    assert done.exit_code == 0, done.stderr
    track = track_of(run, robot)
    floor = floor_plan(plan_world, [track[0]])
    data, resolution, origin = mapped(world, tmp_path / "map")
    assert set(np.unique(data)) == {0, 100}  # a world is known everywhere: no unknown cells
    compared, agree, wrong = agreement(data, resolution, origin, run / "trajectory.png", floor, track)
    assert wrong == 0, f"{wrong} cells disagree with trajectory.png beyond one cell of an edge"
    assert compared > 0.9 * data.size  # nearly every cell's centre lands on a plainly drawn pixel
    return compared, agree


def test_bundled_house_map_is_the_floor_plan_of_trajectory_png(tmp_path):
    compared, agree = check_against_run("house", load_world("house").plan, REPO / "scenarios" / "house.yaml",
                                        tmp_path, "mobot")
    assert agree > 0.97 * compared  # thin walls: many edge cells


def test_aws_small_house_map_is_the_floor_plan_of_trajectory_png(tmp_path, corpus):
    world = str(corpus / SMALL_HOUSE)
    scenario = tmp_path / "aws.yaml"
    scenario.write_text(yaml.safe_dump({
        "version": 1, "name": "aws", "world": world, "duration": 0.5,
        "robots": [{"name": "mobot", "description": "mobot", "pose": {"x": 3.5, "y": 1.0, "yaw": 0.0}}]}))
    compared, agree = check_against_run(world, load_world(world).plan, scenario, tmp_path, "mobot")
    assert agree > 0.95 * compared  # mesh furniture: more edges


BOXES = """<?xml version='1.0'?>
<sdf version='1.6'><world name='boxes'>
  <model name='crate'><static>true</static><pose>1.02 0.5 0.25 0 0 0</pose><link name='l'>
    <collision name='c'><geometry><box><size>0.5 1.0 0.5</size></box></geometry></collision></link></model>
  <model name='shelf'><static>true</static><pose>-1 -1 2.5 0 0 0</pose><link name='l'>
    <collision name='c'><geometry><box><size>0.4 0.4 0.2</size></box></geometry></collision></link></model>
  <model name='post'><static>true</static><pose>-1 0.4 0.5 0 0 0</pose><link name='l'>
    <collision name='c'><geometry><cylinder><radius>0.2</radius><length>1</length></cylinder></geometry>
    </collision></link></model>
</world></sdf>
"""


@pytest.fixture()
def boxes(tmp_path) -> Path:
    path = tmp_path / "boxes.sdf"
    path.write_text(BOXES)
    return path


def cell(data, resolution, origin, x, y) -> int:
    return int(data[int((y - origin[1]) // resolution), int((x - origin[0]) // resolution)])


def test_band_size_origin_and_inflation(boxes, tmp_path):
    data, res, origin = mapped(str(boxes), tmp_path / "a", "--resolution", "0.1", "--origin", "-2,-2",
                               "--size", "4,3")
    assert data.shape == (30, 40) and res == 0.1 and origin == (-2.0, -2.0, 0.0)
    iy, ix = np.nonzero(data == 100)
    xs, ys = origin[0] + (ix + 0.5) * res, origin[1] + (iy + 0.5) * res
    in_crate = (np.abs(xs - 1.02) < 0.25 + res) & (np.abs(ys - 0.5) < 0.5 + res)
    in_post = np.hypot(xs + 1.0, ys - 0.4) < 0.2 + res
    assert (in_crate | in_post).all()  # nothing further than one cell from the two
    assert in_crate.sum() >= 4 * 10 and in_post.sum() >= 12  # the crate's inner 0.4 x 1.0 m, the post's 12 centres
    assert cell(data, res, origin, 1.0, 0.5) == 100 and cell(data, res, origin, -1.0, 0.4) == 100
    assert cell(data, res, origin, -1.0, -1.0) == 0  # the shelf at 2.4..2.6 m is above the band
    high, *_ = mapped(str(boxes), tmp_path / "b", "--resolution", "0.1", "--origin", "-2,-2", "--size", "4,3",
                      "--band", "2.0,3.0")
    assert cell(high, res, origin, -1.0, -1.0) == 100 and cell(high, res, origin, 1.0, 0.5) == 0
    fat, *_ = mapped(str(boxes), tmp_path / "c", "--resolution", "0.1", "--origin", "-2,-2", "--size", "4,3",
                     "--robot-radius", "0.3")
    assert cell(fat, res, origin, 1.52, 0.5) == 100  # 3 cells east of the crate's last cell (centre 1.25)
    assert cell(fat, res, origin, 1.62, 0.5) == 0
    assert ((fat == 100) >= (data == 100)).all()


def test_default_extent_covers_the_world_with_a_margin(boxes, tmp_path):
    data, res, origin = mapped(str(boxes), tmp_path / "a")
    assert res == 0.05
    # The post's west edge at x = -1.2 and the crate's east edge at x = 1.27, 0.5 m around them on whole cells.
    assert origin[0] == pytest.approx(-1.7) and origin[0] + data.shape[1] * res == pytest.approx(1.8)


@pytest.mark.parametrize("args, message", [
    (["--band", "2,1"], "mobot: error: --band 2,1: ZMIN must be below ZMAX"),
    (["--band", "x"], "mobot: error: --band 'x' is not ZMIN,ZMAX (two finite numbers, a comma between)"),
    (["--resolution", "0"], "mobot: error: --resolution 0 is out of range"),
    (["--size", "3,-1"], "mobot: error: --size 3,-1: width and height must be positive"),
    (["--robot-radius", "-1"], "mobot: error: --robot-radius -1 is out of range"),
    (["--resolution", "0.002", "--size", "20,20"], "mobot: error: the map would have"),
])
def test_bad_options_are_located_errors(boxes, tmp_path, args, message):
    done = invoke(["map", str(boxes), "--out", tmp_path / "m", *args])
    assert (done.exit_code, done.stdout) == (2, "")
    assert done.stderr.startswith(message) and "Traceback" not in done.stderr
    assert not (tmp_path / "m").exists()


def test_unknown_world_and_unwritable_out(tmp_path, boxes):
    done = invoke(["map", "hous"])
    assert done.exit_code == 2 and "Did you mean 'house'?" in done.stderr
    blocker = tmp_path / "file"
    blocker.write_text("")
    done = invoke(["map", str(boxes), "--out", blocker])
    assert done.exit_code == 2 and done.stderr.startswith(f"mobot: error: cannot write {blocker}")


XACRO_WORLD = """<?xml version="1.0"?>
<sdf version="1.6" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:property name="side" value="1.5"/>
  <world name="walls">
    <xacro:macro name="wall" params="name x">
      <model name="${name}"><static>true</static><pose>${x} 0 0.5 0 0 0</pose><link name="l">
        <collision name="c"><geometry><box><size>0.2 4 1</size></box></geometry></collision></link></model>
    </xacro:macro>
    <xacro:wall name="east" x="${side}"/>
    <xacro:wall name="west" x="${-side}"/>
  </world>
</sdf>
"""


def test_a_xacro_world_is_expanded_and_mapped(tmp_path):
    path = tmp_path / "walls.world.xacro"
    path.write_text(XACRO_WORLD)
    data, res, origin = mapped(str(path), tmp_path / "m", "--resolution", "0.1")
    iy, ix = np.nonzero(data == 100)
    xs = origin[0] + (ix + 0.5) * res
    columns = {x: int((np.round(xs, 2) == x).sum()) for x in set(np.round(xs, 2).tolist())}
    # Two walls 0.2 m thick and 4 m long at x = +-1.5: two whole columns of 40 cells each; their
    # corners lie on cell edges, and the cells holding a corner count as occupied too.
    assert sorted(x for x, n in columns.items() if 40 <= n <= 42) == [-1.55, -1.45, 1.45, 1.55]
    assert all(n <= 2 for x, n in columns.items() if n < 40)


def test_a_world_with_a_fuel_include_maps_with_skip_missing(tmp_path, boxes, monkeypatch):
    monkeypatch.setenv("GZ_FUEL_CACHE_PATH", str(tmp_path / "no-fuel"))
    world = tmp_path / "fuel.sdf"
    world.write_text(BOXES.replace("</world>", "<include><uri>https://fuel.gazebosim.org/1.0/OpenRobotics/models/"
                                               "Construction Cone</uri><pose>3 3 0 0 0 0</pose></include></world>"))
    done = invoke(["map", str(world), "--out", tmp_path / "refused"])
    assert done.exit_code == 2 and "--skip-missing" in done.stderr and not (tmp_path / "refused").exists()
    data, res, origin = mapped(str(world), tmp_path / "m", "--skip-missing")
    assert "include left out" in invoke(["map", str(world), "--out", tmp_path / "m2", "--skip-missing"]).stderr
    plain, *_ = mapped(str(boxes), tmp_path / "plain")
    assert np.array_equal(data, plain)  # the boxes' map, the cone left out


SLAB = """<?xml version='1.0'?>
<sdf version='1.6'><world name='slab'>
  <model name='ground'><static>true</static><pose>0 0 -0.37 0 0 0</pose><link name='l'>
    <collision name='c'><geometry><box><size>20 20 0.86</size></box></geometry></collision></link></model>
  <model name='wall'><static>true</static><pose>2 0 {wall_z} 0 0 0</pose><link name='l'>
    <collision name='c'><geometry><box><size>0.2 4 1</size></box></geometry></collision></link></model>
</world></sdf>
"""


@pytest.mark.parametrize("top", [0.06, 0.2])
def test_a_ground_slab_just_above_zero_is_the_floor_not_its_underside(tmp_path, top):
    """AWS's racetrack: no ground plane, a thick ground whose top is 0.06 m up and whose underside is
    0.8 m down. Mapped without robots, the floor is its top: the ground is free, the wall on it not."""
    world = tmp_path / "slab.sdf"
    world.write_text(SLAB.replace("-0.37", f"{top - 0.43:g}").format(wall_z=top + 0.5))
    done = invoke(["map", str(world), "--out", tmp_path / "m", "--origin", "-6,-6", "--size", "12,12"])
    assert done.exit_code == 0 and f"above the floor at z = {top:g} m" in done.stdout
    data, res, origin = load_map(tmp_path / "m" / "map.yaml")
    assert cell(data, res, origin, 0.0, 0.0) == 0 and cell(data, res, origin, -5.0, 5.0) == 0
    assert cell(data, res, origin, 2.0, 0.0) == 100 and cell(data, res, origin, 2.0, 1.9) == 100
    assert (data == 100).sum() == pytest.approx(4 * 80, rel=0.1)  # the wall's 0.2 x 4 m, nothing of the ground


def test_goals_and_coverage_on_a_raised_ground_see_its_walls_not_the_ground(tmp_path):
    """The same slab world in a scenario: a goal on the ground is free (it was 'inside' the ground,
    its top in the band above z = 0), one in the wall is refused naming it, and coverage lanes fill
    the ground around the wall."""
    from mobot_cli.errors import ScenarioError
    from mobot_cli.scenario.prepare import prepare

    (tmp_path / "slab.sdf").write_text(SLAB.format(wall_z=0.56))
    scenario = tmp_path / "s.yaml"
    body = ("version: 1\nworld: slab.sdf\nduration: 5\nrobots:\n  - name: r\n    description: mobot\n"
            "    pose: {{x: 0, y: 0, z: 0.07}}\n    commands:\n      - {{at: 0.5, {goal}}}\n")
    scenario.write_text(body.format(goal="goto: {x: 1.0, y: 0.5}"))
    assert prepare(scenario).plan.robots[0].commands[0].points == ((1.0, 0.5),)
    scenario.write_text(body.format(goal="goto: {x: 2.0, y: 0.5}"))
    with pytest.raises(ScenarioError, match="goto \\(2, 0.5\\) is inside world model 'wall'"):
        prepare(scenario)
    scenario.write_text(body.format(goal="coverage: {area: [0.5, 3.5, -1, 1], spacing: 0.5}"))
    lanes = prepare(scenario).plan.robots[0].commands[0].points
    assert min(x for x, _ in lanes) < 1.0 and max(x for x, _ in lanes) > 3.0  # both sides of the wall
    assert not any(abs(x - 2.0) < 0.2 and abs(y) < 2.1 for x, y in lanes)  # none in it (around its end)
