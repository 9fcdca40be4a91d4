"""Cars found from their plugins and joints, and the drives mobot refuses, each named in one notice."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from mobot_cli.assets import load_robot
from mobot_cli.assets.description.drive import detect
from mobot_cli.assets.description.robot import NO_DRIVE
from mobot_cli.cli import invoke
from tests.sim.car import GAZEBO_ROS, GZ, TRACK, TRACKED, WHEELBASE, car

ROBOTS = Path(__file__).resolve().parents[1] / "sim" / "robots"
REAR = ("rear_left_wheel_joint",), ("rear_right_wheel_joint",)
STEERING = ("left_steering_joint", "right_steering_joint")


def joint_limited_angle(limit: float) -> float:
    """The bicycle angle at which the inner wheel of our car reaches ``limit``."""
    return math.atan(WHEELBASE / (WHEELBASE / math.tan(limit) + TRACK / 2))


def test_gazebo_ros_ackermann_drive_plugin():
    notices = []
    spec = detect(car(GAZEBO_ROS), notices=notices).spec
    assert (spec.kind, spec.source, spec.odometry) == ("ackermann", "plugin", "ground_truth")
    assert (spec.left_joints, spec.right_joints) == REAR
    assert spec.steering_joints == STEERING
    assert (spec.wheelbase, spec.wheel_separation, spec.wheel_radius) == pytest.approx((0.5, 0.4, 0.1))
    assert spec.max_steering_angle == pytest.approx(0.45)  # max_steer: tighter than the joints' limit
    assert spec.twist_feedback is False and notices == []


def test_gz_ackermann_steering_system_in_an_sdf_model():
    robot = load_robot(str(ROBOTS / "ackermann_car_gz.sdf"))
    spec = robot.drive
    assert (spec.kind, spec.source, spec.odometry) == ("ackermann", "plugin", "encoder")
    assert (spec.left_joints, spec.right_joints, spec.steering_joints) == (*REAR, STEERING)
    # gz keeps the radius at or above wheel_base / sin(steering_limit)
    assert WHEELBASE / math.tan(spec.max_steering_angle) == pytest.approx(WHEELBASE / math.sin(0.5))
    assert not any(NO_DRIVE in str(n) for n in robot.notices)


def test_gz_plugin_in_a_urdf_gazebo_block_matches_the_sdf():
    spec = detect(car(GZ)).spec
    assert spec == load_robot(str(ROBOTS / "ackermann_car_gz.sdf")).drive


def test_steering_joints_without_a_plugin_make_a_car():
    notices = []
    spec = detect(car(), notices=notices).spec
    assert (spec.kind, spec.source, spec.odometry) == ("ackermann", "urdf", "encoder")
    assert (spec.left_joints, spec.right_joints, spec.steering_joints) == (*REAR, STEERING)
    assert spec.max_steering_angle == pytest.approx(joint_limited_angle(0.6))
    assert notices == []


def test_a_steering_axis_along_minus_z_gets_sign_minus_one():
    spec = detect(car(steer_axis="0 0 -1")).spec
    signs = dict(spec.joint_signs)
    assert (signs["left_steering_joint"], signs["right_steering_joint"]) == (-1.0, -1.0)
    assert spec.max_steering_angle == pytest.approx(joint_limited_angle(0.6))


def test_a_joint_limit_tighter_than_the_plugin_wins_with_a_notice():
    notices = []
    spec = detect(car(GAZEBO_ROS, limit=0.3), notices=notices).spec
    assert spec.max_steering_angle == pytest.approx(joint_limited_angle(0.3))
    assert len(notices) == 1 and "steering joints' limits allow" in notices[0].message


@pytest.mark.parametrize("gazebo, named", [
    (TRACKED, "tracked vehicle (gz::sim::systems::TrackedVehicle)"),
    ('<gazebo><plugin name="tracks" filename="libSimpleTrackedVehiclePlugin.so"/></gazebo>',
     "tracked vehicle (libSimpleTrackedVehiclePlugin.so)"),
    ('<gazebo><plugin name="trike" filename="libgazebo_ros_tricycle_drive.so"/></gazebo>',
     "tricycle drive (libgazebo_ros_tricycle_drive.so)"),
    ('<gazebo><plugin name="hover" filename="libhover_drive_plugin.so"/></gazebo>',
     "drive plugin of a kind mobot does not know (libhover_drive_plugin.so)"),
])
def test_drives_mobot_cannot_simulate_are_refused_in_one_notice(gazebo, named):
    notices = []
    found = detect(car(gazebo), notices=notices)
    assert found.spec is None and found.refused == named
    assert [n.message for n in notices] == [
        f"mobot cannot drive this robot's {named}: it is a passive body and refuses velocity commands"]


def test_mesh_tyres_are_measured_as_a_diff_drives_are(tmp_path):
    """A car on meshed tyres (AgileX's Hunter 2.0) is driven: the radius is the mesh's farthest
    vertex from the spin axis. It was refused as "mesh-only wheels", and drive: overrides could not
    make it drivable."""
    trimesh = pytest.importorskip("trimesh")
    trimesh.creation.cylinder(radius=0.1, height=0.05, sections=64).export(tmp_path / "tyre.stl")
    path = tmp_path / "meshcar.urdf"
    path.write_text(car(mesh=str(tmp_path / "tyre.stl")))
    spec = load_robot(str(path)).drive
    assert (spec.kind, spec.source) == ("ackermann", "urdf")
    assert (spec.left_joints, spec.right_joints, spec.steering_joints) == (*REAR, STEERING)
    assert spec.wheel_radius == pytest.approx(0.1, abs=1e-6)


def test_steered_wheels_without_a_radius_are_refused(tmp_path):
    path = tmp_path / "boxcar.urdf"
    path.write_text(car().replace('<cylinder radius="0.1" length="0.05"/>', '<box size="0.2 0.05 0.2"/>'))
    robot = load_robot(str(path))
    assert robot.drive is None
    assert robot.refused_drive.startswith("Ackermann steering with wheels of no measurable radius")
    said = [str(n) for n in robot.notices]
    assert sum("mobot cannot drive" in n for n in said) == 1 and not any(NO_DRIVE in n for n in said)


def test_the_refusal_survives_the_cache(tmp_path):
    path = tmp_path / "tracked.urdf"
    path.write_text(car(TRACKED))
    cold, warm = load_robot(str(path)), load_robot(str(path))
    assert warm.refused_drive == cold.refused_drive == "tracked vehicle (gz::sim::systems::TrackedVehicle)"
    car_path = tmp_path / "car.urdf"
    car_path.write_text(car(GZ))
    assert load_robot(str(car_path)).drive == load_robot(str(car_path)).drive  # steering joints as a tuple


def test_inspect_reports_the_minimum_turning_radius():
    done = invoke(["inspect", ROBOTS / "ackermann_car.urdf", "--json"])
    assert done.exit_code == 0, done.stderr
    drive = json.loads(done.stdout)["drive"]
    assert drive["kind"] == "ackermann"
    assert drive["min_turning_radius"] == pytest.approx(WHEELBASE / math.tan(0.45), abs=1e-6)
    text = invoke(["inspect", ROBOTS / "ackermann_car.urdf"]).stdout
    assert "min turning radius 1.035 m" in text


def test_gz_ros2_control_ackermann_demo_is_a_car(corpus):
    """Continuous steering joints that ros2_control commands by position: a car, not a diff drive."""
    robot = load_robot(str(corpus / "gz_ros2_control/gz_ros2_control_demos/urdf/test_ackermann_drive.xacro.urdf"))
    spec = robot.drive
    assert spec.kind == "ackermann"
    assert spec.steering_joints == ("left_wheel_steering_joint", "right_wheel_steering_joint")
    assert (spec.left_joints, spec.right_joints) == (("rear_left_wheel_joint",), ("rear_right_wheel_joint",))
    assert (spec.wheelbase, spec.wheel_separation, spec.wheel_radius) == pytest.approx((1.7, 1.0, 0.3))
    assert any("have no limit" in str(n) for n in robot.notices)


def test_an_arm_held_by_position_control_is_no_steering_joint():
    """A vertical base joint that ros2_control commands by position, a continuous wrist far below it:
    the robot stays a diff drive."""
    from tests.assets.test_drive import robot, wheel

    arm = ('<link name="link1"/><joint name="joint_1" type="continuous"><parent link="base"/>'
           '<child link="link1"/><origin xyz="0 0 0.2"/><axis xyz="0 0 1"/></joint>'
           '<link name="link2"/><joint name="joint_2" type="revolute"><parent link="link1"/>'
           '<child link="link2"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>'
           + wheel("wrist", "0 0 0.3", parent="link2", radius=0.03)
           + '<ros2_control name="arm" type="system"><joint name="joint_1"><command_interface name="position"/>'
           '</joint><joint name="wrist"><command_interface name="position"/></joint></ros2_control>')
    spec = detect(robot(wheel("l", "0 0.2 0"), wheel("r", "0 -0.2 0"), arm)).spec
    assert spec.kind == "diff" and (spec.left_joints, spec.right_joints) == (("l",), ("r",))


def test_a_plugin_naming_a_missing_joint_is_a_located_error(tmp_path):
    path = tmp_path / "typo.urdf"
    path.write_text(car(GZ.replace("<left_steering_joint>left_steering_joint", "<left_steering_joint>left_steer")))
    done = invoke(["inspect", path])
    assert done.exit_code == 2 and "Traceback" not in done.stderr
    assert (f"{path}, key 'gazebo.plugin.left_steering_joint': the gz::sim::systems::AckermannSteering "
            "plugin names left_steering_joint 'left_steer', which is not in the URDF. "
            "Did you mean 'left_steering_joint'?") in done.stderr
