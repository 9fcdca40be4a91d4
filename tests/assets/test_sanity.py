"""Robot descriptions that used to fail deep inside PyBullet are refused by name, at load."""

from __future__ import annotations

from pathlib import Path

import pytest

from mobot_cli.assets.description.sanity import MAX_LINKS
from mobot_cli.cli import invoke

INERTIAL = '<inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>'
BOX = '<geometry><box size="0.3 0.2 0.1"/></geometry>'


def robot(tmp_path: Path, body: str, name: str = "r.urdf") -> Path:
    path = tmp_path / name
    path.write_text(f'<robot name="r">{body}</robot>')
    return path


def refused(path: Path) -> str:
    outcome = invoke(["check", path])
    assert outcome.exit_code == 2 and outcome.stdout == "" and "Traceback" not in outcome.stderr
    return outcome.stderr


def test_a_robot_without_collision_geometry_is_refused(tmp_path):
    """It used to spawn, fall through the floor and end asking whether there is a floor (issue 26)."""
    path = robot(tmp_path, f'<link name="base_link"><visual>{BOX}</visual>{INERTIAL}</link>')
    err = refused(path)
    assert err.startswith(f"mobot: error: {path}: the robot has no collision geometry: "), err
    assert "Add <collision> to its links" in err


@pytest.mark.parametrize("element", ['<origin xyz="nan 0 0"/>', '<origin rpy="0 inf 0"/>'])
def test_non_finite_numbers_are_refused(tmp_path, element):
    path = robot(tmp_path, f'<link name="base_link"><collision>{element}{BOX}</collision>{INERTIAL}</link>')
    err = refused(path)
    assert err.startswith(f"mobot: error: {path}, key 'link.base_link': <origin ") and "is not 3 finite numbers" in err


def test_a_nan_joint_axis_is_refused(tmp_path):
    path = robot(tmp_path, f'<link name="base_link"><collision>{BOX}</collision>{INERTIAL}</link>'
                           f'<link name="w"><collision>{BOX}</collision>{INERTIAL}</link>'
                           '<joint name="j" type="continuous"><parent link="base_link"/><child link="w"/>'
                           '<axis xyz="0 nan 1"/></joint>')
    assert "key 'joint.j': <axis xyz=\"0 nan 1\"> in joint 'j' is not 3 finite numbers" in refused(path)


@pytest.mark.parametrize("content", [b"", b"garbage\x00\x01 not a mesh", b"solid x\nendsolid x\n"],
                         ids=["empty", "garbage", "no-triangles"])
def test_collision_meshes_that_are_not_meshes_are_refused(tmp_path, content):
    (tmp_path / "part.stl").write_bytes(content)
    path = robot(tmp_path, f'<link name="base_link"><collision><geometry><mesh filename="part.stl"/></geometry>'
                           f'</collision>{INERTIAL}</link>')
    err = refused(path)
    assert f"collision mesh {tmp_path / 'part.stl'} of link 'base_link'" in err
    assert "Check that the file is a valid STL, OBJ or COLLADA mesh." in err


@pytest.mark.parametrize("inertial, message", [
    ('<mass value="-2"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/>',
     "link 'base_link' has a negative mass (-2 kg)"),
    ('<mass value="2"/><inertia ixx="-0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/>',
     "link 'base_link' has a negative moment of inertia (ixx=-0.01)"),
])
def test_negative_mass_or_inertia_is_an_error_not_a_near_zero_warning(tmp_path, inertial, message):
    path = robot(tmp_path, f'<link name="base_link"><collision>{BOX}</collision><inertial>{inertial}</inertial></link>')
    err = refused(path)
    assert message in err and "near-zero" not in err


def test_too_many_links_are_refused_at_once(tmp_path):
    links = "".join(f'<link name="l{i}"/><joint name="j{i}" type="fixed"><parent link="base_link"/>'
                    f'<child link="l{i}"/></joint>' for i in range(MAX_LINKS))
    path = robot(tmp_path, f'<link name="base_link"><collision>{BOX}</collision>{INERTIAL}</link>{links}')
    assert f"the robot has {MAX_LINKS + 1} links, more than mobot's limit of {MAX_LINKS}" in refused(path)
