"""Scans that wait and are cast together give the numbers of scans cast one by one, noise and all."""

from __future__ import annotations

import dataclasses

import numpy as np

from mobot_cli.plan import RayAxis
from mobot_cli.sim.bullet.world import World
from mobot_cli.sim.pb import p
from mobot_cli.sim.sensing import lidar as lidar_rays
from mobot_cli.sim.sensing.raycast import StaticScene
from mobot_cli.sim.sensing.rig import MAX_WAITING_SCANS, noise_rng
from tests.sim.sensor_world import lidar, one_robot, planned

NOISY = lidar(xyz=(0.0, 0.0, 0.3), range_max=3.0, noise_stddev=0.02, range_resolution=0.01)
CLOUD = lidar("velodyne", samples=300, vertical=RayAxis(16, -0.26, 0.26), range_max=30.0, xyz=(0.0, 0.0, 0.4),
              noise_stddev=0.008, range_resolution=0.001)


def _drive(world: World, scans: int, every: int = 7) -> list:
    """``scans`` readings of both lidars while the robot turns and drives, none of them read."""
    world.set_command("mobot", 0.4, 0.9)
    taken = []
    for _ in range(scans):
        taken.append(world.sense([("mobot", "scan"), ("mobot", "velodyne")]))
        for _ in range(every):
            world.step()
    return taken


def _noised(spec, rng: np.random.Generator, ranges: np.ndarray) -> np.ndarray:
    """The <noise> and <range><resolution> of the README: gaussian on returns, clamped, then
    rounded to the resolution; +inf stays +inf."""
    noisy = ranges + rng.normal(spec.noise_mean, spec.noise_stddev, ranges.shape).astype(np.float32)
    out = np.where(np.isfinite(ranges), np.clip(noisy, spec.range_min, spec.range_max), ranges)
    step = np.float32(spec.range_resolution)
    return (np.round(out / step) * step).astype(np.float32)


def test_waiting_scans_are_the_scans_cast_one_by_one(tmp_path):
    plan, _ = planned(one_robot(tmp_path, duration=5.0), "mobot", NOISY, CLOUD)
    with World(plan.physics, plan.world, seed=plan.seed) as world:
        world.spawn(plan.robots[0])
        taken = _drive(world, 2 * MAX_WAITING_SCANS + 7)  # more than wait at once: cast in turns
        scene = StaticScene(plan.world)
        body = world.body_id("mobot")
        for spec, column in ((NOISY, 0), (CLOUD, 1)):
            rng = noise_rng(plan.seed, "mobot", spec.name)
            beams = lidar_rays.Beams.of(spec)
            for reading in taken:
                scan = reading[column]
                rotation = np.array(p.getMatrixFromQuaternion(scan.quat), dtype=np.float32).reshape(3, 3)
                job = lidar_rays.ScanJob(spec, beams, np.array(scan.position), rotation, body)
                (alone,) = lidar_rays.cast(world.client_id, scene, [job], {})
                expected = _noised(spec, rng, alone)
                assert scan.ranges.dtype == np.float32 and scan.ranges.tobytes() == expected.tobytes()
    moved = np.ptp([r[0].position[0] for r in taken])
    assert moved > 0.3  # the scans were taken at different poses


def test_a_second_robot_casts_the_waiting_scans_first(tmp_path):
    """Scans taken alone, then with another robot in the room (cast at once, robots and all):
    the same ranges as when each scan is read as soon as it is taken, so noise stays in order."""
    plan, _ = planned(one_robot(tmp_path, duration=5.0), "mobot", NOISY, CLOUD)
    mobot = plan.robots[0]
    pose = dataclasses.replace(mobot.pose, xyz=(-1.5, -1.0, mobot.pose.xyz[2]))
    other = dataclasses.replace(mobot, name="other", namespace="/other", frame_prefix="other/", sensors=(),
                                pose=pose)
    runs = []
    for read_at_once in (False, True):
        with World(plan.physics, plan.world, seed=plan.seed) as world:
            world.spawn(plan.robots[0])
            first = _drive(world, 5)
            if read_at_once:
                [scan.ranges for reading in first for scan in reading]
            world.spawn(other)
            later = _drive(world, 4)
            runs.append([scan.ranges.tobytes() for reading in first + later for scan in reading])
    assert runs[0] == runs[1]
