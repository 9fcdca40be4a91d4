"""linear_y in the Python API, the Gymnasium environment and ROS 2 cmd_vel's checks."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from mobot_cli.api import Simulation
from mobot_cli.errors import UsageError
from mobot_cli.gym.env import MobotEnv
from mobot_cli.ros2 import inputs

MECANUM = "mecanum"  # bundled: robots/mecanum


def test_api_command_takes_linear_y_and_a_diff_robot_refuses_it():
    with Simulation.open("empty") as sim:
        sim.spawn("m", MECANUM, args={"drive": "plugin"})
        sim.spawn("d", "mobot", x=3.0)
        sim.run_for(0.5)
        start = sim.state("m")
        sim.command("m", 0.0, 0.0, linear_y=-0.2, duration=2.5)
        sim.run_for(3.0)
        end = sim.state("m")
        assert end.true_y - start.true_y == pytest.approx(-0.5, rel=0.02)
        assert end.odom_y - start.odom_y == pytest.approx(-0.5, rel=0.02)
        with pytest.raises(UsageError, match="robot 'd' has a diff drive: it cannot move sideways"):
            sim.command("d", 0.1, 0.0, linear_y=0.1)
        with pytest.raises(UsageError, match="linear_y"):
            sim.command("m", linear_y=float("nan"))


def test_gym_holonomic_action_is_three_wide():
    env = MobotEnv(description=MECANUM, args={"drive": "plugin"}, holonomic=True, normalize=False,
                   max_linear=0.5, goal=(0.0, 1.0), scan=False)
    assert env.action_space.shape == (3,)
    env.reset(seed=1)
    for _ in range(10):  # 1 s at 10 Hz, sideways at 0.3 m/s
        obs, *_ = env.step(np.array([0.0, 0.0, 0.3], np.float32))
    assert obs[1] == pytest.approx(0.3, abs=0.02) and abs(obs[0]) < 0.01
    with pytest.raises(UsageError, match=r"\[linear, angular, linear_y\]"):
        env.step([0.1, 0.0])
    env.close()
    assert MobotEnv(scan=False).action_space.shape == (2,)  # default unchanged
    with pytest.raises(UsageError, match="holonomic=True: robot 'robot' \\(mobot\\) has a diff drive"):
        MobotEnv(holonomic=True, scan=False)


def _twist_cdr(lx: float, ly: float, az: float) -> bytes:
    return b"\x00\x01\x00\x00" + struct.pack("<6d", lx, ly, 0.0, 0.0, 0.0, az)


def test_ros2_cmd_vel_keeps_linear_y_and_checks_it():
    assert inputs.cmd_vel(_twist_cdr(0.1, 0.2, 0.3)) == (0.1, 0.3, 0.2)
    assert inputs.cmd_vel(_twist_cdr(0.1, float("nan"), 0.3)) == inputs.NOT_FINITE
    assert inputs.cmd_vel(_twist_cdr(0.0, 1e3, 0.0)) == inputs.TOO_FAST
    assert "only holonomic" in inputs.sideways_ignored("r", "diff")
