"""Generated worlds (assets/world/generate/): the same seed gives the same world, each kind
keeps its promise (BARN's grid and free way, a perfect maze, rooms joined by doors, boxes
apart), and the SDF file written for a world loads back to the same obstacles, as Gazebo's
format has them."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from mobot_cli.assets.world import occupancy
from mobot_cli.assets.world.generate.barn import CELL, CYLINDER_RADIUS, START
from mobot_cli.assets.world.generate.make import generate, load_generated
from mobot_cli.assets.world.generate.sdf import to_plan, to_sdf
from mobot_cli.assets.world.worldplan import load_world
from mobot_cli.common.raster import Grid
from mobot_cli.timeline.planner import astar

KINDS = {"barn": {}, "boxes": {"count": 12}, "maze": {"cells": (4, 3)}, "rooms": {"rooms": (3, 2)}}


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_one_seed_one_world_another_seed_another(kind):
    one, again = (to_sdf(generate(kind, 11, KINDS[kind]), "c") for _ in range(2))
    other = to_sdf(generate(kind, 12, KINDS[kind]), "c")
    assert one == again and one != other


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_the_saved_world_loads_back_to_the_same_obstacles(kind, tmp_path):
    loaded, text = load_generated(kind, 5, KINDS[kind])
    (tmp_path / "generated.world").write_text(text, encoding="utf-8")
    again = load_world(str(tmp_path / "generated.world")).plan
    assert again.ground_plane and loaded.plan.ground_plane
    assert again.bodies == loaded.plan.bodies  # names, poses, shapes and sizes, number for number
    assert len(again.bodies) == len(generate(kind, 5, KINDS[kind]).obstacles) > 0


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_the_world_file_is_sdf_gazebo_opens(kind):
    root = ET.fromstring(load_generated(kind, 2, KINDS[kind])[1])
    assert root.tag == "sdf" and root.get("version") == "1.6"
    (world,) = root.findall("world")
    models = world.findall("model")
    assert models[0].get("name") == "ground_plane" and len(models) > 1
    assert len({m.get("name") for m in models}) == len(models)  # Gazebo refuses a name twice
    for model in models:
        assert model.findtext("static") == "true"
        (link,) = model.findall("link")
        collision, visual = link.find("collision/geometry"), link.find("visual/geometry")
        assert collision is not None and visual is not None
        assert ET.tostring(collision) == ET.tostring(visual)
        if model.get("name") != "ground_plane":
            x, y, z, roll, pitch, yaw = (float(v) for v in model.findtext("pose").split())
            shape = collision[0]
            height = float(shape.findtext("length") or shape.findtext("size").split()[2])
            assert z == pytest.approx(height / 2) and roll == pitch == 0.0  # standing on the floor


def test_barn_cylinders_sit_on_barns_grid_and_leave_a_way_through():
    for seed in range(8):
        world = generate("barn", seed, {"fill": 0.3})
        grid, path = world.info["grid"], world.info["path"]
        cylinders = [o for o in world.obstacles if o.name.startswith("cylinder_")]
        assert all(o.kind == "cylinder" and o.size == (CYLINDER_RADIUS, 1.0) for o in world.obstacles)
        xs = np.array([o.x for o in cylinders])
        ys = np.array([o.y for o in cylinders])
        assert xs.min() == pytest.approx(-4.425) and xs.max() == pytest.approx(-0.075)  # x -4.5..0
        assert ys.min() >= 5.075 - 1e-9 and ys.max() <= 9.425 + 1e-9  # y 5..9.5
        assert np.allclose(np.round((xs + 4.425) / CELL), (xs + 4.425) / CELL, atol=1e-6)
        assert grid[0].all() and grid[-1].all()  # the side rows
        assert path[0][1] == 0 and path[-1][1] == grid.shape[1] - 3  # first column to last
        for (r, c), (r2, c2) in zip(path, path[1:]):
            assert abs(r - r2) + abs(c - c2) == 1
        assert not any(grid[r:r + 3, c:c + 3].any() for r, c in path)  # 3 x 3 free cells all along


def test_barn_start_to_goal_is_planned_through_every_world():
    """Independent of the generator's own check: A* on the world's occupancy grid, as goals plan."""
    for seed in range(6):
        plan = to_plan(generate("barn", seed, {"fill": 0.3, "corridor": 4}))
        grid = Grid.covering(-5.0, 0.5, -0.5, 14.0, 0.05)
        blocked = occupancy.occupancy(plan, grid).inflated(0.2)
        assert astar(blocked, grid.cell_of(*START[:2]), grid.cell_of(START[0], 13.0)).cells, seed


def test_the_maze_is_perfect_and_every_cell_reachable():
    world = generate("maze", 3, {"cells": (5, 4), "cell": 1.0})
    assert world.info["passages"] == 5 * 4 - 1  # a spanning tree: one way between any two cells
    plan = to_plan(world)
    grid = Grid.covering(-3.0, 3.0, -2.5, 2.5, 0.05)
    blocked = occupancy.occupancy(plan, grid).inflated(0.2)
    centres = [c for column in world.info["centres"] for c in column]
    assert len(centres) == 20
    for x, y in centres[1:]:
        assert astar(blocked, grid.cell_of(*centres[0]), grid.cell_of(x, y)).cells


def test_rooms_are_joined_by_doors_of_the_width_asked():
    world = generate("rooms", 8, {"size": (12.0, 8.0), "rooms": (3, 2), "door": 0.9})
    grid = Grid.covering(-6.5, 6.5, -4.5, 4.5, 0.05)
    occ = occupancy.occupancy(to_plan(world), grid)
    centres = world.info["centres"]
    for x, y in centres[1:]:
        assert astar(occ.inflated(0.4), grid.cell_of(*centres[0]), grid.cell_of(x, y)).cells  # 0.8 m passes
    for x, y in centres[1:]:  # and a robot wider than the doors is shut in its room
        assert not astar(occ.inflated(0.5), grid.cell_of(*centres[0]), grid.cell_of(x, y)).cells


def test_boxes_keep_their_gap_and_say_when_they_do_not_fit():
    world = generate("boxes", 4, {"count": 15, "gap": 0.6, "keep_clear": [(0.0, 0.0, 1.0)]})
    boxes = [o for o in world.obstacles if o.name.startswith("box_")]
    assert len(boxes) == 15 and world.info["notices"] == []
    for i, a in enumerate(boxes):
        ra = math.hypot(*a.size[:2]) / 2
        assert math.hypot(a.x, a.y) >= ra + 1.0 - 1e-6
        for b in boxes[i + 1:]:
            assert math.hypot(a.x - b.x, a.y - b.y) >= ra + math.hypot(*b.size[:2]) / 2 + 0.6 - 1e-6
    crowded = generate("boxes", 4, {"size": (3.0, 3.0), "count": 40})
    placed = crowded.info["placed"]
    assert placed < 40 and crowded.info["notices"] == [
        f"boxes: {placed} of 40 boxes found a place 0.6 m from the others and the walls"]
