"""The static world in a PyBullet client: the ground plane and the world's bodies, as a World
builds them (and builds them again, in the same order and so with the same ids, after a reset)."""

from __future__ import annotations

from typing import Callable, NamedTuple

from mobot_cli.errors import WorldError
from mobot_cli.plan import Physics, WorldPlan
from mobot_cli.sim import static_shapes
from mobot_cli.sim.bullet import friction
from mobot_cli.sim.bullet.urdf_file import links_with_friction
from mobot_cli.sim.pb import p


class Statics(NamedTuple):
    """The static bodies by id: their labels (for refusals), names (what a collision was with),
    those with an inside (not planes), the ground plane's id (None without one), and those that
    hold triangle meshes (PyBullet keeps a fixed body's meshes concave: sim/clearance.py)."""

    labels: dict[int, str]
    names: dict[int, str]
    solids: set[int]
    ground: int | None
    meshes: set[int]


def build(cid: int, physics: Physics, world: WorldPlan, load: Callable[..., int]) -> Statics:
    """Set the engine's parameters and make the static world; ``load(urdf, xyz, quat, fixed=True)``
    loads a body written as URDF (-1 when PyBullet refuses it)."""
    p.setPhysicsEngineParameter(
        fixedTimeStep=physics.dt, numSolverIterations=physics.solver_iterations,
        numSubSteps=0, deterministicOverlappingPairs=1, enableConeFriction=friction.CONE_FRICTION,
        physicsClientId=cid)
    p.setGravity(*physics.gravity, physicsClientId=cid)
    labels: dict[int, str] = {}
    names: dict[int, str] = {}
    solids: set[int] = set()
    meshes: set[int] = set()
    ground: int | None = None
    if world.ground_plane:
        ground = plane(cid, 0.0)
        labels[ground] = "the ground plane"
        names[ground] = "ground_plane"
    for body in world.bodies:
        if body.shapes:
            uids = static_shapes.create(cid, body)
            for uid in uids:
                p.changeDynamics(uid, -1, physicsClientId=cid, lateralFriction=friction.DEFAULT_FRICTION
                                 if body.friction is None else body.friction)
        else:
            uids = [load(body.urdf, body.xyz, body.quat, fixed=True)]
            if uids[0] < 0:
                raise WorldError(f"PyBullet could not load static body '{body.name}'",
                                 hint="Check its geometry: meshes must exist and be readable.")
            friction.set_friction(cid, uids[0], links_with_friction(body.urdf), {}, friction.DEFAULT_FRICTION)
        for uid in uids:
            labels[uid] = body.label or f"static body '{body.name}'"
            names[uid] = body.name
            if not any(shape.kind == "plane" for shape in body.shapes):
                solids.add(uid)
            if not body.shapes or any(shape.kind == "mesh" for shape in body.shapes):  # URDF: may hold meshes
                meshes.add(uid)
    return Statics(labels, names, solids, ground, meshes)


def plane(cid: int, z: float) -> int:
    """An infinite plane at height ``z``, with the floor's friction."""
    shape = p.createCollisionShape(p.GEOM_PLANE, physicsClientId=cid)
    uid = p.createMultiBody(0.0, shape, basePosition=(0.0, 0.0, z), physicsClientId=cid)
    p.changeDynamics(uid, -1, lateralFriction=friction.FLOOR_FRICTION, physicsClientId=cid)
    return uid
