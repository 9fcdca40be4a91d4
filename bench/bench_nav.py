#!/usr/bin/env python3
"""How long does ``planner: astar`` take to plan a goal in the bundled house?

The house's occupancy grid at 0.05 m (264 x 224 cells, as `mobot map house` writes it), inflated
by the bundled robot's footprint radius (0.26 m), then A* (timeline/planner.py) between every
pair of the four rooms' centres and three far corners of the house (the longest searches),
each pruned to its turns. CPU time per search, median and worst over ``--repeat`` rounds (goal:
<= 50 ms); the grid's making (rasterising the floor plan, casting for the floor's edges, inflating
it) is timed apart, as a goal pays it only when its world's grid is not cached yet.

    python3 bench/bench_nav.py [--repeat 20]
"""

from __future__ import annotations

import argparse
import itertools
import statistics
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from mobot_cli.assets.world import dropoffs, occupancy  # noqa: E402
from mobot_cli.assets.world.floorplan import BAND, body_shadows  # noqa: E402
from mobot_cli.assets.world.worldplan import load_world  # noqa: E402
from mobot_cli.sim.sensing import raycast  # noqa: E402
from mobot_cli.timeline.planner import astar, prune  # noqa: E402

CELL = 0.05
RADIUS = 0.262  # the bundled robot: its footprint's corners at (-0.2 | 0.1, +-0.17)
POINTS = {"living": (-2.5, -2.0), "kitchen": (3.5, -2.0), "office": (3.5, 3.0), "bedroom": (-2.5, 3.0),
          "south-west": (-5.5, -4.5), "south-east": (5.5, -4.5), "north": (2.0, 4.5)}


def cpu_ms(fn) -> tuple[float, object]:
    start = time.process_time()
    out = fn()
    return (time.process_time() - start) * 1000.0, out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=20)
    args = parser.parse_args()
    world = load_world("house").plan
    grid = occupancy.grid_for(world, CELL, BAND)
    making = []
    for _ in range(max(3, args.repeat // 4)):
        body_shadows.cache_clear()
        occupancy._mask.cache_clear()  # noqa: SLF001 - timing the uncached path on purpose
        dropoffs.edges.cache_clear()
        raycast.forget_kept()
        ms, blocked = cpu_ms(lambda: occupancy.drivable(world, grid).inflated(RADIUS))
        making.append(ms)
    print(f"grid {grid.nx} x {grid.ny} cells of {CELL} m, the floor's edges cast for, inflated by {RADIUS} m: "
          f"made in {statistics.median(making):.1f} ms CPU (median of {len(making)})")
    print(f"{'from':>11} {'to':>11} {'path m':>7} {'turns':>5} {'median ms':>9} {'worst ms':>8}")
    medians = []
    for (a, pa), (b, pb) in itertools.combinations(POINTS.items(), 2):
        start, goal = grid.cell_of(*pa), grid.cell_of(*pb)
        times, turns, found = [], 0, None
        for _ in range(args.repeat):
            ms, (found, turns) = cpu_ms(lambda: (lambda f: (f, prune(blocked, f.cells)))(astar(blocked, start, goal)))
            times.append(ms)
        if found.reason:
            print(f"{a:>11} {b:>11}  {found.reason}")
            continue
        medians.append(statistics.median(times))
        print(f"{a:>11} {b:>11} {found.length * CELL:7.2f} {len(turns):5d} {medians[-1]:9.2f} {max(times):8.2f}")
    print(f"A* + pruning over {len(medians)} pairs: median {statistics.median(medians):.2f} ms, "
          f"slowest pair {max(medians):.2f} ms (goal <= 50 ms)")


if __name__ == "__main__":
    main()
