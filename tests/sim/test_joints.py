"""Passive joints Gazebo holds, in PyBullet: a spring-suspended caster keeps the chassis level
(and a very stiff spring does not launch it), a passive arm under ros2_control position
interfaces stays where it starts while the base drives; without them both give way, and the
joints left free are named."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from mobot_cli.api.sensors import robot_plan
from mobot_cli.assets.description.describe import load_robot
from mobot_cli.plan import Physics, RobotPlan, SpawnPose, WorldPlan
from mobot_cli.sim.bullet.world import World

ROBOTS = Path(__file__).parent / "robots"
CASTER = ROBOTS / "spring_caster.urdf.xacro"
ARM = ROBOTS / "passive_arm.urdf.xacro"
RATE = 240
ARM_START = {"shoulder_joint": -0.6, "elbow_joint": 1.2}  # the initial_value of each


@pytest.fixture(autouse=True)
def own_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("MOBOT_CACHE_DIR", str(tmp_path / "cache"))


def caster_plan(**args: str) -> RobotPlan:
    desc = load_robot(str(CASTER), args)
    return RobotPlan(name="r", namespace="/r", frame_prefix="r/", urdf=desc.urdf, root_link=desc.root_link,
                     pose=SpawnPose(z_auto=True), drive=desc.drive, holds=desc.holds)


def run(plan: RobotPlan, rest: float, drive: float = 0.0, speed: float = 0.3):
    """States after resting ``rest`` s, then after driving ``drive`` s and stopping for 1 s."""
    with World(Physics(rate_hz=RATE), WorldPlan()) as world:
        world.spawn(plan)
        start = world.read(plan.name)
        for _ in range(round(rest * RATE)):
            world.step()
        rested = world.read(plan.name)
        if not drive:
            return start, rested, rested
        world.set_command(plan.name, speed, 0.0)
        for _ in range(round(drive * RATE)):
            world.step()
        world.set_command(plan.name, 0.0, 0.0)
        for _ in range(RATE):
            world.step()
        return start, rested, world.read(plan.name)


def test_spring_caster_keeps_the_chassis_level():
    _, rested, driven = run(caster_plan(), 2.0, 2.0)
    # 42 N on a 2e4 N/m spring: 2.1 mm of travel over the 0.35 m from the axle, 0.35 deg.
    assert rested.joint_positions["caster_joint"] == pytest.approx(0.0021, abs=3e-4)
    for state in (rested, driven):
        assert abs(math.degrees(state.true_pitch)) < 1.0 and abs(math.degrees(state.true_roll)) < 1.0
    assert driven.true_x == pytest.approx(0.6, rel=0.05)


def test_spring_reference_preloads_the_spring():
    """A soft spring sags 21.5 mm under the load; its reference takes the sag back."""
    _, soft, _ = run(caster_plan(stiffness="2000"), 2.0)
    _, preloaded, _ = run(caster_plan(stiffness="2000", reference="-0.02"), 2.0)
    assert soft.joint_positions["caster_joint"] == pytest.approx(0.0215, abs=1e-3)
    assert math.degrees(soft.true_pitch) > 3.0
    assert abs(math.degrees(preloaded.true_pitch)) < 1.0


def test_without_the_spring_the_caster_gives_way_and_is_named():
    desc = load_robot(str(CASTER), {"spring": "false"})
    assert [n.message for n in desc.notices if "left free" in n.message] == [
        "joints left free (no spring, position controller or plugin holds them): caster_joint"]
    _, rested, _ = run(caster_plan(spring="false"), 2.0)
    assert math.degrees(rested.true_pitch) > 5.0  # on the joint's 4 cm limit: 6.6 deg


@pytest.mark.parametrize("stiffness", ["2e5", "2e6"])
def test_a_very_stiff_spring_does_not_launch_the_robot(stiffness):
    """Applied as an explicit torque these sent the robot 36 m and 300 m away."""
    _, rested, driven = run(caster_plan(stiffness=stiffness), 2.0, 2.0)
    assert math.hypot(rested.true_x, rested.true_y) < 0.01 and rested.true_z == pytest.approx(0.1, abs=0.002)
    assert abs(math.degrees(driven.true_pitch)) < 1.0
    assert 0.4 < driven.true_x < 0.7 and abs(driven.true_y) < 0.05


def test_passive_arm_holds_its_initial_pose_and_the_base_drives():
    plan = robot_plan("arm", str(ARM), rate_hz=RATE)
    assert {h.joint: h.target for h in plan.holds} == ARM_START
    start, rested, driven = run(plan, 3.0, 2.0)
    for state in (start, rested, driven):
        for joint, angle in ARM_START.items():
            assert state.joint_positions[joint] == pytest.approx(angle, abs=0.05)
    # Not launched: at rest it stays put on its wheels, level.
    assert math.hypot(rested.true_x, rested.true_y) < 0.01 and rested.true_z == pytest.approx(0.1, abs=0.005)
    assert abs(rested.true_pitch) < 0.02 and abs(rested.true_roll) < 0.02
    assert driven.true_x == pytest.approx(0.6, rel=0.05) and abs(driven.true_y) < 0.05


def test_passive_arm_without_controllers_falls_and_is_named():
    desc = load_robot(str(ARM), {"control": "false"})
    assert [n.message for n in desc.notices if "left free" in n.message] == [
        "joints left free (no spring, position controller or plugin holds them): shoulder_joint, elbow_joint"]
    plan = RobotPlan(name="r", namespace="/r", frame_prefix="r/", urdf=desc.urdf, root_link=desc.root_link,
                     pose=SpawnPose(z_auto=True), drive=desc.drive, holds=desc.holds)
    _, rested, driven = run(plan, 3.0, 2.0)
    assert rested.joint_positions["shoulder_joint"] > 0.5  # the arm lies on the floor
    assert driven.true_x < 0.3  # and drags: the base barely moves
