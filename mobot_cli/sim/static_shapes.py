"""Static world bodies from collision shapes: one PyBullet body per world model.

Meshes are built as concave triangle meshes (GEOM_FORCE_CONCAVE_TRIMESH), never convex
hulls: the hull of a house's walls fills every room. PyBullet's URDF importer ignores
``concave="yes"`` for meshes in this version, so static bodies do not go through URDF.
"""

from __future__ import annotations

import dataclasses
import hashlib
from pathlib import Path

from mobot_cli.errors import WorldError
from mobot_cli.plan import StaticBody, StaticShape
from mobot_cli.sim.pb import p

_TYPES = {"box": p.GEOM_BOX, "cylinder": p.GEOM_CYLINDER, "capsule": p.GEOM_CAPSULE,
          "sphere": p.GEOM_SPHERE, "plane": p.GEOM_PLANE, "mesh": p.GEOM_MESH}


# PyBullet's command buffer holds at most 16 shapes per compound (MAX_COMPOUND_COLLISION_SHAPES);
# more overwrite memory and crash the process, so larger models become several bodies.
MAX_SHAPES_PER_BODY = 16
# PyBullet answers a closest-point query with one point per triangle within the distance, into
# a buffer that overflows (and crashes the process) past about 46,000 points: a body holds at
# most this many triangles, a larger mesh being cut into pieces of this many, each a body.
MAX_TRIANGLES_PER_BODY = 20_000


def create(cid: int, body: StaticBody) -> list[int]:
    """Fixed bodies holding the body's shapes, at most 16 and 20,000 triangles to a body; their ids."""
    return [_create(cid, body, group) for group in groups(body.shapes)]


def groups(shapes: tuple[StaticShape, ...]) -> list[tuple[StaticShape, ...]]:
    """The shapes in bodies' worth, in order: at most MAX_SHAPES_PER_BODY shapes and
    MAX_TRIANGLES_PER_BODY triangles each (a larger mesh is cut into pieces)."""
    out: list[tuple[StaticShape, ...]] = []
    current: list[StaticShape] = []
    triangles = 0
    for shape in shapes:
        for piece, count in _pieces(shape):
            if current and (len(current) == MAX_SHAPES_PER_BODY or triangles + count > MAX_TRIANGLES_PER_BODY):
                out.append(tuple(current))
                current, triangles = [], 0
            current.append(piece)
            triangles += count
    if current:
        out.append(tuple(current))
    return out


def _pieces(shape: StaticShape) -> list[tuple[StaticShape, int]]:
    """The shape and its triangles, or a mesh over MAX_TRIANGLES_PER_BODY as OBJ pieces (cached)."""
    if shape.kind != "mesh":
        return [(shape, 0)]
    import numpy as np

    from mobot_cli.common import cache
    from mobot_cli.common.meshfile import obj_text, read_mesh

    vertices, faces = read_mesh(shape.mesh)
    if len(faces) <= MAX_TRIANGLES_PER_BODY:
        return [(shape, len(faces))]
    out = []
    for start in range(0, len(faces), MAX_TRIANGLES_PER_BODY):
        part = faces[start:start + MAX_TRIANGLES_PER_BODY]
        used, local = np.unique(part, return_inverse=True)
        data = obj_text(vertices[used], local.reshape(-1, 3), f"piece {start // MAX_TRIANGLES_PER_BODY} of "
                        f"{Path(shape.mesh).name}").encode("utf-8")
        path = cache.store_file("meshes", f"piece-{hashlib.sha256(data).hexdigest()}.obj", data)
        out.append((dataclasses.replace(shape, mesh=str(path)), len(part)))
    return out


def _create(cid: int, body: StaticBody, shapes: tuple[StaticShape, ...]) -> int:
    try:
        if len(shapes) == 1:
            shape = p.createCollisionShape(physicsClientId=cid, **shape_args(shapes[0]))
        else:
            shape = p.createCollisionShapeArray(physicsClientId=cid, **_array(shapes))
    except p.error:
        meshes = sorted({s.mesh for s in shapes if s.kind == "mesh"})
        raise WorldError(
            f"PyBullet could not build the collision shapes of {body.label or body.name}"
            + (f" (meshes: {', '.join(meshes)})" if meshes else ""),
            hint="Check that its meshes are readable triangle meshes.") from None
    # A plain static rigid body (maximal coordinates), not a fixed-base multibody: the solver
    # skips it each step; as multibodies, the 87 models of the AWS house halved the step rate.
    return p.createMultiBody(0.0, shape, basePosition=body.xyz, baseOrientation=body.quat,
                             useMaximalCoordinates=True, physicsClientId=cid)


def shape_args(shape: StaticShape) -> dict:
    """createCollisionShape's arguments for one shape, posed in its body's frame."""
    args = {"shapeType": _TYPES[shape.kind], "collisionFramePosition": shape.xyz,
            "collisionFrameOrientation": shape.quat}
    kind, size = shape.kind, shape.size
    if kind == "box":
        args["halfExtents"] = [s / 2.0 for s in size]
    elif kind in ("cylinder", "capsule"):
        args["radius"], args["height"] = size[0], size[1]
    elif kind == "sphere":
        args["radius"] = size[0]
    elif kind == "plane":
        args["planeNormal"] = list(size)
    else:
        args.update(fileName=shape.mesh, meshScale=list(size), flags=p.GEOM_FORCE_CONCAVE_TRIMESH)
    return args


def _array(shapes: tuple[StaticShape, ...]) -> dict:
    """createCollisionShapeArray's parallel lists (it names a cylinder's height 'lengths')."""
    out: dict[str, list] = {key: [] for key in (
        "shapeTypes", "radii", "halfExtents", "lengths", "fileNames", "meshScales", "planeNormals",
        "flags", "collisionFramePositions", "collisionFrameOrientations")}
    for shape in shapes:
        single = shape_args(shape)
        out["shapeTypes"].append(single["shapeType"])
        out["radii"].append(single.get("radius", 0.0))
        out["halfExtents"].append(single.get("halfExtents", [0.0, 0.0, 0.0]))
        out["lengths"].append(single.get("height", 0.0))
        out["fileNames"].append(single.get("fileName", ""))
        out["meshScales"].append(single.get("meshScale", [1.0, 1.0, 1.0]))
        out["planeNormals"].append(single.get("planeNormal", [0.0, 0.0, 1.0]))
        out["flags"].append(single.get("flags", 0))
        out["collisionFramePositions"].append(list(shape.xyz))
        out["collisionFrameOrientations"].append(list(shape.quat))
    return out
