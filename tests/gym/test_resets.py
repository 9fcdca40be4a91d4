"""Resets from what the first reset kept (the prepared scenario, the robot, the PyBullet client with
the static world and the robot's body) give the episodes a build from nothing gives, byte for byte."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

from mobot_cli.gym.env import MobotEnv
from mobot_cli.sim.bullet.clients import keep_clients


def episode(env: MobotEnv, seed: int, steps: int = 15, truth: bool = False) -> str:
    """The hash of an episode: every observation, reward, flag and info (and, with ``truth``,
    the robot's ground-truth state beside what the agent sees)."""
    obs, info = env.reset(seed=seed)
    actions = np.random.default_rng(seed)
    h = hashlib.sha256()
    for _ in range(steps):
        for part in obs.values() if isinstance(obs, dict) else (obs,):
            h.update(np.asarray(part).tobytes())
        if truth:
            h.update(repr(env._sim.state(env.robot)).encode())  # noqa: SLF001
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


def drive(sim, steps: int = 60) -> str:
    """A Simulation's robot driven on a fixed script: the hash of its states."""
    h = hashlib.sha256()
    for k in range(steps):
        if k % 20 == 0:
            sim.command("robot", 0.4 - 0.1 * (k // 20), 0.6 * (-1) ** (k // 20))
        sim.step(1)
        h.update(repr(sim.state("robot")).encode())
    return h.hexdigest()


@pytest.mark.parametrize("engine", ["bullet", "kinematic"])
def test_a_kept_robot_body_is_taken_back_or_taken_out(engine, tmp_path, fresh_clients, monkeypatch):
    """The robot's body stays in the kept client between an env's resets (sim/bullet/kept_body.py):
    the same spawn takes it back, with the same body id. Outside a reset nothing is kept: after
    env.close(), a World with the same robot, another pose, or stepped before its first spawn gives
    what a new client gives."""
    from mobot_cli.api import Simulation

    monkeypatch.chdir(tmp_path)
    world = tmp_path / "house.yaml"
    world.write_text(f"version: 1\nname: h\nworld: house\nduration: 60\nphysics: {{engine: {engine}, rate_hz: 40}}\n")
    env = MobotEnv(world=world, pose=(-3.0, -2.5, 0.0), scan=False)
    env.reset(seed=1)
    body = env._sim._world.body_id("robot")  # noqa: SLF001 - which body the spawn used
    bodies = env._sim._world.client_id  # noqa: SLF001
    from mobot_cli.sim.pb import p

    count = p.getNumBodies(physicsClientId=bodies)
    env.reset(seed=2)
    assert env._sim._world.body_id("robot") == body  # noqa: SLF001 - taken back, not loaded again
    assert p.getNumBodies(physicsClientId=env._sim._world.client_id) == count  # noqa: SLF001
    env.close()

    def run(pose, step_first: bool) -> str:
        with Simulation.open(world) as sim:
            if step_first:
                sim.step(3)
            sim.spawn("robot", "mobot", x=pose[0], y=pose[1])
            return drive(sim)

    # Each case after an env used the kept client and closed.
    kept = []
    for pose, step_first in [((-3.0, -2.5), False), ((-2.5, -2.5), False), ((-3.0, -2.5), True)]:
        env = MobotEnv(world=world, pose=(-3.0, -2.5, 0.0), scan=False)
        env.reset(seed=1)
        env.close()
        kept.append(run(pose, step_first))
    keep_clients(0)
    fresh = [run(pose, step_first) for pose, step_first in
             [((-3.0, -2.5), False), ((-2.5, -2.5), False), ((-3.0, -2.5), True)]]
    assert kept == fresh
    assert fresh[0] != fresh[1]  # the other pose drives another path (stepping an empty world first changes nothing)
