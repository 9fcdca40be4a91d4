"""The robot commands (inspect, xacro, check) and a corpus robot run through the real CLI."""

from __future__ import annotations

import csv
import json
import math
import subprocess
import sys
from dataclasses import astuple
from pathlib import Path

import pytest

from mobot_cli.cli import invoke

REPO = Path(__file__).resolve().parents[2]
BURGER = "turtlebot3/turtlebot3_description/urdf/turtlebot3_burger.urdf.xacro"


def tree_links(node: dict) -> set[str]:
    return {node["link"]}.union(*(tree_links(child) for child in node["children"]))


def test_inspect_bundled_robot_json():
    code, out, err = astuple(invoke(["inspect", "mobot", "lidar:=true", "imu:=true", "--json"]))
    assert code == 0 and err == ""
    info = json.loads(out)
    assert info["root_link"] == "base_footprint"
    assert info["links"] == 6 and info["joints"] == 5
    assert tree_links(info["tree"]) == {"base_footprint", "base_link", "left_wheel", "right_wheel", "caster",
                                        "lidar_link"}
    assert info["drive"]["left_joints"] == ["left_wheel_joint"]
    assert info["drive"]["wheel_radius"] == pytest.approx(0.05)
    assert info["total_mass"] == pytest.approx(4.821, abs=1e-3)


def test_inspect_without_lidar_has_no_lidar_link():
    code, out, err = astuple(invoke(["inspect", "mobot", "--json"]))
    assert code == 0 and err == ""
    info = json.loads(out)
    assert "lidar_link" not in tree_links(info["tree"])
    assert info["total_mass"] == pytest.approx(4.651, abs=1e-3)


def test_inspect_text_shows_tree_and_drive():
    code, out, err = astuple(invoke(["inspect", "mobot"]))
    assert code == 0 and err == ""
    assert "left_wheel  (continuous joint left_wheel_joint, 0.3 kg)" in out
    assert "wheel radius 0.0500 m" in out


def test_inspect_lists_sensors_in_80_columns():
    code, out, err = astuple(invoke(["inspect", "mobot", "lidar:=true", "imu:=true"]))
    assert code == 0 and err == ""
    listed = out.split("sensors:\n", 1)[1].splitlines()
    assert listed == ["  lidar (ray, 2D lidar) on lidar_link, topic scan, 10 Hz",
                      "    360 rays -3.142..3.142 rad, range 0.12..12 m, noise 0.01 m",
                      "  imu (imu) on base_link, topic imu, 120 Hz",
                      "    noise: gyro 0.0002 rad/s, accel 0.017 m/s^2"]
    assert max(len(line) for line in listed) <= 80


def test_inspect_json_sensors_hold_their_kind_fields():
    code, out, err = astuple(invoke(["inspect", "mobot", "lidar:=true", "imu:=true", "--json"]))
    lidar, imu = json.loads(out)["sensors"]
    assert {k: lidar[k] for k in ("name", "type", "kind", "link", "topic", "frame_id", "rate_hz",
                                  "samples", "vertical_samples", "range_min", "range_max")} == \
        {"name": "lidar", "type": "ray", "kind": "lidar", "link": "lidar_link", "topic": "scan",
         "frame_id": "lidar_link", "rate_hz": 10.0, "samples": 360, "vertical_samples": 1,
         "range_min": 0.12, "range_max": 12.0}
    assert imu == {"name": "imu", "type": "imu", "kind": "imu", "link": "base_link", "topic": "imu",
                   "frame_id": "base_link", "rate_hz": 120.0, "xyz": [0.0, 0.0, 0.0],
                   "quat": [0.0, 0.0, 0.0, 1.0], "noise_mean": 0.0, "noise_stddev": 0.0002,
                   "accel_noise_stddev": 0.017}


def test_inspect_a_robot_without_sensors(tmp_path):
    path = tmp_path / "r.urdf"
    path.write_text('<robot name="r"><link name="a"><collision><geometry><box size="1 1 1"/></geometry></collision>'
                    '<inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/>'
                    '</inertial></link></robot>')
    code, out, err = astuple(invoke(["inspect", str(path)]))
    assert code == 0 and out.rstrip().endswith("sensors: none")


def test_xacro_prints_expanded_urdf_with_args():
    code, out, err = astuple(invoke(["xacro", "mobot", "lidar:=true"]))
    assert code == 0 and err == ""
    assert out.lstrip().startswith("<?xml") and "xacro:" not in out
    assert '<link name="lidar_link">' in out


def test_xacro_bad_argument_syntax():
    code, out, err = astuple(invoke(["xacro", "mobot", "lidar=true"]))
    assert code == 2 and out == ""
    assert err == "mobot: error: argument 'lidar=true' is not NAME:=VALUE. e.g. lidar:=true\n"


def test_check_corpus_robot_and_its_notices(corpus, monkeypatch):
    monkeypatch.setenv("MOBOT_RESOURCE_PATH", str(corpus / "turtlebot3"))
    code, out, err = astuple(invoke(["check", corpus / BURGER]))
    assert code == 0
    assert out == f"ok: robot 'turtlebot3_burger' ({corpus / BURGER})\n"
    assert "link 'base_footprint' has no <inertial>" in err


def test_check_robot_with_missing_meshes_fails(corpus, monkeypatch):
    path = corpus / "turtlebot3__main/turtlebot3_description/urdf/turtlebot3_burger.urdf"
    monkeypatch.setenv("MOBOT_RESOURCE_PATH", str(corpus / "turtlebot3__main"))
    code, out, err = astuple(invoke(["check", path]))
    assert code == 2 and out == ""
    assert "burger_base.stl" in err and "cannot be found" in err
    code, out, err = astuple(invoke(["inspect", path, "--skip-missing", "--json"]))
    assert code == 0
    info = json.loads(out)
    assert info["drive"]["wheel_radius"] == pytest.approx(0.033)  # its collisions are cylinders
    assert any("meshes cannot be found and are left out (skip_missing): visual 'package://turtlebot3_"
               "description/meshes/bases/burger_base.stl' of link 'base_link'" in n for n in info["notices"])


def test_corpus_burger_drives_through_mobot_run(corpus, tmp_path, monkeypatch):
    """A real user flow: a scenario naming a ROS package's xacro, found via MOBOT_RESOURCE_PATH."""
    scenario = tmp_path / "burger.yaml"
    scenario.write_text(
        "version: 1\nname: burger\nduration: 7.0\nrobots:\n"
        f"  - name: tb3\n    description: {corpus / BURGER}\n    pose: {{x: 1.0, y: -1.0, yaw: 1.5707963}}\n"
        "    commands:\n      - {at: 0.5, linear: 0.2, for: 5.0}\n      - {at: 6.0, linear: -0.1, for: 0.9}\n")
    env = {**__import__("os").environ, "MOBOT_RESOURCE_PATH": str(corpus / "turtlebot3")}
    result = subprocess.run([sys.executable, "-m", "mobot_cli", "run", str(scenario), "--out", str(tmp_path / "r"),
                             "--json"], capture_output=True, text=True, env=env, timeout=120)
    assert result.returncode == 0, result.stderr
    summary = json.loads(result.stdout)
    pose = summary["robots"]["tb3"]["final_pose"]
    # 1 m north along +y (yaw 90 deg), then 0.09 m back.
    assert pose["x"] == pytest.approx(1.0, abs=0.03)
    assert pose["y"] == pytest.approx(-1.0 + 1.0 - 0.09, abs=0.03)
    with (tmp_path / "r" / "odom" / "tb3.csv").open() as f:
        rows = [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]
    reversing = [r for r in rows if 6.3 <= r["t"] <= 6.8]
    assert reversing and all(r["odom_vx"] < 0 and r["true_vx"] < 0 for r in reversing)
    assert rows[-1]["odom_x"] == pytest.approx(0.91, abs=0.03)  # odom frame: +x is the spawn heading
    assert math.degrees(rows[-1]["true_yaw"]) == pytest.approx(90.0, abs=3.0)


@pytest.fixture()
def package(tmp_path, monkeypatch):
    """A package 'pkg' with one mesh, found through MOBOT_RESOURCE_PATH."""
    trimesh = pytest.importorskip("trimesh")
    root = tmp_path / "pkg"
    (root / "meshes").mkdir(parents=True)
    (root / "package.xml").write_text("<package><name>pkg</name></package>")
    trimesh.creation.box((0.3, 0.2, 0.1)).export(root / "meshes" / "body.stl")
    monkeypatch.setenv("MOBOT_RESOURCE_PATH", str(tmp_path))
    return root


def test_xacro_leaves_a_mesh_in_a_comment_alone(package):
    robot = package / "commented.urdf"
    robot.write_text('<robot name="c"><link name="base"><visual><geometry>\n'
                     '<!-- <mesh filename="package://pkg/meshes/old_lidar.stl"/> -->\n'
                     '<mesh filename="package://pkg/meshes/body.stl"/></geometry></visual>'
                     '<collision><geometry><box size="0.2 0.2 0.1"/></geometry></collision></link></robot>')
    done = invoke(["xacro", robot])
    assert (done.exit_code, done.stderr) == (0, "")
    assert '<!-- <mesh filename="package://pkg/meshes/old_lidar.stl"/> -->' in done.stdout
    assert f'<mesh filename="{package / "meshes" / "body.stl"}"/>' in done.stdout
    assert invoke(["inspect", robot]).exit_code == 0


def many_links(package, missing: str = "") -> Path:
    """A chain of a base and 12 long-named frames without <inertial>; a lidar whose mesh is gone."""
    frames = "".join(f'<link name="a_frame_with_a_long_descriptive_name_{i}"/>'
                     f'<joint name="a_joint_with_a_long_descriptive_name_{i}" type="fixed">'
                     f'<parent link="{"base" if i == 0 else f"a_frame_with_a_long_descriptive_name_{i - 1}"}"/>'
                     f'<child link="a_frame_with_a_long_descriptive_name_{i}"/></joint>' for i in range(12))
    lidar = ('<link name="lidar"><inertial><mass value="0.2"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" '
             'iyz="0" izz="1e-4"/></inertial><visual><geometry><mesh filename="package://pkg/meshes/'
             f'{missing or "body.stl"}"/></geometry></visual><collision><geometry><mesh filename='
             f'"package://pkg/meshes/{missing or "body.stl"}"/></geometry></collision></link>'
             '<joint name="lidar_joint" type="fixed"><parent link="base"/><child link="lidar"/></joint>')
    path = package / "many.urdf"
    path.write_text('<robot name="many"><link name="base"><inertial><mass value="2"/><inertia ixx="0.1" ixy="0" '
                    'ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial><collision><geometry><mesh filename='
                    f'"package://pkg/meshes/body.stl"/></geometry></collision></link>{frames}{lidar}</robot>')
    return path


def test_links_without_inertial_make_one_warning_and_piped_tree_lines_are_whole(package):
    done = invoke(["inspect", many_links(package)])
    assert done.exit_code == 0
    inertial = [line for line in done.stderr.splitlines() if "<inertial>" in line]
    assert len(inertial) == 1 and inertial[0].endswith(
        ": 12 links (" + ", ".join(f"a_frame_with_a_long_descriptive_name_{i}" for i in range(12))
        + ") have no usable <inertial> (none, or a near-zero mass): PyBullet would give each 1 kg, so mobot "
        "gives each 1 g and 1e-06 kg*m^2 (Gazebo lumps such links into their parent through fixed joints, "
        "or drops them)")
    deepest = "a_frame_with_a_long_descriptive_name_11  (fixed joint a_joint_with_a_long_descriptive_name_11, 0 kg)"
    assert any(line.endswith(deepest) for line in done.stdout.splitlines())  # 100+ columns, not cut at 80


def test_a_missing_robot_mesh_is_left_out_with_skip_missing(package):
    path = many_links(package, missing="lidar.stl")
    refused = invoke(["check", path])
    assert refused.exit_code == 2 and "lidar.stl' of link 'lidar' cannot be found" in refused.stderr
    assert "--skip-missing" in refused.stderr
    done = invoke(["check", path, "--skip-missing"])
    assert done.exit_code == 0 and done.stdout.startswith("ok: robot 'many'")
    (left_out,) = [line for line in done.stderr.splitlines() if "left out" in line]
    assert ("2 meshes cannot be found and are left out (skip_missing): collision "
            "'package://pkg/meshes/lidar.stl' of link 'lidar'; visual 'package://pkg/meshes/lidar.stl' of link "
            "'lidar'. The first: ") in left_out
    scenario = package / "s.yaml"
    scenario.write_text(f"version: 1\nduration: 1\nrobots:\n  - name: r\n    description: {path}\n"
                        "    pose: {x: 0, y: 0, z: 0.2}\n")
    assert invoke(["check", scenario]).exit_code == 2
    assert invoke(["check", scenario, "--skip-missing"]).exit_code == 0
    assert invoke(["check", scenario, "--set", "skip_missing=true"]).exit_code == 0
    longer = invoke(["check", scenario, "--skip-missing", "--set", "duration=2.5", "--json"])
    assert longer.exit_code == 0 and json.loads(longer.stdout)["duration"] == 2.5
    wrong = invoke(["check", path, "--set", "x=1"])
    assert wrong.exit_code == 2 and "--set overrides keys of a scenario" in wrong.stderr
