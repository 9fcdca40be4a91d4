#!/usr/bin/env python3
"""Drive fidelity per robot: straight distance, turn in place, arc radius and speed on arcs.

Each robot settles 0.5 s on the empty world (z: auto), takes one command, and the ground truth
(never odometry) is measured over the steady part (after the first quarter):

* straight: 2 m at the robot's test speed; the distance covered, as a percentage error
* turn: 90 deg in place at the test turn rate; degrees off
* arc: linear v and angular v / R for a 1 m radius at each speed in --speeds; the radius of the
  circle fitted to the path (percent off), the mean forward speed (percent off) and the yaw rate

    python3 bench/bench_arcs.py [--corpus PATH] [--robots husky,jackal] [--speeds 0.3,0.5]
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "tests"))

RATE = 240


def load_plans(corpus: Path, names: list[str]):
    from mobot_cli.assets.description.load import load_robot
    from mobot_cli.sim.plan import RobotPlan, SpawnPose
    from sim.test_fidelity import CASES, PACKAGES

    os.environ["MOBOT_RESOURCE_PATH"] = ":".join(str(corpus / pkg) for pkg in PACKAGES)
    os.environ.setdefault("MOBOT_CACHE_DIR", tempfile.mkdtemp(prefix="mobot-bench-"))
    plans = {}
    for name in names:
        case = CASES[name]
        source = case.description if name == "mobot" else str(corpus / case.description)
        desc = load_robot(source, dict(case.args))
        plans[name] = (case, RobotPlan(name=name, namespace=f"/{name}", frame_prefix=f"{name}/",
                                       urdf=desc.urdf, root_link=desc.root_link,
                                       pose=SpawnPose(z_auto=True), drive=desc.drive))
    return plans


def drive(plan, linear: float, angular: float, seconds: float):
    """Settle, command, stop; the states before, during (every 12 steps) and after."""
    from mobot_cli.sim.plan import Physics, WorldPlan
    from mobot_cli.sim.world import World

    with World(Physics(rate_hz=RATE), WorldPlan()) as world:
        world.spawn(plan)
        for _ in range(RATE // 2):
            world.step()
        before = world.read(plan.name)
        world.set_command(plan.name, linear, angular)
        samples = []
        for i in range(round(seconds * RATE)):
            world.step()
            if i % 12 == 0:
                samples.append(world.read(plan.name))
        world.set_command(plan.name, 0.0, 0.0)
        for _ in range(RATE):
            world.step()
        return before, samples, world.read(plan.name)


def fit_circle(points) -> float:
    """Radius of the least-squares (Kasa) circle through the points."""
    import numpy as np

    xy = np.array(points)
    a = np.column_stack([2 * xy[:, 0], 2 * xy[:, 1], np.ones(len(xy))])
    b = (xy ** 2).sum(axis=1)
    cx, cy, c = np.linalg.lstsq(a, b, rcond=None)[0]
    return float(math.sqrt(c + cx * cx + cy * cy))


def arc(plan, speed: float, radius: float = 1.0) -> tuple[float, float, float]:
    """(radius error %, speed error %, yaw rate / commanded) on a 3/4 circle."""
    w = speed / radius
    seconds = 1.5 * math.pi / w
    _, samples, _ = drive(plan, speed, w, seconds)
    steady = samples[len(samples) // 4:]
    measured = fit_circle([(s.true_x, s.true_y) for s in steady])
    v = sum(s.true_vx for s in steady) / len(steady)
    wz = sum(s.true_wz for s in steady) / len(steady)
    return 100 * (measured / radius - 1), 100 * (v / speed - 1), wz / w


def straight(case, plan) -> float:
    v = case.speed
    before, _, after = drive(plan, v, 0.0, 2.0 / v)
    return 100 * (math.hypot(after.true_x - before.true_x, after.true_y - before.true_y) / 2.0 - 1)


def turn(case, plan) -> float:
    w = case.turn_rate
    before, _, after = drive(plan, 0.0, w, (math.pi / 2) / w)
    turned = math.degrees((after.true_yaw - before.true_yaw + math.pi) % (2 * math.pi) - math.pi)
    return turned - 90.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--corpus", type=Path, default=REPO.parent / "shared" / "corpus")
    parser.add_argument("--robots", default="")
    parser.add_argument("--speeds", default="0.3,0.5")
    args = parser.parse_args()
    from sim.test_fidelity import CASES

    names = args.robots.split(",") if args.robots else list(CASES)
    speeds = [float(s) for s in args.speeds.split(",")]
    plans = load_plans(args.corpus.resolve(), names)
    print("robot | straight % | turn deg | " + " | ".join(
        f"arc {s:g} m/s: radius %, speed %, yaw ratio" for s in speeds))
    for name, (case, plan) in plans.items():
        cells = [f"{straight(case, plan):+.2f}", f"{turn(case, plan):+.2f}"]
        for speed in speeds:
            r, v, ratio = arc(plan, speed)
            cells.append(f"{r:+.1f}, {v:+.1f}, {ratio:.3f}")
        print(f"{name} | " + " | ".join(cells), flush=True)


if __name__ == "__main__":
    main()
