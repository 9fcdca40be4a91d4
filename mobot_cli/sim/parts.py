"""How refusals name the part of a static world body a robot or a goal ran into.

A world model is one body holding all of its collision shapes, so "inside world model
'house_walls'" says which model but not which of its twenty walls. Each shape keeps its name from
the world file (``link::collision``); this module says which one it is and where it stands, in
the world frame, for messages only (no PyBullet here: goal checks use it too).
"""

from __future__ import annotations

from mobot_cli.common.transforms import compose_poses, pose_point
from mobot_cli.plan import StaticBody, StaticShape


def describe(body: StaticBody, shape: StaticShape) -> str:
    """E.g. "its collision 'house_walls::walls::wall_3', a 2.00 x 0.15 x 2.50 m box centred
    at (5.00, 1.00, 1.25)"; "" for a nameless shape of a one-shape body (the label says it all)."""
    if not shape.name and len(body.shapes) <= 1:
        return ""
    lo, hi = world_bounds(body, shape)
    centre = tuple((a + b) / 2.0 for a, b in zip(lo, hi))
    name = f"'{body.name}::{shape.name}'" if shape.name else f"number {body.shapes.index(shape) + 1}"
    where = "centred" if shape.kind != "plane" else "through"
    return f"its collision {name}, {_what(shape, lo, hi)} {where} at ({_xyz(centre)})"


def world_bounds(body: StaticBody, shape: StaticShape):
    """The world-axis box (lo, hi) around ``shape`` as ``body`` places it."""
    xyz, quat = compose_poses((body.xyz, body.quat), (shape.xyz, shape.quat))
    corners = [pose_point(xyz, quat, c) for c in _local_corners(shape)]
    lo = tuple(min(c[i] for c in corners) for i in range(3))
    hi = tuple(max(c[i] for c in corners) for i in range(3))
    return lo, hi


def _local_corners(shape: StaticShape) -> list[tuple[float, float, float]]:
    kind, size = shape.kind, shape.size
    if kind == "box":
        half = [s / 2.0 for s in size[:3]]
    elif kind == "sphere":
        half = [size[0]] * 3
    elif kind == "cylinder":
        half = [size[0], size[0], size[1] / 2.0]
    elif kind == "capsule":
        half = [size[0], size[0], size[1] / 2.0 + size[0]]
    elif kind == "mesh":
        return _mesh_corners(shape)
    else:  # a plane: its pose is all there is to say
        half = [0.0, 0.0, 0.0]
    return [(sx * half[0], sy * half[1], sz * half[2]) for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]


def _mesh_corners(shape: StaticShape) -> list[tuple[float, float, float]]:
    from mobot_cli.common.meshfile import read_mesh  # numpy: only on the error path

    vertices, _ = read_mesh(shape.mesh)
    if len(vertices) == 0:
        return [(0.0, 0.0, 0.0)]
    scaled = vertices * [float(s) for s in shape.size[:3]]
    lo, hi = scaled.min(axis=0).tolist(), scaled.max(axis=0).tolist()
    return [(x, y, z) for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]


def _what(shape: StaticShape, lo, hi) -> str:
    size = shape.size
    if shape.kind == "box":
        return f"a {_m(size[0])} x {_m(size[1])} x {_m(size[2])} m box"
    if shape.kind == "sphere":
        return f"a sphere of radius {_m(size[0])} m"
    if shape.kind in ("cylinder", "capsule"):
        return f"a {shape.kind} of radius {_m(size[0])} m, {_m(size[1])} m long"
    if shape.kind == "mesh":
        across = " x ".join(_m(b - a) for a, b in zip(lo, hi))
        return f"a mesh {across} m across"  # its file is the converted copy in the cache: no name to give
    return "a plane"


def _m(value: float) -> str:
    return f"{value:.2f}"


def _xyz(point) -> str:
    return ", ".join(f"{round(v, 2) + 0.0:.2f}" for v in point)  # never '-0.00'
