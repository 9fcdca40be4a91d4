"""The corpus worlds load unchanged, with the counts and extents their authors built them with."""

from __future__ import annotations

import pytest

from mobot_cli.assets.world.worldplan import load_world
from mobot_cli.errors import WorldError
from mobot_cli.sim.preflight import check_world

SMALL_HOUSE = "aws-robomaker-small-house-world/worlds/small_house.world"
BOOKSTORE = "aws-robomaker-bookstore-world/worlds/bookstore.world"
TB3_WORLD = "turtlebot3_simulations/turtlebot3_gazebo/worlds/turtlebot3_world.world"
TB3_HOUSE = "turtlebot3_simulations/turtlebot3_gazebo/worlds/turtlebot3_house.world"
PLAYPEN = "husky/husky_gazebo/worlds/clearpath_playpen.world"
DOLLY_EMPTY = "dolly/dolly_gazebo/worlds/dolly_empty.world"


@pytest.fixture(scope="module")
def small_house(corpus):
    return load_world(str(corpus / SMALL_HOUSE))


def test_small_house_has_87_placements_in_centimetre_meshes(small_house):
    s = small_house.summary
    assert s["models"] == 87 and s["static_models"] == 87 and len(small_house.plan.bodies) == 87
    assert s["shapes"] == {"mesh": 85, "sphere": 2}
    assert s["meshes"]["files"] == 62 and s["meshes"]["converted"] == 62
    # ~19 x 11 x 3 m: the COLLADA unit (centimetres) is applied, node transforms too.
    assert s["bounds"]["min"] == pytest.approx([-9.5, -5.7, -0.04], abs=0.01)
    assert s["bounds"]["max"] == pytest.approx([9.5, 5.7, 3.0], abs=0.01)
    assert not small_house.plan.ground_plane  # the house brings its own mesh floor
    assert s["ignored"]["light"] == 8 and s["max_step_size"] == 0.001
    assert small_house.notices == ("small_house.world: ignored 8 lights, atmosphere, gravity (physics.gravity "
                                   "applies), gui, magnetic_field, physics (max_step_size 0.001 s; mobot steps "
                                   "at physics.rate_hz), scene, spherical_coordinates (mobot simulates "
                                   "collision geometry)",)
    bed = next(b for b in small_house.plan.bodies if b.name == "Bed_01_001")
    assert bed.label == "world model 'Bed_01_001' at (-6.17, 2.03, 0.00)"
    check_world(small_house.plan)  # every converted mesh loads into PyBullet


def test_bookstore_needs_skip_missing_for_its_case_mismatch(corpus):
    with pytest.raises(WorldError, match="has 'aws_spotlight_01_collision.DAE', which differs only in case "
                                         "from 'aws_Spotlight_01_collision.DAE'") as info:
        load_world(str(corpus / BOOKSTORE))
    assert info.value.location.line == 11 and "Spotlight_01/model.sdf" in str(info.value.location.file)
    world = load_world(str(corpus / BOOKSTORE), skip_missing=True)
    s = world.summary
    assert s["models"] == 139 and s["skipped_models"] == ["BookE_01_009"]  # the book at z = 343 km
    assert len(world.plan.bodies) == 137 and s["meshes"]["files"] == 25  # the spotlight left out
    assert s["bounds"]["size"] == pytest.approx([15.70, 14.63, 3.72], abs=0.01)
    assert any("343582.7" in n and "BookE_01_009" in n for n in world.notices)
    check_world(world.plan)


def test_turtlebot3_world_needs_its_fuel_ground_plane(corpus):
    with pytest.raises(WorldError, match="'https://fuel.gazebosim.org/1.0/OpenRobotics/models/Ground Plane' "
                                         "is on Gazebo Fuel"):
        load_world(str(corpus / TB3_WORLD))
    world = load_world(str(corpus / TB3_WORLD), skip_missing=True)
    assert world.summary["shapes"] == {"cylinder": 9, "mesh": 6}  # the ROS symbol, hexagons and walls
    assert sum("include left out" in n for n in world.notices) == 2
    check_world(world.plan)


def test_turtlebot3_house_static_multi_link_model_loads(corpus):
    """pybullet.loadSDF crashes on this model; here it is one static model of 34 links."""
    world = load_world(str(corpus / TB3_HOUSE), skip_missing=True)
    assert world.summary["links"] == 34 and world.summary["shapes"]["box"] == 100
    check_world(world.plan)  # 108 shapes: more than PyBullet's 16 per compound


def test_clearpath_playpen_applies_the_world_state(corpus, monkeypatch):
    monkeypatch.setenv("GAZEBO_MODEL_PATH", str(corpus / "gazebo_models"))
    world = load_world(str(corpus / PLAYPEN))
    s = world.summary
    assert s["models"] == 36 and s["held_fixed"] == 14 and s["state_poses"] == 36
    assert world.plan.ground_plane
    dumpster = next(b for b in world.plan.bodies if b.name == "Dumpster")
    assert dumpster.xyz == pytest.approx((2.0181, 8.87221, 0.050916))  # <state>, not <model><pose>
    check_world(world.plan)


def test_dolly_empty_has_dolly_as_a_robot(corpus):
    world = load_world(str(corpus / DOLLY_EMPTY))
    assert world.plan.ground_plane  # model://ground_plane: mobot's bundled copy
    assert [r.name for r in world.robots] == ["Dolly"] and world.plan.bodies == ()
    dolly = world.robot("Dolly")
    assert dolly.xyz == (0.0, 0.0, 0.33)  # the include's pose replaces the model's own 0.225
    assert '<plugin name="diff_drive" filename="libgazebo_ros_diff_drive.so">' in dolly.urdf
