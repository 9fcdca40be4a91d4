#!/usr/bin/env python3
"""How much does mobot cost over raw PyBullet? Prints wall-time ratios and start-up figures.

For 1 and 10 bundled robots it runs the same scenario twice: through mobot's ``execute``
(timeline, drive controllers, odometry, CSV sinks) and through a hand-written PyBullet loop
on the same URDF text, rate, solver iterations and logging rate (bench/raw_run.py: velocity
motors set when a command changes, base state and wheel joints read and a CSV row written at the
log rate). Then it times whole processes: ``mobot --help``, a 10-simulated-second ``mobot run``,
and the fixed cost of a run: a whole ``mobot run`` of one robot for 60 simulated s minus its
loop (the same plan's ``simulate`` from its first record to its last, in this warm process),
beside the same figure for raw_run.py as a whole process (minus the loop it times itself),
interleaved, and the same `mobot run` without its helper process (MOBOT_HELPER=0). The first
figure takes the loop as timed again in this process (``simulate``, no files); the last, as
raw_run.py does, times the run's own loop inside it (bench/run_probe.py: ``_play``, its sinks
writing), so that both fixed costs are the whole process minus its own loop. The issue's goal
was <= 0.25 s when the raw script's was 0.15 s.

    python3 bench/bench_run.py [--seconds 20] [--repeat 3]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from mobot_cli.run.execute import execute  # noqa: E402
from mobot_cli.run.prepare import prepare  # noqa: E402
from mobot_cli.run.timeline import simulate  # noqa: E402

from common import bytecode_state, process_seconds, timed  # noqa: E402  (bench/common.py)
from raw_run import raw_loop  # noqa: E402  (bench/raw_run.py)


def scenario_text(robots: int, seconds: float) -> str:
    """N bundled robots 1 m apart, each driving a circle after settling."""
    poses = ", ".join(f"[{(i % 5) * 1.0}, {(i // 5) * 1.0}, 0]" for i in range(robots))
    return (f"version: 1\nname: bench{robots}\nduration: {seconds}\nsettle: 0.5\n"
            f"physics: {{rate_hz: 240, solver_iterations: 50}}\nlog: {{rate_hz: 48}}\n"
            f"robots:\n  - name: r_{{i}}\n    count: {robots}\n    poses: [{poses}]\n"
            f"    commands: [{{at: 0.5, linear: 0.3, angular: 0.3}}]\n")


def spec(plan, out_dir: Path) -> dict:
    """What raw_run.py needs of a plan (written as JSON for its whole-process run)."""
    urdf = out_dir / "robot.urdf"
    urdf.write_text(plan.robots[0].urdf)
    drive, cmd = plan.robots[0].drive, plan.robots[0].commands[0]
    return {"urdf": str(urdf), "rate_hz": plan.physics.rate_hz, "solver_iterations": plan.physics.solver_iterations,
            "gravity": list(plan.physics.gravity), "total_steps": plan.total_steps, "log_every": plan.log_every,
            "robots": [[r.name, list(r.pose.xyz), list(r.pose.quat)] for r in plan.robots],
            "wheels": list(drive.left_joints + drive.right_joints), "wheel_separation": drive.wheel_separation,
            "wheel_radius": drive.wheel_radius, "max_wheel_torque": drive.max_wheel_torque,
            "command": [cmd.step, cmd.linear, cmd.angular]}


def mobot_loop(prepared, out_dir: Path) -> float:
    """A whole `mobot run` minus start-up: simulation, CSV, summary, trajectory.png."""
    execute(prepared.plan, prepared.resolved_yaml, out_dir)


def mobot_sim_only(prepared, out_dir: Path) -> None:
    """mobot's timeline alone (spawn checks, drive, odometry, contacts, reads), no files."""
    for _ in simulate(prepared.plan):  # every record, nothing written
        pass


def loop_seconds(plan) -> float:
    """The simulation loop alone: ``simulate(plan)`` from its first record (robots spawned) to its last."""
    records = simulate(plan)
    next(records)
    started = time.perf_counter()
    for _ in records:
        pass
    return time.perf_counter() - started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=20.0, help="simulated seconds per run")
    parser.add_argument("--repeat", type=int, default=3, help="runs per figure (the median is shown)")
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="mobot-bench-"))
    try:
        print(f"mobot vs raw PyBullet, {args.seconds:g} simulated s at 240 Hz, 50 solver iterations, "
              f"log 48 Hz; medians of {args.repeat}, interleaved")
        print(f"{'robots':>6} {'what':<22} {'raw s':>7} {'mobot s':>8} {'wall ratio':>10} {'CPU ratio':>10}")
        for robots in (1, 10):
            path = work / f"bench{robots}.yaml"
            path.write_text(scenario_text(robots, args.seconds))
            prepared = prepare(path)
            results: dict[str, list[tuple[float, float]]] = {"raw": [], "run": [], "sim": []}
            for i in range(args.repeat):
                (work / f"raw{robots}-{i}").mkdir()
                results["raw"].append(timed(raw_loop, spec(prepared.plan, work), work / f"raw{robots}-{i}"))
                results["run"].append(timed(mobot_loop, prepared, work / f"mobot{robots}-{i}"))
                results["sim"].append(timed(mobot_sim_only, prepared, work))
            raw_wall = statistics.median(w for w, _ in results["raw"])
            raw_cpu = statistics.median(c for _, c in results["raw"])
            for key, label in (("run", "whole run (files, png)"), ("sim", "simulation loop only")):
                wall = statistics.median(w for w, _ in results[key])
                cpu = statistics.median(c for _, c in results[key])
                print(f"{robots:>6} {label:<22} {raw_wall:>7.3f} {wall:>8.3f} {wall / raw_wall:>10.3f} "
                      f"{cpu / raw_cpu:>10.3f}")
        mobot = shutil.which("mobot") or "mobot"
        real = Path(sys.executable).parent / "mobot"
        mobot = str(real) if real.exists() else mobot
        ten = work / "ten.yaml"
        ten.write_text(scenario_text(1, 10.0))
        subprocess.run([mobot, "run", str(ten), "--out", str(work / "warm"), "--quiet"], check=True)
        print(f"mobot --help, whole process:                {process_seconds([mobot, '--help'], 5):.3f} s")
        t = process_seconds([mobot, "run", str(ten), "--out", str(work / "ten"), "--quiet"], args.repeat)
        print(f"mobot run, 10 simulated s, whole process:   {t:.3f} s (warm cache)")
        sixty = work / "sixty.yaml"
        sixty.write_text(scenario_text(1, 60.0))
        plan = prepare(sixty).plan
        raw_spec = work / "raw.json"
        raw_spec.write_text(json.dumps(spec(plan, work)))
        raw_cmd = [sys.executable, str(Path(__file__).with_name("raw_run.py")), str(raw_spec), str(work)]
        mobot_out, alone_out, raw_out, inside_out = [], [], [], []  # (whole process, its loop) pairs
        alone = {**os.environ, "MOBOT_HELPER": "0"}
        probe = [sys.executable, str(Path(__file__).with_name("run_probe.py")), "run", str(sixty), "--quiet"]
        for i in range(args.repeat):  # interleaved: all four see the same load
            mobot_out.append((process_seconds([mobot, "run", str(sixty), "--out", str(work / f"sixty{i}"), "--quiet"],
                                              1), loop_seconds(plan)))
            alone_out.append((process_seconds([mobot, "run", str(sixty), "--out", str(work / f"alone{i}"), "--quiet"],
                                              1, env=alone), loop_seconds(plan)))
            started = time.perf_counter()
            loop = float(subprocess.run(raw_cmd, check=True, capture_output=True, text=True).stdout)
            raw_out.append((time.perf_counter() - started, loop))
            started = time.perf_counter()
            done = subprocess.run([*probe, "--out", str(work / f"inside{i}")], check=True, capture_output=True,
                                  text=True)
            inside_out.append((time.perf_counter() - started, float(done.stderr.split()[-1])))
        for label, pairs in (("mobot run", mobot_out), ("mobot run, MOBOT_HELPER=0", alone_out),
                             ("raw PyBullet script", raw_out), ("mobot run, its loop timed inside it", inside_out)):
            whole, loop = statistics.median(w for w, _ in pairs), statistics.median(lp for _, lp in pairs)
            outside = statistics.median(w - lp for w, lp in pairs)
            print(f"{label + ', one robot, 60 simulated s:':<52} whole process {whole:.3f} s, loop {loop:.3f} s, "
                  f"outside the loop {outside:.3f} s")
        extra = statistics.median((w - lp) - (rw - rlp) for (w, lp), (rw, rlp) in zip(mobot_out, raw_out))
        print(f"mobot's time outside the loop beyond the raw script's: {extra:.3f} s "
              f"(the issue's goal: <= 0.25 s outside when the raw script's was 0.15 s, so <= 0.10 s beyond it)")
        inside = statistics.median((w - lp) - (rw - rlp) for (w, lp), (rw, rlp) in zip(inside_out, raw_out))
        print(f"the same, both loops timed inside their own processes (bench/run_probe.py): {inside:.3f} s")
        # The goal was set where the raw script's fixed cost was 0.15 s: on a slower or busier machine
        # both grow, so their ratio is what carries over (the goal's: 0.25 / 0.15 = 1.67).
        ratio = statistics.median((w - lp) / (rw - rlp) for (w, lp), (rw, rlp) in zip(inside_out, raw_out))
        print(f"mobot's time outside the loop over the raw script's, pair by pair: {ratio:.2f}x "
              f"(so {0.15 * ratio:.3f} s where the raw script's is 0.15 s; the goal: <= 1.67x, 0.25 s)")
        print(f"mobot's own modules: {bytecode_state(REPO)}")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
