"""Faults and stalls of the physics engine: states no driven ground robot should reach.

At the World's health rate each robot is checked for a non-finite state, falling out of the
world, tipping over (its up axis tilted beyond ``max_tilt`` from where it pointed at spawn:
roll or pitch), flying (touching nothing for ``flying_time`` while higher than where it last
touched something: a robot driving off a ledge falls below that and is not flying) and runaway
speed (the root link faster than ``max_speed``, or twice the fastest command given, if more).
Each is a SimulationFault naming the robot, the step and what happened (docs/faults.md).

A stall is not a fault: wheels held at their torque limit for ``STALL_SECONDS`` while the
robot is commanded give one notice per robot, naming the step it began.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mobot_cli.errors import SimulationFault
from mobot_cli.plan import FaultLimits
from mobot_cli.sim.contacts import CONTACT_SLOP
from mobot_cli.sim.pb import p

# A robot this far below its spawn (or below z = 0, whichever is lower) has fallen out of the world.
FLOOR_OF_THE_WORLD = -10.0  # m
# Higher than its last support by more than this (m) counts as above it: not a robot rolling
# off a curb.
FLYING_MARGIN = 0.05
# A wheel whose motor torque is within this fraction of its limit is at the limit.
AT_LIMIT = 0.98
STALL_SECONDS = 1.0
# Where a drive's max_wheel_torque came from (DriveSpec.torque_source), as a stall notice says it.
TORQUE_SOURCES = {"scenario": "drive.max_wheel_torque", "plugin": "its drive plugin",
                  "urdf": "its wheel joints' <limit effort>", "mass": "mobot's default for its mass"}


@dataclass
class Watch:
    """What the checks remember of one robot between two looks."""

    up: tuple[float, float, float]  # the world's up axis in the body frame at spawn
    touched_at: int  # the step it last touched something (its spawn step at first)
    touched_z: float  # its height then
    fastest: float = 0.0  # m/s, the largest linear speed commanded so far
    at_limit_since: int = -1  # the step its wheels reached their torque limit under command; -1: not
    stall_told: bool = False
    fall_z: float = FLOOR_OF_THE_WORLD  # below this height it fell out: FLOOR_OF_THE_WORLD under its spawn


class Health:
    """The checks of one World: its limits in whole steps and a Watch per robot."""

    def __init__(self, cid: int, limits: FaultLimits, rate_hz: int):
        self.cid, self.limits, self.dt = cid, limits, 1.0 / rate_hz
        self.flying_steps = max(1, round(limits.flying_time * rate_hz))
        self.stall_steps = max(1, round(STALL_SECONDS * rate_hz))
        self.cos_tilt = math.cos(limits.max_tilt)
        self.watches: dict[str, Watch] = {}

    def watch(self, robot, step: int) -> None:
        """Start watching a robot as it stands at its spawn: its up axis is the reference."""
        pos, orn = robot.link_pose()
        m = p.getMatrixFromQuaternion(orn)
        # A world may be sunk far below z = 0 (PX4's kth_marinarium: a tank floor at z = -96.8 m).
        base_z = p.getBasePositionAndOrientation(robot.body, physicsClientId=self.cid)[0][2]
        self.watches[robot.name] = Watch(up=(m[6], m[7], m[8]), touched_at=step, touched_z=pos[2],
                                         fall_z=min(0.0, base_z) + FLOOR_OF_THE_WORLD)

    def moved(self, robot, step: int) -> None:
        """A robot was put somewhere (a teleport): its flight starts over, its up axis stays."""
        w = self.watches[robot.name]
        w.touched_at, w.touched_z = step, robot.link_pose()[0][2]

    def forget(self, name: str) -> None:
        self.watches.pop(name, None)

    def commanded(self, name: str, linear: float) -> None:
        """Note a commanded linear speed (a runaway is judged against the fastest)."""
        w = self.watches.get(name)
        if w is not None and abs(linear) > w.fastest:
            w.fastest = abs(linear)

    def check(self, robot, step: int) -> None:
        """SimulationFault when the robot's state is a fault now."""
        cid, limits, w = self.cid, self.limits, self.watches[robot.name]
        pos, orn = p.getBasePositionAndOrientation(robot.body, physicsClientId=cid)
        # One comparison chain first; NaN and inf fail it, then we look closer.
        if not (w.fall_z < pos[2] < math.inf and abs(pos[0]) + abs(pos[1]) < math.inf):
            _lost(robot.name, pos, step, _collides(cid, robot.body))
        pos, orn = robot.link_pose()
        m = p.getMatrixFromQuaternion(orn)
        ux, uy, uz = w.up
        cos_tilt = m[6] * ux + m[7] * uy + m[8] * uz  # the spawn's up axis, in the world now: its z
        if cos_tilt < self.cos_tilt:
            roll, pitch, _ = p.getEulerFromQuaternion(orn)
            tilt = math.degrees(math.acos(max(-1.0, min(1.0, cos_tilt))))
            raise SimulationFault(
                f"robot '{robot.name}' tipped over at step {step}: tilted {tilt:.0f} deg (roll "
                f"{math.degrees(roll):.0f} deg, pitch {math.degrees(pitch):.0f} deg), beyond faults.max_tilt "
                f"{math.degrees(limits.max_tilt):g} deg", robot=robot.name, step=step, kind="tipped_over",
                hint="Lower its speed or acceleration, or check its centre of mass, the ground and any "
                     "joints left free (an arm Gazebo's plugins would hold: hold: all holds them); "
                     "faults.max_tilt sets the limit.")
        linear = p.getBaseVelocity(robot.body, physicsClientId=cid)[0]
        speed = math.sqrt(linear[0] ** 2 + linear[1] ** 2 + linear[2] ** 2)
        limit = max(limits.max_speed, 2.0 * w.fastest)
        if speed > limit:
            raise SimulationFault(
                f"robot '{robot.name}' ran away at step {step}: moving at {speed:.1f} m/s (vertical "
                f"{linear[2]:+.1f} m/s), beyond the limit of {limit:g} m/s", robot=robot.name, step=step,
                kind="runaway", hint="Something launched it: look for overlapping or exploding joints, "
                                     "or raise physics.rate_hz; faults.max_speed sets the limit.")
        contacts = p.getContactPoints(bodyA=robot.body, physicsClientId=cid)
        if any(c[8] <= CONTACT_SLOP for c in contacts):
            w.touched_at, w.touched_z = step, pos[2]
        elif step - w.touched_at >= self.flying_steps and pos[2] > w.touched_z + FLYING_MARGIN:
            raise SimulationFault(
                f"robot '{robot.name}' is flying at step {step}: it has touched nothing for "
                f"{(step - w.touched_at) * self.dt:.1f} s and is {pos[2] - w.touched_z:.2f} m above where it "
                f"last did (vertical speed {linear[2]:+.2f} m/s)", robot=robot.name, step=step, kind="flying",
                hint="Something launched it, or gravity points up; faults.flying_time sets how long is too long.")

    def stall(self, robot, step: int) -> str | None:
        """A notice when the robot's wheels have sat at their torque limit for STALL_SECONDS
        while it is commanded to move (once per robot), else None."""
        drive, w = robot.drive, self.watches[robot.name]
        if w.stall_told or drive is None or not drive.wheels:  # no wheels (planar_move): no torque limit
            return None
        if robot.cmd == (0.0, 0.0) and not robot.cmd_y:
            w.at_limit_since = -1
            return None
        states = p.getJointStates(robot.body, drive.wheels, physicsClientId=self.cid)
        if not any(abs(s[3]) >= AT_LIMIT * f for s, f in zip(states, drive.forces)):
            w.at_limit_since = -1
            return None
        if w.at_limit_since < 0:
            w.at_limit_since = step
            return None
        if step - w.at_limit_since < self.stall_steps:
            return None
        w.stall_told = True
        source = TORQUE_SOURCES.get(drive.spec.torque_source, "mobot's default")
        return (f"robot '{robot.name}': its wheels have been at their torque limit ({max(drive.forces):g} N*m, "
                f"from {source}) since step {w.at_limit_since} ({(step - w.at_limit_since) * self.dt:.1f} s) "
                "while commanded to move: it cannot follow the command (drive.max_wheel_torque raises the limit)")


def _lost(name: str, pos, step: int, collides: bool) -> None:
    if not all(math.isfinite(v) for v in pos):
        raise SimulationFault(f"robot '{name}' has a non-finite state at step {step}", robot=name, step=step,
                              kind="non_finite",
                              hint="Raise physics.rate_hz, or check the robot's masses and inertias.")
    fell = f"robot '{name}' fell out of the world (z = {pos[2]:.1f} m) at step {step}"
    if not collides:
        raise SimulationFault(f"{fell}: it has no collision geometry, so nothing holds it up", robot=name,
                              step=step, kind="out_of_world",
                              hint="Add <collision> to its links (a box the size of its body will do).")
    raise SimulationFault(fell, robot=name, step=step, kind="out_of_world",
                          hint="Is there a floor under its spawn pose?")


def _collides(cid: int, body: int) -> bool:
    """True when any link of ``body`` has a collision shape PyBullet can touch."""
    links = range(-1, p.getNumJoints(body, physicsClientId=cid))
    return any(p.getCollisionShapeData(body, link, physicsClientId=cid) for link in links)
