"""The World: the only owner of a PyBullet client. Spawns robots, drives them, steps, reports.

Everything is headless (``pybullet.DIRECT``) and every call names its client, so several
Worlds can live in one process (tests, sweeps in threads).
"""

from __future__ import annotations

import math

import pybullet as p

from mobot_cli.errors import SimulationFault, SpawnError, did_you_mean
from mobot_cli.sim import placement
from mobot_cli.sim.plan import Physics, RobotPlan, WorldPlan
from mobot_cli.sim.robot import SimRobot
from mobot_cli.sim.state import RobotState
from mobot_cli.sim.urdf_file import links_with_friction, urdf_path

__all__ = ["World", "RobotState"]

# Friction a link gets when its URDF does not set one. Gazebo's default mu is 1 and it
# combines with min(); PyBullet multiplies, so the floor has 1.0 and a link keeps its own
# value as the pair's friction, as in Gazebo. PyBullet's own default (0.5) made every
# robot in the corpus slip on turns.
DEFAULT_FRICTION = 1.0
FLOOR_FRICTION = 1.0
# A caster that URDF models as a fixed sphere or box cannot roll or swivel here, so it would
# scrape the floor with full friction, which a real caster does not. Links (other than drive
# wheels) whose lowest point is within CASTER_BAND of the robot's lowest point, and which set
# no friction themselves, get CASTER_FRICTION: the value linorobot2 gives its casters.
CASTER_FRICTION = 0.01
CASTER_BAND = 0.005  # m
# Encoder odometry is folded in at this rate (diff_drive_controller's default update rate);
# reads bring it up to date as well, so no reader sees stale odometry.
ODOMETRY_RATE_HZ = 50
# A robot below this height has fallen out of the world.
FLOOR_OF_THE_WORLD = -10.0  # m
URDF_FLAGS = p.URDF_USE_INERTIA_FROM_FILE | p.URDF_USE_IMPLICIT_CYLINDER


class World:
    """A headless physics world built from a plan; robots come and go by name."""

    def __init__(self, physics: Physics, world: WorldPlan, seed: int = 0):
        self.physics = physics
        self.plan = world
        self.seed = seed  # PyBullet itself draws no random numbers; kept for sensors and noise
        self._cid = p.connect(p.DIRECT)
        self._steps = 0
        self._robots: dict[str, SimRobot] = {}
        self._ramping: list[SimRobot] = []
        self._odom_every = max(1, round(physics.rate_hz / ODOMETRY_RATE_HZ))
        cid = self._cid
        p.resetSimulation(physicsClientId=cid)
        p.setPhysicsEngineParameter(
            fixedTimeStep=physics.dt, numSolverIterations=physics.solver_iterations,
            numSubSteps=0, deterministicOverlappingPairs=1, physicsClientId=cid)
        p.setGravity(*physics.gravity, physicsClientId=cid)
        self._statics: dict[int, str] = {}
        self._ground: int | None = None
        if world.ground_plane:
            self._ground = self._plane(0.0)
            self._statics[self._ground] = "the ground plane"
        for body in world.bodies:
            uid = p.loadURDF(str(urdf_path(body.urdf)), body.xyz, body.quat, useFixedBase=True,
                             flags=URDF_FLAGS, physicsClientId=cid)
            _set_friction(cid, uid, links_with_friction(body.urdf), {}, DEFAULT_FRICTION)
            self._statics[uid] = f"static body '{body.name}'"

    def _plane(self, z: float) -> int:
        cid = self._cid
        shape = p.createCollisionShape(p.GEOM_PLANE, physicsClientId=cid)
        uid = p.createMultiBody(0.0, shape, basePosition=(0.0, 0.0, z), physicsClientId=cid)
        p.changeDynamics(uid, -1, lateralFriction=FLOOR_FRICTION, physicsClientId=cid)
        return uid

    @property
    def step_count(self) -> int:
        """Whole physics steps taken since the world was built."""
        return self._steps

    @property
    def client_id(self) -> int:
        """The PyBullet client, for sensors living in ``mobot_cli.sim``."""
        return self._cid

    def names(self) -> list[str]:
        """Names of the robots in the world, in spawn order."""
        return list(self._robots)

    def body_id(self, name: str) -> int:
        """The PyBullet body of a robot."""
        return self._robot(name).body

    def has_drive(self, name: str) -> bool:
        """True when the robot takes velocity commands."""
        return self._robot(name).drive is not None

    def spawn(self, robot: RobotPlan) -> None:
        """Load a robot at its pose, checked: unique name, on or above the floor, not inside things."""
        if robot.name in self._robots:
            raise SpawnError(f"a robot named '{robot.name}' already exists",
                             hint="Robot names must be unique; pick another name.")
        cid, pose = self._cid, robot.pose
        uid = p.loadURDF(str(urdf_path(robot.urdf)), pose.xyz, pose.quat, flags=URDF_FLAGS,
                         physicsClientId=cid)
        try:
            self._settle_in(uid, robot)
            sim_robot = SimRobot(cid, uid, robot, self.physics.dt)
        except BaseException:
            p.removeBody(uid, physicsClientId=cid)
            raise
        self._robots[robot.name] = sim_robot

    def _settle_in(self, uid: int, robot: RobotPlan) -> None:
        """Place the robot (z: auto), refuse overlaps, set contact and damping defaults."""
        cid, pose = self._cid, robot.pose
        probe = self._ground if self._ground is not None else self._plane(0.0)
        try:
            lowest = placement.lowest_points(cid, uid, probe)
            if pose.z_auto:
                floors = set(self._statics) | {probe}
                placement.rest_on_floor(cid, uid, probe, floors, pose.xyz, pose.quat, robot.name)
        finally:
            if probe != self._ground:
                p.removeBody(probe, physicsClientId=cid)
        z = placement.link_frame_z(cid, uid)
        others = dict(self._statics)
        others.update({r.body: f"robot '{n}'" for n, r in self._robots.items()})
        placement.check_clear(cid, uid, others, robot.name, z)
        bottom = min(lowest.values(), default=0.0)
        wheels = _wheel_links(cid, uid, robot)
        casters = {link for link, h in lowest.items()
                   if h - bottom <= CASTER_BAND and link not in wheels}
        explicit = links_with_friction(robot.urdf)
        _set_friction(cid, uid, explicit, {link: CASTER_FRICTION for link in casters},
                      DEFAULT_FRICTION)
        for link in range(-1, p.getNumJoints(uid, physicsClientId=cid)):
            # PyBullet damps every body (0.04) by default; Gazebo does not, and it slows robots.
            p.changeDynamics(uid, link, linearDamping=0.0, angularDamping=0.0,
                             activationState=p.ACTIVATION_STATE_DISABLE_SLEEPING,
                             physicsClientId=cid)

    def remove(self, name: str) -> None:
        """Delete a robot from the world."""
        robot = self._robot(name)
        p.removeBody(robot.body, physicsClientId=self._cid)
        del self._robots[name]
        if robot in self._ramping:
            self._ramping.remove(robot)

    def set_command(self, name: str, linear: float, angular: float) -> None:
        """Command a body twist (m/s, rad/s); ValueError for a robot without a drive."""
        robot = self._robot(name)
        robot.set_command(linear, angular)
        if robot.drive.ramping and robot not in self._ramping:
            self._ramping.append(robot)

    def step(self) -> None:
        """Advance one physics step; SimulationFault when a robot's state goes bad."""
        if self._ramping:
            for robot in self._ramping:
                robot.drive.ramp_step()
            self._ramping = [r for r in self._ramping if r.drive.ramping]
        p.stepSimulation(physicsClientId=self._cid)
        self._steps += 1
        if self._steps % self._odom_every == 0:
            for robot in self._robots.values():
                self._check(robot)
                if robot.drive is not None:
                    robot.drive.integrate()

    def _check(self, robot: SimRobot) -> None:
        pos = p.getBasePositionAndOrientation(robot.body, physicsClientId=self._cid)[0]
        if not all(math.isfinite(v) for v in pos):
            raise SimulationFault(
                f"robot '{robot.name}' has a non-finite state at step {self._steps}",
                hint="Lower the physics step (raise rate_hz) or check the robot's masses and inertias.")
        if pos[2] < FLOOR_OF_THE_WORLD:
            raise SimulationFault(
                f"robot '{robot.name}' fell out of the world (z = {pos[2]:.1f} m) at step {self._steps}",
                hint="Is there a floor under its spawn pose?")

    def read(self, name: str) -> RobotState:
        """The robot's command, odometry and ground truth now."""
        return self._robot(name).state()

    def _robot(self, name: str) -> SimRobot:
        try:
            return self._robots[name]
        except KeyError:
            raise KeyError(f"no robot named '{name}'. {did_you_mean(name, self._robots)}".strip()) from None

    def close(self) -> None:
        """Disconnect from PyBullet; the world is unusable afterwards."""
        if self._cid >= 0:
            p.disconnect(physicsClientId=self._cid)
            self._cid = -1

    def __enter__(self) -> World:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _wheel_links(cid: int, uid: int, robot: RobotPlan) -> set[int]:
    """Link indices of the drive wheels (a joint's index is its child link's index)."""
    if robot.drive is None:
        return set()
    names = set(robot.drive.left_joints) | set(robot.drive.right_joints)
    return {j for j in range(p.getNumJoints(uid, physicsClientId=cid))
            if p.getJointInfo(uid, j, physicsClientId=cid)[1].decode() in names}


def _set_friction(cid: int, uid: int, explicit: frozenset[str], chosen: dict[int, float],
                  default: float) -> None:
    """Give links without a URDF friction ``chosen`` or ``default`` friction."""
    names = {-1: p.getBodyInfo(uid, physicsClientId=cid)[0].decode()}
    for j in range(p.getNumJoints(uid, physicsClientId=cid)):
        names[j] = p.getJointInfo(uid, j, physicsClientId=cid)[12].decode()
    for link, name in names.items():
        if name not in explicit:
            p.changeDynamics(uid, link, lateralFriction=chosen.get(link, default),
                             physicsClientId=cid)
