#!/usr/bin/env python3
"""What do sensors cost? Ray engines, a 2D lidar's share of a run, a VLP-16's pace and memory.

1. Ray engines on the same scene and rays: Embree (the static scene mobot casts) against
   PyBullet's rayTestBatch, in the bundled house and (with the corpus) the AWS small house.
2. The bundled house scenario, one robot: without sensors and with a 360-beam 2D lidar at 10 Hz
   (the bundled mobot's own <sensor>), interleaved, medians of --repeat; wall and CPU ratios.
3. jackal with a stock VLP-16 (1875 x 16 rays at 10 Hz) in the bundled house: the run's pace
   against real time, with the CSV and with the bag, and where the time goes.
4. Memory of that run over --memory-seconds simulated (csv + bag, every record streamed):
   RSS sampled as it goes, its peak, and the bytes written, extrapolated to one hour.

    python3 bench/bench_sensors.py [--seconds 20] [--repeat 3] [--memory-seconds 120]
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

import numpy as np  # noqa: E402
from common import timed  # noqa: E402  (bench/common.py)

from mobot_cli.plan import Physics, RayAxis, SensorSpec  # noqa: E402
from mobot_cli.run import execute  # noqa: E402
from mobot_cli.scenario.prepare import prepare  # noqa: E402
from mobot_cli.sim.bullet.world import World  # noqa: E402
from mobot_cli.sim.pb import p  # noqa: E402
from mobot_cli.sim.sensing import lidar  # noqa: E402
from mobot_cli.sim.sensing.raycast import StaticScene, forget_kept  # noqa: E402

CORPUS = REPO.parent / "shared" / "corpus"
MOBOT_LIDAR = SensorSpec(name="lidar", kind="lidar", link="lidar_link", every=24, topic="scan",
                         horizontal=RayAxis(360, -3.14159, 3.14159), range_min=0.12, range_max=12.0,
                         range_resolution=0.01)
VLP16 = SensorSpec(name="velodyne", kind="lidar", link="base_link", every=24, xyz=(0.0, 0.0, 0.45),
                   topic="mid/points", horizontal=RayAxis(1875, -math.pi, math.pi),
                   vertical=RayAxis(16, -math.radians(15), math.radians(15)), range_min=0.055,
                   range_max=140.0, range_resolution=0.001)


def engines(world_plan, label: str, where: list[tuple[float, float]]) -> None:
    """Embree against rayTestBatch on the same rays from a few places."""
    scene = StaticScene(world_plan)
    with World(Physics(), world_plan) as world:
        cid = world.client_id
        for spec in (MOBOT_LIDAR, VLP16):
            beams = lidar.Beams.of(spec)
            n = len(beams.directions)
            times = {"embree": [], "rayTestBatch": [], "rayTestBatch threads": []}
            for x, y in where:
                origin = np.array([x, y, 0.3])
                starts = origin + beams.directions * spec.range_min
                ends = origin + beams.directions * spec.range_max
                lengths = np.full(n, spec.range_max - spec.range_min)
                reps = 5 if n > 1000 else 30
                for name, call in (
                        ("embree", lambda: scene.cast(starts, beams.directions, lengths)),
                        ("rayTestBatch", lambda: _bullet(cid, starts, ends, 1)),
                        ("rayTestBatch threads", lambda: _bullet(cid, starts, ends, 0))):
                    started = time.process_time()
                    for _ in range(reps):
                        call()
                    times[name].append((time.process_time() - started) / reps)
            base = statistics.median(times["embree"])
            for name, values in times.items():
                t = statistics.median(values)
                print(f"  {label:<16} {spec.name:<9} {n:>6} rays  {name:<21} {t * 1e3:8.3f} ms CPU "
                      f"{n / t / 1e6:6.2f} M rays/s  x{t / base:5.1f}")


def _bullet(cid: int, starts, ends, threads: int) -> None:
    for i in range(0, len(starts), lidar.MAX_BATCH):
        p.rayTestBatch(starts[i:i + lidar.MAX_BATCH], ends[i:i + lidar.MAX_BATCH], numThreads=threads,
                       physicsClientId=cid)


def with_sensor(plan, spec, formats=None):
    robot = replace(plan.robots[0], sensors=(spec,))
    return replace(plan, robots=(robot,), **({"formats": formats} if formats else {}))


def house_share(seconds: float, repeat: int, work: Path) -> None:
    """The bundled house scenario, mobot with lidar:=true, with its 360-beam lidar off and on."""
    prepared = prepare(REPO / "scenarios" / "house.yaml", [f"duration={seconds}", "robots.mobot.args.lidar=true"])
    own = prepared.plan.robots[0].sensors  # the bundled mobot's own <sensor>: 10 Hz, noise, 1 cm steps
    assert [spec.kind for spec in own] == ["lidar"], own
    plans = {"no sensors": replace(prepared.plan, robots=(replace(prepared.plan.robots[0], sensors=()),)),
             "2D lidar 10 Hz": prepared.plan}
    results = {name: [] for name in plans}
    load = os.getloadavg()[0]  # a shared machine: ratios move with the load beside them
    for i in range(repeat):
        for name, plan in plans.items():
            forget_kept()  # each run builds its ray scene, as a `mobot run` does (a sweep's next run would not)
            results[name].append(timed(execute, plan, prepared.resolved_yaml, work / f"house-{i}-{len(name)}"))
    base_wall = statistics.median(w for w, _ in results["no sensors"])
    base_cpu = statistics.median(c for _, c in results["no sensors"])
    base_min = min(c for _, c in results["no sensors"])
    for name, values in results.items():
        wall, cpu = statistics.median(w for w, _ in values), statistics.median(c for _, c in values)
        least = min(c for _, c in values)  # the least disturbed run: steadier on a shared machine
        print(f"  {name:<16} {wall:7.3f} s wall  {cpu:7.3f} s CPU   wall x{wall / base_wall:5.3f}  "
              f"CPU x{cpu / base_cpu:5.3f}  least CPU x{least / base_min:5.3f}   ({seconds / wall:5.1f}x real time)")
    # Each lidar run against the run without sensors just before it: the spread of the ratio.
    pairs = sorted(c / b for (_, b), (_, c) in zip(results["no sensors"], results["2D lidar 10 Hz"]))
    quarter = len(pairs) // 4
    print(f"  lidar / no sensors, CPU, run by run: median x{statistics.median(pairs):5.3f}, middle half "
          f"x{pairs[quarter]:5.3f}-x{pairs[-1 - quarter]:5.3f}, all x{pairs[0]:5.3f}-x{pairs[-1]:5.3f} "
          f"({len(pairs)} pairs; load average {load:.1f} before, {os.getloadavg()[0]:.1f} after, "
          f"on {os.cpu_count()} cores)")


def jackal_plan(seconds: float, formats: tuple[str, ...]):
    folder = Path(tempfile.mkdtemp(prefix="mobot-bench-jackal-"))
    desc = CORPUS / "jackal/jackal_description/urdf/jackal.urdf.xacro"
    (folder / "s.yaml").write_text(
        f"version: 1\nname: jackal_vlp16\nworld: house\nduration: {seconds}\nseed: 1\n"
        f"robots:\n  - name: jackal\n    description: {desc}\n    args: {{gazebo_controllers: /dev/null}}\n"
        f"    pose: {{x: -3.0, y: -2.5}}\n    commands: [{{at: 0.5, linear: 0.3, angular: 0.1}}]\n")
    prepared = prepare(folder / "s.yaml")
    return with_sensor(prepared.plan, VLP16, formats), prepared.resolved_yaml


def jackal_pace(seconds: float, work: Path) -> None:
    """jackal + VLP-16 in the house: pace (wall, and CPU time, steadier on a shared machine), and
    the share of casting the rays (scans are cast when read, a few at a time: the CPU time inside
    lidar.cast and lidar.cast_scans)."""
    spent = {"cast": 0.0}
    originals = {name: getattr(lidar, name) for name in ("cast", "cast_scans")}

    def timing(call):
        def timed_call(*args, **kwargs):
            started = time.process_time()
            try:
                return call(*args, **kwargs)
            finally:
                spent["cast"] += time.process_time() - started
        return timed_call

    for name, call in originals.items():
        setattr(lidar, name, timing(call))
    try:
        bare, resolved = jackal_plan(seconds, ("csv",))
        bare = replace(bare, robots=(replace(bare.robots[0], sensors=()),))
        wall, cpu = timed(execute, bare, resolved, work / "jackal-bare")
        print(f"  {'no sensors':<22} {wall:7.3f} s wall {cpu:7.3f} s CPU  {seconds / wall:5.1f}x real time "
              f"({seconds / cpu:5.1f}x by CPU time)")
        for formats in (("csv",), ("csv", "mcap")):
            plan, resolved = jackal_plan(seconds, formats)
            spent["cast"] = 0.0
            wall, cpu = timed(execute, plan, resolved, work / f"jackal-{len(formats)}")
            rays = 1875 * 16 * 10 * seconds
            print(f"  {'VLP-16, ' + '+'.join(formats):<22} {wall:7.3f} s wall {cpu:7.3f} s CPU  "
                  f"{seconds / wall:5.1f}x real time ({seconds / cpu:5.1f}x by CPU time), "
                  f"{rays / cpu / 1e6:5.2f} M rays per CPU second overall; casting {spent['cast']:.3f} s CPU "
                  f"({rays / spent['cast'] / 1e6:.2f} M rays/s), records and physics the rest")
    finally:
        for name, call in originals.items():
            setattr(lidar, name, call)


def memory(seconds: float, work: Path) -> None:
    """RSS over a long jackal + VLP-16 run with every record streamed to disk."""
    plan, resolved = jackal_plan(seconds, ("csv", "mcap"))
    out = work / "jackal-memory"
    samples: list[tuple[float, float]] = []
    every = max(1, int(plan.physics.rate_hz * seconds / 12))

    def progress(step: int, total: int) -> None:
        if step % every < plan.log_every:
            samples.append((step / plan.physics.rate_hz, _rss_mb()))

    started = time.perf_counter()
    execute(plan, resolved, out, progress)
    wall = time.perf_counter() - started
    written = sum(f.stat().st_size for f in out.rglob("*") if f.is_file())
    ranges = (out / "sensors/jackal/velodyne.npy").stat().st_size
    print("  RSS while running: " + ", ".join(f"{t:.0f} s: {m:.0f} MB" for t, m in samples))
    print(f"  peak RSS {_peak_mb():.0f} MB; {seconds:g} s simulated in {wall:.1f} s; wrote {written / 1e6:.0f} MB "
          f"({ranges / 1e6:.0f} MB of ranges); one hour would write {written * 3600 / seconds / 1e9:.1f} GB "
          f"with RSS flat (no whole-run arrays)")


def _rss_mb() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def _peak_mb() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=20.0, help="simulated seconds per timed run")
    parser.add_argument("--repeat", type=int, default=3, help="runs per figure (the median is shown)")
    parser.add_argument("--memory-seconds", type=float, default=120.0, help="simulated seconds of the memory run")
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="mobot-bench-sensors-"))
    house = prepare(REPO / "scenarios" / "house.yaml").plan.world
    print("1. ray engines, same rays (CPU time per scan, medians over 3 places)")
    engines(house, "bundled house", [(-3.0, -2.5), (2.0, -1.0), (-4.0, 3.0)])
    aws = CORPUS / "aws-robomaker-small-house-world/worlds/small_house.world"
    if aws.is_file():
        folder = Path(tempfile.mkdtemp(prefix="mobot-bench-aws-"))
        (folder / "s.yaml").write_text(f"version: 1\nname: aws\nworld: {aws}\nduration: 1\n")
        engines(prepare(folder / "s.yaml").plan.world, "AWS small house", [(-3.0, 1.0), (2.0, -1.0), (6.0, 2.0)])
    print(f"2. bundled house, one robot, {args.seconds:g} s simulated, whole runs (medians of {args.repeat})")
    house_share(args.seconds, args.repeat, work)
    if (CORPUS / "jackal").is_dir():
        os.environ.setdefault("MOBOT_RESOURCE_PATH", ":".join(
            str(CORPUS / pkg) for pkg in ("jackal", "velodyne_simulator")))
        print(f"3. jackal + VLP-16 (1875 x 16 at 10 Hz) in the bundled house, {args.seconds:g} s simulated")
        jackal_pace(args.seconds, work)
        print(f"4. memory: jackal + VLP-16, {args.memory_seconds:g} s simulated, csv + bag + sensors/")
        memory(args.memory_seconds, work)


if __name__ == "__main__":
    main()
