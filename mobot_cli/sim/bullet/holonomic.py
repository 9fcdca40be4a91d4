"""A holonomic (mecanum or omni) base in PyBullet: the body follows its planar twist.

PyBullet's anisotropic friction is along the link's own axes, so it cannot model rollers at 45
degrees to the wheel. mobot drives the base as gazebo_ros's planar_move does, but through forces
rather than by setting the velocity: every step a force at the robot's centre of mass and a
torque about the vertical pull its planar twist to the command, no harder than a grip of
``GRIP`` g allows (so walls and other robots stop it, and nothing lifts or tips it: the force
is horizontal through the centre of mass). The wheels roll on frictionless rollers (they carry
the weight, the base force moves it) and their joints turn at MecanumDrive's wheel speeds, so
encoders and joint states are what Gazebo shows. Encoder odometry integrates those wheels as
gz-math's MecanumDriveOdometry does; planar_move robots report the model's pose instead.

Tracking was measured on the bundled robots/mecanum (tests/sim/test_holonomic.py): see
``GAIN``.
"""

from __future__ import annotations

import math

from mobot_cli.errors import SpawnError
from mobot_cli.plan import DriveSpec
from mobot_cli.sim.drive import ramp, wrap_angle
from mobot_cli.sim.holonomic import PlanarOdometry, corners, mecanum_body_twist, side_rates
from mobot_cli.sim.pb import p

# Fraction of the twist error corrected per physics step. 1.0 (dead-beat) tracked a sideways
# 1 m to 0.1 % and held roll and pitch under 0.1 deg; the contact solver adds no overshoot.
GAIN = 1.0
# The most the base force may accelerate the robot, in g: a wheel grip of mu = 1 (Gazebo's default).
GRIP = 1.0
# What holonomic wheels roll on: frictionless (the base force moves the robot).
ROLLER_FRICTION = 0.0


class HolonomicDrive:
    """Base force and torque toward the commanded (vx, vy, wz), wheel joints at mecanum speeds."""

    trim = None  # the skid-steer twist loop (twist_trim.py) never runs here

    def __init__(self, robot, spec: DriveSpec, forward_sign=None):
        """``forward_sign(robot, joint index)`` gives a wheel's sign when the spec does not."""
        self.robot = robot
        self.spec = spec
        missing = [j for j in spec.left_joints + spec.right_joints if j not in robot.joints]
        if missing:
            raise SpawnError(f"robot '{robot.name}': drive joints {missing} are not movable joints "
                             "of its URDF", hint="Name its wheel joints in drive.left/right.")
        self.radius = spec.wheel_radius * spec.wheel_radius_multiplier
        self.separation = spec.wheel_separation * spec.wheel_separation_multiplier
        self.n_left = len(spec.left_joints)
        turning = self.radius > 0.0 and self.n_left > 0 and len(spec.right_joints) > 0
        names = spec.left_joints + spec.right_joints if turning else ()
        self.left = [robot.joints[j] for j in spec.left_joints] if turning else []
        self.right = [robot.joints[j] for j in spec.right_joints] if turning else []
        self.wheels = self.left + self.right
        self.slots = [robot.joint_indices.index(j) for j in self.wheels]
        given = dict(spec.joint_signs)
        self.signs = [float(given.get(j, 0.0)) or (forward_sign(robot, robot.joints[j]) if forward_sign else 1.0)
                      for j in names]
        self.scale = [sign * self.radius for sign in self.signs]
        # No wheels to read (planar_move on a wheel-less body): odometry is the model's pose.
        self.encoder = spec.odometry == "encoder" and bool(self.wheels)
        self.odometry = PlanarOdometry()
        self.last = [s[0] for s in p.getJointStates(robot.body, self.wheels, physicsClientId=robot.cid)] \
            if self.wheels else []
        self.integrated_at = -1
        self.odom_vy = 0.0  # the sideways speed the encoders give, as of the last odometry_now
        self.twist = self.goal = (0.0, 0.0, 0.0)  # (vx, vy, wz) followed now, and commanded
        reach = 0.5 * (self.separation + spec.wheelbase) or 0.1
        rim = (spec.max_wheel_acceleration or 0.0) * robot.dt * (self.radius or 1.0)
        self.max_step = (rim, rim, rim / reach)  # per step; 0: unlimited
        self.forces = [spec.max_wheel_torque] * len(self.wheels)
        self._mass_properties()
        self._apply()

    def _mass_properties(self) -> None:
        """Total mass, its centre in the base's inertial frame and its inertia about the vertical."""
        cid, body = self.robot.cid, self.robot.body
        parts = []
        base_pos, base_orn = p.getBasePositionAndOrientation(body, physicsClientId=cid)
        for link in range(-1, p.getNumJoints(body, physicsClientId=cid)):
            info = p.getDynamicsInfo(body, link, physicsClientId=cid)
            if link < 0:
                pos, orn = base_pos, base_orn
            else:
                state = p.getLinkState(body, link, computeForwardKinematics=True, physicsClientId=cid)
                pos, orn = state[0], state[1]
            m = p.getMatrixFromQuaternion(orn)
            izz = sum(m[6 + k] ** 2 * info[2][k] for k in range(3))  # R diag(I) R^T, zz
            parts.append((info[0], pos, izz))
        mass = sum(part[0] for part in parts) or 1.0
        centre = [sum(part[0] * part[1][k] for part in parts) / mass for k in range(3)]
        self.mass = mass
        self.inertia = sum(izz + m_ * ((pos[0] - centre[0]) ** 2 + (pos[1] - centre[1]) ** 2)
                           for m_, pos, izz in parts) or 1e-3
        inv_pos, inv_orn = p.invertTransform(base_pos, base_orn)
        self.centre = p.multiplyTransforms(inv_pos, inv_orn, centre, (0.0, 0.0, 0.0, 1.0))[0]

    def command(self, linear: float, angular: float, lateral: float = 0.0) -> None:
        """Take a body twist; ramped later when acceleration is limited."""
        self.goal = (float(linear), float(lateral), float(angular))
        if self.max_step[0] <= 0.0:  # else ramp_step() moves the twist there
            self.twist = self.goal
            self._apply()

    @property
    def ramping(self) -> bool:
        return self.max_step[0] > 0.0 and self.twist != self.goal

    def ramp_step(self) -> None:
        """Move the followed twist one step toward the command, within the acceleration limit."""
        self.twist = tuple(ramp(t, g, m) for t, g, m in zip(self.twist, self.goal, self.max_step))
        self._apply()

    def _apply(self) -> None:
        """Wheel joint targets for the twist followed now."""
        if not self.wheels:
            return
        vx, vy, wz = self.twist
        rates = side_rates(self.n_left, len(self.right), vx, vy, wz, self.separation,
                           self.spec.wheelbase, self.radius)
        p.setJointMotorControlArray(
            self.robot.body, self.wheels, p.VELOCITY_CONTROL,
            targetVelocities=[r * s for r, s in zip(rates, self.signs)], forces=self.forces,
            physicsClientId=self.robot.cid)

    def push(self, dt: float) -> None:
        """This step's base force and torque (PyBullet clears them after every step)."""
        cid, body = self.robot.cid, self.robot.body
        com, orn = p.getBasePositionAndOrientation(body, physicsClientId=cid)
        lin, ang = p.getBaseVelocity(body, physicsClientId=cid)
        centre = p.multiplyTransforms(com, orn, self.centre, (0.0, 0.0, 0.0, 1.0))[0]
        origin, link_orn = self.robot.link_pose()
        yaw = p.getEulerFromQuaternion(link_orn)[2]
        vx, vy, wz = self.twist
        c, s = math.cos(yaw), math.sin(yaw)
        # wanted: the link origin moves at (vx, vy) in its frame and the body turns at wz;
        # the centre then moves at that plus wz x (centre - origin)
        dx, dy = centre[0] - origin[0], centre[1] - origin[1]
        want = (vx * c - vy * s - wz * dy, vx * s + vy * c + wz * dx)
        rx, ry = centre[0] - com[0], centre[1] - com[1]
        have = (lin[0] - ang[2] * ry, lin[1] + ang[2] * rx)
        gain = GAIN / dt
        fx, fy = (self.mass * gain * (w - h) for w, h in zip(want, have))
        limit = GRIP * self.mass * 9.81
        size = math.hypot(fx, fy)
        if size > limit:
            fx, fy = fx * limit / size, fy * limit / size
        torque = self.inertia * gain * (wz - ang[2])
        top = limit * (0.5 * (self.separation + self.spec.wheelbase) or 0.1)
        torque = max(-top, min(top, torque))
        p.applyExternalForce(body, -1, (fx, fy, 0.0), centre, p.WORLD_FRAME, physicsClientId=cid)
        p.applyExternalTorque(body, -1, (0.0, 0.0, torque), p.WORLD_FRAME, physicsClientId=cid)

    def integrate(self, states=None) -> None:
        """Fold the wheel travel since the last call into the encoder odometry."""
        if not self.encoder:
            return
        if states is None:
            states = p.getJointStates(self.robot.body, self.wheels, physicsClientId=self.robot.cid)
        travel = []
        for k, state in enumerate(states):
            travel.append((state[0] - self.last[k]) * self.scale[k])
            self.last[k] = state[0]
        self.odometry.integrate(*mecanum_body_twist(*corners(travel, self.n_left), self.separation,
                                                    self.spec.wheelbase))

    def odometry_now(self, joints, step: int = -1) -> tuple[float, float, float, float, float]:
        """Odometry pose and twist (forward, turn), brought up to date from ``joints``."""
        wheels = [joints[k] for k in self.slots]
        if step < 0 or step != self.integrated_at:
            self.integrate(wheels)
            self.integrated_at = step
        rims = [state[1] * scale for state, scale in zip(wheels, self.scale)]
        vx, self.odom_vy, wz = mecanum_body_twist(*corners(rims, self.n_left), self.separation,
                                                  self.spec.wheelbase)
        odo = self.odometry
        return odo.x, odo.y, wrap_angle(odo.yaw), vx, wz
