#!/usr/bin/env python3
"""How fast do sweeps go? Wall time of a 16- or 32-run sweep at 1 and 2 jobs, and per-run overhead.

1. A 16-run grid (or 32 with ``--runs 32``; bundled robot, ``--seconds`` simulated each, no pictures) through
   the local pool at ``--jobs 1`` and ``--jobs 2``: the wall time of the whole sweep (workers
   started, runs, results.csv), runs per second, and the speed-up (goal: >= 1.8x on 2 cores).
2. Per-run overhead in a warm worker beyond the simulation loop (goal: <= 100 ms; the
   kinematic engine's issue asks <= 50 ms): with one worker and the runs queued back to back,
   the time between two finished runs is everything a run costs (sending the plan, the world
   and the spawn checks, the run folder's files, summary, expectations, the results row); the
   loop alone (``simulate(plan)`` from its first record to its last, nothing written) is
   subtracted.

3. ``--command``: the whole ``mobot sweep one.yaml --grid seed=0,...,31 --jobs 2 --quiet`` command
   of bench_kinematic.py's scenario (one bundled robot, a 60 s script, kinematic engine at 10 Hz,
   logged at 10 Hz), start-up included: wall time, runs per second (goal >= 30), the CPU time of
   every process it starts (the sweep, the fork server, the workers: reaped here as a
   subreaper) and the median wall time of one run in its worker, after one command per tree not
   counted (the first run in a new folder expands the robot's xacro and loads the world again,
   cached for the folder's later runs; it also checked the description again, ~0.9 s, before
   those checks were shared between folders). ``--trees A,B`` runs the
   command with each source tree first on PYTHONPATH in turn (e.g. a checkout of the code
   before a change, and this one), so that both see the same load.

    python3 bench/bench_sweep.py [--seconds 10] [--repeat 3] [--runs 16|32]
    python3 bench/bench_sweep.py --command [--repeat 5] [--trees /tmp/base,.]
"""

from __future__ import annotations

import argparse
import csv
import ctypes
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from mobot_cli.sweep.execution import run_sweep  # noqa: E402
from mobot_cli.sweep.executor_local import LocalExecutor  # noqa: E402
from mobot_cli.sweep.expand import expand  # noqa: E402
from mobot_cli.sweep.spec import build_spec  # noqa: E402
from mobot_cli.timeline.loop import simulate  # noqa: E402

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
    run_sweep(sweep, work / tag, executor, {}, pictures=False)  # as `mobot sweep` without --pictures
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


def whole_command(tree: Path, scenario: Path, out: Path, runs: int,
                  extra: tuple[str, ...] = ()) -> tuple[float, float, float, float]:
    """(wall s, CPU s of every process, CPU s of the sweep process alone, median in-worker wall s
    of one run) of one whole ``mobot sweep --jobs 2`` with ``tree`` first on the path."""
    shutil.rmtree(out, ignore_errors=True)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    subprocess.run([sys.executable, "-m", "mobot_cli", "sweep", str(scenario), "--grid",
                    "seed=" + ",".join(str(i) for i in range(runs)), "--jobs", "2", "--out", str(out), "--quiet",
                    *extra],
                   check=True, cwd=scenario.parent, env={**os.environ, "PYTHONPATH": str(tree)})
    wall = time.perf_counter() - started
    mid = resource.getrusage(resource.RUSAGE_CHILDREN)
    while True:  # the fork server and its workers outlive the sweep by a moment: reap them too
        try:
            os.wait()
        except ChildProcessError:
            break
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    with (out / "results.csv").open() as f:
        per_run = statistics.median(float(r["wall_time"]) for r in csv.DictReader(f))
    return (wall, after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime,
            mid.ru_utime + mid.ru_stime - before.ru_utime - before.ru_stime, per_run)


def command_main(trees: list[Path], repeat: int, runs: int) -> None:
    sys.path.insert(0, str(REPO / "bench"))
    from bench_kinematic import one_robot
    from common import bytecode_state

    ctypes.CDLL(None).prctl(36, 1, 0, 0, 0)  # PR_SET_CHILD_SUBREAPER: orphaned workers come to us
    work = Path(tempfile.mkdtemp(prefix="mobot-bench-sweep-cmd-"))
    try:
        scenario = work / "one.yaml"
        scenario.write_text(one_robot("kinematic", 10))
        # Each tree without pictures (the default) and with --pictures (what every sweep drew before)
        cases = [(tree, extra) for tree in trees for extra in ((), ("--pictures",))]
        figures: dict[tuple, list[tuple[float, float, float, float]]] = {c: [] for c in cases}
        for i, (tree, extra) in enumerate(cases):  # not counted: a new folder's first run fills its caches
            whole_command(tree, scenario, work / f"out{i}", runs, extra)
        load = os.getloadavg()[0]
        for _ in range(repeat):  # interleaved: every tree sees the same load
            for i, (tree, extra) in enumerate(cases):
                figures[(tree, extra)].append(whole_command(tree, scenario, work / f"out{i}", runs, extra))
        print(f"{runs}-run `mobot sweep --jobs 2` of the kinematic 60 s script, whole command, medians of "
              f"{repeat} (load average {load:.1f} before, {os.getloadavg()[0]:.1f} after)")
        print(f"{'tree':<40} {'wall s':>7} {'runs/s':>7} {'CPU s':>6} {'sweep CPU s':>11} {'one run ms':>10}")
        for (tree, extra), rows in figures.items():
            wall, cpu, parent, per_run = (statistics.median(r[k] for r in rows) for k in range(4))
            label = f"{tree} {' '.join(extra)}".strip()
            print(f"{label:<40} {wall:>7.3f} {runs / wall:>7.1f} {cpu:>6.2f} {parent:>11.2f} "
                  f"{per_run * 1000:>10.0f}   (walls {', '.join(f'{r[0]:.2f}' for r in rows)})")
            print(f"{'':<40} {bytecode_state(tree)}")
        print("goal: >= 60 runs/s without pictures (the row with --pictures is what every sweep did before)")
    finally:
        shutil.rmtree(work, ignore_errors=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0, help="simulated seconds per run")
    parser.add_argument("--repeat", type=int, default=3, help="sweeps per figure (the median is shown)")
    parser.add_argument("--runs", type=int, default=16, choices=(16, 32), help="runs per sweep")
    parser.add_argument("--command", action="store_true", help="time the whole sweep command (32 runs)")
    parser.add_argument("--trees", default=str(REPO), help="with --command: source trees to compare, a,b,...")
    args = parser.parse_args()
    if args.command:
        return command_main([Path(t).resolve() for t in args.trees.split(",")], args.repeat, 32)
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
