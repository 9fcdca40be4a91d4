#!/usr/bin/env python3
"""What do movers cost? The bundled house, one robot with its 360-beam lidar at 10 Hz driving
through it, without movers and with 50 social-force walkers (docs/movers.md), interleaved,
best of --repeat; the walkers' share of the run in wall and CPU time. The issue's bound: 25 %.
``--parts`` then profiles one run of each (cProfile, CPU time: its overhead swells the Python
parts several times over, PyBullet's C calls hardly) and prints where the walkers' time goes:
PyBullet stepping with their bodies (and with the robot they block), moving them, the lidar's
rays at them, movers.csv, trajectory.png.

    python3 bench/bench_movers.py [--seconds 20] [--repeat 5] [--walkers 50] [--parts]
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from common import timed  # noqa: E402  (bench/common.py)

from mobot_cli.plan import MoverPlan  # noqa: E402
from mobot_cli.run import execute  # noqa: E402
from mobot_cli.scenario.prepare import prepare  # noqa: E402

BOUND = 0.25
# (what, [(file, function)]): the profile's cumulative time of these, crowded run less lone run
PARTS = (
    ("PyBullet stepping", [("~", "<built-in method pybullet.stepSimulation>")]),
    ("moving the walkers", [("movers/stage.py", "update")]),
    ("  of which the social force", [("movers/crowd.py", "_force")]),
    ("    of which its wall rays", [("movers/stage.py", "_walls")]),
    ("lidar rays at the walkers", [("sensing/rig.py", "_see_movers")]),
    ("movers.csv", [("record/movers_csv.py", "write"), ("record/movers_csv.py", "close")]),
    ("trajectory.png (paths, picture)", [("record/trajectory.py", "write"), ("record/trajectory.py", "close")]),
    ("the walkers entering", [("movers/door.py", "add_mover")]),
    ("contacts sampled", [("sim/contacts.py", "sample")]),
    ("the whole run (profiled)", [("mobot_cli/run.py", "execute")]),
)


def plans(seconds: float, walkers: int):
    """The house scenario with the robot's lidar on, and the same with ``walkers`` walkers in the
    living room and the kitchen (half each)."""
    prepared = prepare(REPO / "scenarios" / "house.yaml", ["robots.mobot.args.lidar=true", f"duration={seconds}"])
    plan = prepared.plan
    rooms = [(-5.5, 0.5, -4.5, 0.5), (1.5, 5.5, -4.5, 0.5)]
    movers = tuple(MoverPlan(name=f"walker_{i}", shape="person", size=(0.3, 1.7), region=rooms[i % 2], speed=1.0)
                   for i in range(walkers))
    return prepared.resolved_yaml, plan, replace(plan, movers=movers)


def profiled(plan, resolved: str, out: Path) -> dict[tuple[str, int, str], tuple]:
    profile = cProfile.Profile(time.process_time)  # CPU time: steadier on a shared machine
    profile.runcall(execute, plan, resolved, out)
    return pstats.Stats(profile).stats


def cumulative(stats: dict, where: str, name: str) -> float:
    return sum(row[3] for (file, _, function), row in stats.items() if function == name and file.endswith(where))


def parts(resolved: str, alone, crowded, work: Path) -> None:
    """Where the walkers' time goes, by cProfile: crowded run less lone run."""
    lone, crowd = profiled(alone, resolved, work / "p_alone"), profiled(crowded, resolved, work / "p_crowded")
    print("where the walkers' time goes (cProfile, crowded less alone, ms):")
    for what, functions in PARTS:
        extra = sum(cumulative(crowd, *f) - cumulative(lone, *f) for f in functions)
        print(f"  {what:34s} {1000 * extra:7.1f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--walkers", type=int, default=50)
    parser.add_argument("--parts", action="store_true", help="then profile where the walkers' time goes")
    args = parser.parse_args()
    resolved, alone, crowded = plans(args.seconds, args.walkers)
    times: dict[str, list[tuple[float, float]]] = {"alone": [], "crowded": []}
    with tempfile.TemporaryDirectory() as work:
        execute(alone, resolved, Path(work) / "warm")  # imports, caches and the scene, once
        for i in range(args.repeat):
            for label, plan in (("alone", alone), ("crowded", crowded)) if i % 2 == 0 else \
                    (("crowded", crowded), ("alone", alone)):
                times[label].append(timed(execute, plan, resolved, Path(work) / f"{label}{i}"))
        report(args, times)
        if args.parts:
            parts(resolved, alone, crowded, Path(work))


def report(args, times: dict[str, list[tuple[float, float]]]) -> None:
    wall = {k: min(t[0] for t in v) for k, v in times.items()}
    cpu = {k: min(t[1] for t in v) for k, v in times.items()}
    print(f"house, one robot with a 2D lidar, {args.seconds:g} s simulated, best of {args.repeat}:")
    for label in ("alone", "crowded"):
        print(f"  {label:8s} wall {wall[label]:.3f} s  cpu {cpu[label]:.3f} s")
    added_wall = wall["crowded"] / wall["alone"] - 1.0
    added_cpu = cpu["crowded"] / cpu["alone"] - 1.0
    print(f"{args.walkers} walkers add {100 * added_wall:.1f} % wall, {100 * added_cpu:.1f} % CPU "
          f"(bound {100 * BOUND:.0f} %): {'ok' if max(added_wall, added_cpu) <= BOUND else 'OVER'}")


if __name__ == "__main__":
    main()
