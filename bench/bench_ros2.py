#!/usr/bin/env python3
"""What does publishing to ROS 2 cost a run? Prints wall time with and without `--ros2`.

10 bundled robots with their 2D lidar (``lidar:=true``: 360 beams at 10 Hz) for 20 simulated
seconds at 250 Hz physics with odometry, joint states, /tf and /clock at 50 Hz: the scans go
out as a run makes them (``RobotMessages.reading``, the bag's bytes), and the lidar's ray
casting is part of the run on both sides. A subscriber process takes every odom, scan and
/tf (so those messages are built and sent; /clock and joint_states, unread, are not). Three
ways, interleaved: no bridge; the bridge publishing on the world's thread (the default); the
bridge's own thread. DDS stays on loopback (the same settings as the tests). Reports CPU
seconds of the whole process (every thread: steadier than wall time on a shared machine), the
overhead and messages per second.

    python3 bench/bench_ros2.py [--seconds 20] [--repeat 3]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
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

ROBOTS, RAYS = 10, 360  # the bundled robot's lidar: 360 beams at 10 Hz
LISTENER = textwrap.dedent("""
    import os, sys, time
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    from mobot_cli.ros2 import idl
    dp = DomainParticipant(int(os.environ["ROS_DOMAIN_ID"]))
    readers = [DataReader(dp, Topic(dp, "rt/tf", idl.TFMessage))]
    for i in range(int(sys.argv[1])):
        readers.append(DataReader(dp, Topic(dp, f"rt/r_{i}/odom", idl.Odometry)))
        readers.append(DataReader(dp, Topic(dp, f"rt/r_{i}/scan", idl.LaserScan)))
    print("ready", flush=True)
    while True:
        for r in readers:
            r.take(100)
        time.sleep(0.01)
""")


def scenario(seconds: float) -> str:
    poses = ", ".join(f"[{(i % 5) * 1.0}, {(i // 5) * 1.0}, 0]" for i in range(ROBOTS))
    return (f"version: 1\nname: bench_ros2\nduration: {seconds}\nsettle: 0.5\n"
            f"physics: {{rate_hz: 250}}\nlog: {{rate_hz: 50}}\n"
            f"robots:\n  - name: r_{{i}}\n    count: {ROBOTS}\n    args: {{lidar: 'true'}}\n    poses: [{poses}]\n"
            f"    commands: [{{at: 0.5, linear: 0.3, angular: 0.3}}]\n")


def run(prepared, out: Path, bridge: bool, threaded: bool = False) -> tuple[float, float, object]:
    """(wall, CPU of every thread of this process, bridge stats) of one run."""
    attachments = [Bridge(prepared.plan, Ros2Settings(), threaded=threaded)] if bridge else []
    started, cpu = time.perf_counter(), time.process_time()
    execute(prepared.plan, prepared.resolved_yaml, out, attachments=attachments)
    wall, cpu = time.perf_counter() - started, time.process_time() - cpu
    return wall, cpu, attachments[0].stats if attachments else None


def isolated_cost(prepared, repeat: int) -> None:
    """The same work measured apart, in CPU time of one thread: simulating the run (records
    only), then publishing its records with the subscriber listening, then the same with the
    DDS write left out (mobot's own Python)."""
    started = time.thread_time()
    records = list(simulate(prepared.plan))
    sim = time.thread_time() - started
    blind = dataclasses.replace(prepared.plan,
                                robots=tuple(dataclasses.replace(r, sensors=()) for r in prepared.plan.robots))
    started = time.thread_time()
    for _ in simulate(blind):
        pass
    sim_blind = time.thread_time() - started
    participant = dds.Participant(int(os.environ["ROS_DOMAIN_ID"]), names.discovery_config(os.environ, True))
    topics = publishing.Topics(participant, "mobot", "/", 16)
    publisher = publishing.RecordPublisher(topics, prepared.plan.physics.rate_hz, lambda *a: None)
    for record in records[:20]:  # writers made, the subscriber matched
        publisher(record)
    time.sleep(2.0)
    real_write, costs = dds.ddspy_write, []
    for _ in range(repeat):
        sent, started = topics.sent, time.thread_time()
        for record in records[20:]:
            publisher(record)
        cost, sent = time.thread_time() - started, topics.sent - sent
        dds.ddspy_write = lambda ref, data: 0
        started = time.thread_time()
        for record in records[20:]:
            publisher(record)
        python = time.thread_time() - started
        dds.ddspy_write = real_write
        costs.append((cost, python, sent))
    participant.close()
    cost, python, sent = (statistics.median(c[i] for c in costs) for i in range(3))
    print(f"  apart, CPU of one thread: simulating {sim:.3f} s ({sim_blind:.3f} s without casting the lidars' rays); "
          f"publishing {cost:.3f} s = {cost / sim * 100:.1f} % of it "
          f"({cost / sim_blind * 100:.1f} % of the run without rays) "
          f"({python:.3f} s mobot's Python, {cost - python:.3f} s DDS writes); {sent:.0f} messages, "
          f"{sent / cost:,.0f} per CPU second, {sent / (sim + cost):,.0f}/s at this run's pace")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="bench-ros2-"))
    (work / "s.yaml").write_text(scenario(args.seconds))
    prepared = prepare(work / "s.yaml")
    run(prepared, work / "warm", False)  # caches, imports
    modes = {"no bridge": (False, False), "bridge, sim thread": (True, False), "bridge, own thread": (True, True)}
    results: dict[str, list] = {label: [] for label in modes}
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    listener = subprocess.Popen([sys.executable, "-c", LISTENER, str(ROBOTS)], env=env, stdout=subprocess.PIPE,
                                text=True)
    listener.stdout.readline()
    print(f"{ROBOTS} robots, {args.seconds:g} s simulated, 250 Hz physics, 50 Hz odometry, "
          f"{RAYS}-ray scans at 10 Hz; a subscriber takes every odom, scan and /tf")
    try:
        isolated_cost(prepared, args.repeat)
        for i in range(args.repeat):  # interleaved, so that a busy neighbour hits every mode alike
            for label, (bridge, threaded) in modes.items():
                if listener.poll() is not None:
                    raise SystemExit("the subscriber process died")
                results[label].append(run(prepared, work / f"r{i}", bridge, threaded))
    finally:
        listener.kill()
    base_wall = statistics.median(w for w, _, _ in results["no bridge"])
    base_cpu = statistics.median(c for _, c, _ in results["no bridge"])
    print(f"  whole runs, interleaved, median of {args.repeat}; CPU = every thread of the process:")
    for label, runs in results.items():
        wall, cpu = statistics.median(w for w, _, _ in runs), statistics.median(c for _, c, _ in runs)
        line = f"  {label:32s} {wall:6.2f} s wall, {cpu:6.2f} s CPU"
        stats = [s for _, _, s in runs if s is not None]
        if stats:
            messages = statistics.median(s.messages for s in stats)
            busy = statistics.median(s.busy_seconds for s in stats)
            dropped = max(s.dropped_samples for s in stats)
            line += (f"  (+{(cpu - base_cpu) / base_cpu * 100:4.1f} % CPU, "
                     f"+{(wall - base_wall) / base_wall * 100:4.1f} % wall); "
                     f"{messages:.0f} msgs, {messages / wall:,.0f} msg/s, publishing {busy:.2f} s, "
                     f"{dropped} samples dropped")
        print(line)


if __name__ == "__main__":
    main()
