"""`gymnasium.make_vec`: N mobot envs stepped in one process, each the episode a lone env gives."""

from __future__ import annotations

import gymnasium
import numpy as np

import mobot_cli.gym  # noqa: F401  (registers mobot/GoTo-v0)
from mobot_cli.gym.env import MobotEnv


def test_make_vec_steps_n_worlds_in_one_process_as_lone_envs_would():
    envs = gymnasium.make_vec("mobot_cli.gym:mobot/GoTo-v0", num_envs=3, vectorization_mode="sync",
                              goal=(1.0, 0.0))
    assert isinstance(envs, gymnasium.vector.SyncVectorEnv)
    obs, _ = envs.reset(seed=40)  # env i gets seed 40 + i
    assert obs.shape == (3, 7) and envs.observation_space.contains(obs)
    actions = np.array([[1.0, 0.0], [0.5, 1.0], [-1.0, -0.5]], np.float32)
    rows = [obs]
    for _ in range(12):
        obs, reward, terminated, truncated, _ = envs.step(actions)
        rows.append(obs)
    envs.close()
    for i in range(3):  # each column is what one env alone does with its seed and actions
        alone = MobotEnv(goal=(1.0, 0.0))
        lone = [alone.reset(seed=40 + i)[0]]
        for _ in range(12):
            lone.append(alone.step(actions[i])[0])
        alone.close()
        assert np.array_equal(np.stack([r[i] for r in rows]), np.stack(lone))
    assert rows[-1][0][0] > 0.1 > rows[-1][2][0]  # forward, and backward: they differ
