"""Where a wheeled robot may be: the world's floor plan (floorplan.py) on a grid, and by name.

Goal commands ask which obstacle a point lies in; coverage planning and the coverage
expectation ask which cells of an area are free. Both read the same shadows as the floor
plan in trajectory.png: static geometry reaching into the band above the floor.
"""

from __future__ import annotations

import functools

import numpy as np

from mobot_cli.assets.world.floorplan import BAND, MeshShadow, body_shadows, body_shapes, shape_shadow
from mobot_cli.common.polygon import contains
from mobot_cli.common.raster import Grid, fill_arrays, fill_shapes
from mobot_cli.common.transforms import compose_poses
from mobot_cli.plan import WorldPlan
from mobot_cli.sim.parts import describe


def probed_floor(world: WorldPlan) -> float:
    """The floor under the world's origin, looked for from z = 0 (floorlevel's probe): where the
    band is measured from when no robot stands in the world yet. Kept for the last few worlds
    (a mesh world takes tens of ms, and every goal point asks)."""
    try:
        hash(world)
    except TypeError:  # a world holding a list somewhere: not kept
        return _probe(world)
    return _kept_probe(world)


def _probe(world: WorldPlan) -> float:
    from mobot_cli.assets.world.floorlevel import floor_level

    return floor_level(world, [(0.0, 0.0, 0.0)], body_shapes, probe=True)


_kept_probe = functools.lru_cache(maxsize=8)(_probe)


def ground_band(world: WorldPlan) -> tuple[float, float]:
    """BAND above the world's probed floor, in absolute heights."""
    floor = probed_floor(world)
    return (floor + BAND[0], floor + BAND[1])


def robot_floor(world: WorldPlan, start: tuple[float, float, float]) -> float:
    """The floor a robot at ``start`` (x, y and its root link's z, or the z it was asked to spawn
    at: 0 when left to the floor) stands on: the floor under it, as its run's planner finds it
    once the robot has come to rest there, up to floorlevel.SPAWN_REACH above ``start``. A raised
    floor slab in a world with a ground plane (Gazebo's cafe) is then the floor it drives on."""
    from mobot_cli.assets.world.floorlevel import SPAWN_REACH, floor_level

    x, y, z = start
    return floor_level(world, [(x, y, z + SPAWN_REACH)], body_shapes)


def obstacle_at(world: WorldPlan, x: float, y: float, floor: float | None = None) -> str | None:
    """How messages name the static body whose shadow holds (x, y), and which of its collisions
    (see sim/parts.py), or None in free space; the band above ``floor`` (a robot's, robot_floor),
    else above the probed floor."""
    band = ground_band(world) if floor is None else (floor + BAND[0], floor + BAND[1])
    for label, parts in body_shadows(world, band):
        if any(_holds(part, x, y) for part in parts):
            return label + _part(world, label, x, y, band)
    return None


def _part(world: WorldPlan, label: str, x: float, y: float, band: tuple[float, float]) -> str:
    """", its collision 'model::link::collision', a ... box centred at (...)", or "": found again
    shape by shape, for the message only."""
    for body in world.bodies:
        if (body.label or f"static body '{body.name}'") != label:
            continue
        for shape in body_shapes(body):
            xyz, quat = compose_poses((body.xyz, body.quat), (shape.xyz, shape.quat))
            if any(_holds(polygon, x, y) for polygon in shape_shadow(shape, xyz, quat, band)):
                text = describe(body, shape)
                return f", {text}" if text else ""
    return ""


def _holds(part, x: float, y: float) -> bool:
    if isinstance(part, MeshShadow):
        return _in_triangles(part.triangles, x, y)
    return len(part) >= 3 and _near_box(part, x, y) and contains(part, x, y)


def _in_triangles(triangles: np.ndarray, x: float, y: float) -> bool:
    """Whether (x, y) lies in one of the triangles (n, 3, 2): ``contains``, for arrays."""
    xs, ys = triangles[:, :, 0], triangles[:, :, 1]
    near = triangles[(xs.min(axis=1) <= x) & (x <= xs.max(axis=1)) & (ys.min(axis=1) <= y) & (y <= ys.max(axis=1))]
    if not len(near):
        return False
    a, b = near, np.roll(near, -1, axis=1)  # each corner and the next: the edges
    ya, yb = a[:, :, 1], b[:, :, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        right = x < a[:, :, 0] + (y - ya) * (b[:, :, 0] - a[:, :, 0]) / (yb - ya)
    crossings = (((ya > y) != (yb > y)) & right).sum(axis=1)  # edges crossed to the right of it
    return bool((crossings % 2 == 1).any())


def obstacle_mask(world: WorldPlan, grid: Grid, band: tuple[float, float] | None = None) -> np.ndarray:
    """The cells of ``grid`` that some static body's shadow (in ``band``, absolute heights; BAND
    above the probed floor when not given) covers."""
    band = band or ground_band(world)
    mask = grid.empty()
    xmax, ymax = grid.x0 + grid.nx * grid.cell, grid.y0 + grid.ny * grid.cell
    shapes, triangles, segments = [], [], []
    for _, parts in body_shadows(world, band):
        for shape in parts:
            if isinstance(shape, MeshShadow):
                triangles.append(shape.triangles)
                segments.append(shape.segments)
                continue
            xs, ys = [p[0] for p in shape], [p[1] for p in shape]
            if max(xs) >= grid.x0 and min(xs) <= xmax and max(ys) >= grid.y0 and min(ys) <= ymax:
                shapes.append(shape)
    fill_shapes(mask, grid, shapes)
    within = [_within(np.concatenate(arrays) if arrays else np.zeros((0, n, 2)), grid.x0, xmax, grid.y0, ymax)
              for arrays, n in ((triangles, 3), (segments, 2))]
    fill_arrays(mask, grid, *within)
    return mask


def _within(shapes: np.ndarray, x0: float, x1: float, y0: float, y1: float) -> np.ndarray:
    """The shapes (n, corners, 2) whose bounding boxes meet the box x0..x1, y0..y1."""
    xs, ys = shapes[:, :, 0], shapes[:, :, 1]
    return shapes[(xs.max(axis=1) >= x0) & (xs.min(axis=1) <= x1) & (ys.max(axis=1) >= y0) & (ys.min(axis=1) <= y1)]


def _near_box(polygon, x: float, y: float) -> bool:
    """A cheap test first: (x, y) within the polygon's bounding box."""
    xs, ys = [p[0] for p in polygon], [p[1] for p in polygon]
    return min(xs) <= x <= max(xs) and min(ys) <= y <= max(ys)
