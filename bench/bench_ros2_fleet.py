#!/usr/bin/env python3
"""A fleet on ROS 2: real-time factor of `--ros2` runs with 10 and 100 robots, and where the time goes.

Every robot is the bundled one with its 2D lidar (``lidar:=true``: 360 beams at 10 Hz) and
publishes odometry, joint_states, /tf and its scan (and /clock goes out) at the log rate; a
subscriber process (Cyclone DDS, as a ROS 2 node's readers on loopback) takes every one of
these topics. Physics at the scenario default (240 Hz), log at 50 Hz. Reported per fleet:

* whole runs without and with the bridge, interleaved, best of ``--repeat``: real-time factor
  (simulated s / wall s) and CPU of the whole process;
* apart, CPU of one thread: simulating (physics, odometry, lidar rays) with and without the
  lidars; publishing the same records, split by record kind (samples: odom, joint_states,
  /tf, /clock; readings: scans) and into mobot's Python (building the CDR bytes) against the
  DDS writes (timed by running again with the write left out).

    python3 bench/bench_ros2_fleet.py [--robots 10 100] [--seconds 5] [--repeat 2] [--engine kinematic]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import subprocess
import sys
import tempfile
import textwrap
import time
from collections import defaultdict
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "tests"))
from conftest import LOOPBACK_DDS  # noqa: E402  (tests/conftest.py: loopback only)

os.environ.update(ROS_DOMAIN_ID=str(150 + os.getpid() % 50), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
                  CYCLONEDDS_URI=LOOPBACK_DDS)

from mobot_cli.plan import Ros2Settings  # noqa: E402
from mobot_cli.ros2 import dds, names  # noqa: E402
from mobot_cli.ros2 import publisher as publishing  # noqa: E402
from mobot_cli.ros2.bridge import Bridge  # noqa: E402
from mobot_cli.run import execute  # noqa: E402
from mobot_cli.scenario.prepare import prepare  # noqa: E402
from mobot_cli.timeline.loop import simulate  # noqa: E402

LISTENER = textwrap.dedent("""
    import os, sys, time
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    from mobot_cli.ros2 import idl
    dp = DomainParticipant(int(os.environ["ROS_DOMAIN_ID"]))
    readers = [DataReader(dp, Topic(dp, "rt/tf", idl.TFMessage)), DataReader(dp, Topic(dp, "rt/clock", idl.Clock))]
    for i in range(int(sys.argv[1])):
        for topic, kind in (("odom", idl.Odometry), ("scan", idl.LaserScan), ("joint_states", idl.JointState)):
            readers.append(DataReader(dp, Topic(dp, f"rt/r_{i}/{topic}", kind)))
    print("ready", flush=True)
    taken = 0
    while True:
        for r in readers:
            taken += len(r.take(1000))
        time.sleep(0.01)
""")


def scenario(robots: int, seconds: float, engine: str) -> str:
    side = max(1, round(robots ** 0.5))
    poses = ", ".join(f"[{(i % side) * 1.5}, {(i // side) * 1.5}, 0]" for i in range(robots))
    physics = "physics: {engine: kinematic, rate_hz: 50}\n" if engine == "kinematic" else ""
    return (f"version: 1\nname: bench_ros2_fleet\nduration: {seconds}\nsettle: 0.5\nlog: {{rate_hz: 50}}\n{physics}"
            f"robots:\n  - name: r_{{i}}\n    count: {robots}\n    args: {{lidar: 'true'}}\n    poses: [{poses}]\n"
            f"    commands: [{{at: 0.5, linear: 0.3, angular: 0.3}}]\n")


def run(prepared, out: Path, bridge: bool) -> tuple[float, float, object]:
    """(wall, CPU of every thread, bridge stats) of one whole run, as fast as it goes."""
    attachments = [Bridge(prepared.plan, Ros2Settings())] if bridge else []
    started, cpu = time.perf_counter(), time.process_time()
    execute(prepared.plan, prepared.resolved_yaml, out, attachments=attachments)
    return time.perf_counter() - started, time.process_time() - cpu, attachments[0].stats if bridge else None


def apart(prepared) -> dict[str, float]:
    """CPU of one thread: simulating, and publishing by record kind, with and without DDS writes."""
    started = time.thread_time()
    records = list(simulate(prepared.plan))
    out = {"simulate": time.thread_time() - started}
    blind = dataclasses.replace(prepared.plan,
                                robots=tuple(dataclasses.replace(r, sensors=()) for r in prepared.plan.robots))
    started = time.thread_time()
    for _ in simulate(blind):
        pass
    out["simulate without lidars"] = time.thread_time() - started
    participant = dds.Participant(int(os.environ["ROS_DOMAIN_ID"]), names.discovery_config(os.environ, True))
    topics = publishing.Topics(participant, "mobot", "/", 16)
    publisher = publishing.RecordPublisher(topics, prepared.plan.physics.rate_hz, lambda *a: None)
    first = next(i for i, r in enumerate(records) if type(r).__name__ == "Sample") + 1
    for record in records[:first]:  # every robot's writers made, the subscriber matched
        publisher(record)
    time.sleep(3.0)
    real_write = dds.ddspy_write
    for label in ("with DDS writes", "Python only"):
        kinds: dict[str, float] = defaultdict(float)
        sent = topics.sent
        for record in records[first:]:
            started = time.thread_time()
            publisher(record)
            kinds[type(record).__name__] += time.thread_time() - started
        out[f"messages ({label})"] = topics.sent - sent
        for kind, seconds in kinds.items():
            out[f"publish {kind} ({label})"] = seconds
        dds.ddspy_write = lambda ref, data: 0  # the second pass leaves the DDS write out
    dds.ddspy_write = real_write
    participant.close()
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, nargs="+", default=[10, 100])
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--engine", choices=("physics", "kinematic"), default="physics",
                        help="PyBullet at 240 Hz (default) or the kinematic engine at 50 Hz")
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="bench-fleet-"))
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    for robots in args.robots:
        (work / f"s{robots}.yaml").write_text(scenario(robots, args.seconds, args.engine))
        prepared = prepare(work / f"s{robots}.yaml")
        run(prepared, work / "warm", False)  # caches, imports
        listener = subprocess.Popen([sys.executable, "-c", LISTENER, str(robots)], env=env, stdout=subprocess.PIPE,
                                    text=True)
        listener.stdout.readline()
        results: dict[bool, list] = {False: [], True: []}
        try:
            costs = apart(prepared)
            for i in range(args.repeat):  # interleaved: a busy neighbour hits both alike
                for bridge in (False, True):
                    results[bridge].append(run(prepared, work / f"r{robots}_{i}_{bridge}", bridge))
        finally:
            listener.kill()
        print(f"{robots} robots, {args.engine} engine, {args.seconds:g} s simulated (+0.5 s settle), "
              f"360-beam scans at 10 Hz, "
              f"odom/joint_states/tf/clock at 50 Hz, a subscriber on every topic:")
        for bridge, runs in results.items():
            wall, cpu, stats = min(runs, key=lambda r: r[0])
            line = (f"  {'--ros2' if bridge else 'no bridge':10s} best wall {wall:6.2f} s: "
                    f"{(args.seconds + 0.5) / wall:5.2f}x real time (CPU {cpu:6.2f} s: "
                    f"{(args.seconds + 0.5) / cpu:5.2f}x)")
            if stats is not None:
                line += f"; {stats.messages} messages, {stats.dropped_samples} samples dropped"
            print(line)
        for key, value in costs.items():
            print(f"  apart: {key:40s} {value:9.3f}" + ("" if key.startswith("messages") else " s CPU"))


if __name__ == "__main__":
    main()
