#!/usr/bin/env python3
"""The kinematic engine against the physics engine, a raw PyBullet loop and the kinematic peers.

One robot drives a 60 s script (0.3 m/s; then 0.3 m/s at 0.3 rad/s; then 0.2 m/s at -0.2 rad/s,
20 s each) in the empty world; 100 robots drive arcs in the bundled house, bumping into walls,
furniture and each other. Every figure is the loop's real-time factor (simulated seconds per
wall second of stepping, world building and spawns excluded), the median of ``--repeat`` runs
taken in turn (kinematic, physics, raw, peers, kinematic, ...), since the machine may be shared.
The peers (IR-SIM, PyRoboSim) run in their own virtual environment, made on first use with
``--peers-venv`` (pip install ir-sim pyrobosim); without it their rows are skipped. Then
batches, whole processes timed from outside, interleaved: a 32-run ``mobot sweep --jobs 2`` of
the kinematic script against each peer running the same 32 runs one after the other in one
process (the issue's goal: mobot's runs per second >= 2x the faster peer's); and the engines
side by side on every bundled scenario: the README's table of final pose differences.

    python3 bench/bench_kinematic.py [--repeat 3] [--peers-venv ~/.cache/mobot-bench/peers]
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
SCRIPT = [(0.0, 0.3, 0.0), (20.0, 0.3, 0.3), (40.0, 0.2, -0.2)]  # (at s, linear, angular)
SECONDS, DT = 60.0, 0.1


# -- the peers: run with the peers' own Python, importing nothing of mobot's ------------------

def irsim_rtf(lidar: bool) -> float:
    """IR-SIM 2: one differential robot, the same script at dt 0.1, headless."""
    import irsim

    sensors = ("    sensors:\n      - {type: lidar2d, range_min: 0.1, range_max: 8.0, angle_range: 6.283185, "
               "number: 360}\n") if lidar else ""
    world = Path(tempfile.mkdtemp()) / "world.yaml"
    world.write_text(f"world:\n  height: 40\n  width: 40\n  step_time: {DT}\n  sample_time: {DT}\n"
                     "  offset: [-20, -20]\n  collision_mode: stop\n"
                     "robot:\n  - kinematics: {name: diff}\n    shape: {name: circle, radius: 0.2}\n"
                     "    state: [0, 0, 0]\n    vel_max: [1.0, 1.0]\n" + sensors)
    env = irsim.make(str(world), headless=True, log_level="ERROR")
    started = time.perf_counter()
    for k in range(round(SECONDS / DT)):
        _, linear, angular = [s for s in SCRIPT if s[0] <= k * DT][-1]
        env.step([linear, angular])
    return SECONDS / (time.perf_counter() - started)


def pyrobosim_rtf() -> float:
    """PyRoboSim 5: its test world's robot, dynamics step and collision check per step at dt 0.1."""
    import numpy as np
    from pyrobosim.core import WorldYamlLoader
    from pyrobosim.utils.general import get_data_folder

    world = WorldYamlLoader().from_file(get_data_folder() / "test_world.yaml")
    robot = world.robots[0]
    started = time.perf_counter()
    for k in range(round(SECONDS / DT)):
        _, linear, angular = [s for s in SCRIPT if s[0] <= k * DT][-1]
        target = robot.dynamics.step(np.array([linear, 0.0, angular]), DT)
        if not robot.is_in_collision(target):
            robot.dynamics.pose = target
    return SECONDS / (time.perf_counter() - started)


PEERS = {"irsim": lambda: irsim_rtf(False), "irsim-lidar": lambda: irsim_rtf(True), "pyrobosim": pyrobosim_rtf}


def peer_main(which: str) -> None:
    print(json.dumps({"rtf": PEERS[which]()}))


def peer_batch_main(which: str, runs: int) -> None:
    """A batch as a peer's user runs one: ``runs`` runs of the script one after the other in one
    process, each with its world made afresh."""
    for _ in range(runs):
        PEERS[which]()


# -- mobot ------------------------------------------------------------------------------------

def one_robot(engine: str, rate: int, lidar: bool = False) -> str:
    commands = ", ".join(f"{{at: {at:g}, linear: {v:g}, angular: {w:g}}}" for at, v, w in SCRIPT)
    sensors = ('    args: {lidar: "true"}\n    sensors: {lidar: {rate_hz: 10, samples: 360}}\n') if lidar else ""
    return (f"version: 1\nname: one\nduration: {SECONDS:g}\nsettle: 0\n"
            f"physics: {{rate_hz: {rate}, engine: {engine}}}\nlog: {{rate_hz: 10}}\n"
            f"robots:\n  - name: r\n    description: mobot\n{sensors}    commands: [{commands}]\n")


def house_poses(count: int, spacing: float = 0.8) -> list[tuple[float, float, float]]:
    """``count`` places in the bundled house where the bundled robot may spawn."""
    from mobot_cli.errors import MobotError
    from mobot_cli.scenario.prepare import prepare
    from mobot_cli.sim.engine import open_world

    plan = prepare(REPO / "scenarios" / "house.yaml", ["physics.engine=kinematic"]).plan
    robot, found = plan.robots[0], []
    with open_world(plan.physics, plan.world) as world:
        for j in range(40):
            for i in range(40):
                x, y = -6.0 + spacing * i, -4.8 + spacing * j
                pose = type(robot.pose)((x, y, 0.0), z_auto=True)
                name = f"p{len(found)}"
                try:
                    world.spawn(type(robot)(**{**robot.__dict__, "name": name, "namespace": "/" + name,
                                               "frame_prefix": name + "/", "pose": pose}))
                except MobotError:
                    continue
                found.append((round(x, 2), round(y, 2), 0.0))
                if len(found) == count:
                    return found
    return found


def fleet(engine: str, rate: int, poses, seconds: float, lidar: bool = False) -> str:
    listed = ", ".join(f"[{x}, {y}, {yaw}]" for x, y, yaw in poses)
    sensors = ('    args: {lidar: "true"}\n    sensors: {lidar: {rate_hz: 10, samples: 360}}\n') if lidar else ""
    return (f"version: 1\nname: fleet\nworld: house\nduration: {seconds:g}\nsettle: 0\n"
            f"physics: {{rate_hz: {rate}, engine: {engine}}}\nlog: {{rate_hz: 10}}\n"
            f"robots:\n  - name: r_{{i}}\n    description: mobot\n{sensors}    count: {len(poses)}\n"
            f"    poses: [{listed}]\n    commands: [{{at: 0, linear: 0.3, angular: 0.15}}]\n")


def mobot_rtf(path: Path) -> tuple[float, int]:
    """The loop's real-time factor for a scenario file (spawns excluded) and the collisions."""
    from mobot_cli.scenario.prepare import prepare
    from mobot_cli.sim.engine import open_world
    from mobot_cli.timeline.loop import Timeline

    plan = prepare(path).plan
    with open_world(plan.physics, plan.world, seed=plan.seed) as world:
        timeline = Timeline(plan, world)
        timeline.attach(lambda record: None)
        timeline.start()
        tick, advance = timeline.tick, timeline.advance
        started = time.perf_counter()
        for _ in range(plan.total_steps):
            tick()
            advance()
        tick()
        wall = time.perf_counter() - started
        hits = sum(world.read(name).collisions for name in world.names())
    return plan.total_steps / plan.physics.rate_hz / wall, hits


def raw_rtf(path: Path) -> float:
    """The same one-robot script as nothing but PyBullet calls at 240 Hz (bench_run.py's loop)."""
    from mobot_cli.scenario.prepare import prepare
    from mobot_cli.sim.bullet.urdf_file import urdf_path
    from mobot_cli.sim.pb import p

    plan = prepare(path).plan
    cid = p.connect(p.DIRECT)
    p.setPhysicsEngineParameter(fixedTimeStep=plan.physics.dt, numSolverIterations=50, numSubSteps=0,
                                deterministicOverlappingPairs=1, enableConeFriction=0, physicsClientId=cid)
    p.setGravity(0, 0, -9.81, physicsClientId=cid)
    p.createMultiBody(0, p.createCollisionShape(p.GEOM_PLANE, physicsClientId=cid), physicsClientId=cid)
    robot = plan.robots[0]
    uid = p.loadURDF(str(urdf_path(robot.urdf)), robot.pose.xyz, robot.pose.quat, physicsClientId=cid,
                     flags=p.URDF_USE_INERTIA_FROM_FILE | p.URDF_USE_IMPLICIT_CYLINDER)
    names = {p.getJointInfo(uid, j, physicsClientId=cid)[1].decode(): j
             for j in range(p.getNumJoints(uid, physicsClientId=cid))}
    wheels = [names[n] for n in robot.drive.left_joints + robot.drive.right_joints]
    half, r = robot.drive.wheel_separation / 2, robot.drive.wheel_radius
    changes = {round(at * plan.physics.rate_hz): ((v - w * half) / r, (v + w * half) / r) for at, v, w in SCRIPT}
    started = time.perf_counter()
    for step in range(plan.total_steps):
        if step in changes:
            p.setJointMotorControlArray(uid, wheels, p.VELOCITY_CONTROL, targetVelocities=changes[step],
                                        forces=[5.0, 5.0], physicsClientId=cid)
        if step % plan.log_every == 0:
            p.getBasePositionAndOrientation(uid, physicsClientId=cid)
            p.getBaseVelocity(uid, physicsClientId=cid)
            p.getJointStates(uid, wheels, physicsClientId=cid)
        p.stepSimulation(physicsClientId=cid)
    wall = time.perf_counter() - started
    p.disconnect(cid)
    return SECONDS / wall


def peer_rtf(venv: Path | None, which: str) -> float | None:
    if venv is None:
        return None
    done = subprocess.run([str(venv / "bin" / "python"), __file__, "--peer", which], capture_output=True, text=True)
    if done.returncode != 0:
        print(f"  ({which} failed: {done.stderr.strip().splitlines()[-1:]})")
        return None
    return json.loads(done.stdout.strip().splitlines()[-1])["rtf"]


def peer_batch_rate(venv: Path | None, which: str, runs: int = 32) -> float | None:
    """Runs per second of a peer's whole batch process (its start and imports included, as the
    sweep's are), one core."""
    if venv is None:
        return None
    started = time.perf_counter()
    done = subprocess.run([str(venv / "bin" / "python"), __file__, "--peer-batch", which, "--runs", str(runs)],
                          capture_output=True, text=True)
    if done.returncode != 0:
        print(f"  ({which} batch failed: {done.stderr.strip().splitlines()[-1:]})")
        return None
    return runs / (time.perf_counter() - started)


def sweep_rate(work: Path, runs: int = 32) -> tuple[float, float]:
    """(runs per second of a whole `mobot sweep --jobs 2`, median in-worker wall time of one run)."""
    path = work / "sweep.yaml"
    path.write_text(one_robot("kinematic", 10))
    seeds = ",".join(str(i) for i in range(runs))
    shutil.rmtree(work / "sweep", ignore_errors=True)
    started = time.perf_counter()
    subprocess.run([sys.executable, "-m", "mobot_cli", "sweep", str(path), "--grid", f"seed={seeds}",
                    "--jobs", "2", "--out", str(work / "sweep"), "--quiet"], check=True, cwd=REPO)
    wall = time.perf_counter() - started
    with (work / "sweep" / "results.csv").open() as f:
        walls = [float(row["wall_time"]) for row in csv.DictReader(f)]
    return runs / wall, statistics.median(walls)


def engines_table() -> list[str]:
    """Every bundled scenario in both engines: how far apart each robot ends (the README's table)."""
    from mobot_cli.scenario.prepare import prepare
    from mobot_cli.timeline.loop import simulate
    from mobot_cli.timeline.records import Sample

    lines = ["| scenario | robot | physics end (x, y, yaw) | kinematic end | distance | yaw |",
             "|---|---|---|---|---|---|"]
    for path in sorted((REPO / "scenarios").glob("*.yaml")):
        ends = []
        for overrides in ([], ["physics.engine=kinematic"]):
            last: dict = {}
            for record in simulate(prepare(path, overrides).plan):
                if isinstance(record, Sample):
                    last.update(record.states)
            ends.append(last)
        for name in ends[0]:
            a, b = ends[0][name], ends[1].get(name)
            if b is None:
                continue
            dist = math.hypot(a.true_x - b.true_x, a.true_y - b.true_y)
            yaw = abs((a.true_yaw - b.true_yaw + math.pi) % (2 * math.pi) - math.pi)
            lines.append(f"| {path.stem} | {name} | {a.true_x:.3f}, {a.true_y:.3f}, {a.true_yaw:.3f} | "
                         f"{b.true_x:.3f}, {b.true_y:.3f}, {b.true_yaw:.3f} | {dist * 100:.1f} cm | "
                         f"{math.degrees(yaw):.1f} deg |")
    return lines


def fmt(value: float | None) -> str:
    if value is None:
        return "-"
    return f"{value:,.0f}x" if value >= 10 else f"{value:.2g}x"  # a slow row must not print as 0x


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--peers-venv", type=Path, default=None, help="a venv with ir-sim and pyrobosim")
    parser.add_argument("--robots", type=int, default=100)
    parser.add_argument("--physics-fleet-seconds", type=float, default=1.0,
                        help="simulated seconds of the physics engine's fleet run (it is slow)")
    parser.add_argument("--skip-table", action="store_true")
    parser.add_argument("--rows", default="", help="only these rows, e.g. kin,pyrobosim,fleet-kin (keys of "
                        "`jobs`; the sweep then too only when 'sweep' is among them)")
    parser.add_argument("--peer", help=argparse.SUPPRESS)
    parser.add_argument("--peer-batch", help=argparse.SUPPRESS)
    parser.add_argument("--runs", type=int, default=32, help="runs of the sweep and of the peers' batches")
    args = parser.parse_args()
    if args.peer:
        return peer_main(args.peer)
    if args.peer_batch:
        return peer_batch_main(args.peer_batch, args.runs)
    sys.path.insert(0, str(REPO))
    work = Path(tempfile.mkdtemp(prefix="mobot-bench-kin-"))
    files = {}
    for key, text in {"kin": one_robot("kinematic", 10), "phys": one_robot("bullet", 240),
                      "kin-lidar": one_robot("kinematic", 10, lidar=True),
                      "phys-lidar": one_robot("bullet", 240, lidar=True)}.items():
        files[key] = work / f"{key}.yaml"
        files[key].write_text(text)
    poses = house_poses(args.robots)
    for key, (engine, rate, seconds, lidar) in {
            # 20 s of the fleets: their factors do not depend on the length, their wall time does
            "fleet-kin": ("kinematic", 10, 20.0, False), "fleet-kin-lidar": ("kinematic", 10, 20.0, True),
            "fleet-phys": ("bullet", 240, args.physics_fleet_seconds, False)}.items():
        files[key] = work / f"{key}.yaml"
        files[key].write_text(fleet(engine, rate, poses, seconds, lidar))
    rows: dict[str, list[float]] = {}
    hits: dict[str, int] = {}
    jobs = [("kin", lambda: mobot_rtf(files["kin"])), ("phys", lambda: mobot_rtf(files["phys"])),
            ("raw", lambda: (raw_rtf(files["phys"]), 0)),
            ("kin-lidar", lambda: mobot_rtf(files["kin-lidar"])),
            ("phys-lidar", lambda: mobot_rtf(files["phys-lidar"])),
            ("irsim", lambda: (peer_rtf(args.peers_venv, "irsim"), 0)),
            ("irsim-lidar", lambda: (peer_rtf(args.peers_venv, "irsim-lidar"), 0)),
            ("pyrobosim", lambda: (peer_rtf(args.peers_venv, "pyrobosim"), 0)),
            ("fleet-kin", lambda: mobot_rtf(files["fleet-kin"])),
            ("fleet-kin-lidar", lambda: mobot_rtf(files["fleet-kin-lidar"])),
            ("fleet-phys", lambda: mobot_rtf(files["fleet-phys"]))]
    rows_asked = set(filter(None, args.rows.split(",")))
    if rows_asked:
        jobs = [(key, job) for key, job in jobs if key in rows_asked]
    for _ in range(args.repeat):  # interleaved: every figure sees the same load
        for key, job in jobs:
            rtf, n = job()
            if rtf is not None:
                rows.setdefault(key, []).append(rtf)
                hits[key] = n
    med = {key: statistics.median(values) for key, values in rows.items()}
    get = med.get
    print(f"Loop real-time factor, medians of {args.repeat} interleaved runs (60 s script, dt 0.1 for the "
          f"kinematic engine and the peers, 240 Hz for the physics engine and raw PyBullet)\n")
    print("| | one robot | with a 360-beam lidar at 10 Hz |")
    print("|---|---|---|")
    print(f"| mobot kinematic, 10 Hz | {fmt(get('kin'))} | {fmt(get('kin-lidar'))} |")
    print(f"| mobot physics, 240 Hz | {fmt(get('phys'))} | {fmt(get('phys-lidar'))} |")
    print(f"| raw PyBullet loop, 240 Hz | {fmt(get('raw'))} | - |")
    print(f"| IR-SIM, dt 0.1 | {fmt(get('irsim'))} | {fmt(get('irsim-lidar'))} |")
    print(f"| PyRoboSim, dt 0.1 | {fmt(get('pyrobosim'))} | - |")
    print(f"| {len(poses)} robots in the house, kinematic 10 Hz | {fmt(get('fleet-kin'))} "
          f"({hits.get('fleet-kin', 0)} collisions) | {fmt(get('fleet-kin-lidar'))} |")
    print(f"| {len(poses)} robots in the house, physics 240 Hz | {fmt(get('fleet-phys'))} | - |")
    ratios = [("kinematic / physics", get("kin"), get("phys")), ("kinematic / PyRoboSim", get("kin"), get("pyrobosim")),
              ("kinematic / IR-SIM", get("kin"), get("irsim")),
              ("kinematic+lidar / IR-SIM+lidar", get("kin-lidar"), get("irsim-lidar")),
              ("fleet kinematic / physics", get("fleet-kin"), get("fleet-phys"))]
    print("\n" + "; ".join(f"{name}: {a / b:.1f}x" for name, a, b in ratios if a and b))
    if rows_asked and "sweep" not in rows_asked:
        return
    batches: dict[str, list[float]] = {}
    sweep_rate(work, 2)  # not counted: a new folder's first run expands the xacro and loads the world again
    for _ in range(args.repeat):  # interleaved, as above
        for key, job in (("sweep", lambda: sweep_rate(work, args.runs)),
                         ("irsim", lambda: (peer_batch_rate(args.peers_venv, "irsim", args.runs), 0.0)),
                         ("pyrobosim", lambda: (peer_batch_rate(args.peers_venv, "pyrobosim", args.runs), 0.0))):
            rate, per_run = job()
            if rate is not None:
                batches.setdefault(key, []).append(rate)
                batches.setdefault(key + "-run", []).append(per_run)
    batch = {key: statistics.median(values) for key, values in batches.items()}
    print(f"\n{args.runs}-run batches, whole processes, medians of {args.repeat}: `mobot sweep --jobs 2` of the "
          f"kinematic script {batch['sweep']:.1f} runs/s (one run {batch['sweep-run'] * 1000:.0f} ms in its "
          f"worker); one process, one core: IR-SIM {batch.get('irsim', 0):.1f} runs/s, PyRoboSim "
          f"{batch.get('pyrobosim', 0):.1f} runs/s")
    best = max(batch.get("irsim", 0), batch.get("pyrobosim", 0))
    if best:
        print(f"mobot's sweep / the faster peer's batch: {batch['sweep'] / best:.2f}x (goal >= 2x)")
    if not args.skip_table:
        print("\nEvery bundled scenario in both engines (final true pose):\n")
        print("\n".join(engines_table()))


if __name__ == "__main__":
    main()
