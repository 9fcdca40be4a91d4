"""The World's contract: spawning rules, odometry, determinism, faults. No corpus needed."""

from __future__ import annotations

import math
from dataclasses import replace

import pybullet as p
import pytest

from mobot_cli.errors import SimulationFault, SpawnError
from mobot_cli.plan import DriveSpec, Physics, RobotPlan, SpawnPose, StaticBody, WorldPlan
from mobot_cli.sim.bullet.world import World
from mobot_cli.sim.drive import Odometry, default_separation_multiplier, wheel_speeds

RADIUS, TRACK = 0.05, 0.30


def cart_urdf(axis_sign: int = 1) -> str:
    """A two-wheel cart with a ball caster; axis_sign=-1 flips the wheel axes (to -y)."""
    def wheel(name: str, y: float) -> str:
        return f"""
  <link name="{name}">
    <inertial><mass value="0.3"/><inertia ixx="2e-4" iyy="2e-4" izz="4e-4" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><geometry><cylinder radius="{RADIUS}" length="0.03"/></geometry></collision>
  </link>
  <joint name="{name}_joint" type="continuous">
    <parent link="base_link"/><child link="{name}"/>
    <origin xyz="0 {y} 0" rpy="-1.5707963267948966 0 0"/><axis xyz="0 0 {axis_sign}"/>
  </joint>"""
    return f"""<?xml version="1.0"?>
<robot name="cart">
  <link name="base_footprint">
    <inertial><mass value="0.001"/><inertia ixx="1e-6" iyy="1e-6" izz="1e-6" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <link name="base_link">
    <inertial><origin xyz="-0.05 0 0.05"/><mass value="4.0"/>
      <inertia ixx="0.02" iyy="0.03" izz="0.04" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="-0.05 0 0.06"/><geometry><box size="0.30 0.24 0.10"/></geometry></collision>
  </link>
  <joint name="base_joint" type="fixed">
    <parent link="base_footprint"/><child link="base_link"/><origin xyz="0 0 {RADIUS}"/>
  </joint>
  {wheel("left_wheel", TRACK / 2)}
  {wheel("right_wheel", -TRACK / 2)}
  <link name="caster">
    <inertial><mass value="0.05"/><inertia ixx="1e-5" iyy="1e-5" izz="1e-5" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><geometry><sphere radius="0.025"/></geometry></collision>
  </link>
  <joint name="caster_joint" type="fixed">
    <parent link="base_link"/><child link="caster"/><origin xyz="-0.16 0 -0.025"/>
  </joint>
</robot>"""


DRIVE = DriveSpec(left_joints=("left_wheel_joint",), right_joints=("right_wheel_joint",),
                  wheel_radius=RADIUS, wheel_separation=TRACK, max_wheel_torque=5.0)


def cart(name: str = "cart", *, xyz=(0.0, 0.0, 0.0), yaw: float = 0.0, z_auto: bool = True,
         drive: DriveSpec | None = DRIVE, axis_sign: int = 1) -> RobotPlan:
    quat = (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
    return RobotPlan(name=name, namespace=f"/{name}", frame_prefix=f"{name}/",
                     urdf=cart_urdf(axis_sign), root_link="base_footprint",
                     pose=SpawnPose(xyz=xyz, quat=quat, z_auto=z_auto), drive=drive)


def box_body(name: str, size, xyz) -> StaticBody:
    urdf = f"""<robot name="{name}"><link name="{name}"><collision><geometry>
      <box size="{size[0]} {size[1]} {size[2]}"/></geometry></collision></link></robot>"""
    return StaticBody(name=name, urdf=urdf, xyz=xyz)


def run(world: World, name: str, steps: int, every: int = 0):
    """Step; collect a state every ``every`` steps (never when 0)."""
    states = []
    for i in range(steps):
        world.step()
        if every and i % every == 0:
            states.append(world.read(name))
    return states


def lowest_gap(world: World, name: str, floor: int) -> float:
    points = p.getClosestPoints(world.body_id(name), floor, 1.0, physicsClientId=world.client_id)
    return min(pt[8] for pt in points)


# --- spawning ---------------------------------------------------------------------------

def test_z_auto_rests_lowest_point_on_the_ground():
    with World(Physics(), WorldPlan()) as world:
        world.spawn(cart(xyz=(1.0, 2.0, 0.7)))
        ground = 0  # the ground plane is the world's first body
        assert abs(lowest_gap(world, "cart", ground)) < 0.002
        assert world.read("cart").true_z == pytest.approx(0.0, abs=0.002)


def test_z_auto_rests_on_a_static_platform():
    platform = box_body("platform", (2.0, 2.0, 0.2), (0.0, 0.0, 0.1))
    with World(Physics(), WorldPlan(bodies=(platform,))) as world:
        world.spawn(cart())
        assert world.read("cart").true_z == pytest.approx(0.2, abs=0.002)
        run(world, "cart", 120)  # it stays put: it really rests there
        assert world.read("cart").true_z == pytest.approx(0.2, abs=0.002)


def test_duplicate_name_is_refused():
    with World(Physics(), WorldPlan()) as world:
        world.spawn(cart("r1"))
        with pytest.raises(SpawnError, match="r1"):
            world.spawn(cart("r1", xyz=(3.0, 0.0, 0.0)))
        assert world.names() == ["r1"]


def test_below_the_floor_is_refused_with_name_and_z():
    with World(Physics(), WorldPlan()) as world:
        with pytest.raises(SpawnError, match=r"'sunk'.*z=-0\.050"):
            world.spawn(cart("sunk", xyz=(0.0, 0.0, -0.05), z_auto=False))
        assert world.names() == []
        world.spawn(cart("ok", xyz=(0.0, 0.0, -0.005), z_auto=False))  # a few mm is tolerated


def test_spawning_inside_a_static_body_is_refused():
    crate = box_body("crate", (0.5, 0.5, 0.5), (2.0, 0.0, 0.25))
    with World(Physics(), WorldPlan(bodies=(crate,))) as world:
        with pytest.raises(SpawnError, match="crate"):
            world.spawn(cart(xyz=(2.0, 0.0, 0.0), z_auto=False))


def test_drive_naming_missing_joints_is_refused():
    bad = replace(DRIVE, left_joints=("front_left_wheel_joint",))
    with World(Physics(), WorldPlan()) as world:
        with pytest.raises(SpawnError, match="front_left_wheel_joint"):
            world.spawn(cart(drive=bad))
        assert world.names() == []


def test_remove_and_names():
    with World(Physics(), WorldPlan()) as world:
        world.spawn(cart("a"))
        world.spawn(cart("b", xyz=(2.0, 0.0, 0.0)))
        world.remove("a")
        assert world.names() == ["b"]
        with pytest.raises(KeyError, match="'a'"):
            world.read("a")
        world.spawn(cart("a"))  # the name is free again
        run(world, "a", 10)


# --- driving and odometry ---------------------------------------------------------------

def test_encoder_odometry_tracks_truth_on_a_straight_line():
    # A realistic acceleration limit: a step to full speed would spin the wheels, and then
    # encoder odometry drifts from the truth on a real robot too.
    with World(Physics(), WorldPlan()) as world:
        world.spawn(cart(drive=replace(DRIVE, max_wheel_acceleration=10.0)))
        run(world, "cart", 60)
        world.set_command("cart", 0.5, 0.0)
        run(world, "cart", 4 * 240)
        s = world.read("cart")
        travelled = math.hypot(s.true_x, s.true_y)
        assert travelled > 1.5
        assert math.hypot(s.odom_x - s.true_x, s.odom_y - s.true_y) < 0.01 * travelled
        assert s.odom_vx == pytest.approx(0.5, rel=0.01)
        assert s.true_vx == pytest.approx(0.5, rel=0.01)


def test_ground_truth_odometry_is_truth_relative_to_spawn():
    drive = replace(DRIVE, odometry="ground_truth")
    yaw0 = math.radians(30)
    with World(Physics(), WorldPlan()) as world:
        world.spawn(cart(xyz=(1.0, 2.0, 0.0), yaw=yaw0, drive=drive))
        world.set_command("cart", 0.4, 0.5)
        for s in run(world, "cart", 480, every=40):
            dx, dy = s.true_x - 1.0, s.true_y - 2.0
            assert s.odom_x == pytest.approx(math.cos(yaw0) * dx + math.sin(yaw0) * dy, abs=1e-3)
            assert s.odom_y == pytest.approx(-math.sin(yaw0) * dx + math.cos(yaw0) * dy, abs=1e-3)
            assert s.odom_yaw == pytest.approx(s.true_yaw - yaw0, abs=1e-3)
            assert (s.odom_vx, s.odom_wz) == (s.true_vx, s.true_wz)


def test_spawn_yaw_ninety_drives_along_plus_y():
    with World(Physics(), WorldPlan()) as world:
        world.spawn(cart(yaw=math.pi / 2))
        world.set_command("cart", 0.5, 0.0)
        run(world, "cart", 240)
        s = world.read("cart")
        assert s.true_y > 0.4 and abs(s.true_x) < 0.02
        assert s.odom_x > 0.4 and abs(s.odom_y) < 0.02  # odom frame is the spawn pose


def test_reverse_is_negative_everywhere():
    with World(Physics(), WorldPlan()) as world:
        world.spawn(cart())
        world.set_command("cart", -0.3, 0.0)
        run(world, "cart", 240)
        s = world.read("cart")
        assert s.odom_vx < -0.29 and s.true_vx < -0.29 and s.odom_x < -0.25 and s.true_x < -0.25


def test_flipped_wheel_axes_still_drive_forward():
    with World(Physics(), WorldPlan()) as world:
        world.spawn(cart(axis_sign=-1))
        world.set_command("cart", 0.3, 0.0)
        run(world, "cart", 240)
        s = world.read("cart")
        assert s.true_x > 0.25 and s.odom_x > 0.25


def test_acceleration_limit_ramps_wheel_speed():
    accel = 4.0  # rad/s^2 at the wheel: 0.2 m/s^2 at the rim
    drive = replace(DRIVE, max_wheel_acceleration=accel)
    with World(Physics(), WorldPlan()) as world:
        world.spawn(cart(drive=drive))
        run(world, "cart", 60)
        world.set_command("cart", 0.4, 0.0)
        states = run(world, "cart", 600, every=24)  # a state every 0.1 s
        for k, s in enumerate(states[:15]):
            expected = min(0.4, accel * RADIUS * (k * 24 + 1) / 240)
            assert s.odom_vx == pytest.approx(expected, abs=0.01)
        assert states[-1].odom_vx == pytest.approx(0.4, abs=0.005)


def test_robot_without_drive_is_readable_and_refuses_commands():
    with World(Physics(), WorldPlan()) as world:
        world.spawn(cart(drive=None))
        assert not world.has_drive("cart")
        with pytest.raises(ValueError, match="no drive"):
            world.set_command("cart", 0.1, 0.0)
        run(world, "cart", 10)
        s = world.read("cart")
        assert abs(s.odom_x) < 1e-3 and set(s.joint_positions) == {"left_wheel_joint", "right_wheel_joint"}


# --- determinism and faults ---------------------------------------------------------------

def test_same_plan_gives_bit_identical_states():
    def trace():
        with World(Physics(), WorldPlan()) as world:
            world.spawn(cart("a"))
            world.spawn(cart("b", xyz=(0.0, 1.0, 0.0), yaw=1.0))
            world.set_command("a", 0.3, 0.4)
            world.set_command("b", -0.2, -0.6)
            return [(world.read("a"), world.read("b")) for _ in range(30) if run(world, "a", 10) == []]

    first = trace()
    with World(Physics(), WorldPlan()):  # another world alive in between changes nothing
        second = trace()
    assert first == second


def test_robot_falling_out_of_the_world_is_a_fault():
    with World(Physics(), WorldPlan(ground_plane=False)) as world:
        with pytest.raises(SpawnError, match="nothing to rest on"):
            world.spawn(cart())
        world.spawn(cart(xyz=(0.0, 0.0, 1.0), z_auto=False))
        with pytest.raises(SimulationFault, match=r"'cart'.*step \d+") as info:
            run(world, "cart", 3 * 240)
        assert info.value.exit_code == 3


def test_step_count_counts_whole_steps():
    with World(Physics(rate_hz=100), WorldPlan()) as world:
        run(world, "", 7)
        assert world.step_count == 7


# --- pure drive math ----------------------------------------------------------------------

def test_wheel_speeds_match_diff_drive_controller():
    left, right = wheel_speeds(0.5, 1.0, 0.4, 0.1, 0.1)
    assert (left, right) == pytest.approx(((0.5 - 0.2) / 0.1, (0.5 + 0.2) / 0.1))


def test_exact_integration_closes_a_circle():
    odo = Odometry(separation=0.4)
    for _ in range(100):  # a full circle of radius 1 m in 100 arcs
        odo.integrate(2 * math.pi / 100, 2 * math.pi / 100)
    assert (odo.x, odo.y) == pytest.approx((0.0, 0.0), abs=1e-9)
    assert odo.yaw == pytest.approx(2 * math.pi)


def test_skid_steer_multiplier_model():
    assert default_separation_multiplier(0.5708, 0.512) == pytest.approx(1.2414, abs=1e-4)
    assert default_separation_multiplier(1.0, 0.0) == 1.0
    with pytest.raises(ValueError):
        default_separation_multiplier(0.0, 0.3)
