"""Collision events from real PyBullet contacts: walls and robots count, floors and ramps do not."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import pytest

from mobot_cli.plan import SpawnPose, StaticBody, WorldPlan
from mobot_cli.scenario.prepare import prepare
from mobot_cli.sim.bullet.world import World

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def bundled():
    """The bundled robot's plan and the quickstart physics (240 Hz)."""
    plan = prepare(REPO / "scenarios" / "quickstart.yaml").plan
    return plan.robots[0], plan.physics


def box(name: str, size, xyz, quat=(0.0, 0.0, 0.0, 1.0)) -> StaticBody:
    urdf = (f'<robot name="{name}"><link name="{name}"><collision><geometry><box size="{size[0]} {size[1]} '
            f'{size[2]}"/></geometry></collision></link></robot>')
    return StaticBody(name=name, urdf=urdf, xyz=xyz, quat=quat)


def drive(world: World, names: list[str], seconds: float, linear: float = 0.3) -> dict[str, int]:
    for name in names:
        world.set_command(name, linear, 0.0)
    for _ in range(round(seconds * world.physics.rate_hz)):
        world.step()
    return {name: world.read(name).collisions for name in names}


def test_pushing_into_a_wall_is_one_collision(bundled):
    robot, physics = bundled
    # The robot reaches the wall after about 2.5 s and keeps pushing for 3.5 s: one event.
    with World(physics, WorldPlan(bodies=(box("wall", (0.1, 2.0, 0.5), (1.0, 0.0, 0.25)),))) as world:
        world.spawn(robot)
        assert world.read("mobot").collisions == 0
        assert drive(world, ["mobot"], 6.0) == {"mobot": 1}
        assert world.read("mobot").true_x < 0.95  # it really was stopped by the wall


def test_leaving_and_touching_again_is_a_second_collision(bundled):
    robot, physics = bundled
    with World(physics, WorldPlan(bodies=(box("wall", (0.1, 2.0, 0.5), (0.6, 0.0, 0.25)),))) as world:
        world.spawn(robot)
        assert drive(world, ["mobot"], 3.0) == {"mobot": 1}
        assert drive(world, ["mobot"], 1.0, linear=-0.3) == {"mobot": 1}  # backing off: no new event
        assert drive(world, ["mobot"], 2.0) == {"mobot": 2}


@pytest.mark.parametrize("floor", ["slab", "ramp"])
def test_standing_on_a_static_floor_or_ramp_is_not_a_collision(bundled, floor):
    robot, physics = bundled
    if floor == "slab":  # a box floor and no ground plane, as a mesh floor of an SDF world would be
        world_plan = WorldPlan(ground_plane=False, bodies=(box("slab", (10, 10, 0.1), (0, 0, -0.05)),))
    else:  # a 10 degree ramp to drive up
        a = math.radians(10)
        ramp = box("ramp", (3, 2, 0.1), (1.8, 0, 0.05), (0, -math.sin(a / 2), 0, math.cos(a / 2)))
        world_plan = WorldPlan(bodies=(ramp,))
    with World(physics, world_plan) as world:
        world.spawn(robot)
        assert drive(world, ["mobot"], 6.0) == {"mobot": 0}
        assert world.read("mobot").true_x > 1.2  # it drove on (and, on the ramp, up)


def test_two_robots_meeting_count_one_collision_each(bundled):
    robot, physics = bundled
    facing = SpawnPose(xyz=(1.0, 0.0, 0.0), quat=(0.0, 0.0, 1.0, 0.0), z_auto=True)  # yaw = pi
    with World(physics, WorldPlan()) as world:
        world.spawn(replace(robot, name="a", namespace="/a", frame_prefix="a/"))
        world.spawn(replace(robot, name="b", namespace="/b", frame_prefix="b/", pose=facing))
        assert drive(world, ["a", "b"], 4.0) == {"a": 1, "b": 1}


def test_which_touch_a_robot_hit_names_does_not_depend_on_the_order_they_come_in():
    """Two touches starting in one sample: ``hit`` names the same one whatever order the set
    of touches iterates in (robots hash by address, so a set's order differs run to run)."""
    from types import SimpleNamespace

    from mobot_cli.sim.contacts import ContactCounter

    hits = []
    for order in (1, -1):
        robot = SimpleNamespace(name="r", body=1, collisions=0, people_collisions=0, hit="")
        counter = ContactCounter(name_of=lambda key: f"{key[0]} {key[1]}")
        counter.record([(robot, ("body", 7)), (robot, ("robot", "a")), (robot, ("body", 3))][::order])
        hits.append((robot.collisions, robot.hit))
    assert hits[0] == hits[1] == (3, "robot a")
