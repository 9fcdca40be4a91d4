"""Scenario loading: forms, defaults, overrides, rounding to steps; no simulation."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from mobot_cli.common.transforms import quat_from_rpy
from mobot_cli.errors import ScenarioError
from mobot_cli.scenario.load import load_scenario
from mobot_cli.scenario.units import spawn_pose, steps

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "s.yaml"
    path.write_text(text)
    return path


def test_defaults(tmp_path):
    scenario, _ = load_scenario(write(tmp_path, "version: 1\nduration: 2\n"))
    assert scenario.physics.rate_hz == 240
    assert scenario.physics.gravity == (0.0, 0.0, -9.81)
    assert scenario.physics.solver_iterations == 50
    assert scenario.settle == 0.5
    assert scenario.log.rate_hz is None and scenario.log.formats == ["csv"]
    assert scenario.world == "empty" and scenario.seed == 0 and scenario.robots == []


@pytest.mark.parametrize("pose, xyz, yaw, auto", [
    ("{x: 1, y: 2, yaw: 1.5707963267948966}", (1.0, 2.0, 0.0), math.pi / 2, True),
    ("{x: 1, y: 2, z: 0.3}", (1.0, 2.0, 0.3), 0.0, False),
    ("{x: 1, y: 2, z: auto}", (1.0, 2.0, 0.0), 0.0, True),
    ("{xyz: [1, 2, 0.1], rpy: [0, 0, -1.0]}", (1.0, 2.0, 0.1), -1.0, False),
    ("{xyz: [1, 2, auto], quat: [0, 0, 0.7071067811865476, 0.7071067811865476]}", (1.0, 2.0, 0.0), math.pi / 2, True),
])
def test_pose_forms(tmp_path, pose, xyz, yaw, auto):
    scenario, _ = load_scenario(write(tmp_path, f"version: 1\nduration: 2\nrobots:\n  - name: r\n    pose: {pose}\n"))
    spawn = spawn_pose(scenario.robots[0].pose)
    assert spawn.xyz == pytest.approx(xyz)
    assert spawn.z_auto is auto
    x, y, z, w = spawn.quat
    assert math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)) == pytest.approx(yaw)
    assert math.hypot(*spawn.quat) == pytest.approx(1.0)


@pytest.mark.parametrize("rpy", [(0.1, 0.2, 0.3), (-1.2, 0.4, 2.9), (0.0, 0.0, -3.1)])
def test_quaternion_matches_ros_rpy_convention(rpy):
    import pybullet  # an independent implementation of the same fixed-axis convention

    assert quat_from_rpy(*rpy) == pytest.approx(pybullet.getQuaternionFromEuler(rpy), abs=1e-12)


def test_non_unit_quaternion_is_normalized(tmp_path):
    scenario, _ = load_scenario(write(tmp_path, "version: 1\nduration: 2\nrobots:\n"
                                                "  - {name: r, pose: {xyz: [0, 0, 0], quat: [0, 0, 2, 2]}}\n"))
    assert spawn_pose(scenario.robots[0].pose).quat == pytest.approx((0, 0, 0.70710678, 0.70710678))


@pytest.mark.parametrize("seconds, rate, expected", [(6.6, 240, 1584), (0.5, 240, 120), (0.01, 240, 2),
                                                     (1 / 48, 240, 5), (0.0, 240, 0), (2.5 / 240, 240, 3)])
def test_times_round_to_whole_steps(seconds, rate, expected):
    assert steps(seconds, rate) == expected


def test_set_addresses_robots_by_name_and_parses_yaml(tmp_path):
    path = write(tmp_path, "version: 1\nduration: 2\nrobots:\n  - {name: a}\n  - {name: b, pose: {x: 1}}\n")
    scenario, source = load_scenario(path, ["robots.b.pose.x=2.5", "robots.a.args.lidar=true", "seed=9"])
    assert scenario.robots[1].pose.x == 2.5
    assert scenario.robots[0].args == {"lidar": True}
    assert scenario.seed == 9
    assert source.locate(("robots", 1, "pose", "x")).file == "--set robots.b.pose.x=2.5"


def test_error_names_file_line_key_and_suggests(tmp_path):
    path = write(tmp_path, "version: 1\nduration: 2\nrobots:\n  - name: r\n    comands: []\n")
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert str(info.value) == f"{path}:5, key 'robots.r.comands': unknown key 'comands'. Did you mean 'commands'?"


@pytest.mark.parametrize("path", sorted(SCENARIOS.glob("*.yaml")), ids=lambda p: p.stem)
def test_bundled_scenarios_validate(path):
    scenario, _ = load_scenario(path)
    assert scenario.version == 1 and scenario.robots
