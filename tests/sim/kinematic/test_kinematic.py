"""The kinematic engine on real PyBullet bodies: exact motion, drive limits, walls, robots, floors."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import pytest

from mobot_cli.errors import SpawnError
from mobot_cli.plan import Physics, SpawnPose, StaticBody, StaticShape, WorldPlan
from mobot_cli.scenario.prepare import prepare
from mobot_cli.sim.bullet.world import World
from mobot_cli.sim.engine import open_world
from mobot_cli.sim.kinematic.fit import PENETRATION
from mobot_cli.sim.kinematic.world import KinematicWorld
from mobot_cli.sim.pb import p
from tests.sim.test_contacts import box

REPO = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def bundled():
    """The bundled robot's plan (quickstart: at the origin, facing +x), its wheels without the
    acceleration limit its plugin sets, so that a twist takes effect at once."""
    robot = prepare(REPO / "scenarios" / "quickstart.yaml").plan.robots[0]
    return replace(robot, drive=replace(robot.drive, max_wheel_acceleration=None))


def kinematic(rate_hz: int = 10) -> Physics:
    return Physics(rate_hz=rate_hz, engine="kinematic")


def run(world: World, name: str, linear: float, angular: float, seconds: float) -> None:
    world.set_command(name, linear, angular)
    for _ in range(round(seconds * world.physics.rate_hz)):
        world.step()
    world.set_command(name, 0.0, 0.0)


def gap(world: World, a: str, b: int) -> float:
    """Signed distance between a robot and a body (negative: overlapping), not counting support."""
    points = [c for c in p.getClosestPoints(world.body_id(a), b, 0.5, physicsClientId=world.client_id)
              if c[7][2] <= 0.7]
    return min(c[8] for c in points)


def test_the_plan_picks_the_engine():
    with open_world(kinematic(), WorldPlan()) as world:
        assert isinstance(world, KinematicWorld)
    with open_world(Physics(), WorldPlan()) as world:
        assert type(world) is World


@pytest.mark.parametrize("rate", [10, 50, 240, 1000])
def test_straight_two_metres_lands_at_two_metres(bundled, rate):
    with open_world(kinematic(rate), WorldPlan()) as world:
        world.spawn(bundled)
        start = world.read("mobot")
        run(world, "mobot", 0.5, 0.0, 4.0)
        end = world.read("mobot")
    assert end.true_x - start.true_x == pytest.approx(2.0, abs=1e-9)
    assert end.true_y == pytest.approx(start.true_y, abs=1e-12)
    assert (end.true_z, end.true_roll, end.true_pitch) == (start.true_z, 0.0, 0.0)
    assert (end.odom_x, end.odom_y, end.odom_yaw) == pytest.approx((2.0, 0.0, 0.0), abs=1e-9)
    # The wheels turned by the rotation the distance implies: 2 m / r, in the rolling direction.
    radius = bundled.drive.wheel_radius
    for joint in bundled.drive.left_joints + bundled.drive.right_joints:
        turned = end.joint_positions[joint] - start.joint_positions[joint]
        assert abs(turned) == pytest.approx(2.0 / radius, rel=1e-9)


@pytest.mark.parametrize("rate", [10, 240])
def test_a_quarter_turn_in_place_is_exact(bundled, rate):
    with open_world(kinematic(rate), WorldPlan()) as world:
        world.spawn(bundled)
        run(world, "mobot", 0.0, math.pi / 4.0, 2.0)
        end = world.read("mobot")
    assert end.true_yaw == pytest.approx(math.pi / 2.0, abs=1e-12)
    assert (end.true_x, end.true_y) == pytest.approx((0.0, 0.0), abs=1e-12)
    assert end.odom_yaw == pytest.approx(math.pi / 2.0, abs=1e-12)


def test_an_arc_matches_the_closed_form(bundled):
    # 0.4 m/s at 0.5 rad/s for 2 s: a circle of radius 0.8 m through 1 rad.
    with open_world(kinematic(10), WorldPlan()) as world:
        world.spawn(bundled)
        run(world, "mobot", 0.4, 0.5, 2.0)
        end = world.read("mobot")
    assert (end.true_x, end.true_y, end.true_yaw) == pytest.approx(
        (0.8 * math.sin(1.0), 0.8 * (1.0 - math.cos(1.0)), 1.0), abs=1e-12)
    assert (end.odom_x, end.odom_y, end.odom_yaw) == pytest.approx((end.true_x, end.true_y, 1.0), abs=1e-12)


def test_acceleration_limit_ramps_the_speed(bundled):
    alpha = 4.0  # rad/s^2 at the wheel
    robot = replace(bundled, drive=replace(bundled.drive, max_wheel_acceleration=alpha))
    rate, radius = 50, bundled.drive.wheel_radius
    with open_world(kinematic(rate), WorldPlan()) as world:
        world.spawn(robot)
        world.set_command("mobot", 0.5, 0.0)
        speeds = []
        for _ in range(rate * 4):
            world.step()
            speeds.append(world.read("mobot").true_vx)
        # Every step the wheels gain alpha * dt until the commanded 0.5 m/s.
        expected = [min(0.5, k * alpha / rate * radius) for k in range(1, rate * 4 + 1)]
        assert speeds == pytest.approx(expected, abs=1e-12)
        assert speeds[0] < 0.01 and speeds[-1] == pytest.approx(0.5)
        world.set_command("mobot", 0.0, 0.0)
        world.step()
        assert world.read("mobot").true_vx == pytest.approx(0.5 - alpha / rate * radius)


def test_the_urdf_wheel_velocity_limit_caps_the_speed(bundled):
    radius = bundled.drive.wheel_radius
    with open_world(kinematic(10), WorldPlan()) as world:
        world.spawn(bundled)
        run(world, "mobot", 100.0, 0.0, 1.0)  # the bundled robot's wheels allow 30 rad/s
        assert world.read("mobot").true_x == pytest.approx(30.0 * radius, rel=1e-9)


def test_driving_into_a_wall_stops_at_the_wall_and_counts_once(bundled):
    wall = box("wall", (0.1, 2.0, 0.5), (1.0, 0.0, 0.25))
    with open_world(kinematic(10), WorldPlan(bodies=(wall,))) as world:
        world.spawn(bundled)
        wall_id = next(uid for uid, label in world._statics.items() if "wall" in label)
        run(world, "mobot", 0.5, 0.0, 6.0)
        state = world.read("mobot")
        assert -PENETRATION <= gap(world, "mobot", wall_id) <= 0.001
        assert state.collisions == 1
        stopped_at = state.true_x
        run(world, "mobot", 0.5, 0.0, 2.0)  # pushing on: not a new collision, no further
        assert world.read("mobot").true_x == pytest.approx(stopped_at, abs=1e-9)
        assert world.read("mobot").collisions == 1
        run(world, "mobot", -0.3, 0.0, 1.0)  # backing off is free
        assert world.read("mobot").true_x == pytest.approx(stopped_at - 0.3, abs=1e-9)
        run(world, "mobot", 0.3, 0.0, 2.0)
        assert world.read("mobot").collisions == 2
        assert -PENETRATION <= gap(world, "mobot", wall_id) <= 0.001


def test_two_robots_driving_into_each_other_stop(bundled):
    a = replace(bundled, name="a", namespace="/a", frame_prefix="a/", pose=SpawnPose((-1.0, 0.0, 0.0), z_auto=True))
    b = replace(bundled, name="b", namespace="/b", frame_prefix="b/",
                pose=SpawnPose((1.0, 0.0, 0.0), (0.0, 0.0, 1.0, 0.0), z_auto=True))  # facing -x
    with open_world(kinematic(10), WorldPlan()) as world:
        world.spawn(a)
        world.spawn(b)
        world.set_command("a", 0.4, 0.0)
        world.set_command("b", 0.4, 0.0)
        for _ in range(50):
            world.step()
        sa, sb = world.read("a"), world.read("b")
        assert -PENETRATION <= gap(world, "a", world.body_id("b")) <= 0.001
        assert (sa.collisions, sb.collisions) == (1, 1)
        assert sa.true_x < 0.0 < sb.true_x and sa.true_vx == sb.true_vx == 0.0
        # They met in the middle, give or take the one step (0.04 m) the first to move gains.
        assert sa.true_x == pytest.approx(-sb.true_x, abs=0.04 + 0.002)


def test_standing_and_driving_on_the_floor_is_not_a_collision(bundled):
    with open_world(kinematic(10), WorldPlan()) as world:
        world.spawn(bundled)
        run(world, "mobot", 0.5, 0.3, 5.0)
        assert world.read("mobot").collisions == 0


def ramp_world(shapes: bool) -> tuple[WorldPlan, float]:
    """A 10 degree ramp from x = 1 up to a platform 0.1 m high from x = ~1.57 on (its top)."""
    angle = math.radians(10.0)
    length, height = 0.1 / math.sin(angle), 0.1
    run_x = length * math.cos(angle)
    quat = (0.0, -math.sin(angle / 2.0), 0.0, math.cos(angle / 2.0))
    # A thin slab whose top face rises from (1, 0) to (1 + run_x, 0.1).
    centre = (1.0 + run_x / 2.0 + 0.01 * math.sin(angle), 0.0, height / 2.0 - 0.01 * math.cos(angle))
    slab = (length, 2.0, 0.02)
    deck = ((2.0, 2.0, 0.1), (1.0 + run_x + 1.0, 0.0, 0.05))
    if shapes:
        bodies = (StaticBody("ramp", xyz=centre, quat=quat, shapes=(StaticShape("box", slab),)),
                  StaticBody("deck", xyz=deck[1], shapes=(StaticShape("box", deck[0]),)))
    else:
        bodies = (box("ramp", slab, centre, quat), box("deck", *deck))
    return WorldPlan(bodies=bodies), height


@pytest.mark.parametrize("shapes", [True, False], ids=["embree-floor", "pybullet-floor"])
def test_the_floor_is_followed_up_a_ramp_onto_a_deck(bundled, shapes):
    world_plan, height = ramp_world(shapes)
    with open_world(kinematic(10), world_plan) as world:
        world.spawn(bundled)
        z0 = world.read("mobot").true_z
        run(world, "mobot", 0.5, 0.0, 5.0)  # 2.5 m: up the ramp and along the deck
        end = world.read("mobot")
    assert end.true_x == pytest.approx(2.5, abs=1e-9)
    assert end.true_z - z0 == pytest.approx(height, abs=1e-4)
    assert (end.true_roll, end.true_pitch) == (0.0, 0.0)  # it does not tip
    assert end.collisions == 0


def test_a_step_too_high_to_roll_onto_is_a_wall(bundled):
    step = box("step", (1.0, 2.0, 0.06), (1.5, 0.0, 0.03))
    with open_world(kinematic(10), WorldPlan(bodies=(step,))) as world:
        world.spawn(bundled)
        run(world, "mobot", 0.5, 0.0, 4.0)
        state = world.read("mobot")
        assert state.true_x < 1.0 and state.true_z == pytest.approx(0.0, abs=1e-9)
        assert state.collisions == 1


def test_the_house_mesh_floor_carries_the_robot_through_the_door():
    prepared = prepare(REPO / "scenarios" / "house.yaml",
                       ["physics.engine=kinematic", "physics.rate_hz=20", "log.rate_hz=20"])
    plan = prepared.plan
    robot = plan.robots[0]
    with open_world(plan.physics, plan.world) as world:
        world.spawn(replace(robot, drive=replace(robot.drive, max_wheel_acceleration=None)))
        z0 = world.read("mobot").true_z
        run(world, "mobot", 0.5, 0.0, 9.6)  # 4.8 m east, through the doorway
        end = world.read("mobot")
    assert end.true_x == pytest.approx(-3.0 + 4.8, abs=1e-9)
    assert end.true_z == pytest.approx(z0, abs=1e-4) and end.collisions == 0


def test_a_robot_without_a_floor_under_it_is_refused(bundled):
    with pytest.raises(Exception, match="no floor under it|fell|floor"):
        with open_world(kinematic(10), WorldPlan(ground_plane=False)) as world:
            world.spawn(replace(bundled, pose=SpawnPose((0.0, 0.0, 1.0))))


def test_a_teleported_robot_goes_on_from_where_it_was_put(bundled):
    """set_state in the kinematic engine: the robot stays where it was put, drives on from there,
    reads its new pose back, and a teleport into a wall is refused and leaves it where it was."""
    wall = box("wall", (0.1, 2.0, 0.5), (3.0, 0.0, 0.25))
    with open_world(kinematic(10), WorldPlan(bodies=(wall,))) as world:
        world.spawn(bundled)
        run(world, "mobot", 0.5, 0.0, 1.0)
        world.teleport("mobot", SpawnPose((1.0, 1.0, 0.0), (0.0, 0.0, math.sin(0.25), math.cos(0.25)), z_auto=True))
        world.step()  # standing still: it stays where it was put
        state = world.read("mobot")
        assert (state.true_x, state.true_y, state.true_yaw) == pytest.approx((1.0, 1.0, 0.5), abs=1e-6)
        assert world.kinematics("mobot").position[:2] == pytest.approx((1.0, 1.0), abs=1e-9)
        run(world, "mobot", 0.5, 0.0, 2.0)  # 1 m along its new heading
        state = world.read("mobot")
        assert (state.true_x, state.true_y) == pytest.approx((1.0 + math.cos(0.5), 1.0 + math.sin(0.5)), abs=1e-6)
        before = (state.true_x, state.true_y)
        with pytest.raises(SpawnError):
            world.teleport("mobot", SpawnPose((3.0, 0.0, 0.0), z_auto=True))
        world.step()
        assert (world.read("mobot").true_x, world.read("mobot").true_y) == pytest.approx(before, abs=1e-9)


def test_a_reset_kinematic_world_replays_the_same_motion(bundled):
    wall = box("wall", (0.1, 2.0, 0.5), (1.0, 0.0, 0.25))
    with open_world(kinematic(10), WorldPlan(bodies=(wall,))) as world:
        runs = []
        for _ in range(2):
            world.spawn(bundled)
            run(world, "mobot", 0.5, 0.0, 6.0)  # into the wall: stopped and counted
            runs.append((world.step_count, world.read("mobot")))
            world.reset()
        assert runs[0] == runs[1] and runs[0][1].collisions == 1
