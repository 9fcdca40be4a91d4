"""One robot in the kinematic engine: its twist through its drive's limits, its pose and wheels.

The robot's pose lives here, in Python; its PyBullet body is moved there (``sync``) only when
something looks at it: a collision query, a sensor, a clearance, a later spawn's checks.
"""

from __future__ import annotations

import functools
import math

from mobot_cli.sim.bullet.robot import SimRobot
from mobot_cli.sim.bullet.steered import SteeredDrive
from mobot_cli.sim.drive import Odometry, arc, body_twist, ramp, wheel_speeds, wrap_angle
from mobot_cli.sim.kinematic.seen import Seen
from mobot_cli.sim.pb import p
from mobot_cli.sim.state import RobotState
from mobot_cli.sim.steering import lever_arc, steering_angle


class Mover:
    """A robot that follows its commanded twist: wheel rates ramp toward the command within
    ``max_wheel_acceleration`` and the URDF's wheel velocity limit, and the body moves along
    the exact arc those rates give over one step (diff_drive_controller's integrateExact)."""

    def __init__(self, robot: SimRobot, dt: float, bottom: float, reach: float,
                 feet: list[tuple[float, float]]):
        self.robot, self.dt = robot, dt
        inertial = p.getDynamicsInfo(robot.body, -1, physicsClientId=robot.cid)
        self.link_to_com = (inertial[3], inertial[4])
        x, y, z, roll, pitch, yaw = robot.link_pose_rpy()
        self.x, self.y, self.z, self.yaw = x, y, z, yaw
        # Kept as spawned: the engine does not tip robots (README, "Kinematic engine").
        self.tilt = (roll, pitch)
        self.level = roll == 0.0 and pitch == 0.0
        self.height = z - bottom  # the link origin above the robot's lowest point
        self.floor = bottom
        self.reach = reach  # m: farthest collision point from the link origin, horizontally
        self.above = math.inf  # m: its highest collision point above the link origin
        self.feet = feet  # where it stands (root frame): the floor is looked for under them
        self.v = self.w = 0.0  # the body twist of the last step, as it moved
        self.vy = 0.0  # and its sideways part (holonomic drives: sim/kinematic/holonomic.py)
        self.positions = robot.joint_positions()
        self.velocities = dict.fromkeys(self.positions, 0.0)
        self.clear = 0.0  # m to the nearest static body (not floor) when last measured
        self.used = 0.0  # m the robot's points may have moved since: query again past ``clear``
        self.touches: set[int] = set()  # bodies it touched at the last query
        # Ticks of the World's clock (KinematicWorld._clock), which counts moves and queries:
        self.stuck: tuple | None = None  # (motion, tick): that motion was blocked entirely at that query
        self.moved = 0  # when its pose last changed: a robot stuck against it stays stuck till then
        self.queried = -1  # when it last asked what is in its way
        self.travel = 0.0  # m its collision points may have moved in all, summed over its steps
        self.index = -1  # its row in the World's pair matrix
        self.seen = Seen()  # what its queries found, by pose
        self.rect: tuple[float, ...] | None = None  # its footprint (footprint.py), if it has one
        self.synced = False  # the PyBullet body is at this pose
        self.rates = self.goal = (0.0, 0.0)  # left, right wheel rates (rad/s, forward positive)
        # What the rates give, worked out once per change of ``rates`` (they are a new tuple then):
        # this step's (distance, turn) or None, and each wheel's (name, angle step, rate).
        self._motion_of: tuple | None = None
        self._motion: tuple[float, float] | None = None
        self.bound = 0.0  # m: how far any point of the robot may move in this step's motion()
        # The rates of the last move, when it was none of the step (blocked): another changes
        # nothing (it adds the same zeros again), so it is not made.
        self._stayed: tuple | None = None
        self._wheels_of: tuple | None = None
        self._wheel_steps: list[tuple[str, float]] = []
        self.encoder = False
        self.arc = arc  # how the root moves when the body drives along an arc
        drive = robot.drive
        self.drive = drive
        self.car: SteeredDrive | None = None
        if drive is None:
            return
        if isinstance(drive, SteeredDrive):  # the rear axle's middle follows the arc, not the root
            self.car = drive
            self.arc = functools.partial(lever_arc, drive.rear)
        spec = drive.spec
        self.radius, self.separation = drive.radius, drive.separation
        self.max_step = (spec.max_wheel_acceleration or 0.0) * dt
        limits = [p.getJointInfo(robot.body, j, physicsClientId=robot.cid)[11] for j in drive.wheels]
        self.max_rate = min((v for v in limits if v > 0.0), default=math.inf)
        names = spec.left_joints + spec.right_joints
        n_left = len(spec.left_joints)
        # joint name, sign, side (0 left, 1 right): the wheel turns sign * rate of its side
        self.wheels = [(name, sign, 0 if i < n_left else 1)
                       for i, (name, sign) in enumerate(zip(names, drive.signs))]
        self.odometry = Odometry(self.separation)
        self.encoder = spec.odometry == "encoder"

    def command(self, linear: float, angular: float) -> None:
        """Wheel rates for a body twist; slowed together (same curvature) to the wheels' limit.
        A car's twist is clamped to what it can follow first, its steering joints set at once."""
        if self.car is not None:
            linear, angular = self._steer(linear, angular)
        left, right = wheel_speeds(linear, angular, self.separation, self.radius, self.radius)
        top = max(abs(left), abs(right))
        if top > self.max_rate:
            left, right = left * self.max_rate / top, right * self.max_rate / top
        self.goal = (left, right)
        if self.max_step <= 0.0:
            self.rates = self.goal

    def _steer(self, linear: float, angular: float) -> tuple[float, float]:
        car = self.car
        linear, angular, kappa = car.clamped(linear, angular)
        for name, sign, (x, y) in zip(car.spec.steering_joints, car.steer_signs, car.steered):
            self.positions[name] = steering_angle(1.0, kappa, x, y) * sign
        self.synced = False
        return linear, angular

    def motion(self) -> tuple[float, float] | None:
        """This step's (distance, turn) from the wheel rates, ramped first; None: standing still."""
        rates = self.rates
        if rates != self.goal:
            step, goal = self.max_step, self.goal
            rates = self.rates = (ramp(rates[0], goal[0], step), ramp(rates[1], goal[1], step))
        if rates is not self._motion_of:
            self._motion_of, self._motion = rates, self._twist(rates)
            self.bound = abs(self._motion[0]) + abs(self._motion[1]) * self.reach if self._motion else 0.0
        motion = self._motion
        if motion is None and (self.v or self.w):
            self._stayed = None
            self.v = self.w = 0.0
            self.velocities = dict.fromkeys(self.velocities, 0.0)
            self.synced = False
        return motion

    def _twist(self, rates: tuple[float, float]) -> tuple[float, float] | None:
        left, right = rates
        if left == 0.0 and right == 0.0:
            return None
        r = self.radius * self.dt
        return body_twist(left * r, right * r, self.separation)

    def target(self, distance: float, turn: float, fraction: float) -> tuple[float, float, float]:
        """Where ``fraction`` of this step's arc takes the robot: x, y, yaw."""
        return self.arc(self.x, self.y, self.yaw, distance * fraction, turn * fraction)

    def move(self, distance: float, turn: float, fraction: float) -> None:
        """Make ``fraction`` of this step's motion (``motion()``'s): pose, wheel angles, encoder
        odometry."""
        # Runs every step for every moving robot: a whole step is plain arithmetic on numbers
        # worked out when the rates last changed.
        if fraction == 1.0:
            self.x, self.y, self.yaw = self.arc(self.x, self.y, self.yaw, distance, turn)
            self.synced = False
            self.stuck = self._stayed = None
            dt = self.dt
            self.v, self.w = distance / dt, turn / dt
            if self.rates is not self._wheels_of:
                self._whole_wheel_steps()
            positions = self.positions
            for name, angle in self._wheel_steps:
                positions[name] += angle
            if self.encoder:  # the wheels' arc is the body's: motion() worked it out from them
                odo = self.odometry
                odo.x, odo.y, odo.yaw = self.arc(odo.x, odo.y, odo.yaw, distance, turn)
            return
        if fraction == 0.0:
            if self._stayed is self.rates:  # blocked again at the same rates: see _stayed
                return
            self._stayed = self.rates
        else:
            self._stayed = None
        distance, turn = distance * fraction, turn * fraction
        if fraction > 0.0:
            self.x, self.y, self.yaw = self.arc(self.x, self.y, self.yaw, distance, turn)
            self.synced = False
            self.stuck = None
        dt = self.dt
        self.v, self.w = distance / dt, turn / dt
        left, right = self.rates
        left, right = left * fraction, right * fraction
        positions, velocities = self.positions, {}
        for name, sign, side in self.wheels:
            rate = sign * (right if side else left)
            positions[name] += rate * dt
            velocities[name] = rate
        self.velocities, self._wheels_of = {**self.velocities, **velocities}, None
        if self.encoder:
            travel = self.radius * dt
            odo = self.odometry
            odo.x, odo.y, odo.yaw = self.arc(odo.x, odo.y, odo.yaw,
                                             *body_twist(left * travel, right * travel, self.separation))

    def _whole_wheel_steps(self) -> None:
        """Each wheel's angle step and rate at the current rates; ``velocities`` is a new dict
        (states hand it out as it is: it is never changed in place)."""
        left, right = self._wheels_of = self.rates
        dt, steps, velocities = self.dt, [], dict(self.velocities)
        for name, sign, side in self.wheels:
            rate = sign * (right if side else left)
            steps.append((name, rate * dt))
            velocities[name] = rate
        self._wheel_steps, self.velocities = steps, velocities

    def relocate(self, tick: int) -> None:
        """Take the PyBullet body's pose as the robot's (after a teleport): the floor under it is
        where it stands now, and nothing near it is known any more."""
        x, y, z, roll, pitch, yaw = self.robot.link_pose_rpy()
        self.x, self.y, self.z, self.yaw = x, y, z, yaw
        if (roll, pitch) != self.tilt:  # turned about z, its top stays as high; tipped, not
            self.above = math.inf
        self.tilt, self.level = (roll, pitch), roll == 0.0 and pitch == 0.0
        self.floor = z - self.height
        self.clear = self.used = 0.0
        self.touches, self.stuck, self.moved, self.synced = set(), None, tick, True
        self._stayed = None

    def link_pose(self, x: float, y: float, z: float, yaw: float):
        """The root link's world position and quaternion at this planar pose."""
        if self.level:
            return (x, y, z), (0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0))
        return (x, y, z), p.getQuaternionFromEuler((self.tilt[0], self.tilt[1], yaw))

    def place(self, x: float, y: float, z: float, yaw: float) -> None:
        """Put the PyBullet body at a pose (for a query); ``sync`` puts it back where it is."""
        robot = self.robot
        pos, orn = self.link_pose(x, y, z, yaw)
        if robot.com_offset:  # PyBullet's base frame is the root link's inertial frame
            inertial = self.link_to_com
            pos, orn = p.multiplyTransforms(pos, orn, inertial[0], inertial[1])
        p.resetBasePositionAndOrientation(robot.body, pos, orn, physicsClientId=robot.cid)
        self.synced = (x, y, z, yaw) == (self.x, self.y, self.z, self.yaw)

    def sync(self, full: bool = False) -> None:
        """Move the PyBullet body to the robot's pose; ``full`` also sets velocities and wheel
        angles (for sensors: an IMU reads the body's velocity)."""
        if not self.synced:
            self.place(self.x, self.y, self.z, self.yaw)
        if not full:
            return
        robot = self.robot
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        lin, ang = [self.v * c - self.vy * s, self.v * s + self.vy * c, 0.0], [0.0, 0.0, self.w]
        if robot.com_offset:  # the centre of mass moves as v + w x (com - link)
            com = p.getBasePositionAndOrientation(robot.body, physicsClientId=robot.cid)[0]
            lin[0] -= self.w * (com[1] - self.y)
            lin[1] += self.w * (com[0] - self.x)
        p.resetBaseVelocity(robot.body, lin, ang, physicsClientId=robot.cid)
        for name, index in robot.joints.items():
            p.resetJointState(robot.body, index, self.positions[name], self.velocities[name],
                              physicsClientId=robot.cid)

    def state(self) -> RobotState:
        """Command, odometry and truth now, from the robot's own numbers (no PyBullet call)."""
        # Runs for every robot on every log row.
        robot, v, w = self.robot, self.v, self.w
        if self.encoder:
            odo = self.odometry
            odom_x, odom_y, odom_yaw = odo.x, odo.y, wrap_angle(odo.yaw)
        else:
            x0, y0, yaw0 = robot.spawn_xy_yaw
            dx, dy = self.x - x0, self.y - y0
            c, s = math.cos(yaw0), math.sin(yaw0)
            odom_x, odom_y, odom_yaw = c * dx + s * dy, -s * dx + c * dy, wrap_angle(self.yaw - yaw0)
        cmd, tilt = robot.cmd, self.tilt
        return RobotState(cmd[0], cmd[1], odom_x, odom_y, odom_yaw, v, w, self.x, self.y, self.z, tilt[0], tilt[1],
                          wrap_angle(self.yaw), v, w, dict(self.positions), robot.collisions, self.velocities,
                          hit=robot.hit)
