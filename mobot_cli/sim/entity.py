"""A robot as an entity of simulation_interfaces: its state read, and set (a teleport).

Poses and twists are those of the root link's URDF frame (its origin), as the ground truth in
every record; PyBullet keeps the centre of mass, so both ways go through the link's inertial
offset. Joint states are left as they are (Gazebo's SetEntityState does the same).
"""

from __future__ import annotations

from dataclasses import dataclass

from mobot_cli.sim.bullet.robot import SimRobot
from mobot_cli.sim.pb import p

Vec = tuple[float, float, float]


@dataclass(frozen=True)
class Kinematics:
    """World pose (position, quaternion x y z w) and velocity of a robot's root link origin."""

    position: Vec
    orientation: tuple[float, float, float, float]
    linear: Vec
    angular: Vec


def kinematics(robot: SimRobot) -> Kinematics:
    """The robot's root link pose and velocity now, in the world frame."""
    pos, orn, lin, ang = robot.kinematics()
    return Kinematics(tuple(pos), tuple(orn), tuple(lin), tuple(ang))


def saved(robot: SimRobot) -> tuple:
    """The base's PyBullet pose and velocity, to put back with ``restore``."""
    cid = robot.cid
    return (p.getBasePositionAndOrientation(robot.body, physicsClientId=cid),
            p.getBaseVelocity(robot.body, physicsClientId=cid))


def restore(robot: SimRobot, state: tuple) -> None:
    """Put back what ``saved`` took."""
    (pos, orn), (lin, ang) = state
    p.resetBasePositionAndOrientation(robot.body, pos, orn, physicsClientId=robot.cid)
    p.resetBaseVelocity(robot.body, lin, ang, physicsClientId=robot.cid)


def place(robot: SimRobot, link_xyz, quat) -> None:
    """Put the root link's URDF frame (not the centre of mass) at ``link_xyz`` turned by ``quat``."""
    dyn = p.getDynamicsInfo(robot.body, -1, physicsClientId=robot.cid)
    pos, orn = p.multiplyTransforms(link_xyz, quat, dyn[3], dyn[4])
    p.resetBasePositionAndOrientation(robot.body, pos, orn, physicsClientId=robot.cid)


def set_twist(robot: SimRobot, linear: Vec, angular: Vec) -> None:
    """Give the root link's origin this world-frame twist: the centre of mass gets v + w x (com - link)."""
    cid = robot.cid
    com = p.getBasePositionAndOrientation(robot.body, physicsClientId=cid)[0]
    link = robot.kinematics()[0]
    r = (com[0] - link[0], com[1] - link[1], com[2] - link[2])
    w = angular
    v = (linear[0] + w[1] * r[2] - w[2] * r[1],
         linear[1] + w[2] * r[0] - w[0] * r[2],
         linear[2] + w[0] * r[1] - w[1] * r[0])
    p.resetBaseVelocity(robot.body, v, tuple(w), physicsClientId=cid)
