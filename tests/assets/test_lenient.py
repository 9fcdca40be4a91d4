"""What Gazebo's parsers read, mobot reads: `--` in comments, undeclared prefixes, duplicate model
names, fractions where sdformat reads a whole number, worlds and models written as xacro."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from mobot_cli.assets.lenient import GZ_NAMESPACE, gazebo_xml, sdf_integer
from mobot_cli.cli import invoke

INERTIAL = '<inertial><mass value="2"/><inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial>'
LIDAR = ('<gazebo reference="base_link"><sensor name="lidar" type="ray"><update_rate>5</update_rate><ray><scan>'
         '<horizontal><samples>{samples}</samples><min_angle>-3.14159</min_angle><max_angle>3.14159</max_angle>'
         '</horizontal></scan><range><min>0.12</min><max>8</max></range></ray></sensor></gazebo>')
# A comment as people write them (strict XML refuses both), and gz: used without its xmlns.
QUIRKS = ('<!-- wheels -- two of them --->\n'
          '<gazebo reference="base_link"><mu1>0.9</mu1><fdir1 gz:expressed_in="base_link">1 0 0</fdir1></gazebo>\n')


def urdf_robot(tmp_path: Path, name: str, extra: str, xacro: bool = False) -> Path:
    header = ' xmlns:xacro="http://www.ros.org/wiki/xacro"' if xacro else ""
    path = tmp_path / name
    path.write_text(f'<?xml version="1.0"?>\n<robot name="r"{header}>\n'
                    f'<link name="base_link">{INERTIAL}<collision><geometry><box size="0.3 0.2 0.1"/></geometry>'
                    f'</collision></link>\n{extra}</robot>\n')
    return path


def checked(path: Path, *args: str) -> dict:
    done = invoke(["check", str(path), "--json", *args])
    assert done.exit_code == 0, done.stderr
    return json.loads(done.stdout)


def test_gazebo_xml_keeps_every_line_and_reads_declared_and_undeclared_gz_alike():
    text = '<?xml version="1.0"?>\n<!-- a -- b --->\n<sdf>\n<x gz:expressed_in="l"/>\n</sdf>\n'
    fixed = gazebo_xml(text)
    assert fixed.count("\n") == text.count("\n")
    assert fixed.splitlines()[1] == "<!-- a - - b - -->"
    assert fixed.splitlines()[2] == f'<sdf xmlns:gz="{GZ_NAMESPACE}">'
    declared = f'<sdf xmlns:gz="{GZ_NAMESPACE}"><x gz:expressed_in="l"/></sdf>'
    assert gazebo_xml(declared) == declared
    assert gazebo_xml('<a><![CDATA[<!-- a -- b -->]]></a>') == '<a><![CDATA[<!-- a -- b -->]]></a>'
    assert gazebo_xml("<r><foo:bar/></r>") == '<r xmlns:foo="urn:mobot:undeclared:foo"><foo:bar/></r>'


def test_names_with_double_colons_read_as_tinyxml2_reads_them():
    # gz-sim's examples/worlds/sensors.sdf gives a plugin <gz::system_priority>: strict XML refuses it
    text = ('<sdf>\n<plugin filename="f" name="gz::sim::systems::ForceTorque">\n'
            '  <gz::system_priority>10</gz::system_priority>\n<x a::b="1" c="std::map"/>\n'
            '<!-- <c::d/> --><e>std::vector</e></plugin>\n</sdf>')
    fixed = gazebo_xml(text)
    assert fixed.count("\n") == text.count("\n") and len(fixed) == len(text)
    assert fixed.splitlines()[2] == "  <gz__system_priority>10</gz__system_priority>"
    assert fixed.splitlines()[3] == '<x a__b="1" c="std::map"/>'  # names only: values and text stay
    assert 'name="gz::sim::systems::ForceTorque"' in fixed and "<!-- <c::d/> --><e>std::vector</e>" in fixed


@pytest.mark.parametrize("text, read", [("666.519", (666, True)), ("640", (640, False)), (" 12 ", (12, False)),
                                        ("1e3", (1, True)), ("many", None), (".5", None)])
def test_sdf_integer_reads_leading_digits_as_sdformat_does(text, read):
    assert sdf_integer(text) == read


def test_a_urdf_with_comment_hyphens_and_an_undeclared_prefix_is_read(tmp_path):
    result = checked(urdf_robot(tmp_path, "r.urdf", QUIRKS))
    assert result["ok"] and result["name"] == "r"


def test_a_xacro_robot_with_them_and_a_fractional_lidar_samples_is_read_with_a_warning(tmp_path):
    """The real robot's case: <samples> from an xacro expression, 666.519; refused since sensors landed."""
    extra = ('<xacro:property name="samples" value="${1000 * 0.666519}"/>\n' + QUIRKS
             + LIDAR.format(samples="${samples}"))
    path = urdf_robot(tmp_path, "r.urdf.xacro", extra, xacro=True)
    done = invoke(["check", str(path)])
    assert done.exit_code == 0, done.stderr
    assert (f"mobot: warning: {path}, key 'gazebo.sensor.lidar.ray.scan.horizontal.samples': sensor 'lidar' "
            "has <samples> '666.519': read as 666, as Gazebo (sdformat) reads a whole number\n") in done.stderr
    (sensor,) = checked(path)["sensors"]
    assert sensor["samples"] == 666


def test_a_sample_count_that_is_no_number_is_still_an_error(tmp_path):
    done = invoke(["check", str(urdf_robot(tmp_path, "r.urdf", LIDAR.format(samples="many")))])
    assert done.exit_code == 2 and "sensor 'lidar' has <samples> 'many', which is not a finite number" in done.stderr


WORLD = """<?xml version="1.0"?>
<sdf version="1.9">
  <!-- posts -- two, both named post --->
  <world name="w">
    <model name="ground"><static>true</static><link name="l"><collision name="c"><geometry><plane>
      <normal>0 0 1</normal></plane></geometry></collision></link></model>
    {posts}
  </world>
</sdf>
"""
POST = ('<model name="post"><static>true</static><pose>{x} 0 0.5 0 0 0</pose><link name="l"><collision name="c">'
        '<geometry><box><size>0.2 0.2 1</size></box></geometry><surface><friction><ode><mu>1</mu>'
        '<fdir1 gz:expressed_in="l">1 0 0</fdir1></ode></friction></surface></collision></link></model>')


def test_a_world_with_comment_hyphens_a_prefix_and_duplicate_names_loads_with_a_rename(tmp_path):
    path = tmp_path / "posts.world"
    path.write_text(WORLD.format(posts=POST.format(x=2) + "\n    " + POST.format(x=-2)).replace(
        "</world>", '<plugin filename="p" name="gz::sim::systems::Imu"><gz::system_priority>1</gz::system_priority>'
        '</plugin></world>'))
    done = invoke(["check", str(path)])
    assert done.exit_code == 0, done.stderr
    assert done.stderr == (f"mobot: warning: {path}:8, key 'model[post]': two models are named 'post': this one "
                           "is renamed 'post_1' (Gazebo classic loads both under one name)\n"
                           f"mobot: warning: {path.name}: ignored 1 plugin (mobot simulates collision geometry)\n")
    summary = checked(path)
    assert (summary["models"], summary["static_models"]) == (3, 3)
    # Both posts stand in the world: a robot driving at either one stops against it.
    scenario = tmp_path / "s.yaml"
    scenario.write_text("version: 1\nworld: posts.world\nduration: 6.0\nrobots:\n"
                        "  - name: a\n    description: mobot\n    pose: {x: 0.0, y: 0.0}\n"
                        "    commands:\n      - {at: 0.5, linear: 0.5, for: 5.0}\n"
                        "  - name: b\n    description: mobot\n    pose: {x: -0.6, y: 0.0, yaw: 3.14159}\n"
                        "    commands:\n      - {at: 0.5, linear: 0.5, for: 5.0}\n")
    done = invoke(["run", str(scenario), "--out", str(tmp_path / "run"), "--quiet"])
    assert done.exit_code == 0, done.stderr
    robots = json.loads((tmp_path / "run" / "summary.json").read_text())["robots"]
    assert 1.6 < robots["a"]["final_pose"]["x"] < 1.9  # the post at +2 (0.1 m half width) stopped it
    assert -1.9 < robots["b"]["final_pose"]["x"] < -1.6  # and so did its renamed twin at -2


SANDBOX = """<?xml version="1.0"?>
<sdf version="1.6" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:arg name="headless" default="true"/>
  <xacro:property name="side" value="1.5"/>
  <!-- a world written as xacro -- as nav2's tb3_sandbox.sdf.xacro is -->
  <world name="sandbox">
    <xacro:unless value="$(arg headless)">
      <plugin filename="gz-sim-scene-broadcaster-system" name="gz::sim::systems::SceneBroadcaster"/>
    </xacro:unless>
    <model name="ground"><static>1</static><link name="l"><collision name="c"><geometry><plane>
      <normal>0 0 1</normal><size>100 100</size></plane></geometry></collision></link></model>
    <xacro:macro name="wall" params="name x">
      <model name="${name}"><static>true</static><pose>${x} 0 0.5 0 0 0</pose><link name="l">
        <collision name="c"><geometry><box><size>0.2 4 1</size></box></geometry></collision></link></model>
    </xacro:macro>
    <xacro:wall name="east" x="${side}"/>
    <xacro:wall name="west" x="${-side}"/>
  </world>
</sdf>
"""


# nav2's depot.sdf is xacro by its content only (nav2 runs xacro on every world it is given)
@pytest.mark.parametrize("name", ["sandbox.world.xacro", "sandbox.sdf.xacro", "sandbox.sdf"])
def test_a_world_written_as_xacro_is_expanded_checked_and_run(tmp_path, name):
    (tmp_path / name).write_text(SANDBOX)
    summary = checked(tmp_path / name)
    assert summary["name"] == "sandbox" and summary["models"] == 3
    scenario = tmp_path / "s.yaml"
    scenario.write_text(f"version: 1\nworld: {name}\nduration: 5.0\nrobots:\n"
                        "  - name: r\n    description: mobot\n    pose: {x: 0.0, y: 0.0}\n"
                        "    commands:\n      - {at: 0.5, linear: 0.5, for: 4.5}\n")
    done = invoke(["run", str(scenario), "--out", str(tmp_path / "run"), "--quiet"])
    assert done.exit_code == 0, done.stderr
    x = json.loads((tmp_path / "run" / "summary.json").read_text())["robots"]["r"]["final_pose"]["x"]
    assert 1.1 < x < 1.4  # stopped by the east wall the macro placed at x = 1.5 (inner face 1.4)


def test_an_sdf_model_written_as_xacro_is_a_robot_description(tmp_path):
    path = tmp_path / "cart.sdf.xacro"
    path.write_text("""<?xml version="1.0"?>
<sdf version="1.7" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:property name="size" value="0.4"/>
  <model name="cart"><link name="base"><inertial><mass>3</mass></inertial>
    <collision name="c"><geometry><box><size>${size} ${size / 2} 0.1</size></box></geometry></collision>
  </link></model>
</sdf>
""")
    result = checked(path)
    assert result["name"] == "cart"
    assert result["footprint"]["length"] == pytest.approx(0.4) and result["footprint"]["width"] == pytest.approx(0.2)


def test_a_corpus_robot_with_gazebo_classics_wideanglecamera_is_read(corpus, monkeypatch):
    """turtlebot3_burger_cam's camera is type 'wideanglecamera', which sdformat reads; it was refused."""
    monkeypatch.setenv("GAZEBO_MODEL_PATH", str(corpus / "turtlebot3_simulations" / "turtlebot3_gazebo" / "models"))
    model = corpus / "turtlebot3_simulations/turtlebot3_gazebo/models/turtlebot3_burger_cam/model.sdf"
    done = invoke(["check", str(model), "--json"])
    assert done.exit_code == 0, done.stderr
    result = json.loads(done.stdout)
    assert any("sensors of types mobot does not simulate are left out: wideanglecamera 'camera'" in notice
               for notice in result["notices"])
    assert sorted(s["name"] for s in result["sensors"]) == ["hls_lfcd_lds", "tb3_imu"]
