#!/usr/bin/env python3
"""How fast do sweeps go? Wall time of a 16- or 32-run sweep at 1 and 2 jobs, and per-run overhead.

1. A 16-run grid (or 32 with ``--runs 32``; bundled robot, ``--seconds`` simulated each) through
   the local pool at ``--jobs 1`` and ``--jobs 2``: the wall time of the whole sweep (workers
   started, runs, results.csv), runs per second, and the speed-up (goal: >= 1.8x on 2 cores).
2. Per-run overhead in a warm worker beyond the simulation loop (goal: <= 100 ms; the
   kinematic engine's issue asks <= 50 ms): with one worker and the runs queued back to back,
   the time between two finished runs is everything a run costs (sending the plan, the world
   and the spawn checks, the run folder's files, summary, expectations, the results row); the
   loop alone (``simulate(plan)`` from its first record to its last, nothing written) is
   subtracted.

    python3 bench/bench_sweep.py [--seconds 10] [--repeat 3] [--runs 16|32]
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from mobot_cli.run.timeline import simulate  # noqa: E402
from mobot_cli.sweep.executor_local import LocalExecutor  # noqa: E402
from mobot_cli.sweep.expand import expand  # noqa: E402
from mobot_cli.sweep.runner import run_sweep  # noqa: E402
from mobot_cli.sweep.spec import build_spec  # noqa: E402

GRID = ["robots.mobot.commands.0.linear=0.1,0.2,0.3,0.4", "robots.mobot.commands.0.angular=0,0.2,0.4,0.6"]
GRID32 = [GRID[0], "robots.mobot.commands.0.angular=0,0.1,0.2,0.3,0.4,0.5,0.6,0.7"]


def scenario_text(seconds: float) -> str:
    return (f"version: 1\nname: bench_sweep\nduration: {seconds}\nsettle: 0.5\nlog: {{rate_hz: 48}}\n"
            "robots:\n  - name: mobot\n    commands: [{at: 0.5, linear: 0.3, angular: 0.3}]\n"
            "expect:\n  - {robot: mobot, collisions: 0}\n")


def sweep_seconds(sweep, work: Path, jobs: int, tag: str) -> tuple[float, list[float]]:
    """Wall time of one whole sweep, and the times at which runs finished."""
    finished: list[float] = []
    executor = LocalExecutor(jobs)
    inner_run = executor.run

    def run(tasks, on_done):
        def note(outcome):
            finished.append(time.perf_counter())
            on_done(outcome)
        inner_run(tasks, note)

    executor.run = run
    started = time.perf_counter()
    run_sweep(sweep, work / tag, executor, {})
    return time.perf_counter() - started, finished


def loop_only(plans) -> float:
    """Median time of the runs' simulation loops alone (after the spawns), in this warm process."""
    times = []
    for plan in plans:
        records = simulate(plan)
        next(records)  # the robots are spawned and checked; the loop starts
        started = time.perf_counter()
        for _record in records:
            pass
        times.append(time.perf_counter() - started)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0, help="simulated seconds per run")
    parser.add_argument("--repeat", type=int, default=3, help="sweeps per figure (the median is shown)")
    parser.add_argument("--runs", type=int, default=16, choices=(16, 32), help="runs per sweep")
    args = parser.parse_args()
    grid, runs = (GRID32 if args.runs == 32 else GRID), args.runs
    work = Path(tempfile.mkdtemp(prefix="mobot-bench-sweep-"))
    try:
        path = work / "bench.yaml"
        path.write_text(scenario_text(args.seconds))
        expand(build_spec(path, GRID[:1], [], [], None, None, []))  # fill the asset cache first
        started = time.perf_counter()
        sweep = expand(build_spec(path, grid, [], [], None, None, []))
        prepare_s = time.perf_counter() - started
        print(f"{runs}-run sweep, {args.seconds:g} simulated s per run, {os.cpu_count()} cores; "
              f"preparing (and checking) all {runs} runs, warm cache: {prepare_s:.3f} s")
        walls = {1: [], 2: []}
        intervals = []
        for i in range(args.repeat):
            for jobs in (1, 2):
                wall, finished = sweep_seconds(sweep, work, jobs, f"j{jobs}-{i}")
                walls[jobs].append(wall)
                if jobs == 1:
                    intervals += [b - a for a, b in zip(finished, finished[1:])]
        one, two = statistics.median(walls[1]), statistics.median(walls[2])
        print(f"{'jobs':>4} {'sweep wall s':>12} {'runs/s':>7}")
        print(f"{1:>4} {one:>12.3f} {runs / one:>7.2f}")
        print(f"{2:>4} {two:>12.3f} {runs / two:>7.2f}   speed-up {one / two:.2f}x (goal >= 1.8x on 2 cores)")
        per_run = statistics.median(intervals)
        loop = loop_only([p.plan for p in sweep.prepared])
        print(f"per run in a warm worker: {per_run * 1000:.1f} ms; simulation loop {loop * 1000:.1f} ms; "
              f"overhead {(per_run - loop) * 1000:.1f} ms (goal <= 100 ms)")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
