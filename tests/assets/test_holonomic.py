"""Holonomic drives detected from plugins and from roller friction, in URDF and SDF alike."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from mobot_cli.assets.description.describe import load_robot
from mobot_cli.assets.description.drive import detect_drive
from mobot_cli.assets.description.process import gazebo_friction, roller_links
from mobot_cli.errors import DescriptionError

ROBOTS = Path(__file__).resolve().parents[1] / "sim" / "robots"
MECANUM = "mecanum"  # bundled: robots/mecanum
SDF = ROBOTS / "mecanum_gz.sdf"
CORNERS = {"front_left": (0.2, 0.25), "rear_left": (-0.2, 0.25), "front_right": (0.2, -0.25),
           "rear_right": (-0.2, -0.25)}
INERTIAL = ('<inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" '
            'izz="0.01"/></inertial>')


def four_wheels(gazebo: str = "", plugin: str = "") -> str:
    """A box on four wheel joints (radius 0.05, track 0.5, wheelbase 0.4), with extra <gazebo> text."""
    parts = [f'<robot name="r"><link name="base">{INERTIAL}<collision><geometry><box size="0.5 0.4 0.06"/>'
             '</geometry></collision></link>']
    for name, (x, y) in CORNERS.items():
        parts.append(f'<link name="{name}">{INERTIAL}<collision><origin rpy="1.5707963267948966 0 0"/>'
                     '<geometry><cylinder radius="0.05" length="0.04"/></geometry></collision></link>'
                     f'<joint name="{name}_joint" type="continuous"><parent link="base"/><child link="{name}"/>'
                     f'<origin xyz="{x} {y} 0"/><axis xyz="0 1 0"/></joint>')
        parts.append(gazebo.format(link=name))
    return "".join(parts) + (f"<gazebo>{plugin}</gazebo>" if plugin else "") + "</robot>"


URDF_ROLLERS = '<gazebo reference="{link}"><mu1>1</mu1><mu2>0</mu2><fdir1>1 1 0</fdir1></gazebo>'
SDF_STYLE_ROLLERS = ('<gazebo reference="{link}"><collision><surface><friction><ode><mu>1.0</mu><mu2>0.0</mu2>'
                     '<fdir1>1 -1 0</fdir1></ode></friction></surface></collision></gazebo>')
MECANUM_PLUGIN = ('<plugin filename="gz-sim-mecanum-drive-system" name="gz::sim::systems::MecanumDrive">'
                  '<front_left_joint>front_left_joint</front_left_joint>'
                  '<front_right_joint>front_right_joint</front_right_joint>'
                  '<back_left_joint>rear_left_joint</back_left_joint>'
                  '<back_right_joint>rear_right_joint</back_right_joint>'
                  '<wheel_separation>0.5</wheel_separation><wheelbase>0.4</wheelbase>'
                  '<wheel_radius>0.05</wheel_radius></plugin>')


def test_gz_mecanum_plugin():
    spec = detect_drive(four_wheels(plugin=MECANUM_PLUGIN))
    assert spec.kind == "mecanum" and spec.source == "plugin" and spec.odometry == "encoder"
    assert spec.left_joints == ("front_left_joint", "rear_left_joint")
    assert spec.right_joints == ("front_right_joint", "rear_right_joint")
    assert (spec.wheel_radius, spec.wheel_separation, spec.wheelbase) == (0.05, 0.5, 0.4)


def test_ignition_mecanum_plugin_leaving_values_out_is_measured():
    plugin = MECANUM_PLUGIN.replace("gz-sim-mecanum-drive-system", "ignition-gazebo-mecanum-drive-system")
    plugin = plugin.replace("<wheelbase>0.4</wheelbase>", "").replace("<wheel_radius>0.05</wheel_radius>", "")
    spec = detect_drive(four_wheels(plugin=plugin))
    assert spec.kind == "mecanum"
    assert spec.wheel_radius == pytest.approx(0.05) and spec.wheelbase == pytest.approx(0.4)


def test_mecanum_plugin_naming_a_missing_joint_is_located():
    plugin = MECANUM_PLUGIN.replace("<back_left_joint>rear_left_joint", "<back_left_joint>rear_lefft_joint")
    with pytest.raises(DescriptionError, match="back_left_joint 'rear_lefft_joint'") as err:
        detect_drive(four_wheels(plugin=plugin))
    assert "rear_left_joint" in err.value.hint


@pytest.mark.parametrize("rollers", [URDF_ROLLERS, SDF_STYLE_ROLLERS], ids=["urdf", "sdf-style"])
def test_roller_friction_without_a_plugin_is_mecanum(rollers):
    text = four_wheels(rollers)
    robot = ET.fromstring(text)
    assert roller_links(robot) == frozenset(CORNERS)
    assert gazebo_friction(robot) == dict.fromkeys(CORNERS, 1.0)  # not min(mu, mu2) = 0: it would never move
    spec = detect_drive(text)
    assert spec.kind == "mecanum" and spec.source == "urdf" and spec.wheelbase == pytest.approx(0.4)


def test_plain_anisotropic_friction_is_not_rollers():
    """A skid-steer model's mu2 < mu1 (no fdir1, or not near zero) stays a diff drive with min()."""
    half = '<gazebo reference="{link}"><mu1>1</mu1><mu2>0.5</mu2><fdir1>1 0 0</fdir1></gazebo>'
    no_fdir = '<gazebo reference="{link}"><mu1>1</mu1><mu2>0</mu2></gazebo>'
    for gazebo, mu in ((half, 0.5), (no_fdir, 0.0)):
        robot = ET.fromstring(four_wheels(gazebo))
        assert roller_links(robot) == frozenset()
        assert gazebo_friction(robot) == dict.fromkeys(CORNERS, mu)
        assert detect_drive(robot).kind == "diff"


def test_diff_plugin_on_roller_wheels_is_followed_and_said():
    plugin = ('<plugin filename="gz-sim-diff-drive-system" name="gz::sim::systems::DiffDrive">'
              '<left_joint>front_left_joint</left_joint><left_joint>rear_left_joint</left_joint>'
              '<right_joint>front_right_joint</right_joint><right_joint>rear_right_joint</right_joint>'
              '<wheel_separation>0.5</wheel_separation><wheel_radius>0.05</wheel_radius></plugin>')
    notices = []
    spec = detect_drive(four_wheels(URDF_ROLLERS, plugin), notices=notices)
    assert spec.kind == "diff"
    assert any("roller friction (mecanum)" in n.message and "diff drive" in n.message for n in notices)


def test_planar_move_is_omni_with_ground_truth_odometry():
    plugin = '<plugin name="planar" filename="libgazebo_ros_planar_move.so"><update_rate>50</update_rate></plugin>'
    spec = detect_drive(four_wheels(plugin=plugin))
    assert spec.kind == "omni" and spec.odometry == "ground_truth"
    assert len(spec.left_joints) == len(spec.right_joints) == 2


def test_planar_move_on_a_body_without_wheels():
    text = (f'<robot name="puck"><link name="base">{INERTIAL}<collision><geometry><cylinder radius="0.2" '
            'length="0.1"/></geometry></collision></link><gazebo><plugin name="move" '
            'filename="libgazebo_ros_planar_move.so"/></gazebo></robot>')
    spec = detect_drive(text)
    assert spec.kind == "omni" and spec.left_joints == spec.right_joints == ()


@pytest.mark.parametrize("args", [{"drive": "plugin"}, {"drive": "rollers"}, {"drive": "planar"}])
def test_descriptions_survive_the_cache(tmp_path, monkeypatch, args):
    monkeypatch.setenv("MOBOT_CACHE_DIR", str(tmp_path))
    cold = load_robot(MECANUM, args).drive
    warm = load_robot(MECANUM, args).drive
    assert warm == cold and warm.kind in ("mecanum", "omni") and isinstance(warm.joint_signs[0], tuple)


def test_sdf_rollers_are_read_not_reduced_to_zero(tmp_path, monkeypatch):
    """gz-sim's layout: <surface><friction><ode> mu 1, mu2 0, fdir1; with and without the plugin."""
    monkeypatch.setenv("MOBOT_CACHE_DIR", str(tmp_path))
    with_plugin = load_robot(str(SDF), {})
    assert with_plugin.drive.kind == "mecanum" and with_plugin.drive.source == "plugin"
    assert with_plugin.drive.wheelbase == 0.5 and with_plugin.drive.wheel_separation == 0.6
    text = SDF.read_text()
    start, end = text.index("<plugin"), text.index("</plugin>") + len("</plugin>")
    bare = tmp_path / "bare.sdf"
    bare.write_text(text[:start] + text[end:])
    rollers = load_robot(str(bare), {})
    assert rollers.drive.kind == "mecanum" and rollers.drive.source == "urdf"
    assert rollers.drive.wheelbase == pytest.approx(0.5) and rollers.drive.wheel_separation == pytest.approx(0.6)
    wheel = ET.fromstring(rollers.urdf).find("link[@name='front_left_wheel']")
    assert wheel.find("contact/lateral_friction").get("value") == "1"


def test_inspect_names_the_holonomic_kind(tmp_path, monkeypatch):
    from mobot_cli.cli import invoke

    monkeypatch.setenv("MOBOT_CACHE_DIR", str(tmp_path))
    done = invoke(["inspect", MECANUM, "drive:=planar"])
    assert done.exit_code == 0
    assert ("omni drive (plugin, holonomic: takes linear_y): left front_left_wheel_joint, rear_left_wheel_joint; "
            "right front_right_wheel_joint, rear_right_wheel_joint; wheel radius 0.0500 m, separation 0.5000 m, "
            "wheelbase 0.4000 m; odometry ground_truth") in " ".join(done.stdout.split())


def test_roller_friction_split_over_two_gazebo_blocks():
    split = ('<gazebo reference="{link}"><mu1>0.9</mu1></gazebo>'
             '<gazebo reference="{link}"><mu2>0</mu2><fdir1>1 1 0</fdir1><mu1>1.2</mu1></gazebo>')
    robot = ET.fromstring(four_wheels(split))
    assert roller_links(robot) == frozenset(CORNERS)
    assert gazebo_friction(robot) == dict.fromkeys(CORNERS, 1.2)  # the later block's mu1 wins


def test_inspect_of_a_base_without_wheel_joints_says_so(tmp_path, monkeypatch):
    """neobotix's mpo_700 (wheels on fixed joints, moved by planar_move): not "left none; right
    none; wheel radius 0.0000 m"."""
    from mobot_cli.cli import invoke

    monkeypatch.setenv("MOBOT_CACHE_DIR", str(tmp_path))
    done = invoke(["inspect", str(Path(__file__).resolve().parents[1] / "sim" / "robots" / "planar_box.urdf")])
    assert done.exit_code == 0
    assert ("omni drive (plugin, holonomic: takes linear_y): no wheel joints, the body is moved as gazebo_ros's "
            "planar_move moves it; odometry ground_truth") in " ".join(done.stdout.split())
