"""The wheel torque limit: the plugin's, else the wheel joints' URDF effort, else one scaled
with the robot's mass (never below 20 N*m); a scenario's max_wheel_torque wins over all."""

from __future__ import annotations

import math

import pytest

from mobot_cli.assets.description.drive import detect_drive, drive_from_joints
from mobot_cli.assets.description.torque import mass_torque
from tests.assets.test_drive import ROS1_PLUGIN, four_wheels, wheel


def robot(*parts: str, mass: float = 1.0) -> str:
    inertial = (f'<inertial><mass value="{mass}"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" '
                'izz="1"/></inertial>')
    return (f'<robot name="r"><link name="base">{inertial}<collision><geometry>'
            f'<box size="0.4 0.3 0.1"/></geometry></collision></link>{"".join(parts)}</robot>')


def with_effort(part: str, effort: str) -> str:
    return part.replace("</joint>", f'<limit effort="{effort}" velocity="10"/></joint>')


def test_the_default_scales_with_mass_above_a_20_nm_floor():
    # (1 + 9.81 sin 45 deg) m/s^2 = 7.937 m/s^2: 1 m/s^2 up a 45 deg slope
    assert mass_torque(300.0, 0.2, 4) == pytest.approx(300 * (1 + 9.81 * math.sin(math.radians(45))) * 0.2 / 4,
                                                       abs=1e-3)
    assert mass_torque(300.0, 0.2, 4) == pytest.approx(119.06, abs=0.01)
    assert mass_torque(10.0, 0.1, 2) == 20.0  # a light robot keeps mobot's old fixed default
    spec = detect_drive(robot(*four_wheels(), mass=296.0))  # + 4 wheels of 1 kg: 300 kg, r 0.1
    assert (spec.torque_source, spec.max_wheel_torque) == ("mass", pytest.approx(59.53, abs=0.01))
    light = detect_drive(robot(*four_wheels()))
    assert (light.torque_source, light.max_wheel_torque) == ("mass", 20.0)


def test_a_urdf_effort_limit_wins_over_the_mass_default():
    wheels = [with_effort(w, "12") if i else with_effort(w, "7.5") for i, w in enumerate(four_wheels())]
    spec = detect_drive(robot(*wheels, mass=296.0))
    assert (spec.torque_source, spec.max_wheel_torque) == ("urdf", 7.5)  # the smallest of the wheels'
    for unset in ("0", "1e6", "nan"):  # 0: "not given", as in many URDFs; 1e6: an SDF's unlimited -1
        assert detect_drive(robot(*[with_effort(w, unset) for w in four_wheels()])).torque_source == "mass"
    named = drive_from_joints(robot(*wheels), ("fl", "rl"), ("fr", "rr"))
    assert (named.torque_source, named.max_wheel_torque) == ("urdf", 7.5)


def test_a_plugin_torque_wins_over_the_urdf_effort():
    parts = [with_effort(wheel("l", "0 0.2 0"), "3"), with_effort(wheel("r", "0 -0.2 0"), "3"), ROS1_PLUGIN]
    spec = detect_drive(robot(*parts))
    assert (spec.torque_source, spec.max_wheel_torque) == ("plugin", 7.0)
