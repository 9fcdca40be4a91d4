#!/usr/bin/env python3
"""What do the Python API and the Gymnasium environment cost over `mobot run`'s own loop?

1. A scenario whose script commands the bundled robot every 10 physics steps, run by
   ``execute`` (as `mobot run`), against a Python loop through ``Simulation`` that sends the
   same commands at the same steps to the same scenario without its script (goal: <= 1.10x).
2. ``MobotEnv.step`` at a 10 Hz control rate against ``Simulation.step`` of the same 24
   physics steps (the physics it advances; goal: <= 10 % more).

Both are interleaved and print medians.

    python3 bench/bench_api.py [--seconds 20] [--repeat 5]
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from mobot_cli.api import Simulation  # noqa: E402
from mobot_cli.run.execute import execute  # noqa: E402
from mobot_cli.run.prepare import prepare  # noqa: E402

EVERY = 10  # physics steps between two commands


def scenario(folder: Path, seconds: float) -> Path:
    """A one-robot scenario whose script changes the command every 10 steps after settling."""
    lines = ["version: 1", "name: every10", "world: empty", f"duration: {seconds:g}", "settle: 0.5",
             "log: {formats: [csv]}", "robots:", "  - name: r", "    description: mobot", "    commands:"]
    for step in range(120, int(seconds * 240), EVERY):
        linear = 0.3 + 0.1 * math.sin(step / 240)
        lines.append(f"      - {{at: {step / 240!r}, linear: {linear:.4f}, angular: {0.3 * math.cos(step / 300):.4f}}}")
    path = folder / "every10.yaml"
    path.write_text("\n".join(lines) + "\n")
    return path


def run_loop(path: Path, out: Path) -> float:
    prepared = prepare(path)
    started = time.perf_counter()
    execute(prepared.plan, prepared.resolved_yaml, out)
    return time.perf_counter() - started


def api_loop(path: Path, out: Path) -> float:
    plan = prepare(path).plan
    script = {c.step: (c.linear, c.angular) for c in plan.robots[0].commands}
    started = time.perf_counter()
    with Simulation.open(path, out=out, overrides=["robots.r.commands=[]"]) as sim:
        while sim.step_count < plan.total_steps:
            command = script.get(sim.step_count)
            if command is not None:
                sim.command("r", *command)
            sim.step(EVERY if sim.step_count + EVERY <= plan.total_steps else 1)
    return time.perf_counter() - started


def gym_vs_physics(periods: int) -> tuple[float, float]:
    import numpy as np

    from mobot_cli.gym import MobotEnv

    env = MobotEnv(goal=(50.0, 0.0))
    env.reset(seed=0)
    action = np.array([0.3, 0.1], dtype=np.float32)
    started = time.perf_counter()
    for _ in range(periods):
        env.step(action)
    gym_s = time.perf_counter() - started
    sim = env._sim  # the same world, stepped bare
    started = time.perf_counter()
    for _ in range(periods):
        sim.step(env._steps_per_action)
    bare_s = time.perf_counter() - started
    env.close()
    return gym_s, bare_s


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        path = scenario(folder, args.seconds)
        run_loop(path, folder / "warm")  # descriptions cached, imports done
        runs, apis = [], []
        for i in range(args.repeat):
            runs.append(run_loop(path, folder / f"run{i}"))
            apis.append(api_loop(path, folder / f"api{i}"))
        same = (folder / "run0" / "odom" / "r.csv").read_bytes() == (folder / "api0" / "odom" / "r.csv").read_bytes()
    run_s, api_s = statistics.median(runs), statistics.median(apis)
    print(f"{args.seconds:g} simulated s, a command every {EVERY} steps, medians of {args.repeat}, interleaved")
    print(f"  mobot run loop (execute)      {run_s:.3f} s")
    print(f"  Python API loop (Simulation)  {api_s:.3f} s   ratio {api_s / run_s:.3f} (goal <= 1.10); "
          f"CSV identical: {same}")
    pairs = [gym_vs_physics(200) for _ in range(args.repeat)]
    gym_s, bare_s = statistics.median(p[0] for p in pairs), statistics.median(p[1] for p in pairs)
    print(f"Gymnasium step at 10 Hz (24 physics steps), 200 periods, medians of {args.repeat}")
    print(f"  MobotEnv.step  {gym_s / 200 * 1e3:.3f} ms   Simulation.step(24)  {bare_s / 200 * 1e3:.3f} ms   "
          f"overhead {100 * (gym_s / bare_s - 1):+.1f} % (goal <= 10 %)")


if __name__ == "__main__":
    main()
