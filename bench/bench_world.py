#!/usr/bin/env python3
"""World loading and stepping: the AWS small house (corpus) against the bundled empty world.

* cold load: a fresh cache folder (SDF read, 62 COLLADA meshes converted to OBJ) + PyBullet build
* warm load: the cached world document read back + PyBullet build (the part inside `mobot run`;
  goal <= 0.5 s), and a whole `mobot run` process of a 1 s scenario, cold and warm
* stepping: one bundled robot driving straight for 10 simulated seconds, house vs empty

    python3 bench/bench_world.py [--corpus PATH] [--repeat 5]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
SMALL_HOUSE = "aws-robomaker-small-house-world/worlds/small_house.world"


def load_and_build(world: str) -> tuple[float, float]:
    """Seconds to load the world (cache or cold) and to build it in PyBullet."""
    from mobot_cli.assets.world.worldplan import load_world
    from mobot_cli.plan import Physics
    from mobot_cli.sim.bullet.world import World

    started = time.perf_counter()
    loaded = load_world(world)
    loaded_at = time.perf_counter()
    World(Physics(), loaded.plan).close()
    return loaded_at - started, time.perf_counter() - loaded_at


def step_rate(world: str, seconds: float) -> float:
    """Physics steps per wall second with one robot driving at 0.1 m/s."""
    from mobot_cli.assets.description.describe import load_robot
    from mobot_cli.assets.world.worldplan import load_world
    from mobot_cli.plan import Physics, RobotPlan, SpawnPose
    from mobot_cli.sim.bullet.world import World

    desc = load_robot("mobot")
    xy = (3.5, 1.0) if world != "empty" else (0.0, 0.0)
    plan = RobotPlan(name="r", namespace="/r", frame_prefix="r/", urdf=desc.urdf,
                     root_link=desc.root_link, pose=SpawnPose(xyz=(*xy, 0.0), z_auto=True),
                     drive=desc.drive)
    physics = Physics()
    steps = int(seconds * physics.rate_hz)
    with World(physics, load_world(world).plan) as sim:
        sim.spawn(plan)
        sim.set_command("r", 0.1, 0.0)  # 1 m in 10 s: clear of the kitchen table
        started = time.perf_counter()
        for _ in range(steps):
            sim.step()
        return steps / (time.perf_counter() - started)


def run_process(world: str, out: Path) -> float:
    """Wall seconds of a whole `mobot run` of a 1 s scenario in ``world``."""
    scenario = out / "s.yaml"
    scenario.write_text(f"version: 1\nname: s\nworld: {world}\nduration: 1.0\n"
                        "robots:\n  - {name: r, pose: {x: 3.5, y: 1.0}}\n")
    started = time.perf_counter()
    subprocess.run([sys.executable, "-m", "mobot_cli", "run", str(scenario), "--out", str(out / "run"),
                    "--quiet"], check=True, cwd=REPO)
    return time.perf_counter() - started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--corpus", type=Path, default=Path(os.environ.get(
        "MOBOT_CORPUS", REPO.parent / "shared" / "corpus")))
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    house = str((args.corpus / SMALL_HOUSE).resolve())
    with tempfile.TemporaryDirectory() as tmp:
        os.environ["MOBOT_CACHE_DIR"] = str(Path(tmp) / "cache")
        cold_load, cold_build = load_and_build(house)
        print(f"small house, cold: load {cold_load:.3f} s (SDF + COLLADA -> OBJ), build {cold_build:.3f} s")
        warm = [load_and_build(house) for _ in range(args.repeat)]
        load = statistics.median(w[0] for w in warm)
        build = statistics.median(w[1] for w in warm)
        print(f"small house, warm: load {load:.4f} s, build {build:.4f} s, total {load + build:.4f} s "
              f"(goal <= 0.5 s; median of {args.repeat})")
        os.environ["MOBOT_CACHE_DIR"] = str(Path(tmp) / "cache2")
        print(f"mobot run, 1 s in the small house: cold process {run_process(house, Path(tmp)):.2f} s, "
              f"warm process {run_process(house, Path(tmp)):.2f} s")
        for world in ("empty", house):
            rates = [step_rate(world, 10.0) for _ in range(max(1, args.repeat // 2))]
            label = "empty world" if world == "empty" else "small house"
            print(f"stepping, one robot, {label}: {statistics.median(rates):,.0f} steps/s "
                  f"({statistics.median(rates) / 240:.0f}x real time at 240 Hz)")


if __name__ == "__main__":
    main()
