"""Gazebo actors in a world file: played along their trajectory, seen by a lidar, in both engines.

The world (tests/data/actor_crossing.sdf) has a walker crossing 2 m in front of a robot whose
360-beam lidar faces it; the scans must show the walker's capsule where the world says the
walker is, within 2 cm, scan after scan as it moves.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from mobot_cli.assets.world.loaded import LoadedWorld
from mobot_cli.assets.world.worldplan import _from_document, _to_document
from mobot_cli.cli import invoke
from mobot_cli.scenario.prepare import prepare
from mobot_cli.sim.engine import open_world
from mobot_cli.timeline.loop import Timeline
from mobot_cli.timeline.records import Reading

DATA = Path(__file__).resolve().parents[2] / "data"
RADIUS, HEIGHT = 0.3, 1.7


def scenario(tmp_path: Path, engine: str, expect=(), **robot) -> Path:
    doc = {"version": 1, "name": "actor", "world": str(DATA / "actor_crossing.sdf"), "duration": 5.0,
           "physics": {"engine": engine}, "expect": list(expect),
           "robots": [{"name": "r", "description": "mobot", "args": {"lidar": "true"},
                       "pose": {"x": 0.0, "y": 0.0, "yaw": 0.0},
                       "sensors": {"lidar": {"noise_stddev": 0.0}}, **robot}]}
    path = tmp_path / f"actor_{engine}.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


def width_at(z: float) -> float:
    """The capsule's horizontal radius at height z (it stands on z = 0)."""
    if z < RADIUS:
        return math.sqrt(RADIUS ** 2 - (RADIUS - z) ** 2)
    if z > HEIGHT - RADIUS:
        return math.sqrt(max(RADIUS ** 2 - (z - HEIGHT + RADIUS) ** 2, 0.0))
    return RADIUS


@pytest.mark.parametrize("engine", ["bullet", "kinematic"])
def test_lidar_sees_the_actor_where_it_walks(tmp_path, engine):
    plan = prepare(scenario(tmp_path, engine)).plan
    assert [a.name for a in plan.world.actors] == ["walker"]
    assert not any("ignored" in n and "actor" in n for n in plan.notices)
    with open_world(plan.physics, plan.world, seed=plan.seed) as world:
        timeline = Timeline(plan, world)
        seen = []
        timeline.attach(lambda r: seen.append((r.step, r.data, world.movers()["walker"]))
                        if isinstance(r, Reading) and r.sensor.kind == "lidar" else None)
        timeline.start()
        for _ in range(plan.total_steps):
            timeline.tick()
            timeline.advance()
    bearings, checked = [], 0
    for step, scan, (ax, ay, _) in seen:
        sx, sy, sz = scan.position
        expected = math.hypot(ax - sx, ay - sy) - width_at(sz)
        ranges = scan.ranges.reshape(-1)
        angles = scan.beams.horizontal
        toward = math.atan2(ay - sy, ax - sx)
        sector = np.abs(np.remainder(angles - toward + math.pi, 2 * math.pi) - math.pi) < 0.3
        nearest = float(ranges[sector].min())
        assert abs(nearest - expected) < 0.02, (step, nearest, expected)
        bearings.append(float(angles[sector][np.argmin(ranges[sector])]))
        checked += 1
        # the script: 0.5 s waiting at (2, -2), then north to (2, 2) in 4 s and back, on Gazebo's
        # spline: this trajectory ends where it starts and turns back at (2, 2), so every tangent
        # is zero and each leg is a smoothstep, 3 s^2 - 2 s^3 of the way after a fraction s of it
        u = max(0.0, step / plan.physics.rate_hz - 0.5)
        s = (u if u <= 4.0 else u - 4.0) / 4.0
        way = 4.0 * (3 * s * s - 2 * s ** 3)
        assert abs(ay - (-2.0 + way if u <= 4.0 else 2.0 - way)) < 1e-9
    assert checked >= 45
    assert max(bearings) - min(bearings) > 1.2  # the walker crossed the lidar's view


@pytest.mark.parametrize("engine", ["bullet", "kinematic"])
def test_a_robot_in_the_actors_way_counts_a_collision_with_a_person(tmp_path, engine):
    path = scenario(tmp_path, engine, pose={"x": 2.0, "y": 0.6, "yaw": 0.0},
                    commands=[{"at": 0.5, "goto": {"x": 2.1, "y": 0.6}, "timeout": 4.0}],
                    expect=[{"robot": "r", "metric": {"name": "people_collisions", "max": 0}}])
    done = invoke(["run", str(path), "--out", str(tmp_path / engine), "--json"])
    assert done.exit_code == 1, done.stderr  # the expectation of no collision with people failed

    summary = json.loads((tmp_path / engine / "summary.json").read_text())
    robot = summary["robots"]["r"]
    assert robot["collisions"] >= 1
    metrics = robot["metrics"]
    assert metrics["people_collisions"] >= 1
    assert metrics["people_distance_min"] < 0.5
    assert metrics["people_intimate_time"] > 0.0
    assert "walker" in metrics["collided_with"]
    rows = (tmp_path / engine / "movers.csv").read_text().splitlines()
    assert rows[0] == "t,name,x,y,yaw" and rows[1].startswith("0.000000,walker,2.000000,-2.000000,")


def test_actors_survive_the_world_cache_round_trip(tmp_path):
    """The world cache keeps JSON documents (common/cache.py): the actors come back the same."""
    plan = prepare(scenario(tmp_path, "bullet")).plan
    loaded = LoadedWorld(plan=plan.world, robots=(), static_models=(), summary={}, notices=())
    again = _from_document(json.loads(json.dumps(_to_document(loaded, []))))
    assert again is not None and again.plan == plan.world
    assert again.plan.actors[0].keyframes == ((0.0, 2.0, -2.0, 1.5708), (4.0, 2.0, 2.0, 1.5708),
                                              (8.0, 2.0, -2.0, 1.5708))
    assert (again.plan.actors[0].delay, again.plan.actors[0].loop) == (0.5, True)
    assert again.plan.actors[0].curves == ((0, 2, 0.0),)  # one trajectory, its spline's tension
