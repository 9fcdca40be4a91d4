#!/usr/bin/env python3
"""What does the local controller (``local: dwb``, timeline/local.py) add to a lidar run?

1. scenarios/house_patrol.yaml (the bundled robot with its 180-beam lidar at 5 Hz, a patrol
   through the house's doorway, 28 simulated s) as it is (pure pursuit) and with ``local: dwb``
   on its goal, interleaved, medians of --repeat: wall and CPU ratios. The two runs drive
   slightly different paths, so this is the cost of a whole run, not of the same motion. Within
   the dwb runs, the CPU of the controller's ticks (timeline/goals.py ``Driver._avoid``: the
   points and path put in the robot's frame, then ``Dwb.command``) and of taking each scan's
   points as it comes (``Driver.see``; the scan itself is cast before the clock starts, as the
   pursuit's run casts it for its records) is counted apart (median of the runs); what is left
   of the difference is the run's own work on the drive the controller chose.
2. One control tick of the controller alone, on a scan of the house taken in the living room:
   microseconds per call, with the path clear and with the path blocked (the wavefront).

    python3 bench/bench_local.py [--repeat 5]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

import numpy as np  # noqa: E402
from common import timed  # noqa: E402  (bench/common.py)

from mobot_cli.plan import GoalControl, GoalStep  # noqa: E402
from mobot_cli.run import execute  # noqa: E402
from mobot_cli.scenario.prepare import prepare  # noqa: E402
from mobot_cli.timeline.goals import Driver  # noqa: E402
from mobot_cli.timeline.local import Dwb  # noqa: E402
from mobot_cli.timeline.scan_points import Cloud  # noqa: E402


def with_local(plan):
    robot = plan.robots[0]
    commands = tuple(replace(c, control=replace(c.control, local="dwb")) if isinstance(c, GoalStep) else c
                     for c in robot.commands)
    return replace(plan, robots=(replace(robot, commands=commands),))


class Counted:
    """CPU seconds and calls of a Driver method, counted while installed (``with``); ``first``
    runs before the clock starts (with the method's arguments)."""

    def __init__(self, name: str, first=None):
        self.name, self.first, self.seconds, self.calls = name, first, 0.0, 0

    def __enter__(self):
        self.real = real = getattr(Driver, self.name)

        def counted(driver, *args):
            if self.first is not None:
                self.first(*args)
            started = time.process_time()
            try:
                return real(driver, *args)
            finally:
                self.seconds += time.process_time() - started
                self.calls += 1
        setattr(Driver, self.name, counted)
        return self

    def __exit__(self, *exc):
        setattr(Driver, self.name, self.real)


def whole_runs(repeat: int, work: Path) -> None:
    prepared = prepare(REPO / "scenarios" / "house_patrol.yaml")
    plans = {"pursuit": prepared.plan, "local: dwb": with_local(prepared.plan)}
    results = {name: [] for name in plans}
    parts: list[tuple[Counted, Counted]] = []
    load = os.getloadavg()[0]
    for i in range(repeat):
        for name, plan in plans.items():
            if name == "pursuit":
                results[name].append(timed(execute, plan, prepared.resolved_yaml, work / f"run-{i}-{len(name)}"))
                continue
            # A scan is cast when first read (sim/sensing/readings.py): cast it before the clock
            # starts, as the pursuit's run casts it for its records.
            with Counted("_avoid") as ticks, Counted("see", lambda sensor, data: data.ranges) as scans:
                results[name].append(timed(execute, plan, prepared.resolved_yaml, work / f"run-{i}-{len(name)}"))
            parts.append((ticks, scans))
    base_wall = statistics.median(w for w, _ in results["pursuit"])
    base_cpu = statistics.median(c for _, c in results["pursuit"])
    for name, values in results.items():
        wall, cpu = statistics.median(w for w, _ in values), statistics.median(c for _, c in values)
        print(f"  {name:<11} {wall:7.3f} s wall  {cpu:7.3f} s CPU   wall x{wall / base_wall:5.3f}  "
              f"CPU x{cpu / base_cpu:5.3f}")
    pairs = sorted(c / b for (_, b), (_, c) in zip(results["pursuit"], results["local: dwb"]))
    print(f"  dwb / pursuit, CPU, run by run: median x{statistics.median(pairs):5.3f}, all "
          f"x{pairs[0]:5.3f}-x{pairs[-1]:5.3f} ({len(pairs)} pairs; load average {load:.1f} before, "
          f"{os.getloadavg()[0]:.1f} after)")
    ticks = statistics.median(t.seconds for t, _ in parts)
    scans = statistics.median(s.seconds for _, s in parts)
    calls = parts[0][0].calls
    extra = statistics.median(c for _, c in results["local: dwb"]) - base_cpu
    print(f"  within the dwb runs: the controller's ticks {ticks:.3f} s CPU ({calls} ticks, "
          f"{1e6 * ticks / calls:.0f} us a tick in the run), taking the scans' points "
          f"{scans:.3f} s ({parts[0][1].calls} scans); the rest of the {extra:.3f} s more, "
          f"{extra - ticks - scans:.3f} s, is the run's own work on the different drive")


def one_tick(calls: int = 400) -> None:
    # A room's walls 1.5 m and 2.5 m away, 180 beams, and a chair-sized cluster.
    angles = np.linspace(-np.pi, np.pi, 180, endpoint=False)
    reach = np.minimum(1.5 / np.maximum(np.abs(np.cos(angles)), 1e-9), 2.5 / np.maximum(np.abs(np.sin(angles)), 1e-9))
    walls = np.stack([reach * np.cos(angles), reach * np.sin(angles)], axis=1)
    chair = np.array([[0.9 + dx, dy] for dx in (-0.15, 0.0, 0.15) for dy in (-0.15, 0.0, 0.15)])
    clear = np.array([[0.0, 0.0], [0.0, 1.4]])  # the path goes left, away from the chair
    blocked = np.array([[0.0, 0.0], [1.4, 0.0]])
    for name, points, path in (("path clear", walls, clear), ("path blocked", np.vstack([walls, chair]), blocked)):
        dwb = Dwb(GoalControl(), 0.05, 0.26)
        dwb.v = 0.2
        cloud = Cloud(points)  # as a run keeps a scan's points from tick to tick
        started = time.process_time()
        for _ in range(calls):
            dwb.command(cloud, path)
            dwb.v, dwb.w = 0.2, 0.0
        print(f"  one tick, {name:<13} {1e6 * (time.process_time() - started) / calls:7.0f} us CPU")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="mobot-bench-local-") as work:
        print("house_patrol.yaml, 28 simulated s, pursuit against local: dwb:")
        whole_runs(args.repeat, Path(work))
    print("the controller alone, one tick called over and over on a made-up scan (its caches warm):")
    one_tick()


if __name__ == "__main__":
    main()
