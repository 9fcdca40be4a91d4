"""Drives a ros2_control plugin's controller declares (assets/description/ros2_control.py).

Robots of our own: the four-wheel box of test_holonomic.py with a gz_ros2_control plugin whose
<parameters> names a controller_manager file, written the ways real robots write them (husarion's
rosbot: ``/**/`` node keys and a diff controller over wheels with mecanum-roller friction;
gz_ros2_control's demos: the type under the controller's own parameters; ros2_controllers'
mecanum controller with nested ``kinematics``).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mobot_cli.assets.description import ros2_control
from mobot_cli.assets.description.describe import load_robot
from mobot_cli.errors import DescriptionError, ScenarioError
from tests.assets.test_holonomic import URDF_ROLLERS, four_wheels

ROSBOT_STYLE = """
/**/controller_manager:
  ros__parameters:
    update_rate: 20
    joint_state_broadcaster:
      type: joint_state_broadcaster/JointStateBroadcaster
    base_controller:
      type: diff_drive_controller/DiffDriveController
/**/base_controller:
  ros__parameters:
    left_wheel_names: [front_left_joint, rear_left_joint]
    right_wheel_names: [front_right_joint, rear_right_joint]
    wheel_separation: 0.5
    wheel_radius: 0.05
    wheel_separation_multiplier: 1.45
"""

MECANUM_STYLE = """
controller_manager:
  ros__parameters:
    update_rate: 50
mecanum_controller:
  ros__parameters:
    type: mecanum_drive_controller/MecanumDriveController
    front_left_wheel_command_joint_name: front_left_joint
    front_right_wheel_command_joint_name: front_right_joint
    rear_left_wheel_command_joint_name: rear_left_joint
    rear_right_wheel_command_joint_name: rear_right_joint
    kinematics:
      wheels_radius: 0.05
      sum_of_robot_center_projection_on_X_Y_axis: 0.45
"""

TRICYCLE_STYLE = """
controller_manager:
  ros__parameters:
    tricycle_controller:
      type: tricycle_controller/TricycleController
"""


def robot_with(tmp_path: Path, parameters: str | None, *, rollers: bool = True,
               uri: str | None = None, plugin_name: str = "gz_ros2_control-system") -> Path:
    """The four-wheel box (roller friction on its wheels unless told) with a ros2_control plugin
    naming ``parameters`` written to controllers.yaml (absolute, as xacro's $(find) leaves it)."""
    config = tmp_path / "controllers.yaml"
    if parameters is not None:
        config.write_text(parameters)
    plugin = (f'<plugin filename="{plugin_name}" name="gz_ros2_control::GazeboSimROS2ControlPlugin">'
              f'<parameters>{uri or config}</parameters></plugin>')
    path = tmp_path / "robot.urdf"
    path.write_text(four_wheels(URDF_ROLLERS if rollers else "", plugin))
    return path


def test_a_diff_controller_over_roller_wheels_drives_as_the_controller_does(tmp_path):
    """rosbot's way: mecanum-like friction, but diff_drive_controller turns cmd_vel into wheel speeds."""
    described = load_robot(str(robot_with(tmp_path, ROSBOT_STYLE)))
    drive = described.drive
    assert drive.kind == "diff" and drive.source == "ros2_control"
    assert drive.left_joints == ("front_left_joint", "rear_left_joint")
    assert drive.right_joints == ("front_right_joint", "rear_right_joint")
    assert (drive.wheel_radius, drive.wheel_separation, drive.wheel_separation_multiplier) == (0.05, 0.5, 1.45)
    assert any("roller friction (mecanum)" in n.message and "base_controller" in n.message
               for n in described.notices)


def test_without_the_plugin_the_same_wheels_are_mecanum(tmp_path):
    path = tmp_path / "robot.urdf"
    path.write_text(four_wheels(URDF_ROLLERS))
    assert load_robot(str(path)).drive.kind == "mecanum"


def test_the_controller_file_is_found_through_find_and_package_uris(tmp_path, monkeypatch):
    package = tmp_path / "pkgs" / "my_robot_control"
    (package / "config").mkdir(parents=True)
    (package / "package.xml").write_text("<package><name>my_robot_control</name></package>")
    (package / "config" / "drive.yaml").write_text(ROSBOT_STYLE)
    monkeypatch.setenv("MOBOT_RESOURCE_PATH", str(tmp_path / "pkgs"))
    for uri in ("$(find my_robot_control)/config/drive.yaml", "package://my_robot_control/config/drive.yaml"):
        folder = tmp_path / ("find" if uri.startswith("$") else "package")
        folder.mkdir()
        drive = load_robot(str(robot_with(folder, None, uri=uri))).drive
        assert drive.source == "ros2_control" and drive.wheel_separation_multiplier == 1.45


def test_gazebo_classic_plugin_and_the_type_under_the_controller(tmp_path):
    kind = "type: diff_drive_controller/DiffDriveController\n"
    text = ROSBOT_STYLE.replace("    base_controller:\n      " + kind, "")
    text = text.replace("/**/base_controller:\n  ros__parameters:\n",
                        "/**/base_controller:\n  ros__parameters:\n    " + kind)
    path = robot_with(tmp_path, text, rollers=False, plugin_name="libgazebo_ros2_control.so")
    drive = load_robot(str(path)).drive
    assert drive.source == "ros2_control" and drive.wheel_separation_multiplier == 1.45


def test_radius_multipliers_are_kept(tmp_path):
    text = ROSBOT_STYLE + "    left_wheel_radius_multiplier: 1.02\n    right_wheel_radius_multiplier: 1.02\n"
    assert load_robot(str(robot_with(tmp_path, text))).drive.wheel_radius_multiplier == pytest.approx(1.02)


def test_a_mecanum_controller_with_nested_kinematics(tmp_path):
    drive = load_robot(str(robot_with(tmp_path, MECANUM_STYLE, rollers=False))).drive
    assert drive.kind == "mecanum" and drive.source == "ros2_control"
    assert drive.left_joints == ("front_left_joint", "rear_left_joint")
    assert drive.wheel_radius == 0.05
    assert drive.wheel_separation == pytest.approx(0.5) and drive.wheelbase == pytest.approx(0.4)


def test_a_tricycle_controller_is_refused_by_name(tmp_path):
    described = load_robot(str(robot_with(tmp_path, TRICYCLE_STYLE)))
    assert described.drive is None and "tricycle drive" in described.refused_drive
    assert any("mobot cannot drive" in n.message and "tricycle" in n.message for n in described.notices)


def test_a_controller_naming_a_missing_joint_is_located_in_its_file(tmp_path):
    text = ROSBOT_STYLE.replace("rear_left_joint]", "rear_lefft_joint]")
    with pytest.raises(DescriptionError, match="rear_lefft_joint") as err:
        load_robot(str(robot_with(tmp_path, text)))
    assert err.value.location.file == tmp_path / "controllers.yaml"
    assert err.value.location.key == "base_controller.left_wheel_names"
    assert "rear_left_joint" in err.value.hint



def test_a_mecanum_controller_naming_a_missing_joint_is_located_at_its_own_parameter(tmp_path):
    """The older parameter names (husarion's): a rear wheel's typo is located at that wheel's key."""
    text = (MECANUM_STYLE.replace("_wheel_command_joint_name", "_wheel_name")
            .replace("rear_left_wheel_name: rear_left_joint", "rear_left_wheel_name: rear_lefft_joint"))
    with pytest.raises(DescriptionError, match="rear_lefft_joint") as err:
        load_robot(str(robot_with(tmp_path, text, rollers=False)))
    assert err.value.location.key == "mecanum_controller.rear_left_wheel_name"

@pytest.mark.parametrize("content, said", [(None, "cannot be read"), ("a: [1, 2\n", "not readable YAML")])
def test_an_unreadable_file_is_said_and_the_geometry_decides(tmp_path, content, said):
    described = load_robot(str(robot_with(tmp_path, content)))
    assert described.drive.kind == "mecanum" and described.drive.source == "urdf"
    assert any(said in n.message and "geometry" in n.message for n in described.notices)


def test_an_edited_parameters_file_is_read_again(tmp_path):
    path = robot_with(tmp_path, ROSBOT_STYLE)
    assert load_robot(str(path)).drive.wheel_separation_multiplier == 1.45
    (tmp_path / "controllers.yaml").write_text(ROSBOT_STYLE.replace("1.45", "1.2 "))
    assert load_robot(str(path)).drive.wheel_separation_multiplier == 1.2


def test_a_diff_controller_robot_refuses_sideways_commands_and_drives_straight(tmp_path):
    """Driven as diff_drive_controller drives it: no linear_y, and straight ahead at 0.2 m/s."""
    from mobot_cli.run import execute
    from mobot_cli.scenario.prepare import prepare

    robot = robot_with(tmp_path, ROSBOT_STYLE)
    scenario = tmp_path / "s.yaml"
    body = ("version: 1\nworld: empty\nduration: 3.5\nrobots:\n  - name: r\n    description: robot.urdf\n"
            "    commands:\n      - {{at: 0.5, linear: 0.2, {extra}for: 3.0}}\n")
    scenario.write_text(body.format(extra="linear_y: 0.1, "))
    with pytest.raises(ScenarioError, match="linear_y"):
        prepare(scenario)
    scenario.write_text(body.format(extra=""))
    prepared = prepare(scenario)
    assert prepared.plan.robots[0].drive.source == "ros2_control" and robot.exists()
    execute(prepared.plan, prepared.resolved_yaml, tmp_path / "run", pictures=False)
    final = json.loads((tmp_path / "run" / "summary.json").read_text())["robots"]["r"]["final_pose"]
    assert math.hypot(final["x"], final["y"]) == pytest.approx(0.6, abs=0.06)
    assert abs(final["y"]) < 0.05


parameter_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=True) | st.text(max_size=12),
    lambda children: st.lists(children, max_size=4) | st.dictionaries(
        st.sampled_from(["ros__parameters", "controller_manager", "/**/x", "type", "left_wheel_names",
                         "base_controller", "kinematics", "wheel_radius", "/**"]) | st.text(max_size=8),
        children, max_size=4),
    max_leaves=20)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(document=parameter_values)
def test_any_yaml_document_gives_controllers_or_nothing(tmp_path, document):
    """Whatever a parameters file holds, reading it never raises: controllers, or none."""
    path = tmp_path / "any.yaml"
    path.write_text(yaml.safe_dump(document))
    notices = []
    found = ros2_control._controllers(path, path, notices)
    assert all(isinstance(c.type, str) and isinstance(c.params, dict) for c in found)
    for controller in found:
        ros2_control.names(controller, "left_wheel_names")
        ros2_control.number(controller, "wheel_radius")


def test_a_confined_spawn_does_not_read_a_parameters_file_outside_its_folders(tmp_path):
    """A live spawn may read only its roots: a <parameters> pointing elsewhere is not opened."""
    from mobot_cli.assets import sandbox

    outside = tmp_path / "elsewhere"
    outside.mkdir()
    (outside / "controllers.yaml").write_text(ROSBOT_STYLE)
    inside = tmp_path / "spawn"
    inside.mkdir()
    path = robot_with(inside, None, uri=str(outside / "controllers.yaml"))
    assert load_robot(str(path)).drive.source == "ros2_control"  # unconfined, it is read (and cached)
    with sandbox.confined([inside]):
        described = load_robot(str(path))
    assert described.drive.source == "urdf" and described.drive.kind == "mecanum"
    assert any("cannot be read" in n.message for n in described.notices)
    assert not any("1.45" in n.message for n in described.notices)
