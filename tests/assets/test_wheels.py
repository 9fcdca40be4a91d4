"""A wheel's radius is the one it rolls on, whatever order its collision shapes come in."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from mobot_cli.cli import invoke

INERTIAL = '<inertial><mass value="{m}"/><inertia ixx="{i}" ixy="0" ixz="0" iyy="{i}" iyz="0" izz="{i}"/></inertial>'
TYRE, HUB = 0.05, 0.0456  # the hub 8.8 % smaller: odometry from it was 8.8 % short


def wheel(side: str, y: float, hub_first: bool) -> str:
    hub = (f'<collision><origin xyz="0 0 0" rpy="1.5707963 0 0"/><geometry><cylinder radius="{HUB}" '
           'length="0.07"/></geometry></collision>')
    tyre = (f'<collision><origin xyz="0 0 0" rpy="1.5707963 0 0"/><geometry><cylinder radius="{TYRE}" '
            'length="0.04"/></geometry></collision>')
    shapes = hub + tyre if hub_first else tyre + hub
    return (f'<link name="{side}_wheel">{INERTIAL.format(m=0.5, i=0.0005)}{shapes}</link>'
            f'<joint name="{side}_wheel_joint" type="continuous"><parent link="base_link"/>'
            f'<child link="{side}_wheel"/><origin xyz="0 {y} 0"/><axis xyz="0 1 0"/></joint>')


def hub_robot(tmp_path: Path, hub_first: bool = True) -> Path:
    casters = "".join(
        f'<link name="caster_{n}">{INERTIAL.format(m=0.1, i=1e-5)}<collision><geometry><sphere radius="0.02"/>'
        f'</geometry></collision></link><joint name="caster_{n}_joint" type="fixed"><parent link="base_link"/>'
        f'<child link="caster_{n}"/><origin xyz="{x} 0 -0.03"/></joint>' for n, x in (("front", 0.15), ("rear", -0.15)))
    path = tmp_path / "hubs.urdf"
    path.write_text(f'<?xml version="1.0"?><robot name="hubs"><link name="base_link">'
                    f'{INERTIAL.format(m=4, i=0.03)}<collision><origin xyz="0 0 0.04"/><geometry>'
                    f'<box size="0.4 0.26 0.06"/></geometry></collision></link>'
                    f'{wheel("left", 0.17, hub_first)}{wheel("right", -0.17, hub_first)}{casters}</robot>')
    return path


@pytest.mark.parametrize("hub_first", [True, False], ids=["hub first", "tyre first"])
def test_inspect_gives_the_tyre_radius_wheel_positions_and_the_drive_type(tmp_path, hub_first):
    done = invoke(["inspect", str(hub_robot(tmp_path, hub_first)), "--json"])
    assert done.exit_code == 0, done.stderr
    summary = json.loads(done.stdout)
    assert summary["drive"]["wheel_radius"] == TYRE and summary["drive_type"] == "diff"
    assert summary["wheels"] == [
        {"joint": "left_wheel_joint", "side": "left", "x": 0.0, "y": 0.17, "z": 0.0, "radius": TYRE},
        {"joint": "right_wheel_joint", "side": "right", "x": 0.0, "y": -0.17, "z": 0.0, "radius": TYRE}]


def test_odometry_of_a_wheel_with_a_hub_before_its_tyre_matches_the_ground(tmp_path):
    """1 m straight: odometry within 2 % of the distance driven (it was 8.8 % short)."""
    hub_robot(tmp_path)
    scenario = tmp_path / "s.yaml"
    scenario.write_text("version: 1\nworld: empty\nduration: 4.5\nrobots:\n"
                        "  - name: r\n    description: hubs.urdf\n    pose: {x: 0.0, y: 0.0}\n"
                        "    commands:\n      - {at: 0.5, linear: 0.25, for: 4.0}\n")
    done = invoke(["run", str(scenario), "--out", str(tmp_path / "run"), "--quiet"])
    assert done.exit_code == 0, done.stderr
    robot = json.loads((tmp_path / "run" / "summary.json").read_text())["robots"]["r"]
    truth, odom = robot["final_pose"]["x"], robot["final_odom"]["x"]
    assert truth > 0.9
    assert odom == pytest.approx(truth, rel=0.02)
