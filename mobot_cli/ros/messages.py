"""The ROS 2 messages of a run as CDR bytes: what the bag stores and what `--ros2` publishes.

One place builds them so that a recorded bag and a live ROS 2 topic carry the same bytes:
``/clock``, ``/tf`` (every robot's odom -> base and moving joints in one message),
``/tf_static`` (``world -> <prefix>odom`` and the fixed joints) and per robot odom, cmd_vel,
joint_states and robot_description. Shapes are laid out once per robot (ros/cdr.py); a
message is then one ``struct.pack``. A bag packs a whole log row at once: each robot gives its
numbers in one block (``RobotMessages.row_values``) and says where each message's variables
are in it (``row_messages``, ``tf_sources``).
"""

from __future__ import annotations

import functools
import math
import re
from typing import Iterable, Sequence

from mobot_cli.common.transforms import odom_origin, yaw_quat
from mobot_cli.plan import RobotPlan
from mobot_cli.ros import sensor_topics
from mobot_cli.ros.cdr import Layout, Packer
from mobot_cli.ros.tf import RobotFrames, Transform
from mobot_cli.sim.state import RobotState
from mobot_cli.timeline.records import Reading

WORLD_FRAME = "world"  # Gazebo's name for the frame all robots' odom frames hang from
CLOCK, TF = "rosgraph_msgs/msg/Clock", "tf2_msgs/msg/TFMessage"
ODOMETRY, TWIST = "nav_msgs/msg/Odometry", "geometry_msgs/msg/Twist"
TWIST_STAMPED = "geometry_msgs/msg/TwistStamped"  # cmd_vel from nav2 in Kilted and later
JOINT_STATE, STRING = "sensor_msgs/msg/JointState", "std_msgs/msg/String"
LASER_SCAN = "sensor_msgs/msg/LaserScan"
_MESH_PATH = re.compile(r'(<mesh\b[^>]*?\bfilename\s*=\s*")(/)')
CLOCK_LAYOUT = Layout().var("i").var("I")
CLOCK_PACKER = CLOCK_LAYOUT.build()
STAMP_SOURCES = (1, 2)  # a row's values start with its log time (ns), then the stamp: sec, nanosec
_BLOCK = 10  # a robot's block: x, y, sin and cos of half the yaw, vx, wz, command linear, angular,
# linear_y, and odometry vy

Stamp = tuple[int, int]  # (sec, nanosec)


def stamp_of(step: int, rate_hz: int) -> tuple[int, Stamp]:
    """Sim time of ``step`` as nanoseconds and as a ROS stamp, without float drift."""
    ns = step * 1_000_000_000 // rate_hz
    return ns, divmod(ns, 1_000_000_000)


def file_uris(urdf: str) -> str:
    """Absolute mesh paths as file:// URIs, which rviz and Foxglove load."""
    return _MESH_PATH.sub(r"\1file://\2", urdf)


class RobotMessages:
    """One robot's message shapes: odometry, command, joint states, TF and its description."""

    def __init__(self, plan: RobotPlan, state: RobotState):
        self.plan = plan
        self.frames = RobotFrames(plan.urdf, plan.frame_prefix, plan.root_link)
        cov = self.frames.covariance
        self.odom_layout = (Layout().header(self.frames.odom_frame).string(self.frames.base_frame)
                            .var("d", 7).doubles(cov).var("d", 6).doubles(cov))
        self.twist_layout = Layout().var("d", 6)
        self.joints = list(state.joint_positions)
        n = len(self.joints)
        joints = Layout().header("").strings(self.joints)
        if n:
            joints.u32(n).var("d", n).u32(n).var("d", n)
        else:
            joints.u32(0).u32(0)
        self.joint_layout = joints.u32(0)  # effort: none
        self.row_width = _BLOCK + 2 * n + 7 * len(self.frames.moving)  # values in this robot's block
        self.sensor_frames = {spec.name: sensor_topics.sensor_frame(plan, spec) for spec in plan.sensors}

    # Packers for one message at a time (the live publisher's); a bag packs whole rows instead.
    @functools.cached_property
    def odom_packer(self) -> Packer:
        """Packs ``odom``'s values."""
        return self.odom_layout.build()

    @functools.cached_property
    def twist_packer(self) -> Packer:
        """Packs ``cmd_vel``'s values."""
        return self.twist_layout.build()

    @functools.cached_property
    def joint_packer(self) -> Packer:
        """Packs ``joint_states``' values."""
        return self.joint_layout.build()

    def description(self) -> bytes:
        """std_msgs/String with the URDF, mesh paths as file:// URIs."""
        return Layout().string(file_uris(self.plan.urdf)).pack(())

    def odom(self, stamp: Stamp, state: RobotState) -> bytes:
        """nav_msgs/Odometry in the robot's odom frame."""
        half = state.odom_yaw / 2.0
        return self.odom_packer.pack((*stamp, state.odom_x, state.odom_y, 0.0, 0.0, 0.0, math.sin(half),
                                      math.cos(half), state.odom_vx, state.odom_vy, 0.0, 0.0, 0.0, state.odom_wz))

    def cmd_vel(self, state: RobotState) -> bytes:
        """geometry_msgs/Twist: the command the robot holds."""
        return self.twist_packer.pack((state.cmd_linear, state.cmd_linear_y, 0.0, 0.0, 0.0, state.cmd_angular))

    def joint_states(self, stamp: Stamp, state: RobotState) -> bytes:
        """sensor_msgs/JointState: positions and velocities of every joint the robot had at spawn."""
        positions, velocities = self._joint_numbers(state)
        return self.joint_packer.pack((*stamp, *positions, *velocities))

    def _joint_numbers(self, state: RobotState) -> tuple[Iterable[float], Iterable[float]]:
        """Positions and velocities of the joints the robot had at spawn, in that order (0 for one gone)."""
        positions, velocities = state.joint_positions, state.joint_velocities
        if len(positions) == len(velocities) == len(self.joints):  # the same joints, in order
            return positions.values(), velocities.values()
        return [positions.get(j, 0.0) for j in self.joints], [velocities.get(j, 0.0) for j in self.joints]

    def tf_values(self, stamp: Stamp, state: RobotState, out: list[float]) -> None:
        """This robot's /tf numbers (odom -> base, then each moving joint), appended to ``out``."""
        half = state.odom_yaw / 2.0
        out.extend((*stamp, state.odom_x, state.odom_y, 0.0, 0.0, 0.0, math.sin(half), math.cos(half)))
        positions = state.joint_positions
        for joint in self.frames.moving:
            out.extend((*stamp, *joint.transform(positions)))

    def row_values(self, state: RobotState, out: list[float]) -> None:
        """This robot's block of a row's values, appended to ``out``: the numbers of its odom,
        cmd_vel, joint_states and /tf transforms, each once."""
        half = state.odom_yaw / 2.0
        out += (state.odom_x, state.odom_y, math.sin(half), math.cos(half), state.odom_vx, state.odom_wz,
                state.cmd_linear, state.cmd_angular, state.cmd_linear_y, state.odom_vy)
        positions, velocities = self._joint_numbers(state)
        out += positions
        out += velocities
        for joint in self.frames.moving:
            out += joint.transform(state.joint_positions)

    def row_messages(self, at: int) -> list[tuple[Layout, tuple]]:
        """(layout, sources) of odom, cmd_vel and joint_states with this robot's block at value ``at``."""
        x, y, sin, cos, vx, wz, linear, angular, linear_y, vy = range(at, at + _BLOCK)
        joints = tuple(range(at + _BLOCK, at + _BLOCK + 2 * len(self.joints)))
        return [(self.odom_layout, (*STAMP_SOURCES, x, y, 0.0, 0.0, 0.0, sin, cos, vx, vy, 0.0, 0.0, 0.0, wz)),
                (self.twist_layout, (linear, linear_y, 0.0, 0.0, 0.0, angular)),
                (self.joint_layout, (*STAMP_SOURCES, *joints))]

    def tf_sources(self, at: int) -> tuple:
        """Where this robot's part of /tf (``tf_shape``) takes its variables, its block at ``at``."""
        x, y, sin, cos = range(at, at + 4)
        sources = [*STAMP_SOURCES, x, y, 0.0, 0.0, 0.0, sin, cos]
        first = at + _BLOCK + 2 * len(self.joints)
        for k in range(len(self.frames.moving)):
            sources += (*STAMP_SOURCES, *range(first + 7 * k, first + 7 * k + 7))
        return tuple(sources)

    def statics(self, state: RobotState) -> list[Transform]:
        """``world -> <prefix>odom`` where odometry (0, 0, 0) is (always first), then every fixed
        joint, then every sensor's frame."""
        # The odom frame sits where odometry (0, 0, 0) is: the truth now, less the odometry so far.
        origin = odom_origin(state.true_x, state.true_y, state.true_yaw, state.odom_x, state.odom_y, state.odom_yaw)
        odom = Transform(WORLD_FRAME, self.frames.odom_frame, (origin.x, origin.y, state.true_z), yaw_quat(origin.yaw))
        sensors = [Transform(f.parent, f.frame, f.xyz, f.quat) for f in self.sensor_frames.values() if f.parent]
        return [odom, *self.frames.static, *sensors]

    def reading(self, stamp: tuple[int, int], reading: Reading) -> bytes:
        """One sensor reading as its ROS message (CDR)."""
        from mobot_cli.ros import sensor_cdr  # numpy: only when a robot has sensors

        spec, data = reading.sensor, reading.data
        frame = self.sensor_frames[spec.name].frame
        if spec.kind == "lidar":
            if sensor_topics.is_3d(spec):
                return sensor_cdr.point_cloud2(stamp, frame, data.ranges, data.beams)
            return sensor_cdr.laser_scan(stamp, frame, spec, sensor_cdr.scan_row(data.ranges))
        if spec.kind == "range":
            return sensor_cdr.range_message(stamp, frame, spec, data.range)
        if spec.kind == "imu":
            return sensor_cdr.imu(stamp, frame, spec, data.orientation, data.angular_velocity,
                                  data.linear_acceleration)
        # in the world frame, as gazebo_ros_bumper without a <frame_name>
        collision = f"{self.plan.name}::{spec.link}::{spec.collision or spec.link}"
        return sensor_cdr.contacts_state(stamp, WORLD_FRAME, collision, data.contacts)


def tf_layout(robots: Sequence[RobotFrames]) -> Packer:
    """The /tf message shape for this set of robots: odom -> base, then every moving joint."""
    return tf_shape(robots).build()


def tf_shape(robots: Sequence[RobotFrames]) -> Layout:
    """``tf_layout``, not yet built: its variables are each robot's ``tf_values``, in turn."""
    pairs = []
    for frames in robots:
        pairs.append((frames.odom_frame, frames.base_frame))
        pairs.extend((joint.parent, joint.child) for joint in frames.moving)
    layout = Layout().u32(len(pairs))
    for parent, child in pairs:
        layout.header(parent).string(child).var("d", 7)
    return layout


def tf_static(stamp: Stamp, transforms: Sequence[Transform]) -> bytes:
    """A tf2_msgs/TFMessage of fixed transforms, all stamped ``stamp``."""
    layout = Layout().u32(len(transforms))
    values: list[float] = []
    for t in transforms:
        layout.header(t.parent).string(t.child).var("d", 7)
        values.extend((*stamp, *t.xyz, *t.quat))
    return layout.pack(values)


def laser_scan_layout(frame_id: str, rays: int, intensities: bool = False) -> Packer:
    """sensor_msgs/LaserScan with ``rays`` ranges; values: sec, nanosec, angle_min, angle_max,
    angle_increment, time_increment, scan_time, range_min, range_max, the ranges, then (with
    ``intensities``) as many intensities."""
    layout = Layout().header(frame_id).var("f", 7).u32(rays).var("f", rays)
    if intensities:
        return layout.u32(rays).var("f", rays).build()
    return layout.u32(0).build()
