"""Robots of our own that reproduce what public descriptions do: drive wheels below prismatic
wheel drops, a base whose <inertial><origin rpy> is rotated. z: auto rests each on its wheels,
an explicit z just above the floor is accepted, and the suspended wheels drive."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from mobot_cli.assets.description.describe import load_robot
from mobot_cli.plan import Physics, RobotPlan, SpawnPose, WorldPlan
from mobot_cli.sim.bullet.world import World

WHEELDROP = Path(__file__).parent / "robots" / "wheeldrop.urdf.xacro"
RESTING_Z = 0.035  # base_link above the floor when the wheels (radius 0.035) touch it
ROTATIONS = ("0 0 0", "1.5707963 0 0", "0 1.5707963 0", "0.3 0.7 1.2")


def plan(args: dict[str, str], xyz=(0.0, 0.0, 0.5), yaw=0.6, z_auto=True) -> RobotPlan:
    desc = load_robot(str(WHEELDROP), args)
    quat = (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
    return RobotPlan(name="r", namespace="/r", frame_prefix="r/", urdf=desc.urdf,
                     root_link=desc.root_link, pose=SpawnPose(xyz=xyz, quat=quat, z_auto=z_auto),
                     drive=desc.drive)


@pytest.mark.parametrize("rpy", ROTATIONS)
def test_z_auto_rests_on_the_wheels_whatever_the_inertial_frame(rpy):
    with World(Physics(), WorldPlan()) as world:
        world.spawn(plan({"inertial_rpy": rpy}))
        spawned = world.read("r")
        for _ in range(240):
            world.step()
        settled = world.read("r")
    assert spawned.true_z == pytest.approx(RESTING_Z, abs=1e-3)  # not lying on its side
    assert spawned.true_yaw == pytest.approx(0.6, abs=1e-6)
    assert settled.true_z == pytest.approx(RESTING_Z, abs=1e-3)  # it did not drop
    assert abs(settled.true_roll) < 1e-3 and abs(settled.true_pitch) < 1e-3


@pytest.mark.parametrize("rpy", ROTATIONS)
def test_explicit_z_just_above_the_floor_is_accepted(rpy):
    with World(Physics(), WorldPlan()) as world:
        world.spawn(plan({"inertial_rpy": rpy}, xyz=(1.0, 2.0, RESTING_Z + 0.003), z_auto=False))
        state = world.read("r")
    assert (state.true_x, state.true_y, state.true_z) == pytest.approx((1.0, 2.0, RESTING_Z + 0.003))


@pytest.mark.parametrize("suspension", ["prismatic", "fixed"])
def test_wheels_below_wheel_drops_drive_and_turn(suspension):
    robot = plan({"suspension": suspension, "inertial_rpy": "0.3 0.7 1.2"}, yaw=0.0)
    assert robot.drive.left_joints == ("left_wheel_joint",)
    with World(Physics(), WorldPlan()) as world:
        world.spawn(robot)
        for _ in range(120):
            world.step()
        start = world.read("r")
        world.set_command("r", 0.2, 0.0)
        for _ in range(5 * 240):
            world.step()
        world.set_command("r", 0.0, 1.0)
        for _ in range(round(math.pi / 2 * 240)):
            world.step()
        world.set_command("r", 0.0, 0.0)
        for _ in range(240):
            world.step()
        end = world.read("r")
    assert end.true_x - start.true_x == pytest.approx(1.0, rel=0.03)
    assert math.degrees(end.true_yaw - start.true_yaw) == pytest.approx(90.0, abs=3.0)
