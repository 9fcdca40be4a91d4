"""TinyRenderer draws the static world as tiled visual-only copies (sim/sensing/tiles.py): the
camera sees what it saw without them, and nothing but the camera meets them."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.common.transforms import quat_from_rpy
from mobot_cli.plan import Physics, SensorSpec, StaticBody, StaticShape, WorldPlan
from mobot_cli.sim.bullet.world import World
from mobot_cli.sim.pb import p
from mobot_cli.sim.sensing import render, tiles

# A thin panel 6 m long and 2 m high as a mesh of 12 large triangles (counter-clockwise outside).
PANEL_OBJ = """v 0 0 0\nv 6 0 0\nv 6 0.2 0\nv 0 0.2 0\nv 0 0 2\nv 6 0 2\nv 6 0.2 2\nv 0 0.2 2
f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8
"""
CAMERA = SensorSpec(name="cam", kind="rgbd", link="base_link", every=1, width=160, height=120,
                    field_of_view=1.2, range_min=0.05, range_max=20.0, encoding="rgb8")
# Camera poses 0.3 m above the floor (off round coordinates): along the room, at the long wall
# from close by and at a grazing angle, at the table and the panel.
POSES = [((-4.37, -3.11, 0.3), 0.1), ((-1.13, 0.71, 0.3), 1.3), ((-3.9, 2.27, 0.3), -0.05),
         ((0.61, -1.93, 0.3), 2.6), ((2.2, 1.3, 0.3), -2.2)]


def house(panel: str) -> WorldPlan:
    """A floor slab 12 x 10 m, a long turned wall, a table of a box, a cylinder and a sphere (one
    body), a mesh panel."""
    return WorldPlan(name="tiles", ground_plane=False, bodies=(
        StaticBody(name="floor", xyz=(0.0, 0.0, -0.025), shapes=(StaticShape(kind="box", size=(12.0, 10.0, 0.05)),)),
        StaticBody(name="walls", xyz=(0.0, 3.0, 0.0), quat=quat_from_rpy(0.0, 0.0, 0.3), shapes=(
            StaticShape(kind="box", size=(10.0, 0.15, 2.5), xyz=(0.0, 0.0, 1.25)),
            StaticShape(kind="box", size=(0.15, 4.0, 2.5), xyz=(5.0, -2.0, 1.25)))),
        StaticBody(name="table", xyz=(1.5, -0.5, 0.0), quat=quat_from_rpy(0.0, 0.0, 0.7), shapes=(
            StaticShape(kind="box", size=(1.6, 0.9, 0.05), xyz=(0.0, 0.0, 0.75)),
            StaticShape(kind="cylinder", size=(0.05, 0.75), xyz=(0.6, 0.3, 0.375)),
            StaticShape(kind="sphere", size=(0.2,), xyz=(-0.4, 0.0, 0.98)))),
        StaticBody(name="panel", xyz=(-2.0, -4.0, 0.0), quat=quat_from_rpy(0.0, 0.0, -0.2), shapes=(
            StaticShape(kind="mesh", size=(1.0, 1.0, 1.1), mesh=panel),))))


@pytest.fixture(scope="module")
def world_plan(tmp_path_factory):
    panel = tmp_path_factory.mktemp("tiles") / "panel.obj"
    panel.write_text(PANEL_OBJ)
    return house(str(panel))


def images(plan: WorldPlan, tile: float | None) -> tuple[list, int, list[int]]:
    """The images at POSES in a new world drawn with (or without) tiles, the number of bodies
    before the renderer, and the bodies it added."""
    with World(Physics(renderer="tiny"), plan, fresh=True) as world:
        cid = world.client_id
        before = p.getNumBodies(physicsClientId=cid)
        renderer = render.Renderer(cid, "tiny", plan, tile)
        added = [p.getBodyUniqueId(i, physicsClientId=cid) for i in range(before, p.getNumBodies(physicsClientId=cid))]
        shots = [renderer.image(CAMERA, xyz, quat_from_rpy(0.0, 0.0, yaw)) for xyz, yaw in POSES]
        return shots, before, added


def test_the_tiled_world_looks_as_the_untiled_one(world_plan):
    plain, _, none_added = images(world_plan, None)
    tiled, before, added = images(world_plan, tiles.TILE)
    assert none_added == [] and len(added) >= 3  # the mesh copy, the cylinder and the sphere
    for (rgb0, depth0), (rgb1, depth1) in zip(plain, tiled):
        assert np.isfinite(depth0).mean() > 0.4  # the scene is in view
        assert (np.abs(rgb0.astype(int) - rgb1).max(axis=2) > 2).mean() < 0.001
        assert (np.isfinite(depth0) != np.isfinite(depth1)).mean() < 0.001
        both = np.isfinite(depth0) & np.isfinite(depth1)
        assert np.percentile(np.abs(depth0[both] - depth1[both]), 99.9) < 0.001
    again, _, _ = images(world_plan, tiles.TILE)
    assert all(a[0].tobytes() == b[0].tobytes() and a[1].tobytes() == b[1].tobytes() for a, b in zip(tiled, again))


def test_the_copies_are_small_triangles_nothing_collides_with(world_plan):
    with World(Physics(renderer="tiny"), world_plan, fresh=True) as world:
        cid = world.client_id
        originals = list(range(p.getNumBodies(physicsClientId=cid)))
        start = np.array([-5.5, -4.5, 0.2]) + np.random.default_rng(1).uniform(0, 1, (200, 3)) * [11, 9, 2]
        angle = np.linspace(0, 6.2, 200)
        end = (start + np.stack([7.0 * np.cos(angle), 7.0 * np.sin(angle), np.full(200, -0.3)], axis=1)).tolist()
        start = start.tolist()
        rays = p.rayTestBatch(start, end, physicsClientId=cid)
        assert tiles.retile(cid, world_plan, tiles.TILE) == 4
        copies = list(range(len(originals), p.getNumBodies(physicsClientId=cid)))
        assert len(copies) >= 3
        for uid in originals:  # hidden: TinyRenderer skips what is transparent
            assert all(shape[7][3] == 0.0 for shape in p.getVisualShapeData(uid, physicsClientId=cid))
        assert p.rayTestBatch(start, end, physicsClientId=cid) == rays  # rays meet the originals only
        assert {hit[0] for hit in rays} <= set(originals) | {-1} and sum(hit[0] >= 0 for hit in rays) > 100
        for uid in copies:
            for other in originals:
                assert p.getClosestPoints(uid, other, 1.0, physicsClientId=cid) == ()
        p.stepSimulation(physicsClientId=cid)
        assert p.getContactPoints(physicsClientId=cid) == ()
        # smallest first (the sphere, the cylinder), then one mesh of every box's and mesh's triangles
        kinds = [p.getVisualShapeData(uid, physicsClientId=cid)[0][2] for uid in copies]
        assert kinds == [p.GEOM_SPHERE, p.GEOM_CYLINDER, p.GEOM_MESH]


def test_a_plan_that_is_not_the_clients_leaves_the_drawing_as_it_is(world_plan):
    moved = WorldPlan(name="other", ground_plane=False, bodies=tuple(
        StaticBody(name=b.name, xyz=(b.xyz[0] + 1.0, b.xyz[1], b.xyz[2]), quat=b.quat, shapes=b.shapes)
        for b in world_plan.bodies))
    with World(Physics(renderer="tiny"), world_plan, fresh=True) as world:
        cid = world.client_id
        assert tiles.retile(cid, moved) == 0 and p.getNumBodies(physicsClientId=cid) == len(world_plan.bodies)


triangle = st.lists(st.floats(-8.0, 8.0, allow_nan=False), min_size=9, max_size=9).map(
    lambda v: np.array(v).reshape(3, 3))


@settings(max_examples=60, deadline=None)
@given(triangle, st.floats(0.3, 4.0))
def test_cutting_keeps_the_surface_its_winding_and_no_edge_is_longer_than_the_tile(t, tile):
    normal = np.cross(t[1] - t[0], t[2] - t[0])
    if np.linalg.norm(normal) < 1e-3:
        return  # degenerate
    cut = tiles.split(t[None], tile)
    edges = np.linalg.norm(np.roll(cut, -1, axis=1) - cut, axis=2)
    assert edges.max() <= tile
    areas = np.cross(cut[:, 1] - cut[:, 0], cut[:, 2] - cut[:, 0])
    assert np.allclose(areas.sum(axis=0), normal, atol=1e-9 * max(1.0, np.abs(normal).max()))
    assert (areas @ normal > 0).all()  # every piece faces where the triangle faced


def test_two_triangles_sharing_an_edge_cut_it_at_the_same_points():
    """No T-junctions: the points of either side's pieces on the shared edge are the same."""
    a, b, c, d = np.array([[0.0, 0.0, 0.0], [7.3, 0.4, 0.0], [0.2, 2.9, 0.1], [6.1, 3.3, 0.0]])
    left, right = tiles.split(np.array([[a, b, c]]), 1.0), tiles.split(np.array([[b, d, c]]), 1.0)

    def on_edge(pieces) -> set:
        points = pieces.reshape(-1, 3)
        t = (points - b) @ (c - b) / ((c - b) @ (c - b))
        off = np.linalg.norm(b + t[:, None] * (c - b) - points, axis=1)
        return {tuple(x) for x in points[off < 1e-9]}

    halvings = math.ceil(math.log2(np.linalg.norm(c - b)))  # 7.7 m -> 8 pieces of 0.96 m
    assert on_edge(left) == on_edge(right) and len(on_edge(left)) == 2 ** halvings + 1
