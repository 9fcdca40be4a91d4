"""Where a spawned robot goes and whether it may stay: the World's placement (a mixin).

A robot is rested on the floor below it (z: auto), refused when it reaches into the floor, the
world or another robot (naming the part it met), and given the contact and damping defaults
a Gazebo user expects: wheels, casters and rollers their friction, no PyBullet damping.
"""

from __future__ import annotations

import functools

from mobot_cli.plan import RobotPlan, SpawnPose
from mobot_cli.sim import parts, placement, surroundings
from mobot_cli.sim.bullet import friction
from mobot_cli.sim.bullet.holonomic import ROLLER_FRICTION
from mobot_cli.sim.bullet.urdf_file import links_with_friction
from mobot_cli.sim.pb import p

# A refusal names the part of a world model nearest the robot within this reach (a robot
# inside a closed mesh touches none of it).
PART_REACH = 10.0  # m


class Placing:
    """The World's spawn placement: its client, ground, statics, solids, robots and their boxes."""

    def _settle_in(self, uid: int, robot: RobotPlan) -> None:
        """Place the robot (z: auto), refuse overlaps, set contact and damping defaults."""
        cid, pose = self._cid, robot.pose
        probe_z = 0.0 if self._ground is not None else placement.PROBE_Z
        lowest = placement.lowest_points(self._probes, uid, self._ground, probe_z)
        if pose.z_auto:
            floors = set(self._statics)  # the ground plane is among them
            placement.rest_on_floor(self._probes, uid, self._ground, floors, pose.xyz, pose.quat, robot.name,
                                    probe_z)
        self._check_placed(uid, robot.name, pose.z_auto)
        bottom = min(lowest.values(), default=0.0)
        wheels = friction.wheel_links(cid, uid, robot)
        casters = {link for link, h in lowest.items()
                   if h - bottom <= friction.CASTER_BAND and link not in wheels and friction.rigid(cid, uid, link)}
        holonomic = robot.drive is not None and robot.drive.kind in ("mecanum", "omni")
        if robot.drive is not None and not holonomic and robot.drive.kind != "ackermann" and max(
                len(robot.drive.left_joints), len(robot.drive.right_joints)) > 1:
            fraction = friction.skid_axial_fraction(cid, uid, wheels, robot.drive.wheel_separation)
            friction.soften_axial_friction(cid, uid, wheels, fraction)
        explicit = links_with_friction(robot.urdf)
        friction.set_friction(cid, uid, explicit, {link: friction.CASTER_FRICTION for link in casters},
                              friction.DEFAULT_FRICTION)
        for link in wheels if holonomic else ():  # rollers: the base force moves the robot
            p.changeDynamics(uid, link, lateralFriction=ROLLER_FRICTION, physicsClientId=cid)
        for link in range(-1, p.getNumJoints(uid, physicsClientId=cid)):
            # PyBullet damps every body (0.04) by default; Gazebo does not, and it slows robots.
            p.changeDynamics(uid, link, linearDamping=0.0, angularDamping=0.0,
                             activationState=p.ACTIVATION_STATE_DISABLE_SLEEPING,
                             physicsClientId=cid)

    def _check_placed(self, uid: int, name: str, z_auto: bool) -> None:
        """SpawnError unless the body is clear of the floor, the world and the other robots."""
        cid = self._cid
        xyz = placement.link_frame_xyz(cid, uid)
        others = dict(self._statics)
        # Only the robots whose boxes meet this one's can be reached into (sim/broadphase.py).
        robots = self._robots
        others.update({r.body: f"robot '{r.name}'" for r in self._robot_boxes.near(cid, self._steps, robots.values(),
                                                                                   len(robots), uid)})
        part = functools.partial(self._part, uid)
        placement.check_clear(cid, uid, others, name, xyz, z_auto=z_auto, part=part)
        box = placement.body_bounds(self._probes, uid)
        surroundings.check_not_inside(cid, {b: self._statics[b] for b in self._solids}, name, xyz, box, part)
        if not z_auto:
            surroundings.check_above_floor(cid, self._statics, name, xyz, box, part)

    def _part(self, robot: int, other: int) -> str:
        """Which part of static body ``other`` a refused robot met (error path only)."""
        label = self._statics.get(other)
        body = next((b for b in self.plan.bodies if (b.label or f"static body '{b.name}'") == label), None)
        shape = placement.nearest_part(self._probes, robot, body, PART_REACH) if body is not None else None
        return parts.describe(body, shape) if shape is not None else ""

    def _rest(self, uid: int, pose: SpawnPose, name: str) -> None:
        """Rest a body at (x, y) on the floor below (z: auto), as a spawn does."""
        probe_z = 0.0 if self._ground is not None else placement.PROBE_Z
        placement.rest_on_floor(self._probes, uid, self._ground, set(self._statics), pose.xyz, pose.quat, name,
                                probe_z)
