"""A Gymnasium reset that puts back the kept end of the first settle (sim/bullet/settled.py) gives the
episode a fresh build and a settle that steps give, byte for byte: observations, rewards, infos and
the robot's ground-truth poses; and the world's Python side and PyBullet's contacts are the same
right after the reset. What the settle cannot keep (a lidar's noise, a skid-steer's twist loop,
another pose, another settle) steps as before."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mobot_cli.gym.env import MobotEnv
from mobot_cli.sim.bullet.clients import keep_clients
from mobot_cli.sim.bullet.world import World
from mobot_cli.sim.pb import p
from tests.gym.test_resets import episode as reset_episode

# A static 0.4 m box 0.45 m ahead of the robot: random episodes run into it.
BOX_WORLD = """<?xml version="1.0"?>
<sdf version="1.6">
  <world name="box_ahead">
    <include><uri>model://ground_plane</uri></include>
    <model name="box">
      <static>true</static>
      <pose>0.65 0 0.3 0 0 0</pose>
      <link name="link">
        <collision name="c"><geometry><box><size>0.4 0.4 0.6</size></box></geometry></collision>
        <visual name="v"><geometry><box><size>0.4 0.4 0.6</size></box></geometry></visual>
      </link>
    </model>
  </world>
</sdf>
"""


@pytest.fixture
def fresh_clients():
    keep_clients(0)
    yield
    keep_clients(0)


@pytest.fixture
def steps_taken(monkeypatch):
    """Physics steps taken by Worlds, counted (World.step wrapped before any World binds it)."""
    count = [0]
    step = World.step

    def counted(world):
        count[0] += 1
        step(world)

    monkeypatch.setattr(World, "step", counted)
    return count


def scenario(tmp_path, world: str, engine: str = "bullet"):
    path = tmp_path / "scenario.yaml"
    path.write_text(f"version: 1\nname: s\nworld: {world}\nduration: 60\nphysics: {{engine: {engine}}}\n")
    return path


def episode(env: MobotEnv, seed: int, steps: int = 20) -> str:
    """The hash of an episode: every observation, reward, flag, info and ground-truth pose."""
    return reset_episode(env, seed, steps, truth=True)


def fresh_episodes(kwargs: dict, seeds: list[int], steps: int = 20) -> list[str]:
    """Each episode in a new env and a new PyBullet client: built from nothing, settled by stepping."""
    out = []
    for seed in seeds:
        keep_clients(0)
        env = MobotEnv(**kwargs)
        out.append(episode(env, seed, steps))
        env.close()
    return out


def world_of(env: MobotEnv):
    return env._sim._world  # noqa: SLF001


# Attributes that hold no state of the run: the plan, and the World's cache of URDF files by text
# (a world whose robot body was kept never loads it, one that loads it keeps its file).
CACHES = ("plan", "_files")


def python_side(obj, seen=None, depth: int = 0):
    """The numbers and texts of mobot's objects reachable from ``obj``, as nested plain values
    (callables left out): what a kept settle must have put back."""
    seen = set() if seen is None else seen
    if isinstance(obj, (int, float, str, bool, type(None), bytes)):
        return repr(obj)
    if isinstance(obj, (tuple, frozenset)) and not obj:  # one shared object: which field meets it first is no state
        return []
    if id(obj) in seen or depth > 8 or callable(obj):
        return "<seen>"
    seen.add(id(obj))
    if isinstance(obj, dict):
        return {repr(k): python_side(v, seen, depth + 1) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, set, frozenset)):
        items = sorted(obj, key=repr) if isinstance(obj, (set, frozenset)) else obj
        return [python_side(v, seen, depth + 1) for v in items]
    if isinstance(obj, np.ndarray):  # the broad phase's room for boxes is np.empty: only its shape is state
        return (obj.shape, str(obj.dtype))
    if type(obj).__module__.startswith("mobot_cli") and hasattr(obj, "__dict__"):
        return {k: python_side(v, seen, depth + 1) for k, v in sorted(vars(obj).items()) if k not in CACHES}
    return type(obj).__name__


def after_reset(env: MobotEnv) -> tuple:
    """The world right after a reset: its Python side and what PyBullet holds of the robot."""
    world = world_of(env)
    cid, body = world.client_id, world.body_id(env.robot)
    # Positions, velocities, reaction forces; not the motor torque applied in the last step, an output
    # of that step which PyBullet's saved state does not hold (mobot reads it only after a step).
    joints = [s[:3] for s in p.getJointStates(body, list(range(p.getNumJoints(body, physicsClientId=cid))),
                                              physicsClientId=cid)]
    bullet = (p.getBasePositionAndOrientation(body, physicsClientId=cid), p.getBaseVelocity(body, physicsClientId=cid),
              joints, p.getContactPoints(physicsClientId=cid))
    timeline = env._sim._timeline  # noqa: SLF001
    return python_side(world), timeline.marks(), repr(bullet)


CASES = {
    "empty world": dict(world="empty", pose=(0.0, 0.0, 0.0)),
    "the house": dict(world="house", pose=(-3.0, -2.5, 0.0)),
    "a box ahead": dict(world="box.sdf", pose=(0.0, 0.0, 0.0)),
}


@pytest.mark.parametrize("case", list(CASES))
def test_a_kept_settle_gives_the_episodes_of_a_settle_that_steps(case, tmp_path, fresh_clients, steps_taken,
                                                                  monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "box.sdf").write_text(BOX_WORLD)
    world = scenario(tmp_path, CASES[case]["world"])
    kwargs = dict(world=world, pose=CASES[case]["pose"], scan=False, goal=(1.0, 0.5))
    seeds = [5, 6, 5, 7]
    env = MobotEnv(**kwargs)
    kept, steps_per_episode = [], []
    for seed in seeds:
        before = steps_taken[0]
        kept.append(episode(env, seed))
        steps_per_episode.append(steps_taken[0] - before)
    env.close()
    # The first reset settles by stepping (0.5 s at 240 Hz); the next ones put its end back.
    assert steps_per_episode == [120 + 20 * 24] + [20 * 24] * 3
    assert kept == fresh_episodes(kwargs, seeds)
    assert kept[0] == kept[2] and len(set(kept)) == 3  # the actions follow the seed


def test_right_after_a_kept_settle_the_world_is_as_after_a_settle_that_steps(tmp_path, fresh_clients, monkeypatch):
    """The Python side (odometry, health watch, contact counter, step count, timeline marks) and
    PyBullet's robot and contact points, compared whole; the robot has run into the box and
    been counted (collisions) in the episode before the kept reset."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "box.sdf").write_text(BOX_WORLD)
    kwargs = dict(world=scenario(tmp_path, "box.sdf"), pose=(0.0, 0.0, 0.0), scan=False, goal=(1.0, 0.0))
    env = MobotEnv(**kwargs)
    env.reset(seed=3)
    for _ in range(30):  # straight into the box: the last episode ends touching it
        env.step([1.0, 0.0])
    assert env._sim.state("robot").collisions >= 1  # noqa: SLF001
    env.reset(seed=4)
    kept = after_reset(env)
    env.close()
    keep_clients(0)
    fresh = MobotEnv(**kwargs)
    fresh.reset(seed=4)
    assert after_reset(fresh) == kept
    assert kept[1] == (115, 119) and "'_steps': '120'" in repr(kept[0])
    fresh.close()


def test_what_a_settle_cannot_keep_steps_as_before(tmp_path, fresh_clients, steps_taken, monkeypatch):
    """A lidar (its noise is drawn from the seed) and a skid-steer base (its twist loop) settle by
    stepping at every reset; a robot at another pose, or another settle, in the kept client settles
    again; the kinematic engine never keeps one. Every episode is still the one a
    build from nothing gives."""
    monkeypatch.chdir(tmp_path)
    house = scenario(tmp_path, "house")

    def stepped(env, seed) -> tuple[str, int]:
        before = steps_taken[0]
        digest = episode(env, seed, steps=5)
        return digest, steps_taken[0] - before - 5 * 24

    for kwargs in (dict(world=house, pose=(-3.0, -2.5, 0.0), args={"lidar": "true"}),
                   dict(world=house, description="jackal_like", pose=(-3.0, -2.5, 0.0), scan=False)):
        env = MobotEnv(**kwargs)
        got = [stepped(env, seed) for seed in (1, 1)]
        env.close()
        assert [settle for _, settle in got] == [120, 120]
        assert world_of_kept_settles(env) is None
        assert [digest for digest, _ in got] == fresh_episodes(kwargs, [1], 5) * 2
    keep_clients(0)
    here = dict(world=house, pose=(-3.0, -2.5, 0.0), scan=False)
    there = dict(world=house, pose=(-2.5, -2.5, 0.0), scan=False)
    short = dict(world=house, pose=(-3.0, -2.5, 0.0), scan=False, settle=0.25)
    a, b, c = MobotEnv(**here), MobotEnv(**there), MobotEnv(**short)
    got = []
    for env, seeds in ((a, [1, 2]), (b, [1]), (a, [1]), (c, [1, 1])):  # one kept client, handed on by close()
        got += [stepped(env, seed) for seed in seeds]
        env.close()
    assert [settle for _, settle in got] == [120, 0, 120, 120, 60, 0]
    assert [digest for digest, _ in got] == (fresh_episodes(here, [1, 2], 5) + fresh_episodes(there, [1], 5)
                                             + fresh_episodes(here, [1], 5) + fresh_episodes(short, [1, 1], 5))
    kinematic = MobotEnv(world=scenario(tmp_path, "house", "kinematic"), pose=(-3.0, -2.5, 0.0), scan=False)
    kinematic.reset(seed=1)
    kinematic.reset(seed=1)
    assert world_of_kept_settles(kinematic) is None
    kinematic.close()


def world_of_kept_settles(env: MobotEnv):
    """The settle kept with the env's kept robot body (None: none kept), after env.close()."""
    from mobot_cli.sim.bullet import clients

    stages = [stage for _, stage in clients._idle if stage is not None and stage.body is not None]  # noqa: SLF001
    return stages[0].body.settled if stages else None


def test_settle_seconds_are_checked(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    from mobot_cli.api import Simulation
    from mobot_cli.errors import UsageError

    with Simulation.open("empty") as sim:
        sim.spawn("robot", "mobot")
        with pytest.raises(UsageError, match="settle"):
            sim.settle(math.nan)
        sim.settle(0.25)
        assert sim.step_count == 60
