"""Fleets without N^2: spawn checks through the robots' boxes (sim/broadphase.py) and the
kinematic engine's pair search along x (sim/kinematic/pairs.py) find what all pairs find."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.assets.description.describe import load_robot
from mobot_cli.assets.world.worldplan import load_world
from mobot_cli.errors import SpawnError
from mobot_cli.plan import Physics, RobotPlan, SpawnPose
from mobot_cli.sim.engine import open_world
from mobot_cli.sim.kinematic.pairs import close_pairs


@pytest.fixture(scope="module")
def mobot_desc():
    return load_robot("mobot")


def robot(desc, name, x, y) -> RobotPlan:
    return RobotPlan(name=name, namespace=f"/{name}", frame_prefix=f"{name}/", urdf=desc.urdf,
                     root_link=desc.root_link, pose=SpawnPose(xyz=(x, y, 0.0), z_auto=True), drive=desc.drive)


def all_pairs(x, y, limit, rows):
    close = (np.abs(x[:, None] - x[None, :]) <= limit) & (np.abs(y[:, None] - y[None, :]) <= limit)
    np.fill_diagonal(close, False)
    if rows is not None:
        close &= rows[:, None]
    return np.nonzero(close)


coords = st.lists(st.tuples(st.floats(-50, 50), st.floats(-50, 50)), min_size=0, max_size=60)


@settings(max_examples=200, deadline=None)
@given(coords, st.floats(0.0, 20.0), st.one_of(st.none(), st.integers(0, 2**60)), st.booleans())
def test_pairs_along_x_are_all_pairs(points, limit, pick, snap):
    x = np.array([p[0] for p in points], float)
    y = np.array([p[1] for p in points], float)
    if snap:  # many ties and pairs exactly `limit` apart
        x, y = np.round(x / max(limit, 0.5)) * limit, np.round(y / max(limit, 0.5)) * limit
    rows = None if pick is None else np.array([(pick >> k) & 1 == 1 for k in range(len(x))], bool)
    i, j = close_pairs(x, y, limit, rows)
    a, b = all_pairs(x, y, limit, rows)
    assert i.tolist() == a.tolist() and j.tolist() == b.tolist()


@pytest.mark.parametrize("engine", ["bullet", "kinematic"])
def test_a_fleet_spawn_refuses_what_it_refused(engine, mobot_desc):
    """A grid of robots, then one into the middle of them and one clear of them; then a step,
    a teleport onto a robot and a removal, and the checks still see the robots where they are."""
    plan = load_world("empty").plan
    with open_world(Physics(engine=engine, rate_hz=10 if engine == "kinematic" else 240), plan) as world:
        for k in range(30):
            world.spawn(robot(mobot_desc, f"r{k}", 0.6 * (k % 6), 0.6 * (k // 6)))
        with pytest.raises(SpawnError, match=r"robot 'bad' spawned at .* reaches \d+\.\d cm into robot 'r14'"):
            world.spawn(robot(mobot_desc, "bad", 0.6 * 2 + 0.05, 0.6 * 2))
        world.spawn(robot(mobot_desc, "clear", 10.0, 10.0))
        world.set_command("r0", -0.5, 0.0)  # backwards, out of the grid
        for _ in range(240 if engine == "bullet" else 10):
            world.step()
        moved = world.read("r0").true_x
        assert moved < -0.3
        # r0 has left (0, 0) for about (moved, 0): a spawn there is clear now, one on it is not
        world.spawn(robot(mobot_desc, "where_r0_was", 0.0, 0.0))
        with pytest.raises(SpawnError, match="into robot 'r0'"):
            world.spawn(robot(mobot_desc, "on_r0", moved, 0.0))
        world.remove("r14")
        world.spawn(robot(mobot_desc, "where_r14_was", 0.6 * 2, 0.6 * 2))
        with pytest.raises(SpawnError, match="into robot 'r7'"):
            world.teleport("clear", SpawnPose(xyz=(0.6, 0.6, 0.0), z_auto=True))
        world.teleport("clear", SpawnPose(xyz=(20.0, 0.0, 0.0), z_auto=True))
        world.spawn(robot(mobot_desc, "where_clear_was", 10.0, 10.0))
        with pytest.raises(SpawnError, match="into robot 'clear'"):
            world.spawn(robot(mobot_desc, "on_clear", 20.0, 0.05))
