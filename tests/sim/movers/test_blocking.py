"""A mover in a robot's way stops it, in both engines, and counts as a collision (not with a person)."""

from __future__ import annotations

import json

import pytest
import yaml

from mobot_cli.cli import invoke


@pytest.mark.parametrize("engine", ["bullet", "kinematic"])
def test_a_crate_in_the_way_stops_the_robot(tmp_path, engine):
    doc = {"version": 1, "name": "crate", "world": "empty", "duration": 6.0, "physics": {"engine": engine},
           "robots": [{"name": "r", "description": "mobot", "pose": {"x": 0.0, "y": 0.0},
                       "commands": [{"at": 0.5, "goto": {"x": 3.0, "y": 0.0}, "timeout": 5.0}]}],
           "movers": [{"name": "crate", "shape": "box", "size": [0.4, 1.0, 0.5],
                       "path": [[1.5, 0.0], [1.5, 0.001]], "speed": 0.001}]}
    path = tmp_path / "crate.yaml"
    path.write_text(yaml.safe_dump(doc))
    done = invoke(["run", str(path), "--out", str(tmp_path / "run"), "--quiet"])
    assert done.exit_code == 0, done.stderr
    robot = json.loads((tmp_path / "run" / "summary.json").read_text())["robots"]["r"]
    assert robot["final_pose"]["x"] < 1.3 - 0.1  # the crate's near side is at 1.3 m
    assert robot["collisions"] >= 1
    goal = robot["goals"][0]
    assert goal["status"] != "reached" and "crate" in goal["collided_with"]
    assert "people_collisions" not in goal  # a crate is no person, and no person is in the world
