"""Normalised spaces (the default, issue 26): actions in [-1, 1] scaled to the robot's limits,
observations divided by the goal distance, pi, the maximum speeds and range_max."""

from __future__ import annotations

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium", reason="the gym extra is not installed: pip install -e '.[gym]'")

from gymnasium.utils.env_checker import check_env  # noqa: E402

from mobot_cli.gym import ENV_ID, MobotEnv  # noqa: E402

LIDAR = {"lidar": "true"}


@pytest.mark.parametrize("normalize", [True, False])
@pytest.mark.parametrize("args", [None, LIDAR], ids=["odom", "lidar"])
def test_both_spaces_pass_gymnasiums_env_checker(normalize, args):
    env = gymnasium.make("mobot_cli.gym:" + ENV_ID, normalize=normalize, args=args).unwrapped
    check_env(env, skip_render_check=True)
    env.close()


def drive(env, action, periods=20) -> np.ndarray:
    env.reset(seed=0)
    for _ in range(periods):
        obs, *_ = env.step(np.array(action, dtype=np.float32))
    env.close()
    return obs


def test_the_default_action_space_is_unit_and_scaled_to_the_limits():
    env = MobotEnv(goal=(4.0, 0.0), max_linear=0.5, max_angular=2.0)
    assert env.action_space.low.tolist() == [-1.0, -1.0] and env.action_space.high.tolist() == [1.0, 1.0]
    assert env.reset(seed=0)[0][5:] == pytest.approx([1.0, 0.0])  # the goal, 4 m ahead, in goal distances
    # 3.0 is held at 1.0: full speed ahead, the same run as 0.5 m/s in SI units; a half turn too.
    for action, si in (([3.0, 0.0], [0.5, 0.0]), ([0.2, -0.5], [0.1, -1.0])):
        unit = drive(MobotEnv(goal=(4.0, 0.0)), action)
        raw = drive(MobotEnv(goal=(4.0, 0.0), normalize=False), si)
        scale = np.array([4.0, 4.0, np.pi, 0.5, 2.0, 4.0, 4.0])
        assert unit * scale == pytest.approx(raw, abs=1e-5)
    assert raw[0] > 0.05 and raw[2] < -1.0  # it drove and turned


def test_a_normalised_scan_is_in_range_max_units():
    env = MobotEnv(args=LIDAR)  # the empty world: no beam returns
    obs, _ = env.reset(seed=0)
    assert (obs["scan"] == 1.0).all() and env.observation_space.contains(obs)
    env.close()
