"""A holonomic robot in the kinematic engine: it follows its (vx, vy, wz) exactly.

The twist ramps toward the command within ``max_wheel_acceleration`` (at the rim) and is slowed
as a whole to the wheels' velocity limit; the body moves by the exact planar integration of
that twist over each step (sim/holonomic.planar, gz-math's), the wheels turn at MecanumDrive's
speeds for it, and encoder odometry integrates the same motion. A step is a 3-tuple
(forward, turn, lateral): the world reads its first two as a diff drive's and the robot's
``bound`` covers the lateral part, so collisions are checked as for any robot.
"""

from __future__ import annotations

import math

from mobot_cli.sim.drive import ramp
from mobot_cli.sim.holonomic import PlanarOdometry, planar, side_rates
from mobot_cli.sim.kinematic.body import Mover
from mobot_cli.sim.state import RobotState


class HolonomicMover(Mover):
    """A Mover whose rates are the body twist (vx, vy, wz), not left and right wheel rates."""

    def __init__(self, robot, dt: float, bottom: float, reach: float, feet: list[tuple[float, float]]):
        super().__init__(robot, dt, bottom, reach, feet)
        self.rates = self.goal = (0.0, 0.0, 0.0)
        self.lateral = 0.0  # this step's sideways distance, as motion() worked it out
        drive = self.drive
        self.n_left = drive.n_left
        self.wheelbase = drive.spec.wheelbase
        arm = 0.5 * (self.separation + self.wheelbase) or 0.1
        rim = (drive.spec.max_wheel_acceleration or 0.0) * dt * (self.radius or 1.0)
        self.max_steps = (rim, rim, rim / arm)
        self.odometry = PlanarOdometry()
        self.encoder = drive.encoder

    def command(self, linear: float, angular: float, lateral: float = 0.0) -> None:
        """The twist to follow, slowed together to the wheels' velocity limit."""
        goal = (linear, lateral, angular)
        top = max((abs(r) for r in self._wheel_rates(goal)), default=0.0)
        if top > self.max_rate:
            goal = tuple(v * self.max_rate / top for v in goal)
        self.goal = goal
        if self.max_steps[0] <= 0.0:
            self.rates = goal

    def _wheel_rates(self, twist: tuple[float, float, float]) -> list[float]:
        if not self.wheels or not self.radius:
            return []
        vx, vy, wz = twist
        return side_rates(self.n_left, len(self.wheels) - self.n_left, vx, vy, wz, self.separation,
                          self.wheelbase, self.radius)

    def motion(self):
        """This step's (forward, turn, lateral) from the twist, ramped first; None: standing still."""
        rates = self.rates
        if rates != self.goal:
            rates = self.rates = tuple(ramp(r, g, m) for r, g, m in zip(rates, self.goal, self.max_steps))
        if rates is not self._motion_of:
            vx, vy, wz = rates
            dt = self.dt
            self._motion_of = rates
            self._motion = None if vx == vy == wz == 0.0 else (vx * dt, wz * dt, vy * dt)
            self.lateral = vy * dt
            self.bound = math.hypot(vx * dt, vy * dt) + abs(wz * dt) * self.reach
        motion = self._motion
        if motion is None and (self.v or self.w or self.vy):
            self._stayed = None
            self.v = self.w = self.vy = 0.0
            self.velocities = dict.fromkeys(self.velocities, 0.0)
            self.synced = False
        return motion

    def target(self, distance: float, turn: float, fraction: float) -> tuple[float, float, float]:
        """Where ``fraction`` of this step's motion takes the robot: x, y, yaw."""
        return planar(self.x, self.y, self.yaw, distance * fraction, self.lateral * fraction, turn * fraction)

    def move(self, distance: float, turn: float, fraction: float) -> None:
        """Make ``fraction`` of this step's motion: pose, wheel angles, encoder odometry."""
        if fraction == 0.0:
            if self._stayed is self.rates:
                return
            self._stayed = self.rates
        else:
            self._stayed = None
        forward, lateral, turn = distance * fraction, self.lateral * fraction, turn * fraction
        if fraction > 0.0:
            self.x, self.y, self.yaw = planar(self.x, self.y, self.yaw, forward, lateral, turn)
            self.synced = False
            self.stuck = None
        dt = self.dt
        self.v, self.vy, self.w = forward / dt, lateral / dt, turn / dt
        positions, velocities = self.positions, dict(self.velocities)
        for (name, sign, _), rate in zip(self.wheels, self._wheel_rates((self.v, self.vy, self.w))):
            positions[name] += sign * rate * dt
            velocities[name] = sign * rate
        self.velocities = velocities
        if self.encoder:  # the wheels' forward kinematics give back this same motion
            self.odometry.integrate(forward, lateral, turn)

    def state(self) -> RobotState:
        """Command, odometry and truth now (Mover.state), with the sideways command and speed."""
        state = super().state()
        state.cmd_linear_y = self.robot.cmd_y
        state.odom_vy = state.true_vy = self.vy
        return state
