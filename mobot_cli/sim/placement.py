"""Putting a freshly loaded robot where it was asked to be: on the floor, not inside things."""

from __future__ import annotations

from typing import Callable

from mobot_cli.errors import SpawnError
from mobot_cli.plan import StaticBody, StaticShape
from mobot_cli.sim.pb import p
from mobot_cli.sim.static_shapes import shape_args

# How far below the floor (or into another body) a spawned robot may reach. Gazebo users
# spawn at z = 0 with wheels whose meshes dip a few millimetres into the floor; more than
# this is a mistake worth stopping for.
MAX_SPAWN_PENETRATION = 0.01  # m
# Rays looking for the floor start this far above the top of the robot resting at z = 0.
FLOOR_PROBE_CLEARANCE = 0.05  # m
FLOOR_PROBE_DEPTH = 100.0  # m below z = 0
# Where there is no floor within a robot's height of z = 0, rays look again from this high
# (below the parked robot) and the robot rests on the highest surface under it.
HIGH_PROBE = 100.0  # m
# Where a robot waits while its floor is probed, so rays do not hit the robot itself.
PARKING_HEIGHT = 200.0  # m
# Without a ground plane, lowest points are measured against a temporary plane this far
# down: at z = 0 it would tie with (and hide) a mesh floor at z = 0 from the floor rays.
PROBE_Z = -1000.0  # m
# Rays that look for the surfaces around a robot reach this far and cross at most this many.
RAY_REACH = 1000.0  # m
MAX_CROSSINGS = 64
RAY_STEP = 1e-4  # m a ray moves past each surface it crosses before looking on
# Half-spaces that measure a robot's bounds stand this far from its base on each side.
BOUNDS_REACH = 100.0  # m
# PyBullet's AABBs carry a 1 mm margin; more slack than this on any side means they are loose.
LOOSE_AABB = 0.005  # m


class Probes:
    """Plane collision shapes, without bodies, that measure a robot: made once per world.

    PyBullet is slow to create a body (it serialises each one), and a spawn measured with
    six temporary half-space bodies, twice; getClosestPoints between a body and a shape placed
    in the query costs microseconds and gives the same points to the last bit.
    """

    def __init__(self, cid: int):
        self.cid = cid
        self._shapes: dict[tuple[float, float, float], int] = {}
        self._parts: dict[StaticShape, int] = {}  # kept: removing a shape makes PyBullet print

    def shape(self, shape: StaticShape) -> int:
        """A collision shape, without a body, of one static shape; -1 when PyBullet refuses it."""
        if shape not in self._parts:
            try:
                self._parts[shape] = p.createCollisionShape(physicsClientId=self.cid, **shape_args(shape))
            except p.error:
                self._parts[shape] = -1
        return self._parts[shape]

    def closest(self, body: int, normal: tuple[float, float, float], at, distance: float) -> list:
        """getClosestPoints between ``body`` and a plane through ``at`` facing ``normal``."""
        shape = self._shapes.get(normal)
        if shape is None:
            shape = self._shapes[normal] = p.createCollisionShape(p.GEOM_PLANE, planeNormal=list(normal),
                                                                  physicsClientId=self.cid)
        return p.getClosestPoints(body, -1, distance, collisionShapeB=shape, collisionShapePositionB=list(at),
                                  physicsClientId=self.cid)


def lowest_points(probes: Probes, body: int, ground: int | None, probe_z: float = 0.0) -> dict[int, float]:
    """World z of each link's lowest collision point, measured against the ``ground`` body, or
    without one against a horizontal plane at ``probe_z``."""
    lowest: dict[int, float] = {}
    reach = 2.0 * PARKING_HEIGHT + abs(probe_z)
    if ground is not None:
        points = p.getClosestPoints(body, ground, reach, physicsClientId=probes.cid)
    else:
        points = probes.closest(body, (0.0, 0.0, 1.0), (0.0, 0.0, probe_z), reach)
    for pt in points:
        link, height = pt[3], pt[8] + probe_z
        if height < lowest.get(link, float("inf")):
            lowest[link] = height
    return lowest


Bounds = tuple[tuple[float, float, float], tuple[float, float, float]]


def body_top(cid: int, uid: int) -> float:
    """The highest point of a body's links' collision boxes."""
    return max(p.getAABB(uid, link, physicsClientId=cid)[1][2]
               for link in range(-1, p.getNumJoints(uid, physicsClientId=cid)))


def body_bounds(probes: Probes, body: int) -> Bounds:
    """Exact world bounds (lo, hi) of a body's collision shapes.

    PyBullet's AABBs are loose for a link whose inertial frame is rotated (an <inertial>
    <origin rpy>, or off-diagonal inertia that PyBullet diagonalises): the link's shapes sit in
    that frame and their box is turned with it. Half-spaces on each side, with PyBullet's
    closest points, give the true extremes whatever the frames.
    """
    pos = p.getBasePositionAndOrientation(body, physicsClientId=probes.cid)[0]
    lo, hi = list(pos), list(pos)
    for axis in range(3):
        for side, out in ((-1.0, lo), (1.0, hi)):
            normal = [0.0, 0.0, 0.0]
            normal[axis] = -side  # the half-space's surface faces the robot
            at = list(pos)
            at[axis] += side * BOUNDS_REACH
            points = probes.closest(body, (normal[0], normal[1], normal[2]), at, 2.0 * BOUNDS_REACH)
            if points:
                out[axis] = at[axis] - side * min(pt[8] for pt in points)
    return (lo[0], lo[1], lo[2]), (hi[0], hi[1], hi[2])


def floor_height(cid: int, box: Bounds, floors: set[int], top: float, name: str) -> float:
    """Height of the highest floor (ground or static body) under ``box``, probed from ``top``."""
    (x0, y0, _), (x1, y1, _) = box
    xs, ys = (x0, (x0 + x1) / 2, x1), (y0, (y0 + y1) / 2, y1)
    starts = [(x, y, top) for x in xs for y in ys]
    ends = [(x, y, -FLOOR_PROBE_DEPTH) for x, y, _ in starts]
    rays = p.rayTestBatch(starts, ends, physicsClientId=cid)
    hits = [r[3][2] for r in rays if r[0] in floors]  # another robot is not a floor
    if not hits and top < HIGH_PROBE:  # no floor near z = 0 (a raised stage): the highest surface
        return floor_height(cid, box, floors, HIGH_PROBE, name)
    if not hits:
        x, y = (x0 + x1) / 2, (y0 + y1) / 2
        raise SpawnError(
            f"robot '{name}' has nothing to rest on below ({x:.3f}, {y:.3f})",
            hint="Spawn it over the world's floor, or give the world one (<include><uri>model://ground_plane"
                 "</uri></include>; a Fuel model or a <heightmap> that was left out may have been its floor).")
    return max(hits)


def rest_on_floor(probes: Probes, body: int, ground: int | None, floors: set[int], xyz, quat,
                  name: str, probe_z: float = 0.0) -> tuple[float, float, float]:
    """Move the robot so its lowest collision point touches the floor below (x, y); return xyz.

    The robot is parked high above with its URDF link frame (not its inertial frame, which may
    be rotated) at the asked orientation, and measured there.
    """
    cid = probes.cid
    _place(cid, body, (xyz[0], xyz[1], PARKING_HEIGHT), quat)
    base_z = link_frame_z(cid, body)
    # Its world z, parked; a robot without collision geometry rests its base frame on the floor.
    lowest = min(lowest_points(probes, body, ground, probe_z).values(), default=base_z)
    box = _probe_box(probes, body)
    floor = floor_height(cid, box, floors, box[1][2] - lowest + FLOOR_PROBE_CLEARANCE, name)
    z = floor + (base_z - lowest)
    _place(cid, body, (xyz[0], xyz[1], z), quat)
    return xyz[0], xyz[1], z


def link_frame_z(cid: int, body: int) -> float:
    """z of the base's URDF link frame (PyBullet tracks the inertial frame)."""
    return link_frame_xyz(cid, body)[2]


def link_frame_xyz(cid: int, body: int) -> tuple[float, float, float]:
    """Position of the base's URDF link frame."""
    pos, orn = p.getBasePositionAndOrientation(body, physicsClientId=cid)
    dyn = p.getDynamicsInfo(body, -1, physicsClientId=cid)
    inv = p.invertTransform(dyn[3], dyn[4])
    return tuple(p.multiplyTransforms(pos, orn, inv[0], inv[1])[0])  # type: ignore[return-value]


def _place(cid: int, body: int, link_xyz, quat) -> None:
    """Put the base's URDF link frame (not its centre of mass) at ``link_xyz``."""
    dyn = p.getDynamicsInfo(body, -1, physicsClientId=cid)
    pos, orn = p.multiplyTransforms(link_xyz, quat, dyn[3], dyn[4])
    p.resetBasePositionAndOrientation(body, pos, orn, physicsClientId=cid)


def _part_text(text: str) -> str:
    return f", {text}" if text else ""


def _at(xyz) -> str:
    return f"x={xyz[0]:.3f}, y={xyz[1]:.3f}, z={xyz[2]:.3f}"


# How refusals say which part of a body the robot met (body id -> text, "" for none).
Part = Callable[[int], str]


def no_part(other: int) -> str:
    return ""


def nearest_part(probes: Probes, robot: int, body: StaticBody, reach: float) -> StaticShape | None:
    """The shape of ``body`` deepest into (or else nearest to, within ``reach``) the robot.

    PyBullet reports contacts with a compound body without saying which of its shapes: each is
    tried alone here, on the error path only.
    """
    best, nearest = None, float("inf")
    for shape in body.shapes:
        probe = probes.shape(shape)
        if probe < 0:
            continue
        points = p.getClosestPoints(robot, -1, reach, collisionShapeB=probe, collisionShapePositionB=body.xyz,
                                    collisionShapeOrientationB=body.quat, physicsClientId=probes.cid)
        distance = min((pt[8] for pt in points), default=float("inf"))
        if distance < nearest:
            best, nearest = shape, distance
    return best


def check_clear(cid: int, body: int, others: dict[int, str], name: str, xyz, z_auto: bool = False,
                part: Part = no_part) -> None:
    """Refuse a robot that reaches into the floor or another body by more than a centimetre;
    ``part`` says which part of the other body."""
    hint = ("Move the robot clear of it: z: auto already rested it on the surface below."
            if z_auto else "Raise z, move the robot, or use z: auto to rest it on the floor.")
    for other, label in others.items():
        points = p.getClosestPoints(body, other, 0.0, physicsClientId=cid)
        depth = -min((pt[8] for pt in points), default=0.0)
        if depth > MAX_SPAWN_PENETRATION:
            raise SpawnError(
                f"robot '{name}' spawned at {_at(xyz)} reaches {depth * 100:.1f} cm into {label}"
                + _part_text(part(other)), hint=hint)



def _probe_box(probes: Probes, body: int) -> Bounds:
    """The box floor rays start from: PyBullet's link AABBs where they are tight, else exact.

    Rays started from the AABBs before exact bounds existed; where those are tight (within
    LOOSE_AABB on every side) they still do, so earlier runs reproduce to the last bit (a ray
    started a few nanometres higher hits a mesh floor a few attometres apart, and contacts
    amplify that). Where they are loose (a rotated inertial frame) the exact bounds are used.
    """
    cid = probes.cid
    exact = body_bounds(probes, body)
    lo, hi = p.getAABB(body, -1, physicsClientId=cid)
    for link in range(p.getNumJoints(body, physicsClientId=cid)):
        a, b = p.getAABB(body, link, physicsClientId=cid)
        lo, hi = tuple(map(min, lo, a)), tuple(map(max, hi, b))
    slack = max(*(e - a for a, e in zip(lo, exact[0])), *(a - e for a, e in zip(hi, exact[1])))
    return (tuple(lo), tuple(hi)) if slack <= LOOSE_AABB else exact  # type: ignore[return-value]
