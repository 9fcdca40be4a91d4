"""Sensors in the World: lidar ranges against exact geometry, IMU at rest, contacts, noise."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from mobot_cli.common.transforms import quat_matrix
from mobot_cli.errors import SpawnError
from mobot_cli.plan import RayAxis, SensorSpec, StaticBody, StaticShape, WorldPlan
from mobot_cli.scenario.prepare import prepare
from mobot_cli.sim.bullet.world import World
from mobot_cli.sim.sensing import lidar as lidar_rays
from mobot_cli.sim.sensing.raycast import StaticScene, shape_triangles
from tests.sim.sensor_world import HALF_X, HALF_Y, lidar, one_robot, planned, room_distance, room_scenario, with_sensors


def _world(plan):
    world = World(plan.physics, plan.world, seed=plan.seed)
    for robot in plan.robots:
        world.spawn(robot)
    return world


def _directions(data) -> np.ndarray:
    return data.beams.directions @ np.array(quat_matrix(data.quat)).T


def test_2d_scan_matches_the_room_within_a_centimetre(tmp_path):
    plan, _ = planned(one_robot(tmp_path), "mobot", lidar(xyz=(0.0, 0.0, 0.3), range_max=3.0))
    with _world(plan) as world:
        (scan,) = world.sense([("mobot", "scan")])
    exact = room_distance(scan.position, _directions(scan))
    ranges = scan.ranges.reshape(-1).astype(float)
    near = exact <= 3.0
    assert scan.ranges.dtype == np.float32 and scan.ranges.shape == (1, 360)
    assert near.sum() > 100 and (~near).sum() > 50  # both cases are exercised
    assert np.max(np.abs(ranges[near] - exact[near])) < 0.01
    assert np.all(np.isposinf(ranges[~near]))  # beyond range_max: +inf (REP 117)


def test_beam_angles_are_gazebos_exactly():
    spec = lidar(samples=360, lo=-math.pi, hi=math.pi)
    beams = lidar_rays.Beams.of(spec)
    step = 2 * math.pi / 359
    assert lidar_rays.angle_step(spec.horizontal) == step
    assert beams.horizontal[0] == -math.pi and beams.horizontal[-1] == pytest.approx(math.pi, abs=1e-15)
    assert np.array_equal(beams.horizontal, -math.pi + step * np.arange(360))
    single = lidar_rays.Beams.of(lidar(samples=1, lo=0.25, hi=0.25))
    assert single.horizontal.tolist() == [0.25] and lidar_rays.angle_step(RayAxis(1, 0.25, 0.25)) == 0.0


def test_3d_points_lie_on_the_walls_and_floor(tmp_path):
    velodyne = lidar("velodyne", samples=450, vertical=RayAxis(16, -0.2618, 0.2618), range_max=30.0,
                     xyz=(0.0, 0.0, 0.4))
    plan, _ = planned(one_robot(tmp_path), "mobot", velodyne)
    with _world(plan) as world:
        (scan,) = world.sense([("mobot", "velodyne")])
    points = scan.world_points()
    assert scan.ranges.shape == (16, 450) and len(points) == 16 * 450  # a closed room: every beam returns
    off = np.min(np.abs(np.stack([np.abs(points[:, 0]) - HALF_X, np.abs(points[:, 1]) - HALF_Y,
                                  points[:, 2]])), axis=0)
    assert np.max(off) < 0.01
    exact = room_distance(scan.position, _directions(scan))
    assert np.max(np.abs(scan.ranges.reshape(-1) - exact)) < 0.01


def test_embree_and_pybullet_agree_in_a_mesh_house(corpus, tmp_path):
    """The static scene against PyBullet's own ray test, in the AWS house (meshes, 87 models)."""
    house = corpus / "aws-robomaker-small-house-world" / "worlds" / "small_house.world"
    plan = prepare(one_robot(tmp_path, x=-3.0, y=1.0, yaw=0.0, world=str(house))).plan
    scene = StaticScene(plan.world)
    assert scene.complete and len(scene.triangles) > 10000
    with World(plan.physics, plan.world) as world:
        beams = lidar_rays.Beams.of(lidar(samples=720, vertical=RayAxis(8, -0.3, 0.3), range_max=12.0))
        rng = np.random.default_rng(3)
        for x, y in ((-3.0, 1.0), (2.0, -1.0), (6.0, 2.0)):
            job = lidar_rays.ScanJob(lidar(range_max=12.0), beams, np.array([x, y, 0.5 + rng.random()]),
                                     np.eye(3), own_body=-2)
            fast = lidar_rays.cast(world.client_id, scene, [job], {})[0]
            slow = lidar_rays.cast(world.client_id, None, [job], {})[0]
            both = np.isfinite(fast) & np.isfinite(slow)
            assert np.array_equal(np.isfinite(fast), np.isfinite(slow)) or \
                np.mean(np.isfinite(fast) != np.isfinite(slow)) < 0.002
            assert np.mean(np.abs(fast[both] - slow[both]) < 0.01) > 0.995


@pytest.mark.parametrize("kind, size", [("cylinder", (0.4, 1.0)), ("sphere", (0.3,)), ("capsule", (0.2, 0.6)),
                                        ("cylinder", (2.5, 0.5))])
def test_round_shapes_are_cast_within_a_millimetre(kind, size):
    """Rays from 3 m away aimed at the axis, at every heading and height: the true surface's distance."""
    shape = StaticShape(kind=kind, size=size)
    world = WorldPlan(ground_plane=False, bodies=(StaticBody(name="round", shapes=(shape,), xyz=(1.0, 2.0, 3.0)),))
    scene = StaticScene(world)
    rng = np.random.default_rng(5)
    heading = rng.uniform(0, 2 * math.pi, 500)
    r, half = size[0], (size[1] / 2 if len(size) > 1 else 0.0)
    z = rng.uniform(-half, half, 500) if half else np.zeros(500)
    dirs = np.stack([-np.cos(heading), -np.sin(heading), np.zeros(500)], axis=1)
    origins = np.array([1.0, 2.0, 3.0]) + np.stack([np.cos(heading) * (r + 3), np.sin(heading) * (r + 3), z], axis=1)
    t = scene.cast(origins, dirs, np.full(500, 10.0))
    exact = np.full(500, 3.0) if kind != "sphere" else (r + 3) - np.sqrt(r * r - z * z)
    assert np.max(np.abs(t - exact)) < 0.001
    assert len(shape_triangles(shape)) > 32


def test_own_links_never_appear_but_other_robots_do(tmp_path):
    robots = ("  - name: a\n    description: mobot\n    args: {lidar: 'true'}\n    pose: {x: -1.5, y: 0.0}\n"
              "  - name: b\n    description: mobot\n    pose: {x: 0.5, y: 0.0, yaw: 1.5707963}\n")
    # a: one lidar inside its lidar link (range_min 0: the link's own cylinder is around it) and
    # one behind its chassis looking forward through it.
    inside = lidar("inside", link="lidar_link", range_min=0.0, range_max=6.0)
    behind = lidar("behind", samples=31, lo=-0.15, hi=0.15, range_min=0.0, range_max=6.0,
                   xyz=(-0.35, 0.0, 0.03))
    plan, _ = planned(room_scenario(tmp_path, robots), "a", inside, behind)
    with _world(plan) as world:
        first, through = world.sense([("a", "inside"), ("a", "behind")])
        from mobot_cli.sim.pb import p

        # The reference: PyBullet's own ray test from 0.5 m out, past a's chassis (it ends 0.45 m ahead).
        dirs = _directions(through)
        starts = np.array(through.position) + 0.5 * dirs
        found = p.rayTestBatch(starts, starts + 5.5 * dirs, physicsClientId=world.client_id)
        b_body = world.body_id("b")
    # Above b's chassis (0.17 m up), the lidar in a's own lidar link sees only the room's walls.
    exact = room_distance(first.position, _directions(first))
    assert np.max(np.abs(first.ranges.reshape(-1) - exact)) < 0.01
    # Through a's own chassis, 8 cm up: b (across the x axis 2 m ahead) in the middle beams, walls
    # at the sides, as PyBullet sees them from beyond the chassis.
    expected = np.array([0.5 + 5.5 * hit[2] for hit in found])
    assert [hit[0] == b_body for hit in found].count(True) >= 9
    assert np.max(np.abs(through.ranges.reshape(-1) - expected)) < 0.01


def test_imu_at_rest_reads_gravity_up_and_turns_with_the_robot(tmp_path):
    imu = SensorSpec(name="imu", kind="imu", link="base_link", every=1)
    plan, _ = planned(one_robot(tmp_path, yaw=0.7), "mobot", imu)
    with _world(plan) as world:
        for _ in range(240):
            world.step()
        world.sense([("mobot", "imu")])
        world.step()
        (reading,) = world.sense([("mobot", "imu")])
    assert reading.linear_acceleration == pytest.approx((0.0, 0.0, 9.81), abs=0.02)
    assert reading.angular_velocity == pytest.approx((0.0, 0.0, 0.0), abs=1e-3)
    x, y, z, w = reading.orientation
    assert 2 * math.atan2(z, w) == pytest.approx(0.7, abs=1e-3) and abs(x) + abs(y) < 1e-3


def test_imu_reads_the_turn_rate_and_centripetal_acceleration(tmp_path):
    """Spinning in place at 1 rad/s with the IMU 0.2 m ahead of the axle: w = 1, a_y = -0.2 m/s^2."""
    imu = SensorSpec(name="imu", kind="imu", link="base_link", every=12, xyz=(0.2, 0.0, 0.0))
    plan, _ = planned(one_robot(tmp_path, x=0.0, y=0.0, yaw=0.0), "mobot", imu)
    with _world(plan) as world:
        world.set_command("mobot", 0.0, 1.0)
        readings = []
        for step in range(1, 481):
            world.step()
            if step % 12 == 0:
                readings.extend(world.sense([("mobot", "imu")]))
    late = readings[-10:]
    assert np.mean([r.angular_velocity[2] for r in late]) == pytest.approx(1.0, abs=0.05)
    assert np.mean([r.linear_acceleration[0] for r in late]) == pytest.approx(-0.2, abs=0.05)
    assert np.mean([r.linear_acceleration[2] for r in late]) == pytest.approx(9.81, abs=0.05)


def test_bumper_feels_the_wall_not_the_floor(tmp_path):
    bumper = SensorSpec(name="bumper", kind="contact", link="base_link", every=12)
    plan, _ = planned(one_robot(tmp_path, x=2.5, y=0.0, yaw=0.0), "mobot", bumper)
    with _world(plan) as world:
        (standing,) = world.sense([("mobot", "bumper")])
        world.set_command("mobot", 0.4, 0.0)
        for _ in range(480):
            world.step()
        (pushing,) = world.sense([("mobot", "bumper")])
    assert standing.contacts == ()
    assert pushing.contacts and all("walls" in c.other for c in pushing.contacts)
    assert all(c.normal[0] < -0.9 and c.force > 0.0 for c in pushing.contacts)  # the wall pushes back (-x)


def test_noise_is_seeded_by_the_run_seed_and_the_names(tmp_path):
    noisy = lidar(noise_stddev=0.02, range_max=3.0)

    def scan(seed: int, name: str = "scan"):
        plan, _ = planned(one_robot(tmp_path), "mobot", dataclasses.replace(noisy, name=name), seed=seed)
        with _world(plan) as world:
            return world.sense([("mobot", name)])[0].ranges

    first, again, other_seed, other_name = scan(1), scan(1), scan(2), scan(1, "scan2")
    assert first.tobytes() == again.tobytes()
    assert first.tobytes() != other_seed.tobytes() and first.tobytes() != other_name.tobytes()
    plan, _ = planned(one_robot(tmp_path), "mobot", dataclasses.replace(noisy, noise_stddev=0.0), seed=1)
    with _world(plan) as world:
        clean = world.sense([("mobot", "scan")])[0].ranges
    finite = np.isfinite(clean) & np.isfinite(first)
    error = first[finite] - clean[finite]
    assert 0.012 < np.std(error) < 0.028 and abs(np.mean(error)) < 0.005


def test_a_sensor_on_a_missing_link_refuses_the_spawn(tmp_path):
    plan, _ = planned(one_robot(tmp_path), "mobot", lidar(link="laser_frame"))
    with World(plan.physics, plan.world) as world:
        with pytest.raises(SpawnError, match="sensor 'scan' is on link 'laser_frame'"):
            world.spawn(plan.robots[0])
        assert world.names() == []


def test_many_scans_at_one_step_are_cast_together(tmp_path, monkeypatch):
    """Two robots' lidars due at the same step cost one Embree call."""
    robots = ("  - name: a\n    description: mobot\n    pose: {x: -1.5, y: 0.0}\n"
              "  - name: b\n    description: mobot\n    pose: {x: 1.5, y: 0.0, yaw: 3.14159}\n")
    prepared = prepare(room_scenario(tmp_path, robots))
    mid = lidar(xyz=(0.0, 0.0, 0.05))  # halfway up the chassis, through its own chassis
    plan = with_sensors(with_sensors(prepared.plan, "a", mid), "b", mid)
    calls = []
    original = StaticScene.cast
    monkeypatch.setattr(StaticScene, "cast", lambda self, *a: calls.append(len(a[0])) or original(self, *a))
    with _world(plan) as world:
        a, b = world.sense([("a", "scan"), ("b", "scan")])
    assert calls == [720]
    # each sees the other's chassis front (0.1 m ahead of its axle) 2.9 m ahead
    angle = a.beams.horizontal[180]
    assert float(a.ranges[0, 180]) == pytest.approx(2.9 / math.cos(angle), abs=0.01)
    assert float(b.ranges[0, 180]) == pytest.approx(2.9 / math.cos(angle), abs=0.01)
