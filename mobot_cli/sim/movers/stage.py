"""Movers in a World: the Crowd, a PyBullet body for each, and what the World asks of them.

A mover's body is a mass-0 shape that robots collide with (collision group ``MOVER_GROUP``,
meeting robots only: not the static world, not each other, not the floor rays of the kinematic
engine, not PyBullet's ray tests of the lidar, which casts at movers itself: shapes.py). Only
movers near a robot have a body, moved with them (``resetBasePositionAndOrientation``): it is
given when the mover comes within ``NEAR`` of a robot and taken back when it is ``NEAR + AWAY``
away. Every body in PyBullet costs each step (50 bodies parked out of the way added a fifth
to a house step, measured) and making one costs milliseconds in a furnished world, so bodies
taken back wait (``PARK``, meeting nothing) for the next mover of their shape to come near.
"""

from __future__ import annotations

import math

import numpy as np

from mobot_cli.errors import SpawnError
from mobot_cli.plan import MoverPlan, WorldPlan
from mobot_cli.sim.movers.crowd import Crowd
from mobot_cli.sim.movers.shapes import Snapshot
from mobot_cli.sim.pb import p

MOVER_GROUP = 4  # PyBullet collision filter group (robots are 1, static bodies 2)
ROBOT_MASK = 1
PARK = (0.0, 0.0, -1000.0)  # where spare bodies wait
# m between a mover's and a robot's circles within which it has a body: what clearance sees of
# movers (timeline/metrics.py measures people's distance from their poses, at any distance).
# Between two updates a walker moves at most 6.5 cm and a robot rarely more: a body is in place
# long before anything touches it. Bodies near a robot cost its collision detection every step.
NEAR = 0.5
AWAY = 0.3  # m further than NEAR before its body goes
STATIC_GROUP = 2


class MoverStage:
    """The movers of one World."""

    def __init__(self, cid: int, rate_hz: int, world: WorldPlan, seed: int):
        self.cid, self.world = cid, world
        self.crowd = Crowd(rate_hz, seed, self._walls)
        self.every = self.crowd.every
        self.bodies: dict[str, int] = {}  # mover name -> its body, of the movers near a robot
        self.names: dict[int, str] = {}  # body -> mover name (how collisions name it)
        self.people: set[int] = set()  # bodies of person movers
        self._shapes: dict[tuple, int] = {}  # (shape, size) -> PyBullet collision shape
        self._spare: dict[tuple, list[int]] = {}  # (shape, size) -> parked bodies of that shape
        self._keys: dict[int, tuple] = {}  # body -> its (shape, size)
        self._radius: dict[int, float] = {}  # robot body -> the radius of its circle
        self._scene = None
        self._scene_built = False

    def add(self, plan: MoverPlan, step: int) -> None:
        """A mover enters now; SpawnError when its name is taken."""
        if plan.name in self.crowd.names():
            raise SpawnError(f"a mover named '{plan.name}' already exists", hint="Mover names must be unique.")
        self.crowd.add(plan, step)

    def remove(self, name: str) -> None:
        """A mover leaves; KeyError when there is none of that name."""
        if name not in self.crowd.names():
            raise KeyError(f"no mover named '{name}'")
        if name in self.bodies:
            self._unmake(name)
        self.crowd.remove(name)

    def _make(self, plan: MoverPlan) -> int:
        key = (plan.shape, plan.size)
        spare = self._spare.get(key)
        if spare:
            uid = spare.pop()
        else:
            if key not in self._shapes:
                self._shapes[key] = _shape(self.cid, plan)
            uid = p.createMultiBody(0.0, self._shapes[key], basePosition=PARK, physicsClientId=self.cid)
            p.setCollisionFilterGroupMask(uid, -1, MOVER_GROUP, ROBOT_MASK, physicsClientId=self.cid)
            self._keys[uid] = key
        self.bodies[plan.name], self.names[uid] = uid, plan.name
        if plan.shape == "person":
            self.people.add(uid)
        return uid

    def _unmake(self, name: str) -> None:
        uid = self.bodies.pop(name)
        p.resetBasePositionAndOrientation(uid, PARK, (0.0, 0.0, 0.0, 1.0), physicsClientId=self.cid)
        self._spare.setdefault(self._keys[uid], []).append(uid)
        del self.names[uid]
        self.people.discard(uid)

    def update(self, step: int, robots: list[tuple[int, float, float]]) -> None:
        """Move the movers to ``step`` and the bodies of those near a robot (body, x, y) with them."""
        xy = np.array([(x, y) for _, x, y in robots], dtype=float).reshape(-1, 2)
        radius = np.array([self._robot_radius(body) for body, _, _ in robots])
        crowd = self.crowd
        crowd.update(step, xy, radius)
        if not len(xy):
            gap = np.full(len(crowd), np.inf)
        else:
            apart = np.hypot(crowd.pos[:, None, 0] - xy[None, :, 0], crowd.pos[:, None, 1] - xy[None, :, 1])
            gap = (apart - crowd.radius[:, None] - radius[None, :]).min(axis=1)
        cid, bodies = self.cid, self.bodies
        close = (gap <= NEAR + AWAY).nonzero()[0].tolist()
        x, y, yaw = crowd.pos[close, 0].tolist(), crowd.pos[close, 1].tolist(), crowd.yaw[close].tolist()
        for k, i in enumerate(close):
            plan = crowd.plans[i]
            uid = bodies.get(plan.name)
            if uid is None:
                if gap[i] > NEAR:
                    continue
                uid = self._make(plan)
            half = yaw[k] / 2.0
            p.resetBasePositionAndOrientation(uid, (x[k], y[k], crowd.middle[i]),
                                              (0.0, 0.0, math.sin(half), math.cos(half)), physicsClientId=cid)
        if len(bodies) > len(close):
            keep = {crowd.plans[i].name for i in close}
            for name in [n for n in bodies if n not in keep]:
                self._unmake(name)

    def placed_bodies(self) -> list[int]:
        """The movers' bodies (of those near a robot)."""
        return list(self.bodies.values())

    def snapshot(self) -> Snapshot | None:
        """The movers' shapes now, for a scan; None without movers."""
        return self.crowd.snapshot() if len(self.crowd) else None

    def _robot_radius(self, body: int) -> float:
        """The radius of a robot's circle in the plane (its bounding box when first seen)."""
        if body not in self._radius:
            boxes = [p.getAABB(body, link, physicsClientId=self.cid)
                     for link in range(-1, p.getNumJoints(body, physicsClientId=self.cid))]
            lo, hi = np.min([b[0] for b in boxes], axis=0), np.max([b[1] for b in boxes], axis=0)
            self._radius[body] = float(np.hypot(hi[0] - lo[0], hi[1] - lo[1]) / 2.0)
        return self._radius[body]

    def social(self, robot, state, distance: bool) -> None:
        """Fill a robot's state's people figures (sim/state.py); its distance to people only when
        ``distance`` (its clearance is watched: what its goals' metrics read), as its clearance."""
        state.people_collisions = robot.people_collisions
        if distance:
            state.people_distance = self.crowd.people_distance(state.true_x, state.true_y)

    def forget_robot(self, body: int) -> None:
        self._radius.pop(body, None)

    def _walls(self, origins: np.ndarray, dirs: np.ndarray, lengths: np.ndarray) -> np.ndarray:
        """Distance along each ray to the static world (+inf: nothing within its length)."""
        if not self._scene_built:
            from mobot_cli.sim.sensing.raycast import embree_available, static_scene

            scene = static_scene(self.world) if embree_available() else None
            self._scene = scene if scene is not None and scene.complete else None
            self._scene_built = True
        if self._scene is not None:  # level rays: their heights are their starts'
            z = origins[:, 2]
            return self._scene.cast(origins, dirs, lengths, (float(z.min()), float(z.max()))).astype(float)
        ends = origins + dirs * lengths[:, None]
        hits = p.rayTestBatch(origins.tolist(), ends.tolist(), collisionFilterMask=STATIC_GROUP,
                              physicsClientId=self.cid)
        return np.array([h[2] * length if h[0] >= 0 else math.inf for h, length in zip(hits, lengths)])


def _shape(cid: int, plan: MoverPlan) -> int:
    """A PyBullet collision shape of the mover's shape (upright, centred)."""
    if plan.shape == "box":
        shape = p.createCollisionShape(p.GEOM_BOX, halfExtents=[s / 2.0 for s in plan.size], physicsClientId=cid)
    elif plan.shape == "cylinder":
        shape = p.createCollisionShape(p.GEOM_CYLINDER, radius=plan.size[0], height=plan.size[1], physicsClientId=cid)
    else:  # a person: a capsule, its height from the bottom of one end to the top of the other
        radius = plan.size[0]
        shape = p.createCollisionShape(p.GEOM_CAPSULE, radius=radius, height=max(plan.size[1] - 2.0 * radius, 0.0),
                                       physicsClientId=cid)
    return shape

