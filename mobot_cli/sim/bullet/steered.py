"""An Ackermann car in PyBullet: steering joints held at the bicycle model's angles, driven
wheels at their own speeds, odometry from the rear wheels and the steering angle.

The reference point is the middle of the rear (driven) axle (sim/steering.py): a twist (v, w) is
the speed of that point and the yaw rate. A turn tighter than the minimum turning radius is
driven at that radius, and a turn without forward speed leaves the car standing with its wheels
at full lock (as gz-sim's AckermannSteering does); each is said once per robot in the run's
notices. Encoder odometry integrates the rear wheels' travel along the curvature that the
steering joints' measured angles stand for (gz-sim AckermannSteering's odometry; gazebo_ros
ackermann_drive publishes the model's pose instead: DriveSpec.odometry "ground_truth").
"""

from __future__ import annotations

import math

from mobot_cli.errors import SpawnError
from mobot_cli.plan import DriveSpec
from mobot_cli.sim import steering
from mobot_cli.sim.bullet.robot import SimRobot, _Drive
from mobot_cli.sim.drive import arc, wrap_angle
from mobot_cli.sim.pb import p

# Torque (N*m) a steering joint's position motor may use, per kg of the robot: Gazebo's
# ackermann plugins hold the steering joints with stiff PID loops (gains of 1500 N*m/rad).
STEER_TORQUE_PER_KG = 5.0
MIN_STEER_TORQUE = 20.0  # N*m


class SteeredDrive(_Drive):
    """Driven wheels (velocity motors) and steering joints (position motors) of one car."""

    def __init__(self, robot: SimRobot, spec: DriveSpec):
        super().__init__(robot, spec)
        cid, body = robot.cid, robot.body
        self.trim = None  # a car follows its geometry: no twist loop
        missing = [j for j in spec.steering_joints if j not in robot.joints]
        if missing:
            raise SpawnError(f"robot '{robot.name}': steering joints {missing} are not movable joints "
                             "of its URDF", hint="Name its steering joints in the drive.")
        self.steering = [robot.joints[j] for j in spec.steering_joints]
        self.steer_slots = [robot.joint_indices.index(j) for j in self.steering]
        given = dict(spec.joint_signs)
        self.steer_signs = [float(given.get(j, 1.0)) for j in spec.steering_joints]
        where = _positions(robot, self.wheels + self.steering)
        driven, steered = where[:len(self.wheels)], where[len(self.wheels):]
        rear = min(x for x, _ in driven)
        axle = [(x, y) for x, y in driven if x - rear < 0.01]
        self.rear = (sum(x for x, _ in axle) / len(axle), sum(y for _, y in axle) / len(axle))
        self.wheelbase = spec.wheelbase
        half = spec.wheel_separation / 2.0
        n_left = len(self.left)
        # Driven wheels about the rear axle's middle; the track is the drive's (a plugin's value wins).
        self.driven = [(x - self.rear[0], half if k < n_left else -half) for k, (x, _) in enumerate(driven)]
        self.rear_wheels = [k for k, (x, _) in enumerate(self.driven) if abs(x) < 0.01]
        self.steered = [(self.wheelbase, y - self.rear[1]) for _, y in steered]
        self.min_radius = steering.min_turning_radius(self.wheelbase, spec.max_steering_angle or 0.6)
        mass = sum(p.getDynamicsInfo(body, link, physicsClientId=cid)[0]
                   for link in range(-1, p.getNumJoints(body, physicsClientId=cid)))
        self.steer_force = max(MIN_STEER_TORQUE, STEER_TORQUE_PER_KG * mass)
        self.kappa = 0.0  # the curvature the steering is set to (1/m)
        self.said: set[str] = set()
        self.odometry.x, self.odometry.y = self.rear  # odometry integrates the rear axle's middle
        self.last_steer = self._steer_positions()
        self._steer()

    def _steer_positions(self) -> list[float]:
        states = p.getJointStates(self.robot.body, self.steering, physicsClientId=self.robot.cid)
        return [s[0] for s in states]

    def clamped(self, linear: float, angular: float) -> tuple[float, float, float]:
        """The twist the car can follow and the curvature to steer to; says once when it differs."""
        v, w, why = steering.clamp(linear, angular, self.min_radius)
        name = self.robot.name
        if why == "in place":
            self._say(why, f"robot '{name}' has Ackermann steering and cannot turn in place: a turn "
                           "without forward speed leaves it standing with its wheels at full lock")
            return 0.0, 0.0, math.copysign(1.0 / self.min_radius, angular)
        if why == "radius":
            self._say(why, f"robot '{name}' has Ackermann steering: turns tighter than its minimum "
                           f"turning radius {self.min_radius:.3f} m are driven at that radius")
        return v, w, (w / v if v else 0.0)

    def _say(self, key: str, line: str) -> None:
        if key not in self.said:
            self.said.add(key)
            self.robot.notices.append(line)

    def command(self, linear: float, angular: float) -> None:
        """Steer and drive for a body twist of the rear axle's middle (clamped to what a car can)."""
        v, w, self.kappa = self.clamped(linear, angular)
        self._steer()
        super().command(v, w)

    def _steer(self) -> None:
        targets = [steering.steering_angle(1.0, self.kappa, x, y) * sign
                   for (x, y), sign in zip(self.steered, self.steer_signs)]
        p.setJointMotorControlArray(
            self.robot.body, self.steering, p.POSITION_CONTROL, targetPositions=targets,
            forces=[self.steer_force] * len(self.steering), physicsClientId=self.robot.cid)

    def _set_goal(self) -> None:
        v, w = self.twist
        goal = []
        for (x, y), sign in zip(self.driven, self.signs):
            steer = steering.steering_angle(v, w, x, y) if x > self.wheelbase / 2 else 0.0
            goal.append(steering.rim_speed(v, w, x, y, steer) / self.radius * sign)
        self.goal = goal

    def integrate(self, states=None) -> None:
        """Fold the rear wheels' travel since the last call into the odometry, along the curvature
        the steering joints stand for now."""
        if states is None:
            states = p.getJointStates(self.robot.body, self.wheels + self.steering,
                                      physicsClientId=self.robot.cid)
        n = len(self.wheels)
        last, scale, travel = self.last, self.scale, 0.0
        for k in range(n):
            moved = (states[k][0] - last[k]) * scale[k]
            last[k] = states[k][0]
            if k in self.rear_wheels:
                travel += moved
        travel /= len(self.rear_wheels)
        kappa = self._measured_curvature(states[n:])
        odo = self.odometry
        odo.x, odo.y, odo.yaw = arc(odo.x, odo.y, odo.yaw, travel, travel * kappa)

    def _measured_curvature(self, steer_states) -> float:
        values = [steering.curvature(state[0] * sign, x, y)
                  for state, sign, (x, y) in zip(steer_states, self.steer_signs, self.steered)]
        return sum(values) / len(values)

    def odometry_now(self, joints, step: int = -1) -> tuple[float, float, float, float, float]:
        """Odometry pose (of the root link) and twist, brought up to date from ``joints``."""
        states = [joints[k] for k in self.slots + self.steer_slots]
        if step < 0 or step != self.integrated_at:
            self.integrate(states)
            self.integrated_at = step
        odo = self.odometry
        c, s = math.cos(odo.yaw), math.sin(odo.yaw)
        x = odo.x - c * self.rear[0] + s * self.rear[1]
        y = odo.y - s * self.rear[0] - c * self.rear[1]
        vx = sum(states[k][1] * self.scale[k] for k in self.rear_wheels) / len(self.rear_wheels)
        wz = vx * self._measured_curvature(states[len(self.wheels):])
        return x, y, wrap_angle(odo.yaw), vx, wz


def drive_class(spec: DriveSpec | None) -> type | None:
    """The drive class SimRobot takes for ``spec``: SteeredDrive for a car, else None (its own)."""
    return SteeredDrive if spec is not None and spec.kind == "ackermann" else None


def _positions(robot: SimRobot, joints: list[int]) -> list[tuple[float, float]]:
    """Where these joints' child link frames are, in the root link's frame (x, y)."""
    cid, body = robot.cid, robot.body
    pos, orn = robot.link_pose()
    inv_pos, inv_orn = p.invertTransform(pos, orn)
    out = []
    for joint in joints:
        world = p.getLinkState(body, joint, computeForwardKinematics=True, physicsClientId=cid)[4]
        local = p.multiplyTransforms(inv_pos, inv_orn, world, (0.0, 0.0, 0.0, 1.0))[0]
        out.append((local[0], local[1]))
    return out
