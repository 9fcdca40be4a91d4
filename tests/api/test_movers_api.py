"""Movers through the Python API: added and removed while the world runs, recorded like a scenario's."""

from __future__ import annotations

import csv
import math

import pytest

from mobot_cli.api import Simulation
from mobot_cli.errors import MobotError, UsageError


def test_add_step_remove_and_record(tmp_path):
    with Simulation.open("empty", out=tmp_path / "run") as sim:
        sim.spawn("r", "mobot", x=0.0, y=0.0)
        sim.add_mover("bob", path=[[2.0, -1.0], [2.0, 1.0]], mode="pingpong", speed=0.5)
        sim.add_mover("crate", shape="box", size=[0.4, 0.4, 0.5], path=[[-2.0, 0.0], [-2.0, 2.0]])
        sim.add_mover("w", region=[3.0, 5.0, -1.0, 1.0])
        with pytest.raises(MobotError, match="already exists"):
            sim.add_mover("bob", region=[0, 1, 0, 1])
        with pytest.raises(UsageError, match="exactly one of 'path'"):
            sim.add_mover("nobody")
        sim.run_for(2.0)
        poses = sim.movers()
        assert set(poses) == {"bob", "crate", "w"}
        x, y, yaw = poses["bob"]
        assert x == 2.0 and abs(y - (-1.0 + 0.5 * 2.0)) < 0.05 and abs(yaw - math.pi / 2) < 1e-9
        assert 3.0 - 0.5 < poses["w"][0] < 5.0 + 0.5
        sim.remove_mover("crate")
        with pytest.raises(MobotError, match="no mover named 'crate'"):
            sim.remove_mover("crate")
        sim.run_for(0.5)
        assert set(sim.movers()) == {"bob", "w"}
    with (tmp_path / "run" / "movers.csv").open() as f:
        rows = list(csv.DictReader(f))
    names = {row["name"] for row in rows}
    assert names == {"bob", "crate", "w"}
    last = max(float(row["t"]) for row in rows)
    assert {row["name"] for row in rows if float(row["t"]) == last} == {"bob", "w"}


@pytest.mark.parametrize("engine", ["bullet", "kinematic"])
def test_people_distance_is_measured_for_a_robot_with_a_goal_as_its_clearance(tmp_path, engine):
    """A state's distance to people is what goal metrics read: measured, like its clearance, once
    the robot drives to a goal (+inf before, as its clearance)."""
    with Simulation.open("empty", out=tmp_path / "run", overrides=[f"physics.engine={engine}"]) as sim:
        sim.spawn("r", "mobot", x=0.0, y=0.0)
        sim.add_mover("bob", path=[[2.0, -1.0], [2.0, 1.0]], mode="pingpong", speed=0.5)
        sim.run_for(0.5)
        before = sim.state("r")
        assert before.people_distance == math.inf and before.clearance == math.inf
        sim.goto("r", -1.0, 0.0)
        sim.run_for(0.5)
        state, (x, y, _) = sim.state("r"), sim.movers()["bob"]
        assert 1.5 < state.people_distance < 2.5
        assert state.people_distance == abs(complex(x, y) - complex(state.true_x, state.true_y))
