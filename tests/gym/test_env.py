"""The Gymnasium environment, checked by Gymnasium's own tools."""

from __future__ import annotations

import math

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium", reason="the gym extra is not installed: pip install -e '.[gym]'")

from gymnasium.utils.env_checker import check_env  # noqa: E402

from mobot_cli.gym import ENV_ID, MobotEnv  # noqa: E402


def test_passes_gymnasiums_env_checker():
    env = gymnasium.make("mobot_cli.gym:" + ENV_ID).unwrapped
    check_env(env, skip_render_check=True)
    env.close()


def test_reset_with_a_seed_replays_the_same_episode():
    def episode(seed):
        env = MobotEnv(goal=(1.0, 0.0))
        obs, _ = env.reset(seed=seed)
        trace = [obs]
        for i in range(15):
            obs, reward, *_ = env.step(np.array([0.3, 0.4 * math.sin(i)], dtype=np.float32))
            trace.append(obs)
        env.close()
        return np.stack(trace)

    assert np.array_equal(episode(7), episode(7))


def test_driving_at_the_goal_reaches_it_and_the_reward_is_the_distance():
    env = MobotEnv(goal=(1.0, 0.0), goal_tolerance=0.1, normalize=False)  # SI units
    obs, _ = env.reset(seed=1)
    assert obs[5:] == pytest.approx([1.0, 0.0])
    rewards, done = [], False
    for _ in range(60):
        obs, reward, done, truncated, info = env.step(np.array([0.3, 0.0], dtype=np.float32))
        rewards.append(reward)
        if done:
            break
    env.close()
    assert done and math.hypot(obs[5] - obs[0], obs[6] - obs[1]) < 0.1
    assert rewards[0] == pytest.approx(-(1.0 - 0.03), abs=0.02)  # 0.3 m/s for 0.1 s, from rest
    assert rewards == sorted(rewards)  # closer every period


def test_user_reward_and_termination():
    env = MobotEnv(reward=lambda o: o.state.odom_vx, terminated=lambda o: o.steps >= 3)
    env.reset(seed=0)
    results = [env.step(np.array([0.5, 0.0], dtype=np.float32)) for _ in range(3)]
    env.close()
    assert [r[2] for r in results] == [False, False, True]
    assert 0.0 < results[0][1] < results[2][1] <= 0.5 + 1e-3


def test_runs_in_an_async_vector_env():
    envs = gymnasium.vector.AsyncVectorEnv([lambda: MobotEnv(goal=(1.0, 0.0), normalize=False) for _ in range(2)])
    try:
        obs, _ = envs.reset(seed=[3, 3])
        assert np.array_equal(obs[0], obs[1])
        for _ in range(3):
            obs, rewards, terminated, truncated, _ = envs.step(np.array([[0.3, 0.0], [0.0, 1.0]], dtype=np.float32))
        assert obs[0][0] > 0.05 and abs(obs[1][0]) < 0.01 and obs[1][2] > 0.2  # one drove, one turned
    finally:
        envs.close()
