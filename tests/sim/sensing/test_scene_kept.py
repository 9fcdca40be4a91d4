"""The last world's ray scene is kept for the next World of the same plan: shared BVHs, same bits."""

from __future__ import annotations

import dataclasses
import threading

import numpy as np
import pytest

from mobot_cli.plan import StaticBody, StaticShape, WorldPlan
from mobot_cli.sim.bullet.world import World
from mobot_cli.sim.sensing import raycast
from tests.sim.sensor_world import lidar, one_robot, planned

NOISY = lidar(xyz=(0.0, 0.0, 0.3), range_max=6.0, noise_stddev=0.02, range_resolution=0.01)


def _scans(plan, count: int = 12) -> tuple[bytes, raycast.StaticScene]:
    """The ranges of ``count`` scans of a robot driving a curve, and the scene they were cast at."""
    with World(plan.physics, plan.world, seed=plan.seed) as world:
        world.spawn(plan.robots[0])
        world.set_command("mobot", 0.4, 0.7)
        taken = []
        for _ in range(count):
            taken += world.sense([("mobot", "scan")])
            for _ in range(24):
                world.step()
        return b"".join(scan.ranges.tobytes() for scan in taken), world._sensing.scene


def test_the_next_world_of_a_plan_casts_at_the_kept_scene_with_the_same_bits(tmp_path):
    plan, _ = planned(one_robot(tmp_path), "mobot", NOISY)
    first, scene = _scans(plan)
    again, kept = _scans(dataclasses.replace(plan, world=dataclasses.replace(plan.world)))  # an equal plan
    assert again == first and len(first) == 12 * 360 * 4
    assert kept is not scene and kept._scene is scene._scene and kept.triangles is scene.triangles
    # the band of the first World's slice holds the second's: no new BVH was cut for it
    assert [cut for _, _, cut in kept._slices] == [cut for _, _, cut in scene._slices]
    assert len(scene._cut) == 1 and kept._cut is scene._cut


def test_another_world_gets_its_own_scene(tmp_path):
    plan, _ = planned(one_robot(tmp_path), "mobot", NOISY)
    _, scene = _scans(plan, 1)
    pillar = StaticBody(name="pillar", shapes=(StaticShape(kind="box", size=(0.2, 0.2, 1.0)),), xyz=(2.0, 1.0, 0.5))
    other = dataclasses.replace(plan, world=dataclasses.replace(plan.world, bodies=plan.world.bodies + (pillar,)))
    ranges, changed = _scans(other, 1)
    assert changed._scene is not scene._scene and len(changed.triangles) == len(scene.triangles) + 12
    assert raycast.static_scene(other.world)._scene is changed._scene  # and that one is kept now


def test_threads_cutting_slices_of_a_kept_scene_get_the_same_answers():
    world = WorldPlan(ground_plane=True, bodies=(
        StaticBody(name="wall", shapes=(StaticShape(kind="box", size=(0.2, 8.0, 2.0)),), xyz=(3.0, 0.0, 1.0)),))
    angles = np.linspace(-1.0, 1.0, 200)
    dirs = np.stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)], axis=1)
    lengths = np.full(len(dirs), 10.0)
    answers: dict[int, list[bytes]] = {}

    def cast(i: int) -> None:
        scene = raycast.static_scene(world)
        answers[i] = [scene.cast(np.tile([0.0, 0.0, z], (len(dirs), 1)), dirs, lengths).tobytes()
                      for z in (0.2, 0.6, 1.0, 1.4)]

    threads = [threading.Thread(target=cast, args=(i,)) for i in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    alone = [raycast.StaticScene(world).cast(np.tile([0.0, 0.0, z], (len(dirs), 1)), dirs, lengths)
             for z in (0.2, 0.6, 1.0, 1.4)]
    assert all(answers[i] == [a.tobytes() for a in alone] for i in range(4))
    hit = alone[0][np.abs(angles) < 0.5]
    assert np.allclose(hit, 2.9 / np.cos(angles[np.abs(angles) < 0.5]), atol=1e-4)  # the wall's face at x = 2.9



def _wall(path, x: float) -> None:
    """An OBJ wall, 2 m wide and 1 m high, across the x axis at ``x``."""
    path.write_text(f"v {x} -1 0\nv {x} 1 0\nv {x} 1 1\nv {x} -1 1\nf 1 2 3\nf 1 3 4\n")


def test_a_mesh_file_rewritten_between_two_worlds_is_read_again(tmp_path):
    """The Python API may rewrite a world's mesh between two Worlds of one plan: the next scene
    must see the file as it is now, as PyBullet does."""
    mesh = tmp_path / "wall.obj"
    _wall(mesh, 2.0)
    wall = StaticBody(name="wall", shapes=(StaticShape("mesh", (1, 1, 1), mesh=str(mesh)),))
    world = WorldPlan(name="walls", bodies=(wall,))
    ray = (np.array([[0.0, 0.0, 0.5]], np.float32), np.array([[1.0, 0.0, 0.0]], np.float32),
           np.array([10.0], np.float32))
    first = raycast.static_scene(world)
    assert raycast.static_scene(world)._scene is first._scene  # kept while the file is the same
    assert first.cast(*ray)[0] == pytest.approx(2.0, abs=1e-6)  # Embree's float32 (4.x: one ulp short)
    _wall(mesh, 3.25)  # another size, and a later modification time
    moved = raycast.static_scene(world)
    assert moved._scene is not first._scene
    assert moved.cast(*ray)[0] == pytest.approx(3.25, abs=1e-6)


def test_a_forgotten_scene_is_built_again(tmp_path):
    mesh = tmp_path / "wall.obj"
    _wall(mesh, 2.0)
    wall = StaticBody(name="wall", shapes=(StaticShape("mesh", (1, 1, 1), mesh=str(mesh)),))
    world = WorldPlan(name="walls", bodies=(wall,))
    first = raycast.static_scene(world)
    raycast.forget_kept()
    assert raycast.static_scene(world)._scene is not first._scene
