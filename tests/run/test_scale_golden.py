"""Records pinned byte for byte while mobot is made faster at scale (issue 32).

A fleet (60 kinematic robots in the bundled house, 6 physics robots), Gymnasium episodes after
``reset`` (physics and kinematic, with and without a lidar) and a kinematic sweep's run folders:
their hashes were written by the code before the fast paths existed (broad-phase spawn checks,
grid pair search, resets that restore a saved state, sweeps without pictures), so any of those
that changes a digit fails here. Pictures (trajectory.png) are left out: sweeps draw them only
when asked now. After a deliberate change of what a run writes, write the file again with
``MOBOT_UPDATE_GOLDEN=1`` and say why in the commit.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import os
from pathlib import Path

import numpy as np
import pytest

from mobot_cli.cli import invoke

REPO = Path(__file__).resolve().parents[2]
GOLDEN = REPO / "tests" / "golden" / "scale_records.json"
FLEET = REPO / "tests" / "data" / "fleet60.yaml"
PHYSICS_POSES = [(-5.45, -4.45), (-4.9, -4.45), (-4.35, -4.45), (-5.45, -3.9), (-4.9, -3.9), (-4.35, -3.9)]
PHYSICS_FLEET = f"""version: 1
name: fleet6
world: house
duration: 1.5
settle: 0
physics: {{rate_hz: 240}}
log: {{rate_hz: 48}}
robots:
  - name: r_{{i}}
    description: mobot
    count: 6
    poses: [{", ".join(f"[{x}, {y}, 0.6]" for x, y in PHYSICS_POSES)}]
    commands: [{{at: 0, linear: 0.4, angular: 0.3}}]
"""
SWEEP = ["--grid", "robots.mobot.commands.0.linear=0.1,0.3", "--grid", "robots.mobot.commands.0.for=1.0,2.0",
         "--set", "physics.engine=kinematic", "--set", "duration=4", "--jobs", "2", "--quiet"]


def digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def folder(out: Path) -> dict[str, str]:
    """sha256 of every file of a run folder but its picture; summary.json without its wall time
    and real-time factor (which no two runs share) and the Python that ran it, and this
    checkout's path made '<repo>'."""
    hashes = {}
    for path in sorted(out.rglob("*")):
        if not path.is_file() or path.suffix == ".png":
            continue
        data = path.read_bytes()
        if path.name == "summary.json":
            summary = json.loads(data)
            summary.pop("wall_time", None)
            summary.pop("real_time_factor", None)
            summary.get("versions", {}).pop("python", None)  # the records are the same on 3.10 to 3.13
            data = json.dumps(summary, sort_keys=True).encode()
        hashes[str(path.relative_to(out))] = digest(data.replace(str(REPO).encode(), b"<repo>"))
    return hashes


def run_folder(path: Path, out: Path) -> dict[str, str]:
    done = invoke(["run", str(path), "--out", str(out), "--quiet"])
    assert done.exit_code == 0, done
    return folder(out)


def fleet_kinematic(tmp_path: Path) -> dict:
    return run_folder(FLEET, tmp_path / "run")


def fleet_physics(tmp_path: Path) -> dict:
    path = tmp_path / "fleet6.yaml"
    path.write_text(PHYSICS_FLEET)
    return run_folder(path, tmp_path / "run")


def episodes(env, count: int = 3, steps: int = 25) -> list[str]:
    """Each episode's observations, rewards, ends and times after ``reset(seed=...)``, hashed;
    the actions drawn from a generator seeded by the episode's seed."""
    out = []
    for episode in range(count):
        seed = 100 + episode % 2  # seeds 100, 101, 100: a seed seen before gives its episode again
        obs, info = env.reset(seed=seed)
        actions = np.random.default_rng(seed)
        h = hashlib.sha256()
        for _ in range(steps):
            for part in obs.values() if isinstance(obs, dict) else (obs,):
                h.update(np.asarray(part).tobytes())
            h.update(repr(sorted(info.items())).encode())
            obs, reward, terminated, truncated, info = env.step(actions.uniform(-1.0, 1.0, env.action_space.shape))
            h.update(repr((reward, terminated, truncated)).encode())
        out.append(h.hexdigest())
    env.close()
    return out


def gym_physics(tmp_path: Path) -> list[str]:
    from mobot_cli.gym.env import MobotEnv

    return episodes(MobotEnv(world="empty", goal=(1.5, 0.5), scan=False))


def gym_lidar(tmp_path: Path) -> list[str]:
    from mobot_cli.gym.env import MobotEnv

    return episodes(MobotEnv(world="house", pose=(-3.0, -2.5, 0.0), args={"lidar": "true"}))


def gym_kinematic(tmp_path: Path) -> list[str]:
    from mobot_cli.gym.env import MobotEnv

    world = tmp_path / "kin.yaml"
    world.write_text("version: 1\nname: kin\nworld: house\nduration: 60\nphysics: {rate_hz: 20, engine: kinematic}\n")
    return episodes(MobotEnv(world=world, pose=(-3.0, -2.5, 0.0), args={"lidar": "true"}))


def sweep(tmp_path: Path) -> dict:
    out = tmp_path / "sweep"
    done = invoke(["sweep", str(REPO / "scenarios" / "quickstart.yaml"), *SWEEP, "--out", str(out)])
    assert done.exit_code == 0, done
    table = (out / "results.csv").read_text()
    rows = [{k: v for k, v in r.items() if k != "wall_time"} for r in csv.DictReader(io.StringIO(table))]
    return {"results": digest(json.dumps(rows).encode()),
            "runs": {run.name: folder(run) for run in sorted((out / "runs").iterdir())}}


CASES = {"fleet_kinematic": fleet_kinematic, "fleet_physics": fleet_physics, "gym_physics": gym_physics,
         "gym_lidar": gym_lidar, "gym_kinematic": gym_kinematic, "sweep": sweep}


@pytest.mark.parametrize("name", list(CASES))
def test_records_are_what_they_were(name, tmp_path):
    got = CASES[name](tmp_path)
    golden = json.loads(GOLDEN.read_text()) if GOLDEN.exists() else {}
    if os.environ.get("MOBOT_UPDATE_GOLDEN") == "1":
        golden[name] = got
        GOLDEN.write_text(json.dumps(golden, indent=2, sort_keys=True) + "\n")
    assert got == golden[name]
    if name.startswith("gym"):  # the same seed, the same episode; another seed, another one
        assert got[0] == got[2] and (got[0] != got[1] or name == "gym_physics")
