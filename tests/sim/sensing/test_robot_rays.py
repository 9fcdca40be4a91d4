"""Lidar rays at other robots with Embree (sim/sensing/robot_scene.py) against PyBullet's ray test.

Robots of every collision shape (box, implicit and mesh cylinders, sphere, capsule, a mesh
collided as its hull), on several links with offset and turned frames, moved, tilted and with
a joint turned; ranges of a 3D scan compared beam by beam with ``rayTestBatch`` on the same rays.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from mobot_cli.common.polygon import ROUND_TOLERANCE
from mobot_cli.plan import RayAxis, StaticBody, StaticShape, WorldPlan
from mobot_cli.sim.bullet.world import World
from mobot_cli.sim.pb import p
from mobot_cli.sim.sensing import lidar
from mobot_cli.sim.sensing.raycast import StaticScene
from mobot_cli.sim.sensing.rig import _aabb
from mobot_cli.sim.sensing.robot_scene import RobotShapes, robot_links
from tests.sim.sensor_world import lidar as lidar_spec
from tests.sim.sensor_world import planned, room_scenario

SHAPES_URDF = Path(__file__).resolve().parents[2] / "data" / "robot_shapes" / "shapes.urdf"
WALL = StaticBody(name="wall", shapes=(StaticShape(kind="box", size=(0.2, 8.0, 2.0)),), xyz=(4.0, 0.0, 1.0))
SPEC = lidar_spec(samples=720, vertical=RayAxis(9, -0.3, 0.3), range_min=0.1, range_max=8.0)


@pytest.fixture
def crowd():
    """A PyBullet client with a wall, the ground and eight robots of every shape around the
    origin (half loaded with implicit cylinders as mobot loads URDFs, half with mesh ones)."""
    cid = p.connect(p.DIRECT)
    try:
        wall = p.createCollisionShape(p.GEOM_BOX, halfExtents=(0.1, 4.0, 1.0), physicsClientId=cid)
        p.createMultiBody(0, wall, basePosition=WALL.xyz, physicsClientId=cid)
        p.createMultiBody(0, p.createCollisionShape(p.GEOM_PLANE, physicsClientId=cid), physicsClientId=cid)
        rng = np.random.default_rng(1)
        bodies = []
        for i in range(8):
            angle, distance = 2 * math.pi * i / 8, 1.2 + 0.8 * rng.random()
            quat = p.getQuaternionFromEuler([0.3 * rng.random(), 0.3 * rng.random(), 2 * math.pi * rng.random()])
            body = p.loadURDF(str(SHAPES_URDF), [distance * math.cos(angle), distance * math.sin(angle),
                                                 0.1 + 0.2 * rng.random()], quat,
                              flags=p.URDF_USE_IMPLICIT_CYLINDER if i % 2 == 0 else 0, physicsClientId=cid)
            p.resetJointState(body, 0, rng.uniform(-1.2, 1.2), physicsClientId=cid)
            bodies.append(body)
        yield cid, bodies, rng
    finally:
        p.disconnect(cid)


def _scan(cid: int, bodies: list[int], z: float, shapes: RobotShapes, own: int = -2):
    """(Embree ranges, PyBullet's first hits on the same rays, the rays' directions)."""
    scene = StaticScene(WorldPlan(ground_plane=True, bodies=(WALL,)))
    job = lidar.ScanJob(SPEC, lidar.Beams.of(SPEC), np.array([0.0, 0.0, z]), np.eye(3, dtype=np.float32), own)
    ranges = lidar.cast(cid, scene, [job], {}, shapes.rays(bodies))[0].reshape(-1)
    origins, dirs = lidar._rays(job)
    hits = p.rayTestBatch(origins.astype(float), (origins + dirs * (SPEC.range_max - SPEC.range_min)).astype(float),
                          physicsClientId=cid)
    return ranges, hits, dirs


def _compare(ranges, hits, dirs, bodies):
    """Per beam: PyBullet's range, whether it met a robot, and |cos| of its incidence."""
    reference = np.array([SPEC.range_min + h[2] * (SPEC.range_max - SPEC.range_min) if h[0] >= 0 else np.inf
                          for h in hits])
    robot = np.array([h[0] in bodies for h in hits])
    incidence = np.abs((np.array([h[4] for h in hits]) * dirs).sum(axis=1))
    both_inf = np.isinf(ranges) & np.isinf(reference)
    diff = np.abs(np.where(both_inf, 0.0, ranges) - np.where(both_inf, 0.0, reference))
    return diff, robot, incidence


def test_every_shape_agrees_with_pybullets_ray_test(crowd):
    cid, bodies, rng = crowd
    shapes = RobotShapes(cid)
    assert all(shapes.links(body) is not None for body in bodies)
    for z in (0.3, 0.5):
        for turn in range(2):  # then every robot moved, turned and its joint turned again
            ranges, hits, dirs = _scan(cid, bodies, z, shapes)
            diff, robot, incidence = _compare(ranges, hits, dirs, bodies)
            steep = robot & (incidence >= 0.5)
            assert robot.sum() > 600 and steep.sum() > 400  # the robots fill a good part of the scan
            # Beams that met no robot in PyBullet: the static world's answer, as before, but for a
            # few that graze a robot's surface PyBullet's convex cast misses.
            assert np.mean(diff[~robot] < 1e-5) > 0.995
            # Beams at a robot's surface within 60 degrees of its normal: within the polygons'
            # tolerance along the normal (0.5 mm, twice that across a sphere's quads) plus PyBullet's
            # own error (up to ~1 mm at 8 m). Measured: 99.4-99.7 % within 2 mm, all within 2.6 mm.
            assert np.mean(diff[steep] < 0.002) > 0.99 and np.max(diff[steep]) < 0.003
            assert np.median(diff[steep]) < 1e-5  # flat faces: PyBullet's answer to float32
            assert np.mean(diff[robot] < 0.003) > 0.95  # grazing beams included (measured 0.96-0.98)
            for body in bodies:
                xyz, quat = p.getBasePositionAndOrientation(body, physicsClientId=cid)
                yaw = rng.uniform(-0.5, 0.5)
                p.resetBasePositionAndOrientation(body, np.array(xyz) * 1.1,
                                                  p.multiplyTransforms((0, 0, 0), quat, (0, 0, 0),
                                                                       p.getQuaternionFromEuler([0, 0, yaw]))[1],
                                                  physicsClientId=cid)
                p.resetJointState(body, 0, rng.uniform(-1.2, 1.2), physicsClientId=cid)


def test_a_mesh_is_its_hull_grown_by_pybullets_margin(crowd):
    """The wedge's inner vertex is no corner, and its faces lie 1 mm out, where PyBullet's rays meet them."""
    cid, bodies, _ = crowd
    wedge = [link for link in robot_links(cid, bodies[0]) if link.index == 1][0]
    assert len(wedge.faces) == 8  # a hull of six corners: the seventh vertex is inside
    ranges, hits, dirs = _scan(cid, bodies, 0.3, RobotShapes(cid))
    diff, robot, incidence = _compare(ranges, hits, dirs, bodies)
    on_wedge = robot & np.array([h[1] == 1 for h in hits]) & (incidence >= 0.5)
    assert on_wedge.sum() > 50 and np.median(diff[on_wedge]) < 1e-5 and np.max(diff[on_wedge]) < 0.001


def test_a_robot_never_sees_itself(crowd):
    """A sensor inside its own robot's shapes sees what it would see were its robot not there."""
    cid, bodies, _ = crowd
    own = bodies[0]
    centre = np.array(p.getBasePositionAndOrientation(own, physicsClientId=cid)[0])
    scene = StaticScene(WorldPlan(ground_plane=True, bodies=(WALL,)))
    job = lidar.ScanJob(SPEC, lidar.Beams.of(SPEC), centre, np.eye(3, dtype=np.float32), own)
    shapes = RobotShapes(cid)
    seen = lidar.cast(cid, scene, [job], {}, shapes.rays(bodies))[0]
    without = lidar.cast(cid, scene, [job], {}, shapes.rays(bodies[1:]))[0]
    assert np.array_equal(np.isfinite(seen), np.isfinite(without))  # stepping past its own surfaces
    finite = np.isfinite(seen)
    assert np.max(np.abs(seen[finite] - without[finite])) < 1e-5  # costs float32 rounding
    old = lidar.cast(cid, scene, [job], {body: _aabb(cid, body) for body in bodies})[0]  # PyBullet, as before
    close = np.isfinite(old) & np.isfinite(seen) & (np.abs(np.where(np.isfinite(seen), seen, 0.0) - old) < 0.003)
    assert np.mean(close | (np.isinf(old) & np.isinf(seen))) > 0.97


def test_the_same_scan_twice_is_the_same_bytes(crowd):
    cid, bodies, _ = crowd
    first = _scan(cid, bodies, 0.4, RobotShapes(cid))[0]
    again = _scan(cid, bodies, 0.4, RobotShapes(cid))[0]
    assert first.tobytes() == again.tobytes()


def test_round_shapes_are_within_their_tolerance_of_the_true_surface(tmp_path):
    """A lone upright cylinder of the bundled robot's lidar size: rays at its axis from every
    heading meet it within ROUND_TOLERANCE (0.5 mm) inside the exact circle."""
    urdf = tmp_path / "can.urdf"
    urdf.write_text('<robot name="can"><link name="b"><inertial><mass value="1"/><inertia ixx="1" iyy="1" '
                    'izz="1" ixy="0" ixz="0" iyz="0"/></inertial><collision><geometry><cylinder radius="0.035" '
                    'length="0.04"/></geometry></collision></link></robot>')
    cid = p.connect(p.DIRECT)
    try:
        body = p.loadURDF(str(urdf), (1.0, 2.0, 0.5), flags=p.URDF_USE_IMPLICIT_CYLINDER, physicsClientId=cid)
        heading = np.linspace(0.0, 2 * math.pi, 500, endpoint=False)
        dirs = np.stack([-np.cos(heading), -np.sin(heading), np.zeros(500)], axis=1).astype(np.float32)
        origins = (np.array([1.0, 2.0, 0.5]) - dirs * 3.0).astype(np.float32)
        t = RobotShapes(cid).rays([body]).cast(origins, dirs, np.full(500, 5.0, np.float32), np.full(500, -2),
                                               np.array([[1.0, 2.0, 0.5]]), np.array([8.0]))
    finally:
        p.disconnect(cid)
    assert np.all(t >= 3.0 - 0.035 - 1e-5) and np.all(t <= 3.0 - 0.035 + ROUND_TOLERANCE + 1e-5)
    assert np.max(t) > 3.0 - 0.035 + 0.8 * ROUND_TOLERANCE  # a polygon, not the circle


def test_spawned_and_deleted_robots_are_seen_where_they_are(tmp_path):
    """A lidar among bundled robots: one deleted is gone from the next scan, and one spawned
    after it (PyBullet may give it the same body id) is seen where it stands."""
    robots = ("  - name: a\n    description: mobot\n    args: {lidar: 'true'}\n    pose: {x: -1.5, y: 0.0}\n"
              "  - name: b\n    description: mobot\n    args: {lidar: 'true'}\n    pose: {x: 0.5, y: 0.0}\n")
    ahead = lidar_spec(link="lidar_link", samples=361, range_min=0.12, range_max=12.0)  # beam 180 looks along +x
    plan, _ = planned(room_scenario(tmp_path, robots), "a", ahead)
    b = plan.robots[1]
    with World(plan.physics, plan.world, seed=plan.seed) as world:
        for robot in plan.robots:
            world.spawn(robot)
        (first,) = world.sense([("a", "scan")])
        world.remove("b")
        (alone,) = world.sense([("a", "scan")])
        world.spawn(dataclasses.replace(b, pose=dataclasses.replace(b.pose, xyz=(1.5, 0.0, b.pose.xyz[2]))))
        (moved,) = world.sense([("a", "scan")])
    # a's lidar looks at b's lidar cylinder (radius 35 mm) at its own height, then at the east wall.
    assert float(first.ranges[0, 180]) == pytest.approx(2.0 - 0.035, abs=ROUND_TOLERANCE + 1e-5)
    assert float(alone.ranges[0, 180]) == pytest.approx(4.5, abs=0.001)
    assert float(moved.ranges[0, 180]) == pytest.approx(3.0 - 0.035, abs=ROUND_TOLERANCE + 1e-5)


def test_a_shape_without_triangles_is_left_to_pybullet(crowd):
    """A robot made of a flat plate (no hull: Qhull refuses flat points) is cast at by
    rayTestBatch, as every robot was before, beside the others on Embree."""
    cid, bodies, _ = crowd
    plate = p.createCollisionShape(p.GEOM_MESH, vertices=[(0, -0.3, 0.0), (0, 0.3, 0.0), (0, 0.3, 0.6), (0, -0.3, 0.6)],
                                   physicsClientId=cid)
    body = p.createMultiBody(1.0, plate, basePosition=(-0.9, 0.0, 0.1), physicsClientId=cid)
    shapes = RobotShapes(cid)
    robots = shapes.rays([*bodies, body])
    assert shapes.links(body) is None and robots.bodies == bodies
    scene = StaticScene(WorldPlan(ground_plane=True, bodies=(WALL,)))
    spec = lidar_spec(samples=361, range_min=0.1, range_max=8.0)  # beam 0 looks along -x, at the plate
    job = lidar.ScanJob(spec, lidar.Beams.of(spec), np.array([0.0, 0.0, 0.4]), np.eye(3, dtype=np.float32), -2)
    ranges = lidar.cast(cid, scene, [job], {body: _aabb(cid, body)}, robots)[0]
    origins, dirs = lidar._rays(job)
    ends = origins[:1] + dirs[:1] * 7.9
    hit = p.rayTestBatch(origins[:1].astype(float), ends.astype(float), physicsClientId=cid)[0]
    assert hit[0] == body and float(ranges[0, 0]) == pytest.approx(0.1 + 7.9 * hit[2], abs=1e-5)
    assert float(ranges[0, 0]) == pytest.approx(0.9, abs=0.002)


def test_corpus_robots_agree_with_pybullets_ray_test(corpus, monkeypatch, tmp_path):
    """turtlebot3 burger, husky (a mesh) and jackal, as mobot loads them, around a 3D lidar."""
    from mobot_cli.assets import load_robot
    from mobot_cli.plan import Physics, RobotPlan, SpawnPose

    monkeypatch.setenv("MOBOT_RESOURCE_PATH", ":".join(str(corpus / pkg) for pkg in
                                                        ("turtlebot3", "husky", "jackal", "velodyne_simulator")))
    monkeypatch.setenv("MOBOT_CACHE_DIR", str(tmp_path / "cache"))
    cases = {"burger": ("turtlebot3/turtlebot3_description/urdf/turtlebot3_burger.urdf.xacro", {}),
             "husky": ("husky/husky_description/urdf/husky.urdf.xacro", {"gazebo_controllers": "/dev/null"}),
             "jackal": ("jackal/jackal_description/urdf/jackal.urdf.xacro", {"gazebo_controllers": "/dev/null"})}
    world = WorldPlan(ground_plane=True)
    with World(Physics(), world) as sim:
        cid, bodies = sim.client_id, []
        for i, (name, (path, args)) in enumerate(cases.items()):
            desc = load_robot(str(corpus / path), args)
            angle = 2 * math.pi * i / len(cases)
            pose = SpawnPose(xyz=(2.0 * math.cos(angle), 2.0 * math.sin(angle), 0.0),
                             quat=p.getQuaternionFromEuler([0, 0, 1.7 * angle]), z_auto=True)
            sim.spawn(RobotPlan(name=name, namespace=f"/{name}", frame_prefix=f"{name}/", urdf=desc.urdf,
                                root_link=desc.root_link, pose=pose, drive=desc.drive))
            bodies.append(sim.body_id(name))
        shapes = RobotShapes(cid)
        assert all(shapes.links(body) is not None for body in bodies)
        assert any(shape[2] == p.GEOM_MESH for link in range(-1, p.getNumJoints(bodies[1], physicsClientId=cid))
                   for shape in p.getCollisionShapeData(bodies[1], link, physicsClientId=cid))  # husky's mesh
        spec = lidar_spec(samples=900, vertical=RayAxis(16, -0.4, 0.2), range_min=0.1, range_max=8.0)
        for z in (0.1, 0.25):
            job = lidar.ScanJob(spec, lidar.Beams.of(spec), np.array([0.0, 0.0, z]), np.eye(3, dtype=np.float32), -2)
            ranges = lidar.cast(cid, StaticScene(world), [job], {}, shapes.rays(bodies))[0].reshape(-1)
            origins, dirs = lidar._rays(job)
            hits = p.rayTestBatch(origins.astype(float), (origins + dirs * 7.9).astype(float), physicsClientId=cid)
            diff, robot, incidence = _compare(ranges, hits, dirs, bodies)
            steep = robot & (incidence >= 0.5)
            assert steep.sum() > 300
            assert np.mean(diff[steep] < 0.002) > 0.985  # measured 0.991-0.996
            assert np.mean(diff[robot] < 0.003) > 0.95 and np.mean(diff[~robot] < 1e-5) > 0.995
