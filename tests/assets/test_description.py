"""load_robot on the bundled robot and real robots from the corpus, and its failures."""

from __future__ import annotations

import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from mobot_cli.assets import bundled_robot_names, expand_to_text, inspect_summary, load_robot
from mobot_cli.errors import DescriptionError, ResourceError
from mobot_cli.sim.drive import default_separation_multiplier

ROOTS = ("turtlebot3", "husky", "jackal", "velodyne_simulator", "linorobot2", "gz_ros2_control")
NO_CONTROL = {"gazebo_controllers": "/dev/null"}  # husky/jackal name packages not in the corpus


@pytest.fixture
def corpus_path(corpus, monkeypatch) -> Path:
    monkeypatch.setenv("MOBOT_RESOURCE_PATH", os.pathsep.join(str(corpus / r) for r in ROOTS))
    return corpus


def contact_friction(urdf: str) -> dict[str, float]:
    robot = ET.fromstring(urdf)
    return {link.get("name"): float(link.find("contact/lateral_friction").get("value"))
            for link in robot.findall("link") if link.find("contact") is not None}


def test_bundled_mobot():
    assert "mobot" in bundled_robot_names()
    robot = load_robot("mobot")
    assert (robot.name, robot.root_link, robot.notices) == ("mobot", "base_footprint", ())
    assert robot.total_mass == pytest.approx(4.651)
    assert robot.footprint == pytest.approx((-0.2, 0.1, -0.17, 0.17))
    assert robot.bottom_z == pytest.approx(0.0, abs=1e-9)  # wheels and caster touch the floor
    assert robot.top_z == pytest.approx(0.15)  # the chassis box's top: 0.10 m high, centred 0.10 m up
    drive = robot.drive
    assert drive.left_joints + drive.right_joints == ("left_wheel_joint", "right_wheel_joint")
    assert (drive.wheel_radius, drive.wheel_separation, drive.source) == (0.05, 0.3, "plugin")
    assert drive.joint_signs == (("left_wheel_joint", 1.0), ("right_wheel_joint", 1.0))
    chassis = ET.fromstring(robot.urdf).find("link[@name='base_link']/inertial/inertia")
    assert float(chassis.get("ixx")) == pytest.approx(4.0 * (0.25**2 + 0.1**2) / 12)
    assert float(chassis.get("izz")) == pytest.approx(4.0 * (0.3**2 + 0.25**2) / 12)
    wheel = ET.fromstring(robot.urdf).find("link[@name='left_wheel']/inertial/inertia")
    assert float(wheel.get("iyy")) == pytest.approx(0.3 * 0.05**2 / 2)
    # only Gazebo's <mu1>/<mu2> become PyBullet friction; the rest is the world's default
    assert contact_friction(robot.urdf) == {"left_wheel": 1.0, "right_wheel": 1.0, "caster": 0.01}


def test_bundled_mobot_lidar_arg():
    assert "lidar_link" not in [link.name for link in load_robot("mobot").links]
    robot = load_robot("mobot", {"lidar": "true"})
    assert [link.name for link in robot.links][-1] == "lidar_link"
    assert robot.total_mass == pytest.approx(4.651 + 0.17)


def test_turtlebot3_burger(corpus_path):
    robot = load_robot(str(corpus_path / "turtlebot3/turtlebot3_description/urdf/"
                                         "turtlebot3_burger.urdf.xacro"))
    drive = robot.drive
    assert drive.left_joints + drive.right_joints == ("wheel_left_joint", "wheel_right_joint")
    assert (drive.wheel_radius, drive.wheel_separation) == (0.033, 0.160)
    assert (drive.max_wheel_torque, drive.source) == (10.0, "plugin")
    assert drive.joint_signs == (("wheel_left_joint", 1.0), ("wheel_right_joint", 1.0))
    assert [n.location.key for n in robot.notices] == ["link.base_footprint", "link.imu_link"]
    assert "link 'base_footprint' has no <inertial>: PyBullet would give it 1 kg" in \
        robot.notices[0].message
    assert robot.total_mass == pytest.approx(0.82573504 + 2 * 0.028498940 + 0.005 + 0.114)
    pybullet_urdf = ET.fromstring(robot.urdf)
    injected = pybullet_urdf.find("link[@name='imu_link']/inertial/mass")
    assert injected.get("value") == "0.001"
    meshes = [m.get("filename") for m in pybullet_urdf.iter("mesh")]
    assert len(meshes) == 4 and all(Path(m).is_absolute() and Path(m).is_file() for m in meshes)
    assert contact_friction(robot.urdf)["wheel_left_link"] == 0.1


def test_turtlebot3_waffle_pi(corpus_path):
    robot = load_robot(str(corpus_path / "turtlebot3/turtlebot3_description/urdf/"
                                         "turtlebot3_waffle_pi.urdf.xacro"))
    assert (robot.drive.wheel_radius, robot.drive.wheel_separation) == (0.033, 0.287)
    assert robot.root_link == "base_footprint"


def test_husky_skid_steer_from_geometry(corpus_path):
    robot = load_robot(str(corpus_path / "husky/husky_description/urdf/husky.urdf.xacro"),
                       {**NO_CONTROL, "is_sim": "true"})
    drive = robot.drive
    assert drive.source == "urdf" and drive.wheel_radius == pytest.approx(0.1651)
    assert drive.left_joints == ("front_left_wheel_joint", "rear_left_wheel_joint")
    assert drive.right_joints == ("front_right_wheel_joint", "rear_right_wheel_joint")
    assert drive.wheel_separation == pytest.approx(0.5708)
    assert drive.wheel_separation_multiplier == pytest.approx(
        default_separation_multiplier(0.5708, 0.512))
    assert drive.wheel_separation_multiplier > 1.0
    assert robot.total_mass == pytest.approx(46.034 + 4 * 2.637)
    assert robot.bottom_z == pytest.approx(0.03282 - 0.1651)
    # <mu1 value="1.0"/><mu2 value="0.5"/>: PyBullet gets the smaller one
    assert contact_friction(robot.urdf)["front_left_wheel"] == 0.5


def test_jackal_with_velodyne_package(corpus_path):
    robot = load_robot(str(corpus_path / "jackal/jackal_description/urdf/jackal.urdf.xacro"),
                       NO_CONTROL)
    assert robot.drive.wheel_radius == pytest.approx(0.098)
    assert robot.drive.wheel_separation == pytest.approx(0.37559)
    assert len(robot.drive.left_joints + robot.drive.right_joints) == 4


@pytest.mark.parametrize("name, joints, radius, separation", [
    ("2wd", ("left_wheel_joint", "right_wheel_joint"), 0.045, 0.26),
    ("4wd", ("front_left_wheel_joint", "rear_left_wheel_joint", "front_right_wheel_joint",
             "rear_right_wheel_joint"), 0.07162, 0.271)])
def test_linorobot2(corpus_path, name, joints, radius, separation):
    robot = load_robot(str(corpus_path / f"linorobot2/linorobot2_description/urdf/robots/"
                                         f"{name}.urdf.xacro"))
    drive = robot.drive
    assert drive.left_joints + drive.right_joints == joints and drive.source == "plugin"
    assert drive.wheel_radius == pytest.approx(radius)
    assert drive.wheel_separation == pytest.approx(separation)
    expected = {"front_caster_wheel_link": 0.01, "rear_caster_wheel_link": 0.01} \
        if name == "2wd" else {}
    assert contact_friction(robot.urdf) == expected


def test_gz_ros2_control_diff_drive(corpus_path):
    robot = load_robot(str(corpus_path / "gz_ros2_control/gz_ros2_control_demos/urdf/"
                                         "test_diff_drive.xacro.urdf"))
    assert robot.root_link == "chassis"
    assert (robot.drive.wheel_radius, robot.drive.source) == (0.3, "urdf")
    assert robot.drive.wheel_separation == pytest.approx(2 * 0.625029)


def test_missing_mesh_names_uri_link_and_file(corpus, monkeypatch):
    monkeypatch.setenv("MOBOT_RESOURCE_PATH", str(corpus / "turtlebot3__main"))
    path = corpus / "turtlebot3__main/turtlebot3_description/urdf/turtlebot3_burger.urdf"
    with pytest.raises(DescriptionError) as err:
        load_robot(str(path))
    assert err.value.message.startswith(
        "the visual mesh 'package://turtlebot3_description/meshes/bases/burger_base.stl' of "
        "link 'base_link' cannot be found")
    assert err.value.location.file == path


def write_urdf(tmp_path: Path, body: str) -> Path:
    path = tmp_path / "r.urdf"
    path.write_text(f'<robot name="r">{body}</robot>')
    return path


def test_urdf_without_links(tmp_path):
    with pytest.raises(DescriptionError, match="the robot has no <link> elements"):
        load_robot(str(write_urdf(tmp_path, "")))


def test_joint_naming_missing_link(tmp_path):
    path = write_urdf(tmp_path, '<link name="base"/><link name="wheel"/>'
                                '<joint name="j" type="continuous"><parent link="base"/>'
                                '<child link="wheell"/></joint>')
    with pytest.raises(DescriptionError) as err:
        load_robot("r.urdf", base_dir=tmp_path)
    assert err.value.message == "joint 'j' names child link 'wheell', which does not exist"
    assert err.value.hint == "Did you mean 'wheel'?"
    assert err.value.location.file == path


def test_two_roots_rejected(tmp_path):
    path = write_urdf(tmp_path, '<link name="a"/><link name="b"/>')
    with pytest.raises(DescriptionError, match="links 'a', 'b' have no parent joint"):
        load_robot(str(path))


def test_geometry_checks(tmp_path):
    path = write_urdf(tmp_path, '<link name="a"><collision><geometry/></collision></link>')
    with pytest.raises(DescriptionError, match="a <collision> of link 'a' has 0 shapes"):
        load_robot(str(path))
    path = write_urdf(tmp_path, '<link name="a"><visual><geometry><cylinder radius="0.1"/>'
                                '</geometry></visual></link>')
    with pytest.raises(DescriptionError, match="the <cylinder> of a <visual> of link 'a' has "
                                               "length=None"):
        load_robot(str(path))


def test_yourdfpy_checks_joint_limits(tmp_path):
    path = write_urdf(tmp_path, '<link name="a"/><link name="b"/><joint name="j" type="revolute">'
                                '<parent link="a"/><child link="b"/></joint>')
    with pytest.raises(DescriptionError, match="the URDF is incomplete: .*limit"):
        load_robot(str(path))


def test_unknown_bundled_name_suggests():
    with pytest.raises(ResourceError) as err:
        load_robot("mobto")
    assert err.value.message == "'mobto' is neither a bundled robot nor a .urdf/.xacro file"
    assert err.value.hint.startswith("Did you mean 'mobot'?")


def test_missing_description_file(tmp_path):
    with pytest.raises(ResourceError, match=r"robot description file .*nope.urdf does not exist"):
        load_robot("robots/nope.urdf", base_dir=tmp_path)


def test_expand_to_text_resolves_mesh_paths(corpus_path):
    top = corpus_path / "turtlebot3/turtlebot3_description/urdf/turtlebot3_burger.urdf.xacro"
    text = expand_to_text(str(top))
    mesh_dir = corpus_path / "turtlebot3/turtlebot3_description/meshes"
    assert f'filename="{mesh_dir}/bases/burger_base.stl"' in text
    assert "package://" not in text and "<contact>" not in text
    assert "<wheelSeparation>0.160</wheelSeparation>" in text


def test_inspect_summary():
    summary = inspect_summary(load_robot("mobot"))
    assert summary["total_mass"] == pytest.approx(4.651)
    assert summary["footprint"]["length"] == pytest.approx(0.3)
    assert summary["footprint"]["width"] == pytest.approx(0.34)
    assert summary["drive"]["left_joints"] == ("left_wheel_joint",)
    tree = summary["tree"]
    assert tree["link"] == "base_footprint"
    assert [c["joint"] for c in tree["children"]] == ["base_joint"]
    assert [c["link"] for c in tree["children"][0]["children"]] == [
        "left_wheel", "right_wheel", "caster"]


def test_warm_load_is_identical_and_never_imports_yourdfpy(tmp_path, corpus):
    env = {**os.environ, "MOBOT_CACHE_DIR": str(tmp_path / "cache"),
           "MOBOT_RESOURCE_PATH": str(corpus / "turtlebot3")}
    burger = corpus / "turtlebot3/turtlebot3_description/urdf/turtlebot3_burger.urdf.xacro"
    script = ("import sys\nfrom mobot_cli.assets import load_robot\n"
              f"d = load_robot({str(burger)!r})\n"
              "print(d.drive.wheel_separation, len(d.notices), len(d.urdf), "
              "'yourdfpy' in sys.modules, 'trimesh' in sys.modules, 'xacro' in sys.modules)\n")
    runs = [subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                           text=True, check=True).stdout.split() for _ in range(2)]
    assert runs[0][:3] == runs[1][:3] and runs[0][0] == "0.16"
    assert runs[0][3:] == ["True", "True", "True"]  # cold: the checks ran
    assert runs[1][3:] == ["False", "False", "False"]  # warm: read from the cache


def test_a_new_folder_reuses_the_checked_description_while_its_meshes_lead_to_the_same_files(
        corpus, tmp_path, monkeypatch):
    """The scenario's folder is a search path, but it matters only through where the mesh URIs
    lead: another folder reuses the cached checks, unless a package there shadows the meshes."""
    import shutil

    from mobot_cli.assets.description import robot as robot_module

    monkeypatch.setenv("MOBOT_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("MOBOT_RESOURCE_PATH", str(corpus / "turtlebot3"))
    checks = []
    real_check = robot_module.check_with_yourdfpy
    monkeypatch.setattr(robot_module, "check_with_yourdfpy", lambda *a: checks.append(1) or real_check(*a))
    burger = str(corpus / "turtlebot3/turtlebot3_description/urdf/turtlebot3_burger.urdf.xacro")
    folders = [tmp_path / name for name in ("a", "b", "shadowed")]
    for folder in folders:
        folder.mkdir()
    shutil.copytree(corpus / "turtlebot3/turtlebot3_description", folders[2] / "copy" / "turtlebot3_description")

    first = load_robot(burger, base_dir=folders[0])
    again = load_robot(burger, base_dir=folders[1])
    assert len(checks) == 1 and again.urdf == first.urdf  # the same files: not checked again
    assert load_robot(burger, base_dir=folders[1]).urdf == first.urdf and len(checks) == 1
    shadowed = load_robot(burger, base_dir=folders[2])
    assert len(checks) == 2  # its package comes first in the search: other files, checked
    meshes = [m.get("filename") for m in ET.fromstring(shadowed.urdf).iter("mesh")]
    assert len(meshes) == 4 and all(m.startswith(str(folders[2])) for m in meshes)
    assert load_robot(burger, base_dir=folders[0]).urdf == first.urdf  # and back: the first files


def test_a_mesh_left_out_is_looked_for_again_from_a_folder_that_has_it(corpus, tmp_path, monkeypatch):
    """skip_missing leaves out a mesh nothing finds; from a folder whose package has it, the
    cached description without it must not be served."""
    import shutil

    monkeypatch.setenv("MOBOT_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("MOBOT_RESOURCE_PATH", str(corpus / "turtlebot3__main"))  # its meshes are missing
    burger = str(corpus / "turtlebot3__main/turtlebot3_description/urdf/turtlebot3_burger.urdf")
    bare, stocked = tmp_path / "bare", tmp_path / "stocked"
    bare.mkdir()
    shutil.copytree(corpus / "turtlebot3/turtlebot3_description", stocked / "turtlebot3_description")

    left_out = load_robot(burger, base_dir=bare, skip_missing=True)
    assert not list(ET.fromstring(left_out.urdf).iter("mesh"))
    assert any("left out (skip_missing)" in n.message for n in left_out.notices)
    found = load_robot(burger, base_dir=stocked, skip_missing=True)
    meshes = [m.get("filename") for m in ET.fromstring(found.urdf).iter("mesh")]
    assert len(meshes) == 4 and all(m.startswith(str(stocked)) for m in meshes)
    assert not any("left out" in n.message for n in found.notices)
