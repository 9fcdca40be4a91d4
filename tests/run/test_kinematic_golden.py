"""Golden runs of the kinematic engine: its odometry CSVs and collision counts, byte for byte.

The engine keeps numbers between steps to go faster (sim/kinematic*.py); these runs pin what it
writes, so that a shortcut that changes a single digit fails here. After a deliberate change of
the engine's motion, write the file again with ``MOBOT_UPDATE_GOLDEN=1`` and say why in the commit.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import pytest

from mobot_cli.cli import invoke

REPO = Path(__file__).resolve().parents[2]
GOLDEN = REPO / "tests" / "golden" / "kinematic_runs.json"

# Sixteen robots packed 0.8 m apart in the bundled house, arcing into its walls, its sofa and
# each other, then backing out and turning: every kind of collision query the engine makes.
JAM = """version: 1
name: jam
world: house
duration: 20
settle: 0
physics: {rate_hz: 10, engine: kinematic}
log: {rate_hz: 10}
robots:
  - name: r_{i}
    description: mobot
    count: 16
    poses: [[-5.2, -4.0, 0.0], [-4.4, -4.0, 0.0], [-3.6, -4.0, 0.0], [-2.8, -4.0, 0.0], [-2.0, -4.0, 0.0],
            [-1.2, -4.0, 0.0], [-0.4, -4.0, 0.0], [0.4, -4.0, 0.0], [-5.2, -3.2, 0.0], [-4.4, -3.2, 0.0],
            [-3.6, -3.2, 0.0], [-2.8, -3.2, 0.0], [-2.0, -3.2, 0.0], [-1.2, -3.2, 0.0], [-0.4, -3.2, 0.0],
            [0.4, -3.2, 0.0]]
    commands: [{at: 0, linear: 0.3, angular: 0.15}, {at: 8, linear: -0.2, angular: 0.4},
               {at: 14, linear: 0.25, angular: -0.1}]
"""
CASES = ["quickstart", "events", "patrol", "jam"]


def outcome(name: str, tmp_path: Path) -> dict:
    """What a kinematic run of the case writes: each robot's odometry CSV (sha256) and collisions."""
    if name == "jam":
        path = tmp_path / "jam.yaml"
        path.write_text(JAM)
    else:
        path = REPO / "scenarios" / f"{name}.yaml"
    out = tmp_path / "run"
    done = invoke(["run", str(path), "--out", str(out), "--quiet", "--set", "physics.engine=kinematic"])
    assert done.exit_code == 0, done
    summary = json.loads((out / "summary.json").read_text())
    return {"odom": {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted((out / "odom").iterdir())},
            "collisions": {robot: record["collisions"] for robot, record in summary["robots"].items()}}


@pytest.mark.parametrize("name", CASES)
def test_a_kinematic_run_writes_its_golden_odometry(name, tmp_path):
    got = outcome(name, tmp_path)
    golden = json.loads(GOLDEN.read_text()) if GOLDEN.exists() else {}
    if os.environ.get("MOBOT_UPDATE_GOLDEN") == "1":
        golden[name] = got
        GOLDEN.write_text(json.dumps(golden, indent=2, sort_keys=True) + "\n")
    assert got == golden[name]
    if name == "jam":  # the case is what it says: robots stopped by walls, furniture and each other
        assert sum(got["collisions"].values()) >= 30 and len(got["odom"]) == 16
