"""One spawned robot: its joints, its drive controller and its odometry."""

from __future__ import annotations

import math

from mobot_cli.errors import SpawnError
from mobot_cli.plan import DriveSpec, RobotPlan
from mobot_cli.sim.bullet.holonomic import HolonomicDrive
from mobot_cli.sim.bullet.joints import JointHolds
from mobot_cli.sim.bullet.twist_trim import TwistTrim
from mobot_cli.sim.drive import Odometry, body_twist, ramp, wheel_speeds, wrap_angle
from mobot_cli.sim.holonomic import KINDS
from mobot_cli.sim.pb import p
from mobot_cli.sim.state import RobotState

HOLONOMIC = KINDS  # drive kinds that take a sideways linear_y


class SimRobot:
    """A robot body in one PyBullet client, driven like ros2_control's diff_drive_controller."""

    def __init__(self, cid: int, body: int, plan: RobotPlan, dt: float, notices: list[str] | None = None,
                 drive_class: type | None = None):
        self.cid = cid
        # What its drive says once during the run (a clamped car turn): the World's notices.
        self.notices: list[str] = notices if notices is not None else []
        self.body = body
        self.plan = plan
        self.name = plan.name
        self.dt = dt
        self.cmd = (0.0, 0.0)
        self.cmd_y = 0.0  # the sideways part of the command (holonomic drives)
        self.collisions = 0  # collision events so far, counted by the World's ContactCounter
        self.hit = ""  # what the last of them was with
        self.people_collisions = 0  # of those, the ones with people (movers: sim/movers/)
        self.joints: dict[str, int] = {}  # every non-fixed joint
        self.links: dict[str, int] = {p.getBodyInfo(body, physicsClientId=cid)[0].decode(): -1}
        for index in range(p.getNumJoints(body, physicsClientId=cid)):
            info = p.getJointInfo(body, index, physicsClientId=cid)
            self.links[info[12].decode()] = index
            if info[2] != p.JOINT_FIXED:
                self.joints[info[1].decode()] = index
        # PyBullet's base frame is the base link's inertial frame; remember how to get back
        # to the URDF link frame, which is what the ground truth reports.
        dyn = p.getDynamicsInfo(body, -1, physicsClientId=cid)
        self.com_to_link = p.invertTransform(dyn[3], dyn[4])
        offset = dyn[3] != (0.0, 0.0, 0.0) or dyn[4] != (0.0, 0.0, 0.0, 1.0)
        self.com_offset = offset  # most root links (base_footprint) have none: skip the maths
        self.joint_indices = list(self.joints.values())
        self._free_joints()
        self.drive: _Drive | HolonomicDrive | None = None
        wheels: set[str] = set()
        if plan.drive is not None:  # drive_class: another kind's (steered.drive_class)
            self.drive = HolonomicDrive(self, plan.drive, _forward_sign) if plan.drive.kind in HOLONOMIC \
                else (drive_class or _Drive)(self, plan.drive)
            wheels = {*plan.drive.left_joints, *plan.drive.right_joints, *plan.drive.steering_joints}
        self.holds = JointHolds(cid, body, self.joints, plan.holds, wheels)
        x, y, _, _, _, yaw = self.link_pose_rpy()
        self.spawn_xy_yaw = (x, y, yaw)

    def _free_joints(self) -> None:
        """Turn off the velocity motor PyBullet puts on every joint, so joints move freely."""
        indices = list(self.joints.values())
        if indices:
            p.setJointMotorControlArray(
                self.body, indices, p.VELOCITY_CONTROL, targetVelocities=[0.0] * len(indices),
                forces=[0.0] * len(indices), physicsClientId=self.cid)

    def link_pose(self) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """World position and quaternion of the root link's URDF frame."""
        pos, orn = p.getBasePositionAndOrientation(self.body, physicsClientId=self.cid)
        if not self.com_offset:
            return pos, orn
        return p.multiplyTransforms(pos, orn, self.com_to_link[0], self.com_to_link[1])

    def link_pose_rpy(self) -> tuple[float, float, float, float, float, float]:
        """Root link (x, y, z, roll, pitch, yaw) in the world."""
        pos, orn = self.link_pose()
        roll, pitch, yaw = p.getEulerFromQuaternion(orn)
        return pos[0], pos[1], pos[2], roll, pitch, yaw

    def set_command(self, linear: float, angular: float, linear_y: float = 0.0) -> None:
        """Take a cmd_vel body twist; robots without a drive refuse it, and a sideways
        ``linear_y`` is refused unless the drive is holonomic."""
        check_command(self.name, self.drive.spec if self.drive is not None else None, linear_y)
        self.cmd = (float(linear), float(angular))
        self.cmd_y = float(linear_y)
        if linear_y:
            self.drive.command(linear, angular, linear_y)
        else:
            self.drive.command(linear, angular)

    def kinematics(self) -> tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...], tuple[float, ...]]:
        """World position, quaternion, linear and angular velocity of the root link's URDF frame."""
        cid, body = self.cid, self.body
        com, orn = p.getBasePositionAndOrientation(body, physicsClientId=cid)
        lin, ang = p.getBaseVelocity(body, physicsClientId=cid)
        pos = com
        if self.com_offset:
            pos, orn = p.multiplyTransforms(com, orn, self.com_to_link[0], self.com_to_link[1])
            # Velocity of the link origin, not of the centre of mass: v + w x (link - com).
            r = (pos[0] - com[0], pos[1] - com[1], pos[2] - com[2])
            lin = (lin[0] + ang[1] * r[2] - ang[2] * r[1],
                   lin[1] + ang[2] * r[0] - ang[0] * r[2],
                   lin[2] + ang[0] * r[1] - ang[1] * r[0])
        return pos, orn, lin, ang

    def state(self, step: int = -1) -> RobotState:
        """Command, odometry and truth after ``step`` steps (called at log rate: few PyBullet calls)."""
        cid, body = self.cid, self.body
        pos, orn, lin, ang = self.kinematics()
        roll, pitch, yaw = p.getEulerFromQuaternion(orn)
        rot = p.getMatrixFromQuaternion(orn)
        true_vx = lin[0] * rot[0] + lin[1] * rot[3] + lin[2] * rot[6]  # along the body x axis
        true_wz = ang[0] * rot[2] + ang[1] * rot[5] + ang[2] * rot[8]  # about the body z axis
        joints = p.getJointStates(body, self.joint_indices, physicsClientId=cid) \
            if self.joint_indices else ()
        if self.drive is not None and self.drive.encoder:
            odom = self.drive.odometry_now(joints, step)
        else:
            x0, y0, yaw0 = self.spawn_xy_yaw
            dx, dy = pos[0] - x0, pos[1] - y0
            c, s = math.cos(yaw0), math.sin(yaw0)
            odom = (c * dx + s * dy, -s * dx + c * dy, wrap_angle(yaw - yaw0), true_vx, true_wz)
        state = RobotState(
            self.cmd[0], self.cmd[1], *odom, pos[0], pos[1], pos[2], roll, pitch, yaw,
            true_vx, true_wz, joint_positions={n: j[0] for n, j in zip(self.joints, joints)},
            collisions=self.collisions, hit=self.hit,
            joint_velocities={n: j[1] for n, j in zip(self.joints, joints)}, cmd_linear_y=self.cmd_y)
        if isinstance(self.drive, HolonomicDrive):
            state.true_vy = lin[0] * rot[1] + lin[1] * rot[4] + lin[2] * rot[7]  # along the body y axis
            state.odom_vy = self.drive.odom_vy if self.drive.encoder else state.true_vy
        return state

    def joint_positions(self) -> dict[str, float]:
        """Position of every non-fixed joint, by name."""
        if not self.joints:
            return {}
        states = p.getJointStates(self.body, self.joint_indices, physicsClientId=self.cid)
        return {name: s[0] for name, s in zip(self.joints, states)}


class _Drive:
    """Wheel motors and encoder odometry for one robot."""

    def __init__(self, robot: SimRobot, spec: DriveSpec):
        self.robot = robot
        self.spec = spec
        missing = [j for j in spec.left_joints + spec.right_joints if j not in robot.joints]
        if missing:
            raise SpawnError(f"robot '{robot.name}': drive joints {missing} are not movable joints "
                             "of its URDF", hint="Name its wheel joints in drive.left/right.")
        self.left = [robot.joints[j] for j in spec.left_joints]
        self.right = [robot.joints[j] for j in spec.right_joints]
        self.wheels = self.left + self.right
        self.slots = [robot.joint_indices.index(j) for j in self.wheels]  # in the joint list
        given = dict(getattr(spec, "joint_signs", ()) or ())
        self.signs = [float(given.get(j, 0.0)) or _forward_sign(robot, robot.joints[j])
                      for j in spec.left_joints + spec.right_joints]
        self.radius = spec.wheel_radius * spec.wheel_radius_multiplier
        self.separation = spec.wheel_separation * spec.wheel_separation_multiplier
        self.odometry = Odometry(self.separation)
        self.encoder = spec.odometry == "encoder"
        self.scale = [sign * self.radius for sign in self.signs]  # joint angle -> rim travel
        self.last = self._positions()
        self.integrated_at = -1  # the world step of the last integration
        self.rates = [0.0] * len(self.wheels)  # wheel targets in rad/s, as commanded now
        self.goal = list(self.rates)  # where ramping is heading (acceleration limit)
        self.max_step = (spec.max_wheel_acceleration or 0.0) * robot.dt
        self.forces = [spec.max_wheel_torque] * len(self.wheels)
        self.twist = (0.0, 0.0)  # the commanded body twist
        self.trim = TwistTrim(self.separation / 2.0) if _twist_feedback(spec) else None
        self.trim_from: tuple | None = None  # link pose at the start of the control period
        self._apply()

    def _positions(self) -> list[float]:
        states = p.getJointStates(self.robot.body, self.wheels, physicsClientId=self.robot.cid)
        return [s[0] for s in states]

    def command(self, linear: float, angular: float) -> None:
        """Wheel speed targets for a body twist; ramped later when acceleration is limited."""
        if (linear, angular) != self.twist:
            self.trim_from = None  # the period that saw the change measures nothing
        self.twist = (linear, angular)
        self._set_goal()
        if self.max_step <= 0.0:
            self.rates = list(self.goal)
            self._apply()

    def _set_goal(self) -> None:
        linear, angular = self.twist if self.trim is None else self.trim.apply(*self.twist)
        left, right = wheel_speeds(linear, angular, self.separation, self.radius, self.radius)
        n_left = len(self.left)
        self.goal = [(left if i < n_left else right) * sign for i, sign in enumerate(self.signs)]

    def trim_step(self, dt: float) -> None:
        """Compare the last ``dt`` seconds of body motion with the command; retrim the wheels."""
        pos, orn = self.robot.link_pose()
        start, self.trim_from = self.trim_from, (pos, orn)
        if start is None or self.ramping or self.trim is None:
            return
        (x0, y0, _), yaw0 = start[0], p.getEulerFromQuaternion(start[1])[2]
        yaw1 = p.getEulerFromQuaternion(orn)[2]
        turn = wrap_angle(yaw1 - yaw0)
        mid = yaw0 + turn / 2.0
        forward = (pos[0] - x0) * math.cos(mid) + (pos[1] - y0) * math.sin(mid)
        if self.trim.update(self.twist, (forward / dt, turn / dt), dt):
            # A gain moves by at most GAIN * dt * BAND (2.4 % at 50 Hz) per period: within
            # any acceleration limit, so the new targets apply at once.
            self._set_goal()
            self.rates = list(self.goal)
            self._apply()

    @property
    def ramping(self) -> bool:
        return self.max_step > 0.0 and self.rates != self.goal

    def ramp_step(self) -> None:
        """Move wheel targets one step toward the goal, no faster than the acceleration limit."""
        self.rates = [ramp(r, g, self.max_step) for r, g in zip(self.rates, self.goal)]
        self._apply()

    def _apply(self) -> None:
        p.setJointMotorControlArray(
            self.robot.body, self.wheels, p.VELOCITY_CONTROL, targetVelocities=self.rates,
            forces=self.forces, physicsClientId=self.robot.cid)

    def integrate(self, states=None) -> None:
        """Fold the wheel travel since the last call into the odometry."""
        # Runs at 50 Hz for every robot: one PyBullet call and one plain loop, no temporaries.
        if states is None:
            states = p.getJointStates(self.robot.body, self.wheels, physicsClientId=self.robot.cid)
        last, scale, n_left = self.last, self.scale, len(self.left)
        left = right = 0.0
        for k, state in enumerate(states):
            travel = (state[0] - last[k]) * scale[k]
            last[k] = state[0]
            if k < n_left:
                left += travel
            else:
                right += travel
        self.odometry.advance(left / n_left, right / (len(states) - n_left))

    def odometry_now(self, joints, step: int = -1) -> tuple[float, float, float, float, float]:
        """Odometry pose and twist, brought up to date from ``joints`` (every non-fixed joint)."""
        wheels = [joints[k] for k in self.slots]
        if step < 0 or step != self.integrated_at:  # already folded in at this step: nothing moved
            self.integrate(wheels)
            self.integrated_at = step
        rim = [state[1] * scale for state, scale in zip(wheels, self.scale)]
        n_left = len(self.left)
        vx, wz = body_twist(sum(rim[:n_left]) / n_left, sum(rim[n_left:]) / (len(rim) - n_left),
                            self.separation)
        odo = self.odometry
        return odo.x, odo.y, wrap_angle(odo.yaw), vx, wz


def check_command(name: str, spec: DriveSpec | None, linear_y: float) -> None:
    """ValueError for a command this drive cannot follow: none at all, or a sideways one."""
    if spec is None:
        raise ValueError(f"robot '{name}' has no drive: it cannot take velocity commands")
    if linear_y and spec.kind not in HOLONOMIC:
        raise ValueError(f"robot '{name}' has a {spec.kind} drive: it cannot move sideways "
                         f"(linear_y {linear_y:g} m/s); only holonomic (mecanum, omni) drives can")


def _twist_feedback(spec: DriveSpec) -> bool:
    """Whether the twist loop runs: as set, else for skid steer (several wheels per side)."""
    if spec.twist_feedback is not None:
        return spec.twist_feedback
    return max(len(spec.left_joints), len(spec.right_joints)) > 1


def _forward_sign(robot: SimRobot, joint: int) -> float:
    """+1 when positive joint velocity rolls this wheel forward (axis along the body's +y)."""
    cid, body = robot.cid, robot.body
    axis = p.getJointInfo(body, joint, physicsClientId=cid)[13]
    link_orn = p.getLinkState(body, joint, computeForwardKinematics=True, physicsClientId=cid)[5]
    base_orn = robot.link_pose()[1]
    base_inv = p.invertTransform((0, 0, 0), base_orn)[1]
    rel = p.multiplyTransforms((0, 0, 0), base_inv, (0, 0, 0), link_orn)[1]  # link in base frame
    m = p.getMatrixFromQuaternion(rel)
    axis_y = m[3] * axis[0] + m[4] * axis[1] + m[5] * axis[2]
    return 1.0 if axis_y >= 0.0 else -1.0
