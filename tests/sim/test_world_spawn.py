"""Robots in SDF worlds: resting on mesh floors, refused inside furniture or under the floor,
SDF robots (a world's own, or a model file) driven by name, the bundled worlds' scenarios."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest
import trimesh

from mobot_cli.assets.description.describe import load_robot
from mobot_cli.assets.world.worldplan import load_world
from mobot_cli.cli import CommandResult, invoke
from mobot_cli.errors import ScenarioError, SpawnError
from mobot_cli.plan import Physics, RobotPlan, SpawnPose
from mobot_cli.scenario.prepare import prepare
from mobot_cli.sim.bullet.world import World

REPO = Path(__file__).resolve().parents[2]
SMALL_HOUSE = "aws-robomaker-small-house-world/worlds/small_house.world"


@pytest.fixture(scope="module")
def mobot_desc():
    return load_robot("mobot")


def robot(desc, name="mobot", xyz=(0.0, 0.0, 0.0), z_auto=True) -> RobotPlan:
    return RobotPlan(name=name, namespace=f"/{name}", frame_prefix=f"{name}/", urdf=desc.urdf,
                     root_link=desc.root_link, pose=SpawnPose(xyz=xyz, z_auto=z_auto), drive=desc.drive)


@pytest.fixture(scope="module")
def house_plan(corpus):
    return load_world(str(corpus / SMALL_HOUSE)).plan


def test_tutorial_spawn_rests_on_the_mesh_floor_and_drives(house_plan, mobot_desc):
    with World(Physics(), house_plan) as world:
        world.spawn(robot(mobot_desc, xyz=(3.5, 1.0, 0.7)))  # z: auto finds the floor, not z = 0.7
        start = world.read("mobot")
        assert start.true_z == pytest.approx(0.0, abs=0.002)
        world.set_command("mobot", 0.3, 0.0)
        heights = []
        for step in range(4 * 240):
            world.step()
            if step % 24 == 0:
                heights.append(world.read("mobot").true_z)
        end = world.read("mobot")
    assert end.true_x - start.true_x == pytest.approx(1.2, abs=0.06)
    assert end.true_y == pytest.approx(1.0, abs=0.02)
    assert max(abs(h) for h in heights) < 0.003  # no bumps at the floor mesh's triangle edges


@pytest.mark.parametrize("xy, message", [
    ((-6.165, 2.03), "is inside world model 'Bed_01_001' at (-6.17, 2.03, 0.00)"),
    ((-2.0, -5.2), "is inside world model 'AirconditionerB_01_001' at (-2.00, -5.23, 0.00)"),
])
def test_spawn_inside_furniture_names_it(house_plan, mobot_desc, xy, message):
    with World(Physics(), house_plan) as world:
        with pytest.raises(SpawnError) as info:
            world.spawn(robot(mobot_desc, xyz=(*xy, 0.0)))
        assert message in info.value.message
        assert world.names() == []


def test_a_body_that_moves_does_not_hide_the_furniture_a_robot_is_spawned_in(house_plan, mobot_desc):
    """The inside test's rays see static bodies only: a round body with mass over the robot (a
    ball inside the bed) used to stop the ray looking up, which then walked through it 0.1 mm at
    a time, as far as it may cross surfaces, and never reached the bed's top: the robot was let
    in. (Robots packed in a fleet did that to each other's sideways rays.)"""
    from mobot_cli.sim.pb import p

    with World(Physics(), house_plan) as world:
        cid = world.client_id
        shape = p.createCollisionShape(p.GEOM_SPHERE, radius=0.1, physicsClientId=cid)
        p.createMultiBody(1.0, shape, basePosition=(-6.165, 2.03, 0.3), physicsClientId=cid)
        with pytest.raises(SpawnError, match="is inside world model 'Bed_01_001'"):
            world.spawn(robot(mobot_desc, xyz=(-6.165, 2.03, 0.0)))


def test_spawn_below_the_mesh_floor_is_refused(house_plan, mobot_desc):
    with World(Physics(), house_plan) as world:
        with pytest.raises(SpawnError, match=r"z=-0\.500 is below the floor: world model 'FloorB_01_001'"):
            world.spawn(robot(mobot_desc, xyz=(3.5, 1.0, -0.5), z_auto=False))
        world.spawn(robot(mobot_desc, xyz=(3.5, 1.0, 0.0), z_auto=False))  # on it is fine


def test_z_auto_finds_a_raised_mesh_floor(tmp_path, mobot_desc):
    trimesh.creation.box((4.0, 4.0, 0.2)).export(tmp_path / "slab.stl")
    (tmp_path / "raised.world").write_text(
        "<?xml version='1.0'?><sdf version='1.6'><world name='w'><model name='stage'><static>1</static>"
        "<pose>0 0 0.4 0 0 0</pose><link name='l'><collision name='c'><geometry><mesh>"
        "<uri>slab.stl</uri></mesh></geometry></collision></link></model></world></sdf>")
    plan = load_world(str(tmp_path / "raised.world"), tmp_path).plan
    with World(Physics(), plan) as world:
        world.spawn(robot(mobot_desc))
        assert world.read("mobot").true_z == pytest.approx(0.5, abs=0.002)


def test_bundled_house_origin_is_taken_by_the_coffee_table(mobot_desc):
    with World(Physics(), load_world("house").plan) as world:
        with pytest.raises(SpawnError, match="world model 'coffee_table' at \\(0.00, 0.00, 0.00\\)"):
            world.spawn(robot(mobot_desc))
        world.spawn(robot(mobot_desc, xyz=(-3.0, -2.5, 0.0)))


def _scenario(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "s.yaml"
    path.write_text("version: 1\nname: s\n" + text)
    return path


def test_dolly_in_its_world_is_driven_by_name(corpus, tmp_path):
    path = _scenario(tmp_path, f"world: {corpus / 'dolly/dolly_gazebo/worlds/dolly_empty.world'}\n"
                               "duration: 6.0\nsettle: 1.0\nrobots:\n  - name: Dolly\n"
                               "    commands: [{at: 1.0, linear: 0.5, for: 4.0}]\n")
    out = tmp_path / "run"
    assert invoke(["run", str(path), "--out", str(out), "--quiet"]) == CommandResult(0, "", "")
    with (out / "odom" / "Dolly.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert float(rows[0]["true_z"]) == pytest.approx(0.33)  # the world's pose: it drops onto its wheels
    assert float(rows[-1]["true_z"]) == pytest.approx(0.225, abs=0.003)
    assert float(rows[-1]["true_x"]) == pytest.approx(2.0, abs=0.05)  # the plugin's drive, 0.5 m/s
    resolved = (out / "scenario.yaml").read_text()
    assert "description" not in resolved.split("robots:")[1]  # still the world's own Dolly
    again = tmp_path / "again"
    assert invoke(["run", str(out / "scenario.yaml"), "--out", str(again), "--quiet"]) == CommandResult(0, "", "")
    assert (again / "odom" / "Dolly.csv").read_bytes() == (out / "odom" / "Dolly.csv").read_bytes()


def test_world_robots_not_listed_are_named_and_static_names_are_taken(corpus, tmp_path):
    dolly_world = corpus / "dolly/dolly_gazebo/worlds/dolly_empty.world"
    plan = prepare(_scenario(tmp_path, f"world: {dolly_world}\nduration: 1.0\nrobots:\n"
                                       "  - {name: r1, pose: {x: 3}}\n")).plan
    assert any("world model 'Dolly' is a robot" in n and "- name: Dolly" in n for n in plan.notices)
    with pytest.raises(ScenarioError, match="'coffee_table' is already the name of a static model"):
        prepare(_scenario(tmp_path, "world: house\nduration: 1.0\nrobots:\n  - {name: coffee_table}\n"))


def test_sdf_model_files_are_robot_descriptions(corpus):
    models = corpus / "turtlebot3_simulations/turtlebot3_gazebo/models"
    burger = load_robot(str(models / "turtlebot3_burger" / "model.sdf"))  # gz-sim DiffDrive plugin
    assert burger.drive.source == "plugin" and burger.drive.left_joints == ("wheel_left_joint",)
    assert (burger.drive.wheel_radius, burger.drive.wheel_separation) == (0.033, 0.16)
    assert burger.root_link == "base_footprint"
    dolly = load_robot(str(corpus / "dolly/dolly_gazebo/models/dolly"))  # a model folder
    assert dolly.drive.wheel_separation == 1.25  # the plugin's value, as Gazebo uses it
    assert {j.name: j.type for j in dolly.joints}["caster_wheel"] == "fixed"
    assert any("ball joint 'caster_wheel' becomes fixed" in str(n) for n in dolly.notices)


def _summary_and_rows(tmp_path, name):
    out = tmp_path / name
    result = invoke(["run", str(REPO / "scenarios" / f"{name}.yaml"), "--out", str(out), "--quiet"])
    assert result == CommandResult(0, "", "")
    with (out / "odom" / "mobot.csv").open() as f:
        rows = [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]
    return json.loads((out / "summary.json").read_text()), rows


def test_house_scenario_drives_through_the_doorway(tmp_path):
    summary, rows = _summary_and_rows(tmp_path, "house")
    at_door = min(rows, key=lambda r: abs(r["true_x"] - 1.0))  # the wall between the rooms
    assert at_door["true_y"] == pytest.approx(-2.5, abs=0.05)  # the doorway spans y -3..-2
    end = rows[-1]
    assert end["true_x"] == pytest.approx(1.8, abs=0.1) and end["true_y"] == pytest.approx(-1.9, abs=0.1)
    assert max(abs(r["true_z"]) for r in rows) < 0.005
    assert summary["robots"]["mobot"].get("collisions", 0) == 0


def test_bookstore_scenario_stays_in_its_aisle(tmp_path):
    _, rows = _summary_and_rows(tmp_path, "bookstore")
    assert all(abs(r["true_y"] + 2.0) < 0.05 for r in rows)  # the aisle is 1.4 m wide
    assert rows[-1]["true_x"] == pytest.approx(-1.5, abs=0.1)


def test_skip_missing_flag_for_run_and_check(corpus, tmp_path):
    world = corpus / "aws-robomaker-bookstore-world/worlds/bookstore.world"
    refused = invoke(["check", world])
    assert (refused.exit_code, refused.stdout) == (2, "") and refused.stderr.startswith("mobot: error: ")
    skipped = invoke(["check", world, "--skip-missing"])
    assert skipped.exit_code == 0 and skipped.stdout.startswith("ok: world ")
    assert "differs only in case" in skipped.stderr  # the left-out model, as a warning
    path = _scenario(tmp_path, f"world: {world}\nduration: 0.5\n")
    assert invoke(["run", path, "--out", tmp_path / "no", "--quiet"]) == CommandResult(2, "", refused.stderr)
    assert not (tmp_path / "no").exists()
    out = tmp_path / "run"
    done = invoke(["run", path, "--out", out, "--skip-missing"])
    assert done.exit_code == 0 and done.stdout.endswith(f"run folder: {out} (trajectory.png)\n")
    assert "skip_missing: true" in (out / "scenario.yaml").read_text()  # the rerun skips too
    assert "differs only in case" in done.stderr and "BookE_01_009" in done.stderr


POSTER_WORLD = """<?xml version="1.0"?>
<sdf version="1.6"><world name="posters">
  <include><uri>model://ground_plane</uri></include>
  <model name="poster"><static>true</static><pose>2 0 0.4 0 0 0</pose><link name="l">
    <collision name="c"><geometry><plane><normal>-1 0 0</normal><size>1.5 0.8</size></plane></geometry>
    </collision></link></model>
</world></sdf>
"""


@pytest.mark.parametrize("y, blocked", [(2.0, False), (0.0, True)])
def test_a_finite_plane_blocks_only_where_it_is(tmp_path, mobot_desc, y, blocked):
    """A plane with a <size> is a poster, not an endless wall across the world."""
    (tmp_path / "posters.world").write_text(POSTER_WORLD)
    world_plan = load_world(str(tmp_path / "posters.world")).plan
    with World(Physics(), world_plan) as world:
        world.spawn(robot(mobot_desc, xyz=(0.0, y, 0.0)))
        world.set_command("mobot", 0.3, 0.0)
        for _ in range(10 * 240):
            world.step()
        end = world.read("mobot")
    assert (end.true_x < 2.0) is blocked
    assert not blocked or end.true_x > 1.6  # it drove up to the poster


def test_spawn_into_a_wall_names_the_wall_and_where_it_stands(mobot_desc):
    """Issue 33: the house's walls are one model of twelve boxes; the refusal says which."""
    with World(Physics(), load_world("house").plan) as world:
        with pytest.raises(SpawnError) as info:
            world.spawn(robot(mobot_desc, xyz=(5.0, 1.0, 0.0)))
        assert world.names() == []
        world.spawn(robot(mobot_desc, xyz=(5.0, 2.0, 0.0)))  # a metre north is the kitchen
    assert ("reaches 15.0 cm into world model 'house_walls' at (0.00, 0.00, 0.00), its collision "
            "'house_walls::walls::wall_mid_y_east_1', a 2.00 x 0.15 x 2.50 m box centred at (5.00, 1.00, 1.25)"
            in info.value.message)


def test_spawn_into_a_corpus_multi_link_model_names_its_link(corpus, mobot_desc):
    """turtlebot3_house is one static model of 34 links in seven PyBullet bodies (16 shapes each)."""
    plan = load_world(str(corpus / "turtlebot3_simulations/turtlebot3_gazebo/worlds/turtlebot3_house.world"),
                      skip_missing=True).plan
    with World(Physics(), plan) as world:
        with pytest.raises(SpawnError) as info:
            world.spawn(robot(mobot_desc, xyz=(-5.15, -1.5, 0.0)))
    assert ("into world model 'turtlebot3_house' at (0.00, 0.00, 0.00), its collision "
            "'turtlebot3_house::turtlebot3_house::Wall_88::Wall_88_Collision', a 5.00 x 0.15 x 2.50 m box "
            "centred at (-5.15, -1.50, 1.25)" in info.value.message)


def test_goal_in_a_wall_names_the_wall(tmp_path):
    path = _scenario(tmp_path, "world: house\nduration: 3\nrobots:\n  - name: mobot\n    pose: {x: -3, y: -2.5}\n"
                               "    commands:\n      - {at: 1.0, goto: {x: 5.0, y: 1.0}}\n")
    with pytest.raises(ScenarioError) as info:
        prepare(path)
    assert ("goto (5, 1) is inside world model 'house_walls' at (0.00, 0.00, 0.00), its collision "
            "'house_walls::walls::wall_mid_y_east_1', a 2.00 x 0.15 x 2.50 m box centred at (5.00, 1.00, 1.25)"
            in info.value.message)


def test_house_patrol_scenario_completes_its_patrol_and_scans_the_rooms(tmp_path):
    """scenarios/house_patrol.yaml: the lidar switched on, a patrol that completes, CSV and MCAP."""
    out = tmp_path / "house_patrol"
    assert invoke(["run", str(REPO / "scenarios" / "house_patrol.yaml"), "--out", str(out), "--quiet"]) \
        == CommandResult(0, "", "")
    summary = json.loads((out / "summary.json").read_text())
    mobot = summary["robots"]["mobot"]
    [goal] = mobot["goals"]
    assert (goal["status"], goal["laps"]) == ("reached", 1) and goal["ended_at"] < summary["sim_time"]
    assert goal["path_length"] > 8.0  # living room -> bedroom -> living room, ~9 m
    assert mobot["collisions"] == 0 and summary["expectations"]["failed"] == 0
    [scan] = mobot["sensors"]
    assert (scan["topic"], scan["readings"]) == ("/mobot/scan", 141)  # 5 Hz over 28 s, from t = 0
    ranges = np.load(out / scan["file"])["ranges"]
    seen = np.isfinite(ranges) & (ranges < 8.0)
    assert ranges.shape == (141, 180) and seen.mean() > 0.9  # walls and furniture in every room
    assert (out / "bag" / "bag.mcap").stat().st_size > 0 and (out / "odom" / "mobot.csv").is_file()
