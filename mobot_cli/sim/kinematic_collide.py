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

from mobot_cli.sim.bullet import p
from mobot_cli.sim.contacts import CONTACT_SLOP, SUPPORT_NORMAL_Z
from mobot_cli.sim.plan import WorldPlan

# Static bodies are looked up in a box this much wider than the robot's reach around it and
# looked up again once the robot has gone half of it.
NEAR_MARGIN = 0.5  # m
# Closest points are asked for this far out: the measured clearance lets the robot move
# this far without asking again (conservative advancement).
QUERY_REACH = 0.25  # m
# A contact counts as support only this close above the robot's lowest point: a wheel rolls
# onto a low step, but a floor rising into the chassis is in the way.
SUPPORT_BAND = 0.02  # m
# Floor rays start SUPPORT_BAND above the current floor and look down this far.
FLOOR_DEPTH = 100.0  # m
STATIC_GROUP = 2  # PyBullet's collision filter group of static bodies (robots are 1, see sim/lidar.py)


class Near:
    """The static bodies near a robot that can be in its way, cached until it has moved
    NEAR_MARGIN / 2 (or its floor changed); a body wholly below its support band is floor."""

    def __init__(self, cid: int, tops: dict[int, float]):
        self.cid, self.tops = cid, tops
        self.key: tuple[float, float, float] | None = None
        self.bodies: list[int] = []

    def around(self, x: float, y: float, z: float, reach: float, height: float, floor: float) -> list[int]:
        """Static bodies whose boxes come within reach of a robot at (x, y, z)."""
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
        self.key = (x, y, floor)
        return self.bodies


def distances(cid: int, body: int, statics: list[int], robots: list[int], reach: float, floor: float):
    """(nearest static obstacle, {robot body: its distance}, bodies touched within CONTACT_SLOP):
    distances in m, negative when overlapping, ``reach`` when nothing is that near; support (at
    the bottom of a robot whose lowest point is at ``floor``) does not count."""
    low_static, touching = reach, set()
    band = floor + SUPPORT_BAND
    for other in statics:
        for c in p.getClosestPoints(body, other, reach, physicsClientId=cid):
            # contactNormalOnB points from the static body into the robot: up is a floor, under
            # the robot (not in its way) or holding it up; it is in the way only where it rises
            # into the robot above its lowest band.
            d = c[8]
            if c[7][2] > SUPPORT_NORMAL_Z and (d > 0.0 or c[5][2] <= band):
                continue
            if d < low_static:
                low_static = d
            if d <= CONTACT_SLOP:
                touching.add(other)
    apart = {}
    for other in robots:
        low = reach
        for c in p.getClosestPoints(body, other, reach, physicsClientId=cid):
            d = c[8]
            if d < low:
                low = d
            if d <= CONTACT_SLOP:
                touching.add(other)
        apart[other] = low
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
            from mobot_cli.sim.raycast import StaticScene, embree_available

            scene = StaticScene(self.world) if embree_available() else None
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
