"""The static world as TinyRenderer draws it: visual-only copies, smallest shapes first, large
faces cut into tiles (docs/cameras.md).

TinyRenderer draws the bodies in the order they were made and each triangle by testing every
pixel of its bounding box on the screen (clamped to the image); a pixel that passes the depth
test is shaded, at about twice the test's cost, again each time a nearer surface reaches it.
So its cost is what the faces cover, shaded as often as surfaces drawn later hide earlier ones,
plus the bounding boxes' waste. For TinyRenderer the static bodies built from collision shapes
(SDF worlds' models) are therefore drawn by visual-only copies made at the first image, and their
own drawing is made transparent (which TinyRenderer skips):

* Smallest shapes first (by the diagonal of their box): furniture stands in front of walls and
  everything on the floor, so what is drawn later is mostly hidden and costs a depth test, not a
  shading. Boxes' and meshes' triangles go, in that order, into one mesh per colour; cylinders,
  capsules and spheres are visual shapes of their own kind, which TinyRenderer tessellates as it
  does collision shapes. The ground (render.py) is drawn after them all.
* Triangles longer than TILE on an edge are cut (``split``): a long wall or a floor slab seen at
  a grazing angle, or reaching behind the camera, costs its whole bounding box otherwise. Every
  edge longer than TILE is halved at its midpoint, round after round, and each triangle is
  filled from its halved edges (4 triangles when all three are long, 2 or 3 when one or two
  are): whether an edge is cut depends on the edge alone, so two triangles sharing an edge cut it
  at the same points and the surface stays closed (no cracks); pieces keep their triangle's
  winding (TinyRenderer culls back faces) and carry its face normal at each vertex, as
  TinyRenderer gives a box's faces and a mesh file without normals. Cutting finer adds a cost
  per visible triangle: in the bundled house 3 m cost least (bench/README.md).
* The copies have no collision shape: rays, contacts and physics never meet them; the collision
  shapes stay as they are. Meshes are read with trimesh (a dependency already) from the file
  PyBullet loaded, scaled and posed as their shapes.
* A static body is matched to the plan's by the order World builds them (the ground plane, then
  each body's shapes 16 to a PyBullet body) and checked (no joints, no mass, the plan's pose): at
  the first doubt the rest stay drawn as they are. Bodies with a plane, or of URDF text, stay too.

The pixels are the same as the collision shapes' drawing (RGB byte for byte, depth within
0.2 mm, tests/sim/sensing/test_tiles.py); what it saves per world is in bench/README.md.
"""

from __future__ import annotations

import numpy as np

from mobot_cli.common.transforms import quat_matrix
from mobot_cli.plan import StaticBody, StaticShape, WorldPlan
from mobot_cli.sim.pb import p

TILE = 3.0  # m: the longest edge of a drawn triangle (chosen by measurement: bench/README.md)
MAX_TRIANGLES = 20000  # per visual shape (PyBullet refuses meshes of ~130000 vertices and more)
SHAPES_PER_BODY = 16  # as sim/static_shapes.py builds them
_BOX = np.array([  # a unit cube's 12 triangles, counter-clockwise seen from outside
    [[0, 0, 0], [0, 1, 0], [1, 1, 0]], [[0, 0, 0], [1, 1, 0], [1, 0, 0]],  # -z
    [[0, 0, 1], [1, 0, 1], [1, 1, 1]], [[0, 0, 1], [1, 1, 1], [0, 1, 1]],  # +z
    [[0, 0, 0], [1, 0, 0], [1, 0, 1]], [[0, 0, 0], [1, 0, 1], [0, 0, 1]],  # -y
    [[0, 1, 0], [0, 1, 1], [1, 1, 1]], [[0, 1, 0], [1, 1, 1], [1, 1, 0]],  # +y
    [[0, 0, 0], [0, 0, 1], [0, 1, 1]], [[0, 0, 0], [0, 1, 1], [0, 1, 0]],  # -x
    [[1, 0, 0], [1, 1, 0], [1, 1, 1]], [[1, 0, 0], [1, 1, 1], [1, 0, 1]],  # +x
], dtype=float) - 0.5


def retile(cid: int, world: WorldPlan, tile: float = TILE) -> int:
    """Draw the world's static bodies of shapes as visual-only copies, their shapes smallest first
    and cut into tiles (see the module); how many bodies were copied."""
    shapes, copied = [], 0
    for uid, body_shapes, body in _statics(cid, world):
        try:
            faces = [_triangles(shape, body) for shape in body_shapes]
        except (OSError, ValueError):  # a mesh trimesh cannot read: the body is drawn as it is
            continue
        rgba = tuple(p.getVisualShapeData(uid, physicsClientId=cid)[0][7])
        p.changeVisualShape(uid, -1, rgbaColor=(0.0, 0.0, 0.0, 0.0), physicsClientId=cid)
        copied += 1
        for shape, f in zip(body_shapes, faces):
            size = _size(shape) if f is None else float(np.linalg.norm(np.ptp(f.reshape(-1, 3), axis=0)))
            shapes.append((size, shape, f, rgba, body))
    batch: list[np.ndarray] = []  # triangles of one colour, in drawing order
    colour = None
    for _, shape, f, rgba, body in sorted(shapes, key=lambda item: item[0]):  # stable: ties keep their order
        if batch and (f is None or rgba != colour):
            _mesh_bodies(cid, np.concatenate(batch), colour)
            batch = []
        if f is None:
            _primitive(cid, shape, rgba, body.xyz, body.quat)
        else:
            batch.append(split(f, tile))
            colour = rgba
    if batch:
        _mesh_bodies(cid, np.concatenate(batch), colour)
    return copied


def _size(shape: StaticShape) -> float:
    """The diagonal of a cylinder's, capsule's or sphere's box."""
    if shape.kind == "sphere":
        return 2.0 * 3.0 ** 0.5 * shape.size[0]
    length = shape.size[1] + (2.0 * shape.size[0] if shape.kind == "capsule" else 0.0)
    return float(np.hypot(2.0 ** 1.5 * shape.size[0], length))


def split(triangles: np.ndarray, tile: float) -> np.ndarray:
    """(n, 3, 3) triangles cut until no edge is longer than ``tile`` (see the module)."""
    out, todo = [], np.asarray(triangles, dtype=float)
    while len(todo):
        long = np.linalg.norm(np.roll(todo, -1, axis=1) - todo, axis=2) > tile  # edge i: vertex i -> i+1
        count = long.sum(axis=1)
        out.append(todo[count == 0])
        children = [_red(todo[count == 3])]
        for n, first in ((1, lambda row: int(np.argmax(row))), (2, lambda row: (int(np.argmin(row)) + 1) % 3)):
            rows = np.nonzero(count == n)[0]
            if len(rows):  # turned so that the long edges come first: 0 -> 1 (and 1 -> 2)
                turn = np.array([first(long[r]) for r in rows])
                turned = todo[rows[:, None], (turn[:, None] + np.arange(3)) % 3]
                children.append(_green(turned) if n == 1 else _blue(turned))
        todo = np.concatenate(children)
    return np.concatenate(out)


def _red(t: np.ndarray) -> np.ndarray:
    a, b, c = t[:, 0], t[:, 1], t[:, 2]
    ab, bc, ca = (a + b) / 2.0, (b + c) / 2.0, (c + a) / 2.0
    return np.concatenate([np.stack(v, axis=1) for v in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])


def _green(t: np.ndarray) -> np.ndarray:
    a, b, c = t[:, 0], t[:, 1], t[:, 2]
    ab = (a + b) / 2.0
    return np.concatenate([np.stack(v, axis=1) for v in ((a, ab, c), (ab, b, c))])


def _blue(t: np.ndarray) -> np.ndarray:
    """a -> b and b -> c long: the corner at b, then the quad a, ab, bc, c by its shorter diagonal."""
    a, b, c = t[:, 0], t[:, 1], t[:, 2]
    ab, bc = (a + b) / 2.0, (b + c) / 2.0
    by_a = (np.linalg.norm(bc - a, axis=1) <= np.linalg.norm(c - ab, axis=1))[:, None, None]
    quad_a = np.where(by_a, np.stack((a, ab, bc), axis=1), np.stack((a, ab, c), axis=1))
    quad_b = np.where(by_a, np.stack((a, bc, c), axis=1), np.stack((ab, bc, c), axis=1))
    return np.concatenate([np.stack((ab, b, bc), axis=1), quad_a, quad_b])


def _normals(triangles: np.ndarray) -> np.ndarray:
    normal = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    return normal / np.maximum(np.linalg.norm(normal, axis=1), 1e-300)[:, None]


def _longest(triangles: np.ndarray) -> float:
    return float(np.linalg.norm(np.roll(triangles, -1, axis=1) - triangles, axis=2).max(initial=0.0))


def _triangles(shape: StaticShape, body: StaticBody) -> np.ndarray | None:
    """A box's or a mesh's triangles in the world's frame; None for the other kinds."""
    if shape.kind == "box":
        local = _BOX * np.array(shape.size)
    elif shape.kind == "mesh":
        local = _mesh(shape.mesh) * np.array(shape.size)
        if np.prod(shape.size) < 0:  # a mirroring scale turns the faces inside out
            local = local[:, ::-1]
    else:
        return None
    in_body = local @ np.array(quat_matrix(shape.quat)).T + np.array(shape.xyz)
    return in_body @ np.array(quat_matrix(body.quat)).T + np.array(body.xyz)


def _mesh(path: str) -> np.ndarray:
    from mobot_cli.common.meshfile import load_quietly  # trimesh: only meshed worlds with a TinyRenderer camera

    return np.asarray(load_quietly(path, force="mesh", process=False).triangles, dtype=float)


def _mesh_bodies(cid: int, triangles: np.ndarray, rgba) -> None:
    """Visual-only bodies (no collision shape) drawing the triangles (none for none), each vertex with its face's
    normal."""
    for start in range(0, len(triangles), MAX_TRIANGLES):
        part = triangles[start:start + MAX_TRIANGLES]
        normal = _normals(part)
        visual = p.createVisualShape(p.GEOM_MESH, vertices=part.reshape(-1, 3).tolist(),
                                     indices=list(range(3 * len(part))),
                                     normals=np.repeat(normal, 3, axis=0).tolist(), rgbaColor=rgba,
                                     physicsClientId=cid)
        p.createMultiBody(0.0, -1, visual, useMaximalCoordinates=True, physicsClientId=cid)


def _primitive(cid: int, shape: StaticShape, rgba, xyz, quat) -> None:
    where = {"visualFramePosition": shape.xyz, "visualFrameOrientation": shape.quat}
    if shape.kind in ("cylinder", "capsule"):
        kind = p.GEOM_CYLINDER if shape.kind == "cylinder" else p.GEOM_CAPSULE
        args = {"shapeType": kind, "radius": shape.size[0], "length": shape.size[1], **where}
    elif shape.kind == "sphere":
        args = {"shapeType": p.GEOM_SPHERE, "radius": shape.size[0], **where}
    else:
        return  # a plane: its body is not copied
    visual = p.createVisualShape(physicsClientId=cid, rgbaColor=rgba, **args)
    p.createMultiBody(0.0, -1, visual, basePosition=xyz, baseOrientation=quat,
                      useMaximalCoordinates=True, physicsClientId=cid)


def _statics(cid: int, world: WorldPlan):
    """(PyBullet body id, its shapes, the plan's body) for the world's static bodies of shapes,
    matched in build order and checked; it stops at the first doubt."""
    index = 1 if world.ground_plane else 0
    for body in world.bodies:
        chunks = [body.shapes[i:i + SHAPES_PER_BODY] for i in range(0, len(body.shapes), SHAPES_PER_BODY)] or [()]
        for shapes in chunks:
            if index >= p.getNumBodies(physicsClientId=cid):
                return
            uid = p.getBodyUniqueId(index, physicsClientId=cid)
            index += 1
            position = p.getBasePositionAndOrientation(uid, physicsClientId=cid)[0]
            if (p.getNumJoints(uid, physicsClientId=cid) or p.getDynamicsInfo(uid, -1, physicsClientId=cid)[0]
                    or not np.allclose(position, body.xyz, atol=1e-6)):
                return
            if shapes and all(s.kind != "plane" for s in shapes) and p.getVisualShapeData(uid, physicsClientId=cid):
                yield uid, shapes, body  # a plane stays as it is (render.py draws a horizontal one)
