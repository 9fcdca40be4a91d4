"""Which joints Gazebo holds, read from small hand-written descriptions: springs (URDF and SDF),
ros2_control interfaces, joint plugins, mimics, and the one notice naming joints left free."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from mobot_cli.assets.description.drive import detect_drive
from mobot_cli.assets.description.joints import UNLIMITED_EFFORT, read_holds
from mobot_cli.plan import JointHold
from tests.assets.test_drive import INERTIAL, robot, wheel

TWO_WHEELS = (wheel("left_wheel_joint", "0 0.2 0"), wheel("right_wheel_joint", "0 -0.2 0"))


def joint(name: str, kind: str = "revolute", parent: str = "base", effort: str = "30", extra: str = "") -> str:
    limit = f'<limit lower="-1" upper="1" effort="{effort}" velocity="1"/>' if kind != "continuous" else ""
    return (f'<link name="{name}_link">{INERTIAL}</link><joint name="{name}" type="{kind}">'
            f'<parent link="{parent}"/><child link="{name}_link"/><axis xyz="0 1 0"/>{limit}{extra}</joint>')


def holds(*parts: str) -> tuple[tuple[JointHold, ...], list[str]]:
    element = ET.fromstring(robot(*TWO_WHEELS, *parts))
    notices = []
    found = read_holds(element, detect_drive(element), notices)
    return found, [n.message for n in notices]


def test_a_gazebo_spring_is_read_with_its_reference():
    found, notices = holds(joint("caster_joint", "prismatic", extra='<dynamics damping="5"/>'),
                           '<gazebo reference="caster_joint"><springStiffness>2000</springStiffness>'
                           '<springReference>-0.01</springReference></gazebo>')
    assert found == (JointHold("caster_joint", "spring", target=-0.01, stiffness=2000.0,
                               source="springStiffness"),)
    assert notices == []


def test_ros2_control_position_joints_are_held_at_their_initial_value():
    control = ('<ros2_control name="arm" type="system"><hardware><plugin>gz_ros2_control/GazeboSimSystem'
               '</plugin></hardware>'
               '<joint name="shoulder"><command_interface name="position"/><state_interface name="position">'
               '<param name="initial_value">0.4</param></state_interface></joint>'
               '<joint name="lift"><command_interface name="velocity"/></joint>'
               '<joint name="spinner"><command_interface name="velocity"/></joint>'
               '<joint name="left_wheel_joint"><command_interface name="velocity"/></joint>'
               '<joint name="gripper"><command_interface name="effort"/></joint></ros2_control>')
    found, notices = holds(joint("shoulder", effort="0"), joint("lift", "prismatic"),
                           joint("spinner", "continuous"), joint("gripper", "prismatic"), control)
    assert {h.joint: (h.kind, h.target, h.effort) for h in found} == {
        "shoulder": ("position", 0.4, UNLIMITED_EFFORT), "lift": ("position", 0.0, 30.0)}
    # The wheel is the drive's; a continuous joint under velocity control spins (a wheel);
    # the effort-controlled gripper is free, and it alone is named.
    assert notices == ["joints left free (no spring, position controller or plugin holds them): gripper"]


def test_a_joint_plugin_holds_the_joints_it_names_and_mimics_follow():
    plugin = ('<gazebo><plugin filename="gz-sim-joint-position-controller-system" name="x">'
              '<joint_name>rocker</joint_name><initial_position>0.1</initial_position></plugin></gazebo>'
              '<gazebo><plugin filename="gz-sim-joint-state-publisher-system" name="y">'
              '<joint_name>flap</joint_name></plugin></gazebo>')
    found, notices = holds(joint("rocker"), joint("other_rocker", extra='<mimic joint="rocker" multiplier="-1"/>'),
                           joint("flap"), plugin)
    assert {h.joint: (h.target, h.source) for h in found} == {
        "rocker": (0.1, "gz-sim-joint-position-controller-system"), "other_rocker": (-0.1, "mimic of rocker")}
    assert notices == ["joints left free (no spring, position controller or plugin holds them): flap"]


def test_free_joints_are_named_in_one_notice_and_continuous_ones_not():
    found, notices = holds(joint("a"), joint("b", "prismatic"), joint("caster_swivel", "continuous"))
    assert found == ()
    assert notices == ["joints left free (no spring, position controller or plugin holds them): a, b"]


SDF = """<?xml version="1.0"?>
<sdf version="1.7"><model name="sprung">
  <link name="base"><inertial><mass>5</mass></inertial>
    <collision name="c"><geometry><box><size>0.4 0.3 0.1</size></box></geometry></collision></link>
  <link name="arm"><pose>0.2 0 0 0 0 0</pose><inertial><mass>1</mass></inertial></link>
  <joint name="suspension" type="revolute"><parent>base</parent><child>arm</child>
    <axis><xyz>0 1 0</xyz><limit><lower>-0.5</lower><upper>0.5</upper></limit>
      <dynamics><damping>2</damping><spring_stiffness>150</spring_stiffness>
      <spring_reference>0.05</spring_reference></dynamics></axis></joint>
</model></sdf>
"""


def test_an_sdf_spring_reaches_the_robot(tmp_path: Path, monkeypatch):
    from mobot_cli.assets.description.describe import load_robot

    monkeypatch.setenv("MOBOT_CACHE_DIR", str(tmp_path / "cache"))
    (tmp_path / "model.sdf").write_text(SDF)
    description = load_robot(str(tmp_path / "model.sdf"))
    assert description.holds == (JointHold("suspension", "spring", target=0.05, stiffness=150.0,
                                           source="springStiffness"),)
    again = load_robot(str(tmp_path / "model.sdf"))  # from the cache: the holds survive it
    assert again.holds == description.holds


@pytest.mark.parametrize("text", ["", "<springStiffness>0</springStiffness>",
                                  "<springStiffness>abc</springStiffness>"])
def test_no_spring_without_a_positive_stiffness(text):
    found, _ = holds(joint("j"), f'<gazebo reference="j">{text}</gazebo>')
    assert found == ()
