"""Friction as Gazebo users expect it: defaults, casters that slide, skid-steer wheels that scrub.

World (sim/bullet/world.py) applies these when it builds static bodies and spawns robots.
"""

from __future__ import annotations

from mobot_cli.plan import RobotPlan
from mobot_cli.sim.pb import p

# Friction a link gets when its URDF does not set one. Gazebo's default mu is 1 and it
# combines with min(); PyBullet multiplies, so the floor has 1.0 and a link keeps its own
# value as the pair's friction, as in Gazebo. PyBullet's own default (0.5) made every
# robot in the corpus slip on turns.
DEFAULT_FRICTION = 1.0
FLOOR_FRICTION = 1.0
# A caster that URDF models as a fixed sphere or box cannot roll or swivel here, so it would
# scrape the floor with full friction, which a real caster does not. Rigidly attached links
# (only fixed joints up to the root, not drive wheels) whose lowest point is within CASTER_BAND
# of the robot's lowest point, and which set no friction themselves, get CASTER_FRICTION: the
# value linorobot2 gives its casters. gz_ros2_control's test_diff_drive (a fixed caster
# sphere, no friction given) turns 90 deg in place to -0.06 deg with it, -0.36 deg at 1.0.
CASTER_FRICTION = 0.01
CASTER_BAND = 0.005  # m
# PyBullet's multibody solver (like Gazebo's ODE) uses a friction pyramid whose sides follow
# the world axes. Its "cone" mode is worse here: skid-steer yaw rates swung 0.07..0.5 of the
# command with heading and speed (jackal), so mobot uses the pyramid, as Gazebo does.
CONE_FRICTION = 0
# Skid-steer wheels must scrub sideways to turn. With full sideways friction the turn rate
# depended on heading, speed and (husky) the off-centre mass, 0..0.3 of the command at
# multiplier 1.0. Halving the friction along the wheel axis (as Gazebo skid-steer models do
# with mu2 < mu1) made it steady across 0.3..1.5 rad/s; see drive.default_separation_multiplier.
SKID_AXIAL_FRICTION = 0.5  # fraction of the rolling-direction friction
# Turning in place, the wheels' sideways friction (arm: half the wheelbase) resists what their
# rolling friction (arm: half the track) can push: a base turns only while
# wheelbase * sideways < track * rolling. At 0.5 a base with a wheelbase twice its track could
# not turn at all (0.3 deg of 90, 20 kg, 4 wheels), and one at 1.6 turned 0.60 of its wheel
# kinematics; so bases longer than wide scrub with 0.5 * track / wheelbase, which keeps that
# ratio (and their turns) as on a square base. Bases as long as wide or shorter keep 0.5.


def skid_axial_fraction(cid: int, uid: int, wheels: set[int], track: float) -> float:
    """Sideways friction fraction of skid-steer wheels: SKID_AXIAL_FRICTION, less on long bases."""
    if not wheels or track <= 0.0:
        return SKID_AXIAL_FRICTION
    base_pos, base_orn = p.getBasePositionAndOrientation(uid, physicsClientId=cid)
    to_base = p.invertTransform(base_pos, base_orn)
    xs = [p.multiplyTransforms(*to_base, p.getLinkState(uid, link, physicsClientId=cid)[4],
                               (0.0, 0.0, 0.0, 1.0))[0][0] for link in sorted(wheels)]
    wheelbase = max(xs) - min(xs)
    return SKID_AXIAL_FRICTION * min(1.0, abs(track) / wheelbase) if wheelbase > 0.0 else SKID_AXIAL_FRICTION


def wheel_links(cid: int, uid: int, robot: RobotPlan) -> set[int]:
    """Link indices of the drive wheels (a joint's index is its child link's index)."""
    if robot.drive is None:
        return set()
    names = set(robot.drive.left_joints) | set(robot.drive.right_joints)
    return {j for j in range(p.getNumJoints(uid, physicsClientId=cid))
            if p.getJointInfo(uid, j, physicsClientId=cid)[1].decode() in names}


def rigid(cid: int, uid: int, link: int) -> bool:
    """True when only fixed joints lie between ``link`` and the base (it cannot roll)."""
    while link >= 0:
        info = p.getJointInfo(uid, link, physicsClientId=cid)
        if info[2] != p.JOINT_FIXED:
            return False
        link = info[16]
    return True


def soften_axial_friction(cid: int, uid: int, wheels: set[int], fraction: float) -> None:
    """Scale each wheel's friction along its own axle (its joint axis, in the link frame)."""
    for link in sorted(wheels):
        axis = p.getJointInfo(uid, link, physicsClientId=cid)[13]
        scale = [1.0 - (1.0 - fraction) * abs(a) for a in axis]
        p.changeDynamics(uid, link, anisotropicFriction=scale, physicsClientId=cid)


def set_friction(cid: int, uid: int, explicit: frozenset[str], chosen: dict[int, float],
                  default: float) -> None:
    """Give links without a URDF friction ``chosen`` or ``default`` friction."""
    names = {-1: p.getBodyInfo(uid, physicsClientId=cid)[0].decode()}
    for j in range(p.getNumJoints(uid, physicsClientId=cid)):
        names[j] = p.getJointInfo(uid, j, physicsClientId=cid)[12].decode()
    for link, name in names.items():
        if name not in explicit:
            p.changeDynamics(uid, link, lateralFriction=chosen.get(link, default),
                             physicsClientId=cid)
