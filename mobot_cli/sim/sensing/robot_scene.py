"""The robots as a ray-casting scene: their collision shapes as triangles, moved to where they are.

A lidar among other robots must see them, and PyBullet's ``rayTestBatch`` answers ray by ray (bench/README.md);
with a hundred robots within range of each other most rays pass near one. So each robot's
collision shapes are turned into triangles once, per link, in the link's frame (PyBullet's
inertial frame, the one ``getLinkState`` poses), as PyBullet collides with them:

* boxes exactly; spheres, capsules and cylinders (mobot loads URDFs with implicit cylinders)
  as polygons whose faces lie within ``ROUND_TOLERANCE`` (0.5 mm) inside the true surface, as
  the static world's (sim/sensing/raycast.py);
* meshes as the convex hull of the vertices PyBullet keeps for them (``getMeshData``: a moving
  link's mesh collides as its hull; so does a cylinder loaded without implicit cylinders).

At each cast the links within reach of some sensor and reaching into the heights the rays
span are moved to their current poses and put into one small Embree scene, which every
ray of the cast is traced through (up to its static hit). A robot never sees itself: a ray whose
hit is one of its own robot's triangles goes on from just beyond it (``OWN_STEP``), so its
own links are transparent, as they are when PyBullet casts (sim/sensing/lidar.py).

A robot with a shape that cannot be turned into triangles (a heightfield, a mesh without
scipy's hull) is left to PyBullet's ray test, as every robot was before.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mobot_cli.plan import StaticShape
from mobot_cli.sim.pb import p
from mobot_cli.sim.sensing.raycast import shape_triangles

OWN_STEP = 1e-4  # m: a ray that met its own robot goes on from this far beyond the hit
OWN_PASSES = 16  # own surfaces a single ray may pass through (a convex shape has two)
REACH_MARGIN = 0.1  # m: a link this much beyond range_max is still put into the scene
# m: PyBullet's URDF importer gives every shape a 1 mm collision margin; a box's, sphere's,
# capsule's and implicit cylinder's lie within the shape, a convex hull's outside it (measured:
# rays meet a hull 1.0 mm out along its normals), so hulls are grown by it.
HULL_MARGIN = 0.001
HEIGHT_SLACK = 0.001  # m: a triangle this close to the rays' heights is kept (float32 rounding)
_GEOMS = {p.GEOM_BOX: "box", p.GEOM_SPHERE: "sphere", p.GEOM_CYLINDER: "cylinder", p.GEOM_CAPSULE: "capsule"}


@dataclass(frozen=True)
class Link:
    """One link's collision surface in its (inertial) frame."""

    index: int  # PyBullet link index, -1 for the base
    vertices: np.ndarray  # (n, 3)
    faces: np.ndarray  # (m, 3) indices into vertices
    centre: np.ndarray  # (3,) the middle of the vertices' box
    half: np.ndarray  # (3,) half the box's size


class RobotShapes:
    """Every robot's links as triangles, made at its first cast and kept while its body lives."""

    def __init__(self, cid: int):
        from embreex.rtcore import EmbreeDevice

        self.cid = cid
        self.device = EmbreeDevice()  # one for every cast's scene (a device a scene costs threads)
        self._links: dict[int, tuple[Link, ...] | None] = {}  # body -> links; None: PyBullet casts at it
        self._made: dict[tuple, tuple[Link, ...] | None] = {}  # by the shapes PyBullet has: a fleet's robots share
        self._fleet: Fleet | None = None  # the last cast's robots, their links stacked

    def links(self, body: int) -> tuple[Link, ...] | None:
        """The body's links with triangles, or None when some shape cannot be made into them."""
        if body not in self._links:
            key = shapes_key(self.cid, body)
            if key not in self._made:
                self._made[key] = robot_links(self.cid, body)
            self._links[body] = self._made[key]
        return self._links[body]

    def forget(self, body: int) -> None:
        """The body left the world (PyBullet may give its id to the next one)."""
        self._links.pop(body, None)
        self._fleet = None

    def rays(self, bodies: list[int]) -> "RobotRays":
        """The robots of ``bodies`` whose shapes are triangles, to cast at."""
        meshed = tuple(body for body in bodies if self.links(body) is not None)
        if self._fleet is None or self._fleet.bodies != meshed:
            self._fleet = Fleet.of(meshed, [self.links(body) for body in meshed])
        return RobotRays(self, list(meshed), self._fleet)


@dataclass(frozen=True)
class Fleet:
    """Robots' links in one list, with what each cast needs of them stacked (made when the robots change)."""

    bodies: tuple[int, ...]
    links: list[Link]
    owners: np.ndarray  # (links,) each link's body
    centres: np.ndarray  # (links, 3) each link's box middle in its frame
    halves: np.ndarray  # (links, 3)

    @classmethod
    def of(cls, bodies: tuple[int, ...], links: list[tuple[Link, ...]]) -> "Fleet":
        flat = [link for mine in links for link in mine]
        owners = np.repeat(np.array(bodies, dtype=int), [len(mine) for mine in links])
        return cls(bodies, flat, owners, np.array([link.centre for link in flat]).reshape(-1, 3),
                   np.array([link.half for link in flat]).reshape(-1, 3))


@dataclass
class RobotRays:
    """Robots to cast a batch of rays at (their poses are read at the cast)."""

    shapes: RobotShapes
    bodies: list[int]
    fleet: Fleet

    def cast(self, origins: np.ndarray, dirs: np.ndarray, reach: np.ndarray, owners: np.ndarray,
             sensors: np.ndarray, ranges: np.ndarray) -> np.ndarray:
        """Distance (float32) along each ray (float32 origins and unit directions) to the first
        triangle of a robot other than its owner's within ``reach``; +inf where there is none.
        ``sensors`` (k, 3) and ``ranges`` (k,): where the scans are taken and how far they see."""
        out = np.full(len(origins), np.inf, dtype=np.float32)
        if not len(origins) or not self.bodies:
            return out
        heights = _heights(origins, dirs, reach)
        scene, owner_of = self._scene(sensors, ranges, heights)
        if scene is None:
            return out
        live = np.flatnonzero(reach > 0.0)
        start, left = origins.copy(), reach.astype(np.float32, copy=True)
        done = np.zeros(len(origins), dtype=np.float32)
        for _ in range(OWN_PASSES):
            if not len(live):
                break
            found = scene.run(start[live], dirs[live], dists=left[live].copy(), output=1)
            prim, far = found["primID"], found["tfar"]
            hit = prim >= 0
            own = np.zeros(len(live), dtype=bool)
            own[hit] = owner_of[prim[hit]] == owners[live[hit]]
            other = hit & ~own
            out[live[other]] = done[live[other]] + far[other]
            again = live[own]
            step = far[own] + np.float32(OWN_STEP)
            start[again] += dirs[again] * step[:, None]
            done[again] += step
            left[again] -= step
            live = again[left[again] > 0.0]
        return out

    def _scene(self, sensors: np.ndarray, ranges: np.ndarray, heights: tuple[float, float]):
        """An Embree scene of the links that rays from these sensors can reach at these heights,
        where they are now, and the body of each of its triangles; (None, None) when none can."""
        cid, low, high = self.shapes.cid, heights[0] - HEIGHT_SLACK, heights[1] + HEIGHT_SLACK
        fleet = self.fleet
        links, positions, quats = fleet.links, [], []
        for body in self.bodies:
            for position, quat in _poses(cid, body, self.shapes.links(body)):
                positions.append(position)
                quats.append(quat)
        # Which links can matter, all at once: the box around each link's vertices, turned, must
        # reach into the rays' heights and come within some sensor's range.
        position, rotation = np.array(positions), _matrices(np.array(quats))
        centre = position + np.einsum("lij,lj->li", rotation, fleet.centres)
        reach = np.einsum("lij,lj->li", np.abs(rotation), fleet.halves)
        near = (centre[:, 2] + reach[:, 2] >= low) & (centre[:, 2] - reach[:, 2] <= high)
        apart = np.sqrt(((centre[:, None, :] - sensors[None, :, :]) ** 2).sum(axis=2))  # (links, sensors)
        near &= np.any(apart - np.sqrt((reach ** 2).sum(axis=1))[:, None] <= ranges[None, :] + REACH_MARGIN, axis=1)
        kept = np.flatnonzero(near)
        if not len(kept):
            return None, None
        # The kept links' vertices moved to their poses at once, and their faces that reach the heights.
        counts = np.array([len(links[k].vertices) for k in kept])
        which = np.repeat(np.arange(len(kept)), counts)
        local = np.concatenate([links[k].vertices for k in kept])
        world = np.einsum("nij,nj->ni", rotation[kept][which], local) + position[kept][which]
        starts = np.cumsum(counts) - counts
        faces = np.concatenate([links[k].faces + start for k, start in zip(kept, starts)])
        owner_of = np.repeat(fleet.owners[kept], [len(links[k].faces) for k in kept])
        z = world[faces, 2]
        keep = (z.max(axis=1) >= low) & (z.min(axis=1) <= high)
        if not keep.any():
            return None, None
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh

        scene = rtcore_scene.EmbreeScene(self.shapes.device)
        TriangleMesh(scene, world.astype(np.float32), faces[keep].astype(np.int32))
        return scene, owner_of[keep]


def _poses(cid: int, body: int, links: tuple[Link, ...]) -> list[tuple[tuple, tuple]]:
    """World pose (position, quaternion x, y, z, w) of each link's inertial frame now."""
    moving = [link.index for link in links if link.index >= 0]
    states = iter(p.getLinkStates(body, moving, computeForwardKinematics=1, physicsClientId=cid) if moving else ())
    return [p.getBasePositionAndOrientation(body, physicsClientId=cid) if link.index < 0 else next(states)[:2]
            for link in links]


def _matrices(quats: np.ndarray) -> np.ndarray:
    """Rotation matrices (n, 3, 3) of unit quaternions (n, 4) as (x, y, z, w)."""
    x, y, z, w = quats.T
    return np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),
                     2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
                     2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], axis=1).reshape(-1, 3, 3)


def shapes_key(cid: int, body: int) -> tuple:
    """What PyBullet knows of a body's collision shapes (a mesh's vertices included), without its id."""
    key = []
    for index in range(-1, p.getNumJoints(body, physicsClientId=cid)):
        for number, shape in enumerate(p.getCollisionShapeData(body, index, physicsClientId=cid)):
            mesh = p.getMeshData(body, index, collisionShapeIndex=number, physicsClientId=cid)[1] \
                if shape[2] == p.GEOM_MESH else ()
            key.append((index, *shape[2:], mesh))
    return tuple(key)


def robot_links(cid: int, body: int) -> tuple[Link, ...] | None:
    """A body's links with collision shapes, as triangles in their inertial frames; None when
    some shape cannot be turned into triangles."""
    links = []
    for index in range(-1, p.getNumJoints(body, physicsClientId=cid)):
        triangles = []
        for number, shape in enumerate(p.getCollisionShapeData(body, index, physicsClientId=cid)):
            local = _shape_triangles(cid, body, index, number, shape)
            if local is None:
                return None
            triangles.append(local)
        if triangles:
            vertices, inverse = np.unique(np.concatenate(triangles).reshape(-1, 3), axis=0, return_inverse=True)
            faces = inverse.reshape(-1, 3)
            low, high = vertices.min(axis=0), vertices.max(axis=0)
            links.append(Link(index, vertices, faces, (low + high) / 2.0, (high - low) / 2.0))
    return tuple(links)


def _shape_triangles(cid: int, body: int, link: int, number: int, shape) -> np.ndarray | None:
    """One collision shape (a ``getCollisionShapeData`` row) as triangles (n, 3, 3) in its link's
    inertial frame; None when it cannot be made into triangles."""
    geom, dims, xyz, quat = shape[2], shape[3], shape[5], shape[6]
    if geom == p.GEOM_MESH:
        # PyBullet gives the hull's vertices posed in the link's inertial frame already.
        count, vertices = p.getMeshData(body, link, collisionShapeIndex=number, physicsClientId=cid)
        return _hull(np.array(vertices, dtype=float)) if count else None
    kind = _GEOMS.get(geom)
    if kind is None:
        return None
    size = {"box": dims, "sphere": dims[:1], "cylinder": (dims[1], dims[0]), "capsule": (dims[1], dims[0])}[kind]
    local = shape_triangles(StaticShape(kind=kind, size=tuple(size)))
    rotation = np.array(p.getMatrixFromQuaternion(quat)).reshape(3, 3)
    return local @ rotation.T + np.array(xyz)


def _hull(points: np.ndarray) -> np.ndarray | None:
    """The convex hull of points grown by PyBullet's margin (its faces moved out by
    ``HULL_MARGIN``) as triangles; None without scipy or for a flat set of points."""
    try:
        from scipy.spatial import ConvexHull, HalfspaceIntersection, QhullError
    except ImportError:
        return None
    try:
        planes = ConvexHull(points).equations.copy()  # (normal, offset): normal . x + offset <= 0 inside
        planes[:, 3] -= HULL_MARGIN
        corners = HalfspaceIntersection(planes, points.mean(axis=0)).intersections
        return corners[ConvexHull(corners).simplices]
    except (QhullError, ValueError):
        return None


def _heights(origins: np.ndarray, dirs: np.ndarray, reach: np.ndarray) -> tuple[float, float]:
    """The lowest and highest z the rays reach (from their origins to their ends)."""
    finite = np.isfinite(reach)
    z = origins[:, 2]
    end = z[finite] + dirs[finite, 2] * reach[finite]
    return float(min(z.min(), end.min(initial=np.inf))), float(max(z.max(), end.max(initial=-np.inf)))
