"""xacro expansion: $(find) through the resolver, errors that name files, and the cache."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from mobot_cli.assets.description.xacro import expand, expand_file, is_xacro
from mobot_cli.assets.resources import ResourceResolver
from mobot_cli.errors import DescriptionError, ResourceError

XACRO_HEAD = '<?xml version="1.0"?>\n<robot name="t" xmlns:xacro="http://www.ros.org/wiki/xacro">\n'


def write(path: Path, body: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(XACRO_HEAD + body + "\n</robot>\n")
    return path


def test_burger_expands_with_find_resolved(corpus, monkeypatch):
    monkeypatch.setenv("MOBOT_RESOURCE_PATH", str(corpus / "turtlebot3"))
    top = corpus / "turtlebot3/turtlebot3_description/urdf/turtlebot3_burger.urdf.xacro"
    result = expand_file(top, {}, ResourceResolver(None))
    robot = ET.fromstring(result.text)
    assert robot.get("name") == "turtlebot3_burger"
    assert [j.get("name") for j in robot.findall("joint")] == [
        "base_joint", "wheel_left_joint", "wheel_right_joint", "caster_back_joint",
        "imu_joint", "scan_joint"]
    # the included gazebo.xacro contributed the diff-drive plugin
    assert robot.find("gazebo/plugin/wheelSeparation").text == "0.160"
    assert [p.name for p in result.files] == ["turtlebot3_burger.urdf.xacro",
                                             "common_properties.xacro",
                                             "turtlebot3_burger.gazebo.xacro"]


def test_xacro_state_is_restored_afterwards(tmp_path):
    import xacro
    import xacro.substitution_args as sa

    before = (sa._eval_find, sa._eval_dict["find"], sa._eval_optenv)
    expand(write(tmp_path / "a.xacro", '<link name="x"/>'), {}, ResourceResolver(None))
    assert (sa._eval_find, sa._eval_dict["find"], sa._eval_optenv) == before
    assert xacro.all_includes == [] and xacro.filestack is None


def test_plain_urdf_passes_through_unchanged(tmp_path):
    path = tmp_path / "plain.urdf"
    text = '<robot name="p"><link name="a"/></robot>'
    path.write_text(text)
    assert not is_xacro(path, text)
    assert expand(path, {"ignored": "1"}, ResourceResolver(None)) == text


def test_urdf_that_is_really_xacro_is_expanded(corpus, monkeypatch):
    path = corpus / "turtlebot3__main/turtlebot3_description/urdf/turtlebot3_burger.urdf"
    text = expand(path, {"namespace": "tb1/"}, ResourceResolver(None))
    robot = ET.fromstring(text)
    names = [link.get("name") for link in robot.findall("link")]
    assert "tb1/base_footprint" in names and "tb1/wheel_left_link" in names
    assert not [e.tag for e in robot.iter() if "xacro" in e.tag]


def test_args_and_defaults(tmp_path):
    path = write(tmp_path / "a.xacro", '<xacro:arg name="w" default="0.5"/>\n'
                                       '<link name="l_$(arg w)"/>')
    resolver = ResourceResolver(None)
    assert '<link name="l_0.5"/>' in expand(path, {}, resolver)
    assert '<link name="l_2"/>' in expand(path, {"w": "2"}, resolver)


def test_missing_arg_names_arg_file_and_how_to_pass_it(tmp_path):
    path = write(tmp_path / "a.xacro", '<link name="x"/>\n<link name="$(arg is_sim)"/>')
    with pytest.raises(DescriptionError) as err:
        expand(path, {}, ResourceResolver(None))
    assert "Undefined substitution argument: xacro argument 'is_sim' is not set" in str(err.value)
    assert err.value.location.file == path and err.value.location.line == 4
    assert err.value.hint.startswith("Pass it as is_sim:=value in the scenario's args:")


def test_xml_syntax_error_names_file_and_line(tmp_path):
    path = tmp_path / "bad.xacro"
    path.write_text(XACRO_HEAD + '<link name="a">\n</robot>\n')
    with pytest.raises(DescriptionError) as err:
        expand(path, {}, ResourceResolver(None))
    assert "XML syntax error: mismatched tag" in err.value.message
    assert (err.value.location.file, err.value.location.line) == (path, 4)


def test_syntax_error_in_included_file_names_the_included_file(tmp_path):
    inc = tmp_path / "inc.xacro"
    inc.write_text("<robot><oops></robot>")
    top = write(tmp_path / "top.xacro", '<xacro:include filename="inc.xacro"/>')
    with pytest.raises(DescriptionError) as err:
        expand(top, {}, ResourceResolver(None))
    assert err.value.location.file == inc
    assert f"(included from {top})" in err.value.message


def test_missing_include_names_included_and_including_file(tmp_path):
    top = write(tmp_path / "top.xacro", '<xacro:include filename="parts/wheel.xacro"/>')
    with pytest.raises(DescriptionError) as err:
        expand(top, {}, ResourceResolver(None))
    assert f"included file '{tmp_path / 'parts/wheel.xacro'}' cannot be read" in err.value.message
    assert err.value.location.file == top and err.value.location.line == 3


def test_undefined_property(tmp_path):
    path = write(tmp_path / "a.xacro", '<link name="${wheel_radius * 2}"/>')
    with pytest.raises(DescriptionError, match=r"undefined xacro property or name: name "
                                               r"'wheel_radius' is not defined"):
        expand(path, {}, ResourceResolver(None))


def test_unknown_package_lists_folders_searched(tmp_path, monkeypatch):
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "ws"))
    path = write(tmp_path / "a.xacro", '<xacro:include filename="$(find nowhere_pkg)/x.xacro"/>')
    with pytest.raises(ResourceError) as err:
        expand(path, {}, ResourceResolver(tmp_path))
    assert "package 'nowhere_pkg' not found. Folders searched: " in err.value.message
    assert str(tmp_path / "ws") in err.value.message
    assert err.value.location.file == path


def test_find_in_arg_default_suggests_passing_the_arg(corpus, monkeypatch):
    monkeypatch.setenv("MOBOT_RESOURCE_PATH", f"{corpus / 'husky'}")
    top = corpus / "husky/husky_description/urdf/husky.urdf.xacro"
    with pytest.raises(ResourceError) as err:
        expand(top, {}, ResourceResolver(None))
    assert "package 'husky_control' not found" in err.value.message
    assert "pass gazebo_controllers:=VALUE" in err.value.hint
    # the argument only feeds a Gazebo plugin parameter, so any placeholder works
    text = expand(top, {"gazebo_controllers": "/dev/null", "is_sim": "true"},
                  ResourceResolver(None))
    assert "<parameters>/dev/null</parameters>" in text


def test_unknown_arg_gets_a_notice_with_suggestion(tmp_path):
    path = write(tmp_path / "a.xacro", '<xacro:arg name="lidar" default="false"/><link name="a"/>')
    notices = expand_file(path, {"lidr": "true"}, ResourceResolver(None)).notices
    assert [n.message for n in notices] == [
        "xacro argument 'lidr' is not used by a.xacro. Did you mean 'lidar'?"]


def test_cache_is_invalidated_by_included_file_and_env(tmp_path, monkeypatch):
    inc = tmp_path / "inc.xacro"
    inc.write_text(XACRO_HEAD + '<link name="one"/></robot>')
    top = write(tmp_path / "top.xacro", '<xacro:include filename="inc.xacro"/>'
                                        '<link name="$(optenv MOBOT_TEST_SUFFIX none)"/>')
    resolver = ResourceResolver(None)
    assert '"one"' in expand(top, {}, resolver) and '"none"' in expand(top, {}, resolver)
    inc.write_text(XACRO_HEAD + '<link name="two"/></robot>')
    assert '"two"' in expand(top, {}, resolver)
    monkeypatch.setenv("MOBOT_TEST_SUFFIX", "set")
    assert '"set"' in expand(top, {}, resolver)


def test_xacro_warnings_become_notices_not_output(tmp_path, capfd):
    path = write(tmp_path / "a.xacro", '<xacro:include filename="parts/*.xacro"/><link name="a"/>')
    notices = expand_file(path, {}, ResourceResolver(None)).notices
    spec = f"{tmp_path}/parts/*.xacro"
    assert [n.message for n in notices] == [
        f"xacro: warning: Include tag's filename spec \"{spec}\" matched no files."]
    assert capfd.readouterr() == ("", "")
