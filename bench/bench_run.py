#!/usr/bin/env python3
"""How much does mobot cost over raw PyBullet? Prints wall-time ratios and start-up figures.

For 1 and 10 bundled robots it runs the same scenario twice: through mobot's ``execute``
(timeline, drive controllers, odometry, CSV sinks) and through a hand-written PyBullet loop
on the same URDF text, rate, solver iterations and logging rate (velocity motors set when a
command changes, base state and wheel joints read and a CSV row written at the log rate).
Then it times whole processes: ``mobot --help``, a 10-simulated-second ``mobot run``, and the
fixed cost of a run: a whole ``mobot run`` of one robot for 60 simulated s minus its loop (the
same plan's ``simulate`` from its first record to its last, in this warm process; goal <= 0.25 s).

    python3 bench/bench_run.py [--seconds 20] [--repeat 3]
"""

from __future__ import annotations

import argparse
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
from mobot_cli.sim.bullet import p  # noqa: E402

from common import process_seconds, timed  # noqa: E402  (bench/common.py)


def scenario_text(robots: int, seconds: float) -> str:
    """N bundled robots 1 m apart, each driving a circle after settling."""
    poses = ", ".join(f"[{(i % 5) * 1.0}, {(i // 5) * 1.0}, 0]" for i in range(robots))
    return (f"version: 1\nname: bench{robots}\nduration: {seconds}\nsettle: 0.5\n"
            f"physics: {{rate_hz: 240, solver_iterations: 50}}\nlog: {{rate_hz: 48}}\n"
            f"robots:\n  - name: r_{{i}}\n    count: {robots}\n    poses: [{poses}]\n"
            f"    commands: [{{at: 0.5, linear: 0.3, angular: 0.3}}]\n")


def raw_loop(plan, out_dir: Path) -> None:
    """The same physics with nothing but PyBullet calls."""
    cid = p.connect(p.DIRECT)
    # The same engine settings mobot uses (see mobot_cli/sim/world.py), so only mobot's own
    # work (timeline, controllers, odometry, sinks) differs between the two loops.
    p.setPhysicsEngineParameter(fixedTimeStep=plan.physics.dt, numSolverIterations=plan.physics.solver_iterations,
                                numSubSteps=0, deterministicOverlappingPairs=1, enableConeFriction=0,
                                physicsClientId=cid)
    p.setGravity(*plan.physics.gravity, physicsClientId=cid)
    plane = p.createMultiBody(0, p.createCollisionShape(p.GEOM_PLANE, physicsClientId=cid), physicsClientId=cid)
    p.changeDynamics(plane, -1, lateralFriction=1.0, physicsClientId=cid)
    urdf = out_dir / "robot.urdf"
    urdf.write_text(plan.robots[0].urdf)
    bodies = []
    for robot in plan.robots:
        uid = p.loadURDF(str(urdf), robot.pose.xyz, robot.pose.quat, physicsClientId=cid,
                         flags=p.URDF_USE_INERTIA_FROM_FILE | p.URDF_USE_IMPLICIT_CYLINDER)
        names = {p.getJointInfo(uid, j, physicsClientId=cid)[1].decode(): j
                 for j in range(p.getNumJoints(uid, physicsClientId=cid))}
        for link in range(-1, len(names)):
            p.changeDynamics(uid, link, lateralFriction=1.0, linearDamping=0.0, angularDamping=0.0,
                             activationState=p.ACTIVATION_STATE_DISABLE_SLEEPING, physicsClientId=cid)
        wheels = [names[n] for n in robot.drive.left_joints + robot.drive.right_joints]
        bodies.append((uid, wheels, open(out_dir / f"{robot.name}.csv", "w")))
    drive = plan.robots[0].drive
    cmd = plan.robots[0].commands[0]
    half = drive.wheel_separation / 2
    left, right = (cmd.linear - cmd.angular * half) / drive.wheel_radius, (cmd.linear + cmd.angular * half) / drive.wheel_radius
    for step in range(plan.total_steps + 1):
        if step == cmd.step:
            for uid, wheels, _ in bodies:
                p.setJointMotorControlArray(uid, wheels, p.VELOCITY_CONTROL, targetVelocities=[left, right],
                                            forces=[drive.max_wheel_torque] * 2, physicsClientId=cid)
        if step % plan.log_every == 0:
            for uid, wheels, f in bodies:
                pos, orn = p.getBasePositionAndOrientation(uid, physicsClientId=cid)
                lin, ang = p.getBaseVelocity(uid, physicsClientId=cid)
                joints = p.getJointStates(uid, wheels, physicsClientId=cid)
                rpy = p.getEulerFromQuaternion(orn)
                values = (step / plan.physics.rate_hz, *pos, *rpy, *lin, *ang, joints[0][0], joints[1][0])
                f.write(",".join(f"{v:.6f}" for v in values) + "\n")
        if step < plan.total_steps:
            p.stepSimulation(physicsClientId=cid)
    for _, _, f in bodies:
        f.close()
    p.disconnect(cid)


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
                results["raw"].append(timed(raw_loop, prepared.plan, work / f"raw{robots}-{i}"))
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
        wholes, loops = [], []
        for i in range(args.repeat):  # interleaved: both see the same load
            wholes.append(process_seconds([mobot, "run", str(sixty), "--out", str(work / f"sixty{i}"), "--quiet"], 1))
            loops.append(loop_seconds(plan))
        whole, loop = statistics.median(wholes), statistics.median(loops)
        outside = statistics.median(w - lp for w, lp in zip(wholes, loops))
        print(f"mobot run, one robot, 60 simulated s: whole process {whole:.3f} s, loop {loop:.3f} s, "
              f"outside the loop {outside:.3f} s (goal <= 0.25 s)")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
