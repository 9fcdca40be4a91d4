"""Kept PyBullet clients (sweep workers): a run in a client reset after other runs writes the
same run folder, byte for byte, as a run in a new client."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from mobot_cli.run.execute import execute
from mobot_cli.run.prepare import prepare
from mobot_cli.sim import clients

REPO = Path(__file__).resolve().parents[2]
# Mesh and box worlds, robots deleted and spawned mid-run, a lidar, goals: one after another.
SCENARIOS = ("bookstore", "events", "patrol", "fleet", "quickstart")
OVERRIDES = ["log.formats=[csv, mcap]", "duration=3.0"]


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


def test_runs_in_a_kept_client_equal_runs_in_new_clients(tmp_path, kept):
    prepared = {name: prepare(REPO / "scenarios" / f"{name}.yaml", OVERRIDES) for name in SCENARIOS}
    for name, run in prepared.items():
        execute(run.plan, run.resolved_yaml, tmp_path / "kept" / name)
    assert len(clients._idle) == 1  # every run after the first took the client the one before left
    kept_client = clients._idle[0]
    clients.keep_clients(0)
    for name, run in prepared.items():
        execute(run.plan, run.resolved_yaml, tmp_path / "new" / name)
        assert _folder(tmp_path / "kept" / name) == _folder(tmp_path / "new" / name), name
    assert not clients._idle
    assert kept_client >= 0


def test_a_kept_client_is_reset_and_at_most_count_are_kept(kept):
    first, second = clients.connect(), clients.connect()
    from mobot_cli.sim.bullet import p

    shape = p.createCollisionShape(p.GEOM_SPHERE, radius=0.1, physicsClientId=first)
    p.createMultiBody(1.0, shape, physicsClientId=first)
    clients.release(first)
    clients.release(second)  # one kept already: this one is disconnected
    assert clients._idle == [first] and not p.isConnected(physicsClientId=second)
    again = clients.connect()
    assert again == first and p.getNumBodies(physicsClientId=again) == 0
    clients.release(again)
