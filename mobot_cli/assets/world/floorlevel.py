"""The height of the floor the robots drive on, found in a world's static geometry.

A floor plan shows what reaches into a band above the floor. Worlds put their floors where they
like (a floor mesh at 0.034 m, a stage at 0.19 m), so the band is measured from the floor under
the robots: straight down from where each robot started, the highest surface of a box, a mesh
or a plane at or a little above the robot's root link (the root may sit on the floor itself, as
base_footprint does). Round primitives (cylinders, spheres) are not taken for floors.
"""

from __future__ import annotations

import numpy as np

from mobot_cli.common.transforms import compose_poses, quat_matrix
from mobot_cli.plan import StaticShape, WorldPlan

# A surface this far above a robot's root link may still be its floor (the root's own height
# above the floor is what the robot's wheels and chassis add; base_footprint adds none).
ABOVE_ROOT = 0.05  # m
# Probing a world without robots (at the origin, z = 0): a ground slab whose top is a little
# above z = 0 (AWS's racetrack: 0.06 m) is the floor, not its underside far below.
RAISED = 0.25  # m: how far above z = 0 such a top may be
FAR_BELOW = 0.1  # m: a floor found this far below z = 0 gives way to it
# A robot spawned over a surface up to this high comes to rest on it (sim/placement.py probes
# from above the robot's own height): a floor slab or a stage it stands on, not an obstacle.
SPAWN_REACH = 0.25  # m
Start = tuple[float, float, float]  # x, y, z of a robot's root link when it started


def floor_level(world: WorldPlan, starts: list[Start], shapes_of, probe: bool = False) -> float:
    """The lowest of the floors under ``starts`` (0 without starts or without a floor found).

    ``shapes_of(body)`` gives a body's StaticShapes (floorplan reads URDF bodies for it).
    ``probe``: the starts are no robots but points to look down from (the origin of a world
    mapped without robots), so a surface up to RAISED above one counts as its floor when the
    floor below it lies more than FAR_BELOW down.
    """
    if not starts:
        return 0.0
    reach = ABOVE_ROOT + (RAISED if probe else 0.0)
    found: list[list[float]] = [[0.0] if world.ground_plane and z + ABOVE_ROOT >= 0.0 else []
                                for _, _, z in starts]
    for body in world.bodies:
        for shape in shapes_of(body):
            xyz, quat = compose_poses((body.xyz, body.quat), (shape.xyz, shape.quat))
            surfaces = _surfaces(shape, xyz, quat)  # one mesh read per shape, for every start
            for heights, (x, y, z) in zip(found, starts):
                heights.extend(h for h in surfaces(x, y) if h <= z + reach)
    floors = [_floor(heights, z) for heights, (_, _, z) in zip(found, starts) if heights]
    return min(floors) if floors else 0.0


def _floor(heights: list[float], z: float) -> float:
    """The floor among surfaces met looking down from ``z`` (and, probing, a little above it)."""
    below = [h for h in heights if h <= z + ABOVE_ROOT]
    if below and max(below) >= z - FAR_BELOW:
        return max(below)
    above = [h for h in heights if h > z + ABOVE_ROOT]
    return min(above) if above else max(below)


def _surfaces(shape: StaticShape, xyz, quat):
    """A function (x, y) -> heights where the vertical line through (x, y) meets the shape."""
    rot = np.array(quat_matrix(quat))
    if shape.kind == "box":
        half, centre = np.array(shape.size[:3]) / 2.0, np.array(xyz)
        return lambda x, y: _box_top(half, rot, centre, x, y)
    if shape.kind == "plane":
        normal = rot @ np.array(shape.size[:3])
        if abs(normal[2]) < 1e-9:
            return lambda x, y: []
        return lambda x, y: [float(xyz[2] - (normal[0] * (x - xyz[0])
                                             + normal[1] * (y - xyz[1])) / normal[2])]
    if shape.kind == "mesh":
        from mobot_cli.common.meshfile import read_mesh

        vertices, faces = read_mesh(shape.mesh)
        if len(faces) == 0:
            return lambda x, y: []
        tri = ((vertices * np.array(shape.size[:3])) @ rot.T + np.array(xyz))[faces]
        return lambda x, y: _mesh_heights(tri, x, y)
    return lambda x, y: []


def _box_top(half: np.ndarray, rot: np.ndarray, centre: np.ndarray, x: float, y: float) -> list[float]:
    """The upper end of the line's passage through an oriented box (slab method)."""
    origin = rot.T @ (np.array([x, y, 0.0]) - centre)
    direction = rot.T @ np.array([0.0, 0.0, 1.0])
    low, high = -np.inf, np.inf
    for axis in range(3):
        if abs(direction[axis]) < 1e-12:
            if abs(origin[axis]) > half[axis]:
                return []
            continue
        a = (-half[axis] - origin[axis]) / direction[axis]
        b = (half[axis] - origin[axis]) / direction[axis]
        low, high = max(low, min(a, b)), min(high, max(a, b))
    return [float(high)] if low <= high else []


def _mesh_heights(tri: np.ndarray, x: float, y: float) -> list[float]:
    """Heights of the triangles (n, 3 corners, xyz) straight above or below (x, y)."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    # Barycentric coordinates of (x, y) in each triangle's shadow.
    det = (b[:, 1] - c[:, 1]) * (a[:, 0] - c[:, 0]) + (c[:, 0] - b[:, 0]) * (a[:, 1] - c[:, 1])
    flat = np.abs(det) > 1e-12  # triangles seen edge-on have no surface to stand on
    det = np.where(flat, det, 1.0)
    u = ((b[:, 1] - c[:, 1]) * (x - c[:, 0]) + (c[:, 0] - b[:, 0]) * (y - c[:, 1])) / det
    v = ((c[:, 1] - a[:, 1]) * (x - c[:, 0]) + (a[:, 0] - c[:, 0]) * (y - c[:, 1])) / det
    w = 1.0 - u - v
    inside = flat & (u >= -1e-9) & (v >= -1e-9) & (w >= -1e-9)
    z = u * a[:, 2] + v * b[:, 2] + w * c[:, 2]
    return [float(h) for h in z[inside]]
