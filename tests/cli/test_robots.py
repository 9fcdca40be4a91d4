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
