#!/usr/bin/env python3
"""How much does mobot cost over raw PyBullet? Prints wall-time ratios, loop and whole process.

For 1 and 10 bundled robots it runs the same scenario twice in this process: through mobot's
``execute`` (timeline, drive controllers, odometry, CSV sinks, trajectory.png) and through a
hand-written PyBullet loop on the same URDF text, rate, solver iterations and logging rate
(bench/raw_run.py: velocity motors set when a command changes, base state and wheel joints read
and a CSV row written at the log rate). Then it times whole processes side by side, interleaved
so that both see the same load: a one-robot ``mobot run`` (start-up, the scenario read and
checked, the run, its folder) against ``python3 bench/raw_run.py`` doing the same steps and CSV,
and prints their ratio. The goal: a whole ``mobot run`` at most 2x the raw script. Beside them
runs the raw script importing mobot's chosen libraries first (``raw_run.py --libraries``): the
floor any command line on those libraries starts from.

    python3 bench/bench_run.py [--seconds 10] [--repeat 3]
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from common import bytecode_state, process_seconds, timed  # noqa: E402  (bench/common.py)
from raw_run import raw_loop  # noqa: E402  (bench/raw_run.py)

from mobot_cli.run import execute  # noqa: E402
from mobot_cli.scenario.prepare import prepare  # noqa: E402
from mobot_cli.timeline.loop import simulate  # noqa: E402


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


def mobot_csv(prepared, out_dir: Path) -> None:
    """The loop with its CSV written (as raw_run.py writes its own): no trajectory.png; the few
    lines of summary.json left to the page cache, as a sweep's run leaves them."""
    execute(prepared.plan, prepared.resolved_yaml, out_dir, durable=False, pictures=False)


def mobot_sim_only(prepared, out_dir: Path) -> None:
    """mobot's timeline alone (spawn checks, drive, odometry, contacts, reads), no files."""
    for _ in simulate(prepared.plan):  # every record, nothing written
        pass


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0, help="simulated seconds per run")
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
            results: dict[str, list[tuple[float, float]]] = {"raw": [], "run": [], "csv": [], "sim": []}
            for i in range(args.repeat):
                (work / f"raw{robots}-{i}").mkdir()
                results["raw"].append(timed(raw_loop, spec(prepared.plan, work), work / f"raw{robots}-{i}"))
                results["run"].append(timed(mobot_loop, prepared, work / f"mobot{robots}-{i}"))
                results["csv"].append(timed(mobot_csv, prepared, work / f"csv{robots}-{i}"))
                results["sim"].append(timed(mobot_sim_only, prepared, work))
            raw_wall = statistics.median(w for w, _ in results["raw"])
            raw_cpu = statistics.median(c for _, c in results["raw"])
            for key, label in (("run", "whole run (files, png)"), ("csv", "loop and its CSV"),
                               ("sim", "simulation loop only")):
                wall = statistics.median(w for w, _ in results[key])
                cpu = statistics.median(c for _, c in results[key])
                print(f"{robots:>6} {label:<22} {raw_wall:>7.3f} {wall:>8.3f} {wall / raw_wall:>10.3f} "
                      f"{cpu / raw_cpu:>10.3f}")
        mobot = shutil.which("mobot") or "mobot"
        real = Path(sys.executable).parent / "mobot"
        mobot = str(real) if real.exists() else mobot
        print(f"mobot --help, whole process: {process_seconds([mobot, '--help'], 5):.3f} s")
        one = work / "one.yaml"
        one.write_text(scenario_text(1, args.seconds))
        plan = prepare(one).plan
        raw_spec = work / "raw.json"
        raw_spec.write_text(json.dumps(spec(plan, work)))
        subprocess.run([mobot, "run", str(one), "--out", str(work / "warm"), "--quiet"], check=True)  # caches filled
        triples = []  # (mobot run, raw script, raw script after the libraries) seconds, interleaved
        raw_script = [sys.executable, str(Path(__file__).with_name("raw_run.py")), str(raw_spec)]
        for i in range(args.repeat):
            (work / f"raw{i}").mkdir()
            (work / f"libs{i}").mkdir()
            run = process_seconds([mobot, "run", str(one), "--out", str(work / f"one{i}"), "--quiet"], 1)
            raw = process_seconds([*raw_script, str(work / f"raw{i}")], 1)
            libs = process_seconds([*raw_script, str(work / f"libs{i}"), "--libraries"], 1)
            triples.append((run, raw, libs))
        run, raw, libs = (statistics.median(t[k] for t in triples) for k in range(3))
        ratio = statistics.median(r / w for r, w, _ in triples)
        floor = statistics.median(f / w for _, w, f in triples)
        print(f"one robot, {args.seconds:g} simulated s, whole process: mobot run {run:.3f} s, "
              f"raw PyBullet script {raw:.3f} s, the raw script importing mobot's libraries first {libs:.3f} s")
        print(f"mobot run over the raw script, pair by pair: {ratio:.2f}x (the goal: <= 2x); the libraries "
              f"alone (Typer, pydantic, PyYAML, Pillow): {floor:.2f}x, leaving {(2 * raw - libs) * 1000:.0f} ms "
              f"of the 2x for mobot's own work (it takes {(run - libs) * 1000:.0f} ms)")
        print(f"mobot's own modules: {bytecode_state(REPO)}")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
