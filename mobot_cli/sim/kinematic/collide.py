"""What the kinematic engine asks PyBullet: how far a robot is from things, and where the floor is.

A robot's collision shapes are tested where it would move with ``getClosestPoints`` against
the static bodies near it and the robots whose circles come close; nothing is stepped. A
contact is support, not an obstacle, by the rule sim/contacts.py counts collisions with: its
normal points steeply up into the robot from a static body (a floor, a ramp, the edge of a
step low enough for a wheel to roll onto).
"""

from __future__ import annotations

import math

import numpy as np

from mobot_cli.plan import WorldPlan
from mobot_cli.sim.contacts import CONTACT_SLOP, SEAM, SUPPORT_BAND, SUPPORT_NORMAL_Z
from mobot_cli.sim.pb import p

# Static bodies are looked up in a box this much wider than the robot's reach around it and
# looked up again once the robot has gone half of it.
NEAR_MARGIN = 0.5  # m
# Closest points are asked for this far out: the measured clearance lets the robot move
# this far without asking again (conservative advancement).
QUERY_REACH = 0.25  # m
# Points no higher than this above a robot's lowest point carry it (wheels, casters): the
# floor is looked for under them.
FOOT_BAND = 0.005  # m, as sim/bullet/friction.py's CASTER_BAND
# Floor rays start SUPPORT_BAND above the current floor and look down this far.
FLOOR_DEPTH = 100.0  # m
STATIC_GROUP = 2  # PyBullet's collision filter group of static bodies (robots are 1, see sim/sensing/lidar.py)


# A static body near a robot is asked about only when one of its shapes' boxes, widened by this
# (round shapes' polygons, rounding), comes within the query's reach. PyBullet's margins lie
# inside its boxes, cylinders and spheres; its own boxes (of meshes) hold theirs.
BOX_SLACK = 0.02  # m


class Near:
    """The static bodies near a robot that can be in its way, cached until it has moved
    NEAR_MARGIN / 2 (or its floor changed); a body wholly below its support band is floor."""

    def __init__(self, cid: int, tops: dict[int, float], boxes: dict[int, list[tuple[float, ...]]],
                 groups: dict[int, str] | None = None):
        self.cid, self.tops, self.boxes = cid, tops, boxes
        self.groups = groups or {}  # static body -> the world body it is part of (its label)
        self.key: tuple[float, float, float] | None = None
        self.bodies: list[int] = []
        self.gaps: list[tuple[int, float]] = []  # (body, how far its boxes are from the key's x, y)

    def around(self, x: float, y: float, z: float, reach: float, height: float, floor: float,
               top: float = math.inf) -> list[int]:
        """Static bodies whose boxes come within reach of a robot at (x, y, z) (its lowest point
        at ``floor``, its highest at ``top``)."""
        if not self.tops:  # a world of nothing but ground
            return self.bodies
        key = self.key
        if key is not None and key[2] == floor and math.hypot(x - key[0], y - key[1]) < NEAR_MARGIN / 2.0:
            return self.bodies
        r = reach + QUERY_REACH + NEAR_MARGIN
        found = p.getOverlappingObjects((x - r, y - r, z - height - r), (x + r, y + r, z + height + r),
                                        physicsClientId=self.cid) or ()
        tops, low = self.tops, floor + SUPPORT_BAND
        self.bodies = sorted({uid for uid, _ in found if uid in tops and tops[uid] > low})
        low, high = floor - QUERY_REACH, top + QUERY_REACH  # shapes wholly above or below: out of reach
        self.gaps = [(uid, _gap(self.boxes.get(uid), x, y, low, high)) for uid in self.bodies]
        self.key = (x, y, floor)
        return self.bodies

    def within(self, x: float, y: float, reach: float) -> list[int]:
        """Of the bodies ``around`` found last, those whose boxes may come within ``reach`` of
        (x, y): the others have no point that near, and a query of them would find none."""
        if self.key is None:
            return self.bodies
        limit = reach + math.hypot(x - self.key[0], y - self.key[1])  # how far it is from the key
        return [uid for uid, gap in self.gaps if gap <= limit]


def _gap(boxes: list[tuple[float, ...]] | None, x: float, y: float, low: float, high: float) -> float:
    """How far the nearest of the boxes reaching between heights ``low`` and ``high`` is from
    (x, y) in x and y (+inf: none does; -inf: no boxes known)."""
    if not boxes:
        return -math.inf
    return min((math.hypot(max(x0 - x, 0.0, x - x1), max(y0 - y, 0.0, y - y1))
                for x0, y0, z0, x1, y1, z1 in boxes if z0 <= high and z1 >= low), default=math.inf)


def static_boxes(cid: int, world: WorldPlan, uids: list[int]) -> dict[int, list[tuple[float, ...]]]:
    """Each static body's shapes as boxes (x0, y0, z0, x1, y1, z1), widened by BOX_SLACK, given
    the world's static bodies' ids in the order they were made (sim/bullet/world.py): a body of boxes,
    cylinders, capsules and spheres has one box a shape; any other (a mesh, a plane, URDF
    text) one box, PyBullet's own."""
    from mobot_cli.common.transforms import compose_poses, quat_matrix
    from mobot_cli.sim.sensing.raycast import shape_triangles
    from mobot_cli.sim.static_shapes import MAX_SHAPES_PER_BODY

    chunks = []  # each static body's shapes, as static_shapes.create split them
    for body in world.bodies:
        shapes = body.shapes
        chunks += [(body, shapes[i:i + MAX_SHAPES_PER_BODY]) for i in range(0, len(shapes), MAX_SHAPES_PER_BODY)] \
            if shapes else [(body, ())]
    boxes = {}
    for uid, (body, shapes) in zip(uids, chunks if len(chunks) == len(uids) else [(None, ())] * len(uids)):
        if shapes and all(shape.kind in ("box", "cylinder", "capsule", "sphere") for shape in shapes):
            boxes[uid] = []
            for shape in shapes:
                xyz, quat = compose_poses((body.xyz, body.quat), (shape.xyz, shape.quat))
                corners = shape_triangles(shape).reshape(-1, 3) @ np.array(quat_matrix(quat)).T + np.array(xyz)
                boxes[uid].append(_widened(corners.min(axis=0).tolist(), corners.max(axis=0).tolist()))
            continue
        boxes[uid] = [_widened(*_aabb(cid, uid))]
    return boxes


def _widened(lo, hi) -> tuple[float, ...]:
    return (lo[0] - BOX_SLACK, lo[1] - BOX_SLACK, lo[2] - BOX_SLACK, hi[0] + BOX_SLACK, hi[1] + BOX_SLACK,
            hi[2] + BOX_SLACK)


def _aabb(cid: int, uid: int):
    """PyBullet's box around all of a body's links."""
    found = [p.getAABB(uid, link, physicsClientId=cid) for link in range(-1, p.getNumJoints(uid, physicsClientId=cid))]
    return [min(b[0][i] for b in found) for i in range(3)], [max(b[1][i] for b in found) for i in range(3)]


def distances(cid: int, body: int, statics: list[int], robots: list[int], reach: float, floor: float,
              known: dict[int, float] | None = None, static: tuple[float, frozenset] | None = None,
              groups: dict[int, str] | None = None):
    """(nearest static obstacle, {robot body: its distance}, bodies touched within CONTACT_SLOP):
    distances in m, negative when overlapping, ``reach`` when nothing is that near; support (at
    the bottom of a robot whose lowest point is at ``floor``) does not count. ``known``: robots
    not asked, with their distance (found before, or a lower bound farther than CONTACT_SLOP);
    ``static``: the static part found before (nearest, bodies touched), not asked again."""
    low_static, touching = static if static is not None else (reach, set())
    touching = set(touching)
    band = floor + SUPPORT_BAND
    asked = [(other, p.getClosestPoints(body, other, reach, physicsClientId=cid))
             for other in (statics if static is None else ())]
    # contactNormalOnB points from the static body into the robot: up is a floor, under the
    # robot (not in its way) or holding it up; it is in the way only where it rises into the
    # robot above its lowest band. Beside what holds it up, the edges of the same world body's
    # floor triangles are floor too (SEAM, as sim/contacts.py counts them; ``groups``: the world
    # body of each PyBullet body, a mesh split into several being one floor).
    groups = groups or {}
    supports: dict = {}
    for other, found in asked:
        key = groups.get(other, other)
        for c in found:
            if c[7][2] > SUPPORT_NORMAL_Z and (c[8] > 0.0 or c[5][2] <= band):
                supports[key] = max(supports.get(key, -math.inf), c[6][2])
    for other, found in asked:
        support = supports.get(groups.get(other, other), -math.inf) + SEAM
        for c in found:
            d = c[8]
            if (c[7][2] > SUPPORT_NORMAL_Z and (d > 0.0 or c[5][2] <= band)) or c[6][2] <= support:
                continue
            if d < low_static:
                low_static = d
            if d <= CONTACT_SLOP:
                touching.add(other)
    apart, closest = {}, p.getClosestPoints
    for other in robots:
        if known and other in known:
            low = apart[other] = min(known[other], reach)
            if low <= CONTACT_SLOP:  # found before, touching
                touching.add(other)
            continue
        found = closest(body, other, reach, physicsClientId=cid)
        low = apart[other] = min(reach, min([c[8] for c in found])) if found else reach
        if low <= CONTACT_SLOP:  # reach is more
            touching.add(other)
    return low_static, apart, touching


def nearest(found) -> float:
    """The smallest distance of a ``distances`` answer, static or robot."""
    return min(found[0], min(found[1].values(), default=found[0]))


class Floor:
    """Heights of the floor under points: the world's triangles cast with Embree (as lidars
    are), PyBullet's rays for worlds it cannot triangulate, nothing at all for a bare plane."""

    def __init__(self, cid: int, world: WorldPlan):
        self.cid, self.world = cid, world
        self.flat = not world.bodies  # the ground plane alone (or nothing): the floor is z = 0
        self._scene = None
        self._built = False

    @property
    def scene(self):
        """The static world's ray scene (None when PyBullet must cast)."""
        if not self._built:
            from mobot_cli.sim.sensing.raycast import embree_available, static_scene

            scene = static_scene(self.world) if embree_available() else None
            self._scene = scene if scene is not None and scene.complete else None
            self._built = True
        return self._scene

    def heights(self, points: np.ndarray, tops: np.ndarray) -> np.ndarray:
        """The highest floor below each (x, y) point under its ``top`` (-inf where none)."""
        n = len(points)
        if self.flat:
            return np.where(tops >= 0.0, 0.0, -np.inf) if self.world.ground_plane else np.full(n, -np.inf)
        origins = np.column_stack([points, tops])
        scene = self.scene
        if scene is not None:
            down = np.broadcast_to(np.array([0.0, 0.0, -1.0]), (n, 3))
            t = scene.cast(origins, down, np.full(n, FLOOR_DEPTH)).astype(float)
            return tops - t
        ends = origins - np.array([0.0, 0.0, FLOOR_DEPTH])
        out = np.full(n, -np.inf)
        hits = p.rayTestBatch(origins.tolist(), ends.tolist(), collisionFilterMask=STATIC_GROUP,
                              physicsClientId=self.cid)  # static bodies only: never a robot
        for i, hit in enumerate(hits):
            if hit[0] >= 0 and hit[2] > 0.0:  # a ray that starts inside a body is not on a floor
                out[i] = tops[i] - hit[2] * FLOOR_DEPTH
        return out


def feet(probes, body: int, lo, pose: tuple[float, float, float]) -> list[tuple[float, float]]:
    """Where the robot stands on the floor, in its root frame: the lowest points of its links
    (wheels, casters), found against a plane under it (the world's probe shape, no body)."""
    points = [(c[5], c[8]) for c in probes.closest(body, (0.0, 0.0, 1.0), (0.0, 0.0, lo[2] - 1.0), 2.0)]
    low = min(d for _, d in points)
    x, y, yaw = pose
    c, s = np.cos(yaw), np.sin(yaw)
    found = {(round(c * (q[0] - x) + s * (q[1] - y), 6), round(-s * (q[0] - x) + c * (q[1] - y), 6))
             for q, d in points if d - low <= FOOT_BAND}
    return sorted(found)
