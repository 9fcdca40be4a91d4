"""Static world bodies from collision shapes: one PyBullet body per world model.

Meshes are built as concave triangle meshes (GEOM_FORCE_CONCAVE_TRIMESH), never convex
hulls: the hull of a house's walls fills every room. PyBullet's URDF importer ignores
``concave="yes"`` for meshes in this version, so static bodies do not go through URDF.
"""

from __future__ import annotations

from mobot_cli.errors import WorldError
from mobot_cli.plan import StaticBody, StaticShape
from mobot_cli.sim.pb import p

_TYPES = {"box": p.GEOM_BOX, "cylinder": p.GEOM_CYLINDER, "capsule": p.GEOM_CAPSULE,
          "sphere": p.GEOM_SPHERE, "plane": p.GEOM_PLANE, "mesh": p.GEOM_MESH}


# PyBullet's command buffer holds at most 16 shapes per compound (MAX_COMPOUND_COLLISION_SHAPES);
# more overwrite memory and crash the process, so larger models become several bodies.
MAX_SHAPES_PER_BODY = 16


def create(cid: int, body: StaticBody) -> list[int]:
    """Fixed bodies holding the body's shapes, at most 16 to a compound; their ids."""
    shapes = body.shapes
    return [_create(cid, body, shapes[i:i + MAX_SHAPES_PER_BODY])
            for i in range(0, len(shapes), MAX_SHAPES_PER_BODY)]


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
