"""Drive detection on small hand-written URDFs: geometry, axis signs and plugin blocks."""

from __future__ import annotations

import pytest

from mobot_cli.assets.description.drive import detect_drive, drive_from_joints
from mobot_cli.errors import DescriptionError, Notice
from mobot_cli.sim.drive import default_separation_multiplier

INERTIAL = '<inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" ' \
           'iyz="0" izz="0.01"/></inertial>'


def wheel(name: str, xyz: str, axis: str = "0 1 0", rpy: str = "0 0 0", radius: float = 0.1,
          cyl_rpy: str = "1.5707963 0 0", parent: str = "base", kind: str = "continuous",
          shape: str = "cylinder") -> str:
    geometry = (f'<cylinder radius="{radius}" length="0.04"/>' if shape == "cylinder"
                else f'<sphere radius="{radius}"/>')
    return (f'<link name="{name}_link">{INERTIAL}<collision><origin rpy="{cyl_rpy}"/>'
            f'<geometry>{geometry}</geometry></collision></link>'
            f'<joint name="{name}" type="{kind}"><parent link="{parent}"/>'
            f'<child link="{name}_link"/><origin xyz="{xyz}" rpy="{rpy}"/>'
            f'<axis xyz="{axis}"/></joint>')


def robot(*parts: str) -> str:
    return (f'<robot name="r"><link name="base">{INERTIAL}<collision><geometry>'
            f'<box size="0.4 0.3 0.1"/></geometry></collision></link>{"".join(parts)}</robot>')


def test_two_wheels_from_geometry():
    spec = detect_drive(robot(wheel("l", "0.05 0.2 0"), wheel("r", "0.05 -0.2 0")))
    assert spec.left_joints == ("l",) and spec.right_joints == ("r",)
    assert spec.wheel_radius == pytest.approx(0.1)
    assert spec.wheel_separation == pytest.approx(0.4)
    assert spec.source == "urdf" and spec.wheel_separation_multiplier == 1.0
    assert spec.joint_signs == (("l", 1.0), ("r", 1.0))


def test_axis_minus_y_gets_sign_minus_one():
    spec = detect_drive(robot(wheel("l", "0 0.2 0", axis="0 -1 0"), wheel("r", "0 -0.2 0")))
    assert dict(spec.joint_signs) == {"l": -1.0, "r": 1.0}


def test_turtlebot_style_axis_z_rotated_about_x():
    # axis z in a joint frame rolled by -90 degrees is +y in the root; rolled by +90 it is -y.
    parts = (wheel("l", "0 0.08 0.02", axis="0 0 1", rpy="-1.57 0 0", radius=0.033,
                   cyl_rpy="0 0 0"),
             wheel("r", "0 -0.08 0.02", axis="0 0 1", rpy="1.5707963 0 0", radius=0.033,
                   cyl_rpy="0 0 0"))
    spec = detect_drive(robot(*parts))
    assert spec.wheel_radius == pytest.approx(0.033)
    assert spec.wheel_separation == pytest.approx(0.16)
    assert dict(spec.joint_signs) == {"l": 1.0, "r": -1.0}


def test_skid_steer_four_wheels_uses_separation_multiplier():
    parts = [wheel(n, f"{x} {y} 0") for n, x, y in
             (("fl", 0.25, 0.3), ("rl", -0.25, 0.3), ("fr", 0.25, -0.3), ("rr", -0.25, -0.3))]
    spec = detect_drive(robot(*parts))
    assert spec.left_joints == ("fl", "rl") and spec.right_joints == ("fr", "rr")
    assert spec.wheel_separation == pytest.approx(0.6)
    assert spec.wheel_separation_multiplier == pytest.approx(
        default_separation_multiplier(0.6, 0.5))


def test_non_wheels_are_ignored():
    parts = (wheel("l", "0 0.2 0"), wheel("r", "0 -0.2 0"),
             # a spinning lidar: continuous about z
             wheel("lidar", "0 0 0.2", axis="0 0 1", cyl_rpy="0 0 0"),
             # a cylinder whose axis is not the spin axis cannot roll
             wheel("paddle", "0 0.3 0", cyl_rpy="0 0 0"),
             # a limited revolute joint is an arm, not a wheel
             wheel("arm", "0 -0.3 0", kind="revolute"),
             # a caster wheel on a swivel: not fixed to the root
             '<link name="swivel"/><joint name="sw" type="continuous"><parent link="base"/>'
             '<child link="swivel"/><origin xyz="-0.2 0 0"/><axis xyz="0 0 1"/></joint>',
             wheel("caster_wheel", "0 0.01 -0.05", parent="swivel", radius=0.03))
    spec = detect_drive(robot(*parts))
    assert (spec.left_joints, spec.right_joints) == (("l",), ("r",))


def test_sphere_wheels_and_no_wheels():
    spec = detect_drive(robot(wheel("l", "0 0.5 0", shape="sphere", radius=0.3),
                              wheel("r", "0 -0.5 0", shape="sphere", radius=0.3)))
    assert spec.wheel_radius == pytest.approx(0.3) and spec.wheel_separation == pytest.approx(1.0)
    assert detect_drive(robot()) is None
    assert detect_drive(robot(wheel("l", "0 0.2 0"))) is None  # one side only


ROS1_PLUGIN = """<gazebo><plugin name="d" filename="libgazebo_ros_diff_drive.so">
  <leftJoint>l</leftJoint><rightJoint>r</rightJoint><wheelSeparation>0.5</wheelSeparation>
  <wheelDiameter>0.3</wheelDiameter><wheelTorque>7</wheelTorque>
  <wheelAcceleration>1.5</wheelAcceleration></plugin></gazebo>"""
ROS2_PLUGIN = """<gazebo><plugin name="d" filename="libgazebo_ros_diff_drive.so">
  <num_wheel_pairs>2</num_wheel_pairs>
  <left_joint>fl</left_joint><right_joint>fr</right_joint>
  <left_joint>rl</left_joint><right_joint>rr</right_joint>
  <wheel_separation>0.62</wheel_separation><wheel_separation>0.62</wheel_separation>
  <wheel_diameter>0.25</wheel_diameter><max_wheel_torque>9</max_wheel_torque>
  <max_wheel_acceleration>0</max_wheel_acceleration></plugin></gazebo>"""
SKID_PLUGIN = """<gazebo><plugin name="s" filename="libgazebo_ros_skid_steer_drive.so">
  <leftFrontJoint>fl</leftFrontJoint><rightFrontJoint>fr</rightFrontJoint>
  <leftRearJoint>rl</leftRearJoint><rightRearJoint>rr</rightRearJoint>
  <wheelSeparation>0.7</wheelSeparation><wheelDiameter>0.2</wheelDiameter>
  <torque>35</torque></plugin></gazebo>"""
GZ_PLUGIN = """<gazebo><plugin filename="gz-sim-diff-drive-system"
  name="gz::sim::systems::DiffDrive"><left_joint>l</left_joint><right_joint>r</right_joint>
  <wheel_separation>0.45</wheel_separation><wheel_radius>0.12</wheel_radius></plugin></gazebo>"""


def four_wheels() -> list[str]:
    return [wheel(n, f"{x} {y} 0") for n, x, y in
            (("fl", 0.2, 0.3), ("rl", -0.2, 0.3), ("fr", 0.2, -0.3), ("rr", -0.2, -0.3))]


def test_ros1_diff_drive_plugin_overrides_geometry():
    spec = detect_drive(robot(wheel("l", "0 0.2 0"), wheel("r", "0 -0.2 0"), ROS1_PLUGIN))
    assert spec.source == "plugin"
    assert (spec.wheel_radius, spec.wheel_separation, spec.max_wheel_torque) == (0.15, 0.5, 7.0)
    # gazebo_ros limits rim speed changes in m/s^2; DriveSpec holds rad/s^2 at the wheel
    assert spec.max_wheel_acceleration == pytest.approx(1.5 / 0.15)


def test_ros2_plugin_with_two_wheel_pairs():
    spec = detect_drive(robot(*four_wheels(), ROS2_PLUGIN))
    assert (spec.left_joints, spec.right_joints) == (("fl", "rl"), ("fr", "rr"))
    assert (spec.wheel_radius, spec.wheel_separation, spec.max_wheel_torque) == (0.125, 0.62, 9.0)
    assert spec.max_wheel_acceleration is None  # 0 means unlimited in gazebo_ros
    assert spec.wheel_separation_multiplier == pytest.approx(
        default_separation_multiplier(0.62, 0.4))


def test_skid_steer_and_gz_sim_plugins():
    skid = detect_drive(robot(*four_wheels(), SKID_PLUGIN))
    assert (skid.wheel_radius, skid.wheel_separation, skid.max_wheel_torque) == (0.1, 0.7, 35.0)
    assert skid.left_joints == ("fl", "rl")
    gz = detect_drive(robot(wheel("l", "0 0.2 0"), wheel("r", "0 -0.2 0"), GZ_PLUGIN))
    assert (gz.source, gz.wheel_radius, gz.wheel_separation) == ("plugin", 0.12, 0.45)


def test_plugin_without_values_takes_them_from_geometry():
    plugin = ('<gazebo><plugin filename="libgazebo_ros_diff_drive.so" name="d">'
              '<left_joint>l</left_joint><right_joint>r</right_joint></plugin></gazebo>')
    spec = detect_drive(robot(wheel("l", "0 0.2 0", axis="0 -1 0"), wheel("r", "0 -0.2 0"),
                              plugin))
    assert (spec.source, spec.wheel_radius, spec.wheel_separation) == ("plugin", 0.1, 0.4)
    assert dict(spec.joint_signs) == {"l": -1.0, "r": 1.0}


def test_plugin_naming_a_missing_joint_is_an_error():
    plugin = ROS1_PLUGIN.replace("<leftJoint>l<", "<leftJoint>left_wheel<")
    with pytest.raises(DescriptionError) as err:
        detect_drive(robot(wheel("l", "0 0.2 0"), wheel("r", "0 -0.2 0"), plugin))
    assert err.value.message == ("the libgazebo_ros_diff_drive.so plugin names left wheel joint "
                                 "'left_wheel', which is not in the URDF")


def test_plugin_with_swapped_sides_gets_a_notice():
    plugin = ROS1_PLUGIN.replace("<leftJoint>l<", "<leftJoint>X<").replace(
        "<rightJoint>r<", "<rightJoint>l<").replace("<leftJoint>X<", "<leftJoint>r<")
    notices: list[Notice] = []
    spec = detect_drive(robot(wheel("l", "0 0.2 0"), wheel("r", "0 -0.2 0"), plugin),
                        notices=notices)
    assert spec.left_joints == ("r",)
    sides = [n.message for n in notices if " as a " in n.message]
    assert len(sides) == 2 and "drives 'r' as a left wheel but it sits at y = -0.200 m" in sides[0]


def suspended(name: str, y: float, kind: str = "prismatic", axis: str = "0 0 1") -> str:
    """A wheel below a suspension link: chassis -> {kind} joint -> suspension -> wheel."""
    return (f'<link name="{name}_arm">{INERTIAL}</link>'
            f'<joint name="{name}_suspension" type="{kind}"><parent link="base"/>'
            f'<child link="{name}_arm"/><origin xyz="0.05 {y} 0"/><axis xyz="{axis}"/>'
            '<limit lower="-0.02" upper="0" effort="10" velocity="1"/></joint>'
            + wheel(name, "0 0 -0.03", parent=f"{name}_arm"))


@pytest.mark.parametrize("kind, axis", [("prismatic", "0 0 1"),  # a wheel drop
                                        ("revolute", "1 0 0"),  # a swing arm
                                        ("revolute", "0 1 0")])  # a trailing arm
def test_wheels_below_suspension_joints_are_found(kind, axis):
    spec = detect_drive(robot(suspended("l", 0.2, kind, axis), suspended("r", -0.2, kind, axis)))
    assert (spec.left_joints, spec.right_joints) == (("l",), ("r",))
    assert spec.wheel_radius == pytest.approx(0.1)
    assert spec.wheel_separation == pytest.approx(0.4)


def test_wheels_below_a_vertical_pivot_are_steered_not_driven():
    parts = (suspended("l", 0.2, "revolute", "0 0 1"), suspended("r", -0.2, "revolute", "0 0 1"))
    assert detect_drive(robot(*parts)) is None


def test_plugin_that_disagrees_with_geometry_says_so_once():
    plugin = ROS1_PLUGIN.replace("<wheelSeparation>0.5<", "<wheelSeparation>0.4<").replace(
        "<wheelDiameter>0.3<", "<wheelDiameter>0.22<")
    notices: list[Notice] = []
    spec = detect_drive(robot(wheel("l", "0 0.18 0"), wheel("r", "0 -0.18 0"), plugin),
                        notices=notices)
    assert (spec.wheel_separation, spec.wheel_radius) == (0.4, 0.11)  # Gazebo's values
    assert [n.message for n in notices] == [
        "the libgazebo_ros_diff_drive.so plugin says wheel_separation 0.400 m, but its wheel "
        "joints are 0.360 m apart; and wheel_radius 0.110 m, but its wheels' collisions have "
        "radius 0.100 m: mobot uses the plugin's values, as Gazebo does, so the robot turns "
        "11 % more than commanded and drives 9 % less than commanded (set drive: wheel_radius / "
        "wheel_separation to use the geometry)"]


def test_plugin_within_two_percent_of_geometry_is_quiet():
    plugin = ROS1_PLUGIN.replace("<wheelSeparation>0.5<", "<wheelSeparation>0.407<").replace(
        "<wheelDiameter>0.3<", "<wheelDiameter>0.198<")
    notices: list[Notice] = []
    detect_drive(robot(wheel("l", "0 0.2 0"), wheel("r", "0 -0.2 0"), plugin), notices=notices)
    assert notices == []


def test_named_joints_take_radius_from_a_mesh_and_separation_from_joints(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    stl = tmp_path / "tyre.stl"
    trimesh.creation.cylinder(radius=0.08, height=0.03, sections=64).export(stl)

    def mesh_wheel(name: str, y: float) -> str:
        return (f'<link name="{name}_link">{INERTIAL}<collision><origin rpy="1.5707963 0 0"/>'
                f'<geometry><mesh filename="{stl}"/></geometry></collision></link>'
                f'<joint name="{name}" type="continuous"><parent link="base"/>'
                f'<child link="{name}_link"/><origin xyz="0 {y} 0"/><axis xyz="0 1 0"/></joint>')

    urdf = robot(mesh_wheel("l", 0.21), mesh_wheel("r", -0.21))
    assert detect_drive(urdf) is None  # a mesh is no proof of a wheel
    spec = drive_from_joints(urdf, ("l",), ("r",))
    assert spec.wheel_radius == pytest.approx(0.08, abs=1e-6)
    assert spec.wheel_separation == pytest.approx(0.42)
    assert spec.source == "scenario"
    with pytest.raises(DescriptionError) as err:
        drive_from_joints(urdf, ("left",), ("r",))
    assert err.value.message == "drive names left wheel joint 'left', which is not in the description"
    assert "'l'" in err.value.hint
