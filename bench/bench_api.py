#!/usr/bin/env python3
"""What do the Python API and the Gymnasium environment cost over `mobot run`'s own loop?

1. A scenario whose script commands the bundled robot every 10 physics steps, run by
   ``execute`` (as `mobot run`), against a Python loop through ``Simulation`` that sends the
   same commands at the same steps to the same scenario without its script (goal: <= 1.10x;
   both timed from a prepared scenario: parsing and xacro, the same for both, are left out);
   with a lidar robot in a walled room the loop also reads ``sim.scan`` before each command.
2. ``MobotEnv.step`` at a 10 Hz control rate against ``Simulation.step`` of the same 24
   physics steps of the same world, period by period (the physics it advances, the lidar's
   one scan a period included; goal: <= 10 % more), without and with a lidar; and, steadier
   on a loaded machine, the gym's own work per step timed inside each step against the
   physics within it.

The machine may be shared: runs alternate (run, API, run, API...; gym period, bare period...)
so that a change of load hits both sides, and each figure is the median with its spread.

    python3 bench/bench_api.py [--seconds 20] [--repeat 5] [--periods 300]
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

from common import timed  # noqa: E402  (bench/common.py)

from mobot_cli.api import Simulation  # noqa: E402
from mobot_cli.run import execute  # noqa: E402
from mobot_cli.scenario.prepare import prepare, prepare_target  # noqa: E402
from tests.sim.sensor_world import ROOM_SDF  # noqa: E402

EVERY = 10  # physics steps between two commands
PERIOD = 24  # physics steps of one 10 Hz control period at 240 Hz


def scenario(folder: Path, seconds: float, lidar: bool) -> Path:
    """A one-robot scenario whose script changes the command every 10 steps after settling;
    with ``lidar``, the robot carries the bundled lidar inside a walled room."""
    (folder / "room.sdf").write_text(ROOM_SDF)
    lines = ["version: 1", "name: every10", f"world: {'room.sdf' if lidar else 'empty'}", f"duration: {seconds:g}",
             "settle: 0.5", "log: {formats: [csv]}", "robots:", "  - name: r", "    description: mobot",
             "    args: {lidar: 'true'}" if lidar else "    args: {}", "    pose: {x: -2.0, y: -1.0}",
             "    commands:"]
    for step in range(120, int(seconds * 240), EVERY):
        linear = 0.1 + 0.05 * math.sin(step / 240)  # slow arcs: a 20 s run stays inside the room
        lines.append(f"      - {{at: {step / 240!r}, linear: {linear:.4f}, angular: {0.3 * math.cos(step / 300):.4f}}}")
    path = folder / f"every10{'_lidar' if lidar else ''}.yaml"
    path.write_text("\n".join(lines) + "\n")
    return path


def run_loop(path: Path, out: Path) -> tuple[float, float]:
    """(wall, CPU) seconds of `mobot run`'s loop on the prepared scenario."""
    prepared = prepare(path)
    return timed(execute, prepared.plan, prepared.resolved_yaml, out)


def api_loop(path: Path, out: Path, lidar: bool) -> tuple[float, float]:
    """(wall, CPU) seconds of a Python loop sending the script's commands at its steps."""
    plan = prepare(path).plan
    script = {c.step: (c.linear, c.angular) for c in plan.robots[0].commands}
    bare = prepare_target(str(path), ["robots.r.commands=[]"])  # prepared outside the clock, as for run_loop

    def loop():
        with Simulation(bare, out=out) as sim:
            while sim.step_count < plan.total_steps:
                command = script.get(sim.step_count)
                if command is not None:
                    if lidar:
                        sim.scan("r")  # what a controller would look at first
                    sim.command("r", *command)
                sim.step(EVERY if sim.step_count + EVERY <= plan.total_steps else 1)

    return timed(loop)


def gym_vs_physics(periods: int, lidar: bool, room: Path) -> tuple[float, float, float, float]:
    """Wall and CPU seconds of ``periods`` gym steps and of as many bare 24-step advances of the
    same world, alternating: (gym wall, bare wall, gym CPU, bare CPU). A bare period ends by
    taking the scan due (``sim.scan``, which casts its rays), as a gym step does for its
    observation, so that each side pays for one lidar scan a period. (Not two twin worlds: in one profile PyBullet's
    stepSimulation took 20 % longer in one world than in its twin, more than the gym costs.)"""
    import numpy as np

    from mobot_cli.gym import MobotEnv

    env = MobotEnv(room if lidar else "empty", pose=(-2.5, 0.0, 0.0), goal=(2.5, 0.0),
                   args={"lidar": "true"} if lidar else None, normalize=False)
    env.reset(seed=0)
    sim = env._sim  # the same world, stepped bare
    action = np.array([0.05, 0.2], dtype=np.float32)  # slow, in a circle: it stays in the room
    wall, cpu = time.perf_counter, time.process_time
    sums = [0.0, 0.0, 0.0, 0.0]
    for _ in range(periods):
        w0, c0 = wall(), cpu()
        env.step(action)
        w1, c1 = wall(), cpu()
        sim.step(PERIOD)
        if lidar:
            sim.scan(env.robot)  # the scan as arrays: its rays cast (a reading alone may wait to be)
        w2, c2 = wall(), cpu()
        sums[0] += w1 - w0
        sums[1] += w2 - w1
        sums[2] += c1 - c0
        sums[3] += c2 - c1
    env.close()
    return sums[0], sums[1], sums[2], sums[3]


def gym_own_work(periods: int, lidar: bool, room: Path) -> tuple[float, float]:
    """(µs of the gym's own work per step, µs of the physics and sensing it advances), from one
    world: the time inside ``Simulation.step`` and ``Simulation.scan`` (the scan taken, its rays
    cast, at the observation's step) is the physics and sensing; the rest of ``env.step`` is the gym's.
    Timed within each call, so a change of load between two calls does not enter."""
    import numpy as np

    from mobot_cli.gym import MobotEnv

    env = MobotEnv(room if lidar else "empty", pose=(-2.5, 0.0, 0.0), args={"lidar": "true"} if lidar else None)
    env.reset(seed=0)
    sim, inner = env._sim, [0.0]

    def clocked(fn):
        def call(*a):
            started = time.perf_counter()
            fn(*a)
            inner[0] += time.perf_counter() - started
        return call

    sim.step, sim.scan = clocked(sim.step), clocked(sim.scan)  # sim.scan: the sensing, rays cast
    action = np.array([0.05, 0.2], dtype=np.float32)
    started = time.perf_counter()
    for _ in range(periods):
        env.step(action)
    total = time.perf_counter() - started
    env.close()
    return (total - inner[0]) / periods * 1e6, inner[0] / periods * 1e6


def spread(values: list[float]) -> str:
    return f"median {statistics.median(values):.3f} (min {min(values):.3f}, max {max(values):.3f})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--periods", type=int, default=300)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for lidar in (False, True):
            path = scenario(folder, args.seconds, lidar)
            run_loop(path, folder / "warm")  # descriptions cached, imports done
            walls, cpus, same = [], [], True
            for i in range(args.repeat):
                run_s = run_loop(path, folder / f"run{lidar}{i}")
                api_s = api_loop(path, folder / f"api{lidar}{i}", lidar)
                walls.append(api_s[0] / run_s[0])
                cpus.append(api_s[1] / run_s[1])
            for name in ("odom/r.csv", *(("sensors/r/lidar.npy",) if lidar else ())):
                same &= (folder / f"run{lidar}0" / name).read_bytes() == (folder / f"api{lidar}0" / name).read_bytes()
            print(f"{'lidar robot in a room' if lidar else 'no sensors, empty world'}: {args.seconds:g} simulated s, "
                  f"a command every {EVERY} steps, {args.repeat} interleaved pairs (last run {run_s[0]:.3f} s)")
            print(f"  Python API loop / mobot run loop, wall: {spread(walls)}; CPU: {spread(cpus)} (goal <= 1.10)")
            print(f"  files identical: {same}")
        room = folder / "room.sdf"
        for lidar in (False, True):
            walls, cpus, per_step = [], [], []
            for _ in range(args.repeat):
                gym_w, bare_w, gym_c, bare_c = gym_vs_physics(args.periods, lidar, room)
                walls.append(100 * (gym_w / bare_w - 1))
                cpus.append(100 * (gym_c / bare_c - 1))
                per_step.append(gym_w / args.periods * 1e3)
            print(f"Gymnasium step at 10 Hz ({PERIOD} physics steps), {'lidar' if lidar else 'no lidar'}, "
                  f"{args.periods} alternating periods x {args.repeat}")
            print(f"  MobotEnv.step {spread(per_step)} ms; overhead over Simulation.step({PERIOD}), "
                  f"wall: {spread(walls)} %; CPU: {spread(cpus)} % (goal <= 10 %)")
            own = [gym_own_work(args.periods, lidar, room) for _ in range(args.repeat)]
            print(f"  the gym's own work per step: {spread([o[0] for o in own])} us over "
                  f"{spread([o[1] for o in own])} us of physics: {spread([100 * o[0] / o[1] for o in own])} %")


if __name__ == "__main__":
    main()
