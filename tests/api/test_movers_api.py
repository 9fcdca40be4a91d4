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
