#!/usr/bin/env python3
"""Drive fidelity per robot: straight distance, turn in place, arc radius and speed on arcs.

Each robot settles 0.5 s on the empty world (z: auto), takes one command, and the ground truth
(never odometry) is measured over the steady part (after the first quarter):

* straight: 2 m at the robot's test speed; the distance covered, as a percentage error
* turn: 90 deg in place at the test turn rate; degrees off
* yaw rate / commanded: the mean over the steady part of that turn
* arc: linear v and angular v / R for a 1 m radius, at the robot's test speed and half of it;
  the radius of the circle fitted to the path of the drive wheels' axle centre and its mean
  forward speed, as percentages off

Prints the README's fidelity table (markdown):

    python3 bench/bench_arcs.py [--corpus PATH] [--robots husky,jackal]
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


def load_plans(corpus: Path, names: list[str]):
    from sim.test_fidelity import CASES, PACKAGES

    from mobot_cli.assets.description.describe import load_robot
    from mobot_cli.plan import RobotPlan, SpawnPose

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
    """Settle, command, stop: the fidelity tests' own drive (states before, every 12 steps, after)."""
    from sim.test_fidelity import drive as fidelity_drive

    return fidelity_drive(plan, linear, angular, seconds)


def fit_circle(points) -> float:
    """Radius of the least-squares (Kasa) circle through the points."""
    import numpy as np

    xy = np.array(points)
    a = np.column_stack([2 * xy[:, 0], 2 * xy[:, 1], np.ones(len(xy))])
    b = (xy ** 2).sum(axis=1)
    cx, cy, c = np.linalg.lstsq(a, b, rcond=None)[0]
    return float(math.sqrt(c + cx * cx + cy * cy))


def axle_centre(plan) -> tuple[float, float]:
    """Where the drive wheels' joints average out, in the root frame: the point a diff-drive
    controller steers (gz_ros2_control's test_diff_drive has its base_link 0.55 m ahead of it)."""
    import xml.etree.ElementTree as ET

    from mobot_cli.assets.description.frames import LinkTree

    tree = LinkTree(ET.fromstring(plan.urdf))
    joints = set(plan.drive.left_joints + plan.drive.right_joints)
    points = [tree.frame(j.child).pos for j in tree.joints if j.name in joints]
    return sum(p[0] for p in points) / len(points), sum(p[1] for p in points) / len(points)


def arc(plan, speed: float, radius: float = 1.0) -> tuple[float, float]:
    """(radius error %, speed error %) of the axle centre on three quarters of a circle."""
    w = speed / radius
    _, samples, _ = drive(plan, speed, w, 1.5 * math.pi / w)
    steady = samples[len(samples) // 4:]
    ox, oy = axle_centre(plan)
    path = [(s.true_x + math.cos(s.true_yaw) * ox - math.sin(s.true_yaw) * oy,
             s.true_y + math.sin(s.true_yaw) * ox + math.cos(s.true_yaw) * oy) for s in steady]
    # The commanded speed is along the body's x axis (sideslip is not speed), at the axle centre.
    v = sum(s.true_vx - s.true_wz * oy for s in steady) / len(steady)
    return 100 * (fit_circle(path) / radius - 1), 100 * (v / speed - 1)


def straight(case, plan) -> float:
    v = case.speed
    before, _, after = drive(plan, v, 0.0, 2.0 / v)
    return 100 * (math.hypot(after.true_x - before.true_x, after.true_y - before.true_y) / 2.0 - 1)


def turn(case, plan) -> tuple[float, float]:
    """(degrees off 90, steady yaw rate / commanded)."""
    w = case.turn_rate
    before, samples, after = drive(plan, 0.0, w, (math.pi / 2) / w)
    turned = math.degrees((after.true_yaw - before.true_yaw + math.pi) % (2 * math.pi) - math.pi)
    steady = samples[len(samples) // 4:]
    return turned - 90.0, sum(s.true_wz for s in steady) / len(steady) / w


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--corpus", type=Path, default=REPO.parent / "shared" / "corpus")
    parser.add_argument("--robots", default="")
    args = parser.parse_args()
    from sim.test_fidelity import CASES

    names = args.robots.split(",") if args.robots else list(CASES)
    plans = load_plans(args.corpus.resolve(), names)
    print("| robot (v m/s, w rad/s) | straight 2 m | 90° turn in place | yaw rate / commanded "
          "| arc radius, 1 m at v/2, v | arc speed at v/2, v |")
    print("|---|---|---|---|---|---|")
    for name, (case, plan) in plans.items():
        off, ratio = turn(case, plan)
        arcs = [arc(plan, speed) for speed in (case.speed / 2, case.speed)]
        print(f"| {name} ({case.speed:g}, {case.turn_rate:g}) | {straight(case, plan):+.2f} % "
              f"| {off:+.2f}° | {ratio:.3f} | {arcs[0][0]:+.1f} %, {arcs[1][0]:+.1f} % "
              f"| {arcs[0][1]:+.1f} %, {arcs[1][1]:+.1f} % |", flush=True)


if __name__ == "__main__":
    main()
