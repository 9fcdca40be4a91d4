"""A sweep's warm workers (sweep/preload.py, sweep/executor_local.py): the PyBullet client the fork
server connected, the static world kept between runs and, from the second run in a row with the
same first spawn on, the robot's body kept too (sim/bullet/kept_body.py). Every run folder is the
one `mobot run` writes for that run's scenario.yaml in a new client, byte for byte (summary.json's
wall time and real-time factor aside, and the trajectory.png that sweeps draw only when asked)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from mobot_cli.cli import invoke
from mobot_cli.sim.bullet import clients
from mobot_cli.sim.bullet.kept_body import keeping_robot_bodies
from mobot_cli.sim.bullet.world import World
from mobot_cli.sweep.expand import expand
from mobot_cli.sweep.spec import build_spec
from mobot_cli.sweep.task import Task, run_task

SCENARIO = """version: 1
name: warm
world: house
duration: 2
physics: {{engine: {engine}, rate_hz: {rate}}}
robots:
  - name: mobot
    pose: {{x: -3.0, y: -2.5}}
    commands: [{{at: 0.5, linear: 0.3, angular: 0.4}}, {{at: 1.2, linear: 0.5, angular: -0.3}}]
"""
# A second robot, with a lidar, that drives into the first one's way: the kept body among others.
SECOND = """  - name: other
    description: mobot
    args: {{lidar: "true"}}
    pose: {{x: -2.2, y: -1.8, yaw: -1.57}}
    commands: [{{at: 0.5, linear: 0.4}}]
"""
# Runs 0-2 spawn the robot at one pose, 3-4 at another, 5 at the first again.
ZIP = ["--zip", "robots.mobot.pose.x=-3.0,-3.0,-3.0,-2.5,-2.5,-3.0",
       "--zip", "robots.mobot.commands.0.linear=0.1,0.2,0.3,0.1,0.2,0.3"]
VOLATILE = ("wall_time", "real_time_factor")


def folder_bytes(run: Path) -> dict[str, bytes]:
    """A run folder's files but trajectory.png, summary.json without its wall time and real-time factor."""
    files = {}
    for path in sorted(p for p in run.rglob("*") if p.is_file() and p.name != "trajectory.png"):
        data = path.read_bytes()
        if path.name == "summary.json":
            data = json.dumps({k: v for k, v in json.loads(data).items() if k not in VOLATILE}).encode()
        files[str(path.relative_to(run))] = data
    return files


def run_alone(scenario: Path, out: Path) -> dict[str, bytes]:
    """`mobot run` of one scenario in a new PyBullet client."""
    clients.keep_clients(0)
    assert invoke(["run", scenario, "--out", out, "--quiet"]).exit_code == 0
    return folder_bytes(out)


@pytest.fixture
def no_kept_clients():
    clients.keep_clients(0)
    yield
    clients.keep_clients(0)


@pytest.mark.parametrize("engine,rate,robots", [("bullet", 240, 1), ("kinematic", 20, 1), ("bullet", 240, 2),
                                                ("kinematic", 20, 2)])
def test_a_sweeps_run_folders_are_those_of_runs_alone(engine, rate, robots, tmp_path, no_kept_clients):
    scenario = tmp_path / "warm.yaml"
    scenario.write_text(SCENARIO.format(engine=engine, rate=rate) + (SECOND.format() if robots == 2 else ""))
    out = tmp_path / "sweep"
    assert invoke(["sweep", scenario, *ZIP, "--jobs", "1", "--out", out, "--quiet"]).exit_code == 0
    runs = sorted((out / "runs").iterdir())
    assert len(runs) == 6
    for run in runs:
        assert folder_bytes(run) == run_alone(run / "scenario.yaml", tmp_path / "alone" / run.name), run.name


@pytest.mark.parametrize("engine,rate", [("bullet", 240), ("kinematic", 20)])
def test_a_worker_keeps_a_body_from_the_second_same_spawn_in_a_row(engine, rate, tmp_path, no_kept_clients,
                                                                   monkeypatch):
    """Runs one after another as a worker runs them: bodies loaded only where the first spawn changed
    or came for the first or second time in a row, and the same folders as runs alone."""
    loads = []
    load = World._load

    def counted(world, urdf, xyz, quat, fixed=False):
        if not fixed:
            loads.append(tuple(round(v, 3) for v in xyz[:2]))
        return load(world, urdf, xyz, quat, fixed)

    monkeypatch.setattr(World, "_load", counted)
    scenario = tmp_path / "warm.yaml"
    scenario.write_text(SCENARIO.format(engine=engine, rate=rate))
    spec = build_spec(scenario, [], [ZIP[1], ZIP[3]], [], None, None, [])
    sweep = expand(spec)
    clients.keep_clients(1)
    done = []
    with keeping_robot_bodies(repeated=True):
        for variant in sweep.variants:
            before = len(loads)
            prepared = sweep.prepared[variant.index]
            outcome = run_task(Task(variant.index, prepared.plan, prepared.resolved_yaml,
                                    str(tmp_path / "worker" / str(variant.index)), False))
            assert outcome.status == "passed", outcome.reason
            done.append(len(loads) - before)
    assert done == [1, 1, 0, 1, 1, 1]
    for variant in sweep.variants:
        run = tmp_path / "worker" / str(variant.index)
        assert folder_bytes(run) == run_alone(run / "scenario.yaml", tmp_path / "alone" / str(variant.index))
