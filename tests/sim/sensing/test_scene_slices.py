"""Level lidars are cast at a slice of the static scene: the same bits as the whole scene."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.common.transforms import quat_matrix
from mobot_cli.plan import RayAxis, StaticBody, StaticShape, WorldPlan
from mobot_cli.scenario.prepare import prepare
from mobot_cli.sim.sensing import lidar as lidar_rays
from mobot_cli.sim.sensing.raycast import SLICE_BAND, StaticScene
from tests.sim.sensor_world import lidar

REPO = Path(__file__).resolve().parents[3]


def _whole(scene: StaticScene, origins, dirs, lengths) -> np.ndarray:
    """The rays cast at every triangle of the scene (what casting was before slices)."""
    out = scene._scene.run(origins, dirs, dists=lengths.copy(), query="DISTANCE")
    out[out >= lengths] = np.inf
    return out


def _scans(spec, positions, yaws, pitch: float = 0.0):
    """The float32 rays of scans at these poses (a yaw each, all pitched alike), as cast_scans lays them."""
    rotations = np.array([quat_matrix((0.0, math.sin(pitch / 2), 0.0, math.cos(pitch / 2))) for _ in yaws])
    turn = np.array([[[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0], [0.0, 0.0, 1.0]]
                     for a in yaws])
    rotations = (turn @ rotations).astype(np.float32)
    beams = lidar_rays.Beams.of(spec)
    dirs = np.matmul(beams.directions32, rotations.transpose(0, 2, 1))
    origins = dirs * np.float32(spec.range_min) + np.asarray(positions, np.float32)[:, None, :]
    lengths = np.tile(beams.lengths32, len(yaws))
    return origins.reshape(-1, 3), dirs.reshape(-1, 3), lengths, beams, rotations


def test_a_level_scan_in_the_house_is_cast_at_a_slice_with_the_same_bits():
    world = prepare(REPO / "scenarios" / "house.yaml").plan.world
    scene = StaticScene(world)
    spec = lidar(range_min=0.12, range_max=12.0)
    xs = np.linspace(-3.0, 1.5, 20)
    positions = np.stack([xs, np.full(20, -2.5), np.full(20, 0.17)], axis=1)
    origins, dirs, lengths, beams, rotations = _scans(spec, positions, np.linspace(0.0, 2.0, 20), pitch=0.002)
    heights = lidar_rays.heights(beams, spec.range_max, positions.astype(np.float32), rotations)
    got = scene.cast(origins, dirs, lengths, heights)
    assert got.tobytes() == _whole(scene, origins, dirs, lengths).tobytes()
    assert np.isfinite(got).mean() > 0.99  # walls all round: the rays did meet triangles
    ((low, high, sliced),) = scene._slices
    assert sliced is not scene._scene and low < 0.17 - 0.002 * 12 and high > 0.17 + 0.002 * 12
    assert high - low < 0.2
    # a second batch a little lower is cast at the same slice (no new BVH)
    again = scene.cast(origins - np.float32([0, 0, 0.01]), dirs, lengths)
    assert len(scene._slices) == 1 and np.isfinite(again).mean() > 0.99


@pytest.mark.parametrize("z", [0.3, 0.5, 0.5 + 1e-4, 0.7, 0.7 - 1e-4, 0.9, 1.2])
def test_rays_at_the_edges_of_shapes_hit_what_the_whole_scene_hits(z):
    """Boxes and a cylinder whose tops and bottoms lie at the rays' height: a slice keeps them."""
    world = WorldPlan(ground_plane=True, bodies=(
        StaticBody(name="low", shapes=(StaticShape(kind="box", size=(1.0, 1.0, 0.5)),), xyz=(2.0, 0.0, 0.25)),
        StaticBody(name="high", shapes=(StaticShape(kind="box", size=(1.0, 1.0, 0.4)),), xyz=(-2.0, 0.0, 0.9)),
        StaticBody(name="drum", shapes=(StaticShape(kind="cylinder", size=(0.4, 0.2)),), xyz=(0.0, 2.0, 0.6)),
        StaticBody(name="far", shapes=(StaticShape(kind="box", size=(20.0, 0.2, 3.0)),), xyz=(0.0, -3.0, 1.5))))
    scene = StaticScene(world)
    spec = lidar(samples=720, range_min=0.0, range_max=8.0)
    origins, dirs, lengths, _, _ = _scans(spec, [(0.0, 0.0, z)], [0.1])
    got = scene.cast(origins, dirs, lengths)
    assert got.tobytes() == _whole(scene, origins, dirs, lengths).tobytes()
    assert len(scene._slices) == 1


def test_rays_below_every_shape_meet_only_the_ground_plane():
    world = WorldPlan(ground_plane=True, bodies=(
        StaticBody(name="shelf", shapes=(StaticShape(kind="box", size=(1.0, 1.0, 0.5)),), xyz=(2.0, 0.0, 1.25)),))
    scene = StaticScene(world)
    spec = lidar(samples=90, range_min=0.0, range_max=20.0)
    origins, dirs, lengths, beams, rotations = _scans(spec, [(0.0, 0.0, 0.1)], [0.0], pitch=0.01)  # nose down
    heights = lidar_rays.heights(beams, spec.range_max, origins[:1], rotations)
    got = scene.cast(origins, dirs, lengths, heights)
    ahead = np.abs(np.arctan2(dirs[:, 1], dirs[:, 0])) < 0.5
    assert np.all(np.isfinite(got[ahead])) and np.allclose(got[ahead] * -dirs[ahead, 2], 0.1, atol=1e-4)
    assert np.all(np.isposinf(got[dirs[:, 2] > 0]))  # looking up, backwards: under the shelf, nothing
    ((_, _, sliced),) = scene._slices
    assert sliced is not scene._scene  # a slice without triangles: the shelf is above the rays


def test_3d_lidars_and_tilted_scans_use_the_whole_scene():
    world = prepare(REPO / "scenarios" / "house.yaml").plan.world
    scene = StaticScene(world)
    velodyne = lidar("velodyne", samples=200, vertical=RayAxis(16, -0.2618, 0.2618), range_max=30.0)
    origins, dirs, lengths, _, _ = _scans(velodyne, [(-3.0, -2.5, 0.4)], [0.0])
    assert scene.cast(origins, dirs, lengths).tobytes() == _whole(scene, origins, dirs, lengths).tobytes()
    flat = lidar(range_max=12.0)
    origins, dirs, lengths, _, _ = _scans(flat, [(-3.0, -2.5, 0.4)], [0.0], pitch=0.1)  # 1.2 m up and down
    assert 2 * 12.0 * math.sin(0.1) > SLICE_BAND
    assert scene.cast(origins, dirs, lengths).tobytes() == _whole(scene, origins, dirs, lengths).tobytes()
    assert scene._slices == []


def test_a_slice_holding_most_triangles_is_not_built(monkeypatch):
    """Tall walls: a band across them keeps their sides (8 of each box's 12 triangles)."""
    from mobot_cli.sim.sensing import raycast

    world = WorldPlan(ground_plane=False, bodies=tuple(
        StaticBody(name=f"wall{i}", shapes=(StaticShape(kind="box", size=(0.2, 4.0, 2.0)),), xyz=(i - 5.0, 0.0, 1.0))
        for i in range(10)))
    origins, dirs, lengths, _, _ = _scans(lidar(range_max=12.0), [(0.5, 0.0, 1.0)], [0.0])
    built = []
    for share in (0.8, 0.6):
        monkeypatch.setattr(raycast, "SLICE_SHARE", share)
        scene = StaticScene(world)
        got = scene.cast(origins, dirs, lengths)
        assert got.tobytes() == _whole(scene, origins, dirs, lengths).tobytes() and np.isfinite(got).mean() > 0.5
        built.append(scene._slices[0][2] is not scene._scene)
    assert built == [True, False]


def test_every_scan_of_a_driving_robot_keeps_its_bits(tmp_path):
    """The bundled house scenario, cast with and without slices: the same ranges."""
    from dataclasses import replace

    from mobot_cli.sim.bullet.world import World
    from mobot_cli.sim.sensing import raycast

    prepared = prepare(REPO / "scenarios" / "house.yaml", ["duration=6", "robots.mobot.args.lidar=true"])
    plan = prepared.plan
    spec = replace(plan.robots[0].sensors[0], noise_stddev=0.0, range_resolution=0.0)
    robot = replace(plan.robots[0], sensors=(spec,))
    runs = []
    for band in (raycast.SLICE_BAND, -1.0):  # -1: no band is narrow enough, every ray meets the whole scene
        raycast_band, raycast.SLICE_BAND = raycast.SLICE_BAND, band
        try:
            with World(plan.physics, plan.world, seed=plan.seed) as world:
                world.spawn(robot)
                world.set_command(robot.name, 0.5, 0.4)
                scans = []
                for step in range(6 * 240):
                    if step % 24 == 0:
                        scans.extend(world.sense([(robot.name, spec.name)]))
                    world.step()
                runs.append(b"".join(scan.ranges.tobytes() for scan in scans))
                sliced = [s is not world._sensing.scene._scene for _, _, s in world._sensing.scene._slices]
        finally:
            raycast.SLICE_BAND = raycast_band
        assert sliced == ([True] if band > 0 else [])
    assert runs[0] == runs[1] and len(runs[0]) == 60 * 360 * 4


unit = st.floats(-1.0, 1.0, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(quats=st.lists(st.tuples(unit, unit, unit, unit).filter(lambda q: sum(v * v for v in q) > 0.01),
                      min_size=1, max_size=4),
       rows=st.sampled_from([1, 4]), spread=st.floats(0.0, 1.2), z=st.floats(-2.0, 2.0), reach=st.floats(0.5, 30.0))
def test_heights_bound_every_ray_of_every_pose(quats, rows, spread, z, reach):
    """Whatever the lean of the sensor and its vertical beams, every point of every ray lies
    within the heights cast_scans gives the scene."""
    vertical = RayAxis(rows, -spread, spread) if rows > 1 else None
    spec = lidar(samples=90, vertical=vertical, range_min=0.05, range_max=reach)
    beams = lidar_rays.Beams.of(spec)
    rotations = np.array([quat_matrix(tuple(v / math.sqrt(sum(w * w for w in q)) for v in q)) for q in quats],
                         dtype=np.float32)
    positions = np.array([(0.0, 0.0, z + 0.1 * i) for i in range(len(quats))], dtype=np.float32)
    low, high = lidar_rays.heights(beams, reach, positions, rotations)
    dirs = np.matmul(beams.directions32, rotations.transpose(0, 2, 1))
    for t in (spec.range_min, reach):
        points = dirs * np.float32(t) + positions[:, None, :]
        assert points[..., 2].min() >= low and points[..., 2].max() <= high
