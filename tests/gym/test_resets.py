"""Resets from what the first reset kept (the prepared scenario, the robot, the PyBullet client with
the static world) give the episodes a build from nothing gives, byte for byte."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

from mobot_cli.gym.env import MobotEnv
from mobot_cli.sim.bullet.clients import keep_clients


def episode(env: MobotEnv, seed: int, steps: int = 15) -> str:
    obs, info = env.reset(seed=seed)
    actions = np.random.default_rng(seed)
    h = hashlib.sha256()
    for _ in range(steps):
        for part in obs.values() if isinstance(obs, dict) else (obs,):
            h.update(np.asarray(part).tobytes())
        obs, reward, terminated, truncated, info = env.step(actions.uniform(-1.0, 1.0, env.action_space.shape))
        h.update(repr((reward, terminated, truncated, sorted(info.items()))).encode())
    return h.hexdigest()


@pytest.fixture
def fresh_clients():
    keep_clients(0)  # no client kept from an earlier test
    yield
    keep_clients(0)


@pytest.mark.parametrize("engine", ["bullet", "kinematic"])
def test_kept_resets_equal_builds_from_nothing(engine, tmp_path, fresh_clients, monkeypatch):
    monkeypatch.chdir(tmp_path)
    world = tmp_path / "house.yaml"
    world.write_text(f"version: 1\nname: h\nworld: house\nduration: 60\nphysics: {{engine: {engine}, rate_hz: 20}}\n")
    kwargs = dict(world=world, pose=(-3.0, -2.5, 0.0), args={"lidar": "true"})
    seeds = [5, 6, 5, 7]
    kept = MobotEnv(**kwargs)
    reused = [episode(kept, seed) for seed in seeds]
    kept.close()
    fresh = []
    for seed in seeds:  # a new env and a new PyBullet client for every episode
        keep_clients(0)
        env = MobotEnv(**kwargs)
        fresh.append(episode(env, seed))
        env.close()
    folders = MobotEnv(**kwargs, out=tmp_path / "episodes")  # the full path: prepared each reset, run folders
    written = [episode(folders, seed) for seed in seeds]
    folders.close()
    assert reused == fresh == written
    assert reused[0] == reused[2] and len(set(reused)) == 3  # the lidar's noise follows the seed
    assert (tmp_path / "episodes" / "episode_0003" / "summary.json").is_file()
