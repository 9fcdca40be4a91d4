"""Kept PyBullet clients (sweep workers): a run in a client kept from other runs (reset to
empty, or still holding the same static world) writes the same run folder, byte for byte, as
a run in a new client."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from mobot_cli.run import execute
from mobot_cli.scenario.prepare import prepare
from mobot_cli.sim.bullet import clients
from mobot_cli.sim.bullet.world import World
from mobot_cli.sim.pb import p

REPO = Path(__file__).resolve().parents[2]
# Mesh and box worlds, robots deleted and spawned mid-run, a lidar, goals: one after another,
# some in the world the run before left (its static world kept), some in another.
SCENARIOS = ("bookstore", "events", "fleet", "square", "quickstart", "patrol", "house", "bookstore")
OVERRIDES = ["log.formats=[csv, mcap]", "duration=4.0"]


def _folder(out: Path) -> dict[str, bytes]:
    files = {str(path.relative_to(out)): path.read_bytes() for path in sorted(out.rglob("*")) if path.is_file()}
    summary = json.loads(files.pop("summary.json"))
    del summary["wall_time"], summary["real_time_factor"]
    files["summary.json"] = json.dumps(summary).encode()
    return files


@pytest.fixture
def kept():
    clients.keep_clients(1)
    yield
    clients.keep_clients(0)


def test_runs_in_a_kept_client_equal_runs_in_new_clients(tmp_path, kept, monkeypatch):
    prepared = {name: prepare(REPO / "scenarios" / f"{name}.yaml", OVERRIDES) for name in set(SCENARIOS)}
    built = []
    build = World._build
    monkeypatch.setattr(World, "_build", lambda world, plan: (built.append(plan.name), build(world, plan))[1])
    for i, name in enumerate(SCENARIOS):
        run = prepared[name]
        execute(run.plan, run.resolved_yaml, tmp_path / "kept" / f"{i}-{name}")
    assert len(clients._idle) == 1  # every run after the first took the client the one before left
    # events deletes a robot: its world is not kept; fleet, square and quickstart share "empty",
    # house follows patrol in the house.
    assert built == ["bookstore", "empty", "empty", "house", "bookstore"]
    clients.keep_clients(0)
    for i, name in enumerate(SCENARIOS):
        run = prepared[name]
        execute(run.plan, run.resolved_yaml, tmp_path / "new" / f"{i}-{name}")
        assert _folder(tmp_path / "kept" / f"{i}-{name}") == _folder(tmp_path / "new" / f"{i}-{name}"), name
    assert not clients._idle


def test_a_kept_client_is_reset_and_at_most_count_are_kept(kept):
    (first, _), (second, _) = clients.connect(), clients.connect()
    shape = p.createCollisionShape(p.GEOM_SPHERE, radius=0.1, physicsClientId=first)
    p.createMultiBody(1.0, shape, physicsClientId=first)
    clients.release(first)
    clients.release(second)  # one kept already: this one is disconnected
    assert clients._idle == [(first, None)] and not p.isConnected(physicsClientId=second)
    again, stage = clients.connect(("physics", "world"))
    assert (again, stage) == (first, None) and p.getNumBodies(physicsClientId=again) == 0
    clients.release(again)


def test_a_world_whose_robot_was_deleted_is_not_kept_but_reset(kept, tmp_path):
    plan = prepare(REPO / "scenarios" / "fleet.yaml", OVERRIDES).plan
    with World(plan.physics, plan.world) as world:
        for robot in plan.robots:
            world.spawn(robot)
        world.remove(plan.robots[0].name)
    assert clients._idle[0][1] is None and p.getNumBodies(physicsClientId=clients._idle[0][0]) == 0
    with World(plan.physics, plan.world) as world:
        world.spawn(plan.robots[0])
        statics = p.getNumBodies(physicsClientId=world.client_id) - 1
    stage = clients._idle[0][1]
    assert stage is not None and len(stage.statics) == statics
    assert p.getNumBodies(physicsClientId=clients._idle[0][0]) == statics  # the robot removed, the world kept
