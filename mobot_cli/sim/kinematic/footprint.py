"""A robot's footprint as a rectangle in its root frame, and how far apart two such rectangles
are at least: a robot that far from another need not ask PyBullet about it (world._fit).

The rectangle holds PyBullet's box of every link with collision shapes, the robot placed at
yaw 0, seen from above, and everywhere its wheels can turn to: a link on a revolute or
continuous joint whose shapes are round about the joint's axis (a cylinder on its axle, a
sphere on it) keeps its box; any other link on such a joint is swept round the joint (a
square around the joint as wide as the link's farthest corner). A robot with a link on a
prismatic, planar or spherical joint, or on two moving joints in a row (a steered wheel), has
no rectangle, nor has one not standing level: it is always asked.

The distance between two rectangles is at least their gap along any axis that separates them
(their four edge directions are tried): the robots' collision shapes are no nearer, in the
plane or in space.
"""

from __future__ import annotations

import math

import numpy as np

from mobot_cli.sim.bullet.friction import rigid
from mobot_cli.sim.pb import p

SPHERE, CYLINDER, CAPSULE = p.GEOM_SPHERE, p.GEOM_CYLINDER, p.GEOM_CAPSULE  # round about their z axis
TURNING = (p.JOINT_REVOLUTE,)  # continuous joints are revolute without limits in PyBullet
# Round about an axis within this (m, and the sine of the angle between axes).
ROUND = 1e-7
# Rectangles are widened by this (m): rounding in their corners and in the gap's arithmetic.
SLACK = 1e-6


def rectangle(cid: int, body: int, x: float, y: float) -> tuple[float, ...] | None:
    """(x0, y0, x1, y1): the robot's footprint in its root link's frame, the robot placed with
    that frame at (x, y), level, facing +x; None when it has none (see the module)."""
    lows, highs = [], []
    for link in range(-1, p.getNumJoints(body, physicsClientId=cid)):
        turning = _turning(cid, body, link)
        if turning is False:
            return None
        if not p.getCollisionShapeData(body, link, physicsClientId=cid):
            continue
        lo, hi = (np.array(v) for v in p.getAABB(body, link, physicsClientId=cid))
        if turning is not None and not _round_about(cid, body, link, *turning):
            corners = np.array([[cx, cy, cz] for cx in (lo[0], hi[0]) for cy in (lo[1], hi[1])
                                for cz in (lo[2], hi[2])])
            far = float(np.max(np.linalg.norm(corners - turning[0], axis=1)))
            lo, hi = turning[0] - far, turning[0] + far
        lows.append(lo[:2])
        highs.append(hi[:2])
    if not lows:
        return None
    lo, hi = np.min(lows, axis=0), np.max(highs, axis=0)
    return (float(lo[0]) - x - SLACK, float(lo[1]) - y - SLACK, float(hi[0]) - x + SLACK, float(hi[1]) - y + SLACK)


def _turning(cid: int, body: int, link: int):
    """None: the link is fixed to the root; (joint origin, joint axis) in the world: it turns on a
    revolute or continuous joint of its own, fixed to the root beyond; False: anything else."""
    if link < 0:
        return None
    info = p.getJointInfo(body, link, physicsClientId=cid)
    if info[2] == p.JOINT_FIXED:
        return None if rigid(cid, body, info[16]) else False
    if info[2] not in TURNING or not rigid(cid, body, info[16]):
        return False
    state = p.getLinkState(body, link, computeForwardKinematics=True, physicsClientId=cid)
    frame = np.array(p.getMatrixFromQuaternion(state[5])).reshape(3, 3)
    return np.array(state[4]), frame @ np.array(info[13])


def _round_about(cid: int, body: int, link: int, origin: np.ndarray, axis: np.ndarray) -> bool:
    """True when every collision shape of the link is the same turned about the axis through
    ``origin``: spheres on it, cylinders and capsules along it."""
    axis = axis / np.linalg.norm(axis)
    com = p.getLinkState(body, link, computeForwardKinematics=True, physicsClientId=cid)[:2]
    for shape in p.getCollisionShapeData(body, link, physicsClientId=cid):
        kind = shape[2]
        pos, orn = p.multiplyTransforms(com[0], com[1], shape[5], shape[6])
        off = np.array(pos) - origin
        if np.linalg.norm(off - axis * float(off @ axis)) > ROUND:  # its centre is off the axis
            return False
        if kind == SPHERE:
            continue
        if kind not in (CYLINDER, CAPSULE):
            return False
        m = p.getMatrixFromQuaternion(orn)
        along = (m[2], m[5], m[8])  # the shape's z axis in the world
        if math.hypot(along[1] * axis[2] - along[2] * axis[1], along[2] * axis[0] - along[0] * axis[2],
                      along[0] * axis[1] - along[1] * axis[0]) > ROUND:
            return False
    return True


def shape(rect: tuple[float, ...] | None) -> tuple[float, float, float, float]:
    """A footprint as centre x, y and half sizes in the root frame (NaN: none)."""
    if rect is None:
        return (math.nan,) * 4
    return (rect[0] + rect[2]) / 2.0, (rect[1] + rect[3]) / 2.0, (rect[2] - rect[0]) / 2.0, (rect[3] - rect[1]) / 2.0


def gap(a: tuple[float, ...], ax: float, ay: float, ayaw: float,
        b: tuple[float, ...], bx: float, by: float, byaw: float) -> float:
    """A lower bound of the distance between rectangle ``a`` of a robot at (ax, ay, ayaw) and
    ``b`` of one at (bx, by, byaw) (zero or less: they may touch)."""
    return placed_gap(*_placed(a, ax, ay, ayaw), *_placed(b, bx, by, byaw))


def _placed(rect: tuple[float, ...], x: float, y: float, yaw: float) -> tuple[float, ...]:
    """A rectangle at a pose: its centre in the world, the cosine and sine of its yaw, its half sizes."""
    c, s = math.cos(yaw), math.sin(yaw)
    mx, my = (rect[0] + rect[2]) / 2.0, (rect[1] + rect[3]) / 2.0
    return x + c * mx - s * my, y + s * mx + c * my, c, s, (rect[2] - rect[0]) / 2.0, (rect[3] - rect[1]) / 2.0


def placed_gap(ax, ay, ac, as_, ahx, ahy, bx, by, bc, bs, bhx, bhy, most=max):
    """The largest gap between two placed rectangles along their four edge directions; of
    numbers, or (``most``: an elementwise maximum of its arguments) of numpy arrays of pairs."""
    dx, dy = bx - ax, by - ay
    cd, sd = abs(bc * ac + bs * as_), abs(bs * ac - bc * as_)  # cosine and sine of the angle between them
    return most(abs(dx * ac + dy * as_) - ahx - bhx * cd - bhy * sd,
                abs(dy * ac - dx * as_) - ahy - bhx * sd - bhy * cd,
                abs(dx * bc + dy * bs) - bhx - ahx * cd - ahy * sd,
                abs(dy * bc - dx * bs) - bhy - ahx * sd - ahy * cd) - SLACK


def apart_from(mover, others: list):
    """For a robot (a Mover) about to move among ``others``: a function of its pose (x, y, yaw)
    and a distance ``limit`` giving {body: gap} of the others whose footprints are farther than
    ``limit`` from it there; None when no footprint can tell."""
    rect = mover.rect
    if rect is None or not mover.level:
        return None
    shaped = [(o.robot.body, _placed(o.rect, o.x, o.y, o.yaw)) for o in others if o.rect is not None and o.level]
    if not shaped:
        return None

    def known(x: float, y: float, yaw: float, limit: float) -> dict[int, float]:
        here, found = _placed(rect, x, y, yaw), {}
        for uid, other in shaped:
            apart = placed_gap(*here, *other)
            if apart > limit:
                found[uid] = apart
        return found

    return known
