"""``DIR/bag/``: a rosbag2 folder (metadata.yaml + one MCAP file) that ROS tools open as is.

Written with rosbags: storage plugin mcap with zstd chunks, metadata version 8 (Iron's; Jazzy
reads it, and its QoS profiles are YAML strings as Humble's reader expects), CDR encoded, every
message definition embedded. Topics, per sample at the log rate unless noted:

* ``/clock`` (rosgraph_msgs/Clock): the sim time;
* ``/tf`` (tf2_msgs/TFMessage): per robot ``<prefix>odom -> <prefix><root link>`` from its
  odometry, and every moving joint from the joint positions, as robot_state_publisher does;
* ``/tf_static`` (transient local), once per robot: ``world -> <prefix>odom`` at the pose the
  robot's odometry starts from, so every robot shows in one view, and every fixed joint;
* ``<ns>/odom`` (nav_msgs/Odometry), ``<ns>/cmd_vel`` (geometry_msgs/Twist),
  ``<ns>/joint_states`` (sensor_msgs/JointState) and, once, ``<ns>/robot_description``
  (std_msgs/String, transient local; mesh paths as file:// URIs);
* per sensor, at its own rate: ``<ns>/scan`` (LaserScan), ``<ns>/points`` (PointCloud2),
  ``<ns>/imu`` (Imu), ``<ns>/bumper`` (gazebo_msgs/ContactsState), named and framed as
  run/sensor_topics.py says, each sensor frame on /tf_static.

Message log times and header stamps are both sim time (nanoseconds from the start), so the
same run gives the same bytes. Samples are recorded ``CHUNK_EVERY_SAMPLES`` at a time (or
sooner when sensor readings pile up ``CHUNK_BYTES``), each batch closed as one MCAP chunk and
flushed, so a killed run leaves an MCAP file that a reader
scanning it reads up to its last chunk (metadata.yaml is written only when the bag closes).
"""

from __future__ import annotations

import math
import re
import shutil
from pathlib import Path

from mobot_cli.common.transforms import odom_origin, yaw_quat
from mobot_cli.run import sensor_cdr, sensor_topics
from mobot_cli.run.cdr import Layout, Packer
from mobot_cli.run.ros_msgs import MESSAGES
from mobot_cli.run.ros_sensor_msgs import SENSOR_MESSAGES
from mobot_cli.run.sinks import Sink
from mobot_cli.run.tf import RobotFrames
from mobot_cli.run.timeline import Reading, Sample
from mobot_cli.sim.plan import Plan, RobotPlan
from mobot_cli.sim.state import RobotState

WORLD_FRAME = "world"  # Gazebo's name for the frame all robots' odom frames hang from
CHUNK_EVERY_SAMPLES = 50  # as the CSV's flush: about one second at the default log rate
CHUNK_BYTES = 8 << 20  # sensor data waiting before a chunk is closed anyway (3D lidars)
CLOCK, TF = "rosgraph_msgs/msg/Clock", "tf2_msgs/msg/TFMessage"
ODOMETRY, TWIST = "nav_msgs/msg/Odometry", "geometry_msgs/msg/Twist"
JOINT_STATE, STRING = "sensor_msgs/msg/JointState", "std_msgs/msg/String"
_MESH_PATH = re.compile(r'(<mesh\b[^>]*?\bfilename\s*=\s*")(/)')


def _latched_qos():
    """Reliable, transient local, depth 1: how tf_static and robot_description are published.

    ``ros2 bag play`` offers what the bag says, and rviz subscribes to these two transient
    local; without it they would never connect. Other topics record no QoS, so the player uses
    its reliable, volatile default (rosbags spends ~1.4 ms of YAML on every profile it stores).
    """
    from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime

    zero = QosTime(0, 0)
    return [Qos(QosHistory.KEEP_LAST, 1, QosReliability.RELIABLE, QosDurability.TRANSIENT_LOCAL,
                zero, zero, QosLiveliness.AUTOMATIC, zero, False)]


def file_uris(urdf: str) -> str:
    """Absolute mesh paths as file:// URIs, which rviz and Foxglove load."""
    return _MESH_PATH.sub(r"\1file://\2", urdf)


class BagSink(Sink):
    """Records samples into ``DIR/bag``; a robot's topics open with its first sample."""

    def __init__(self, plan: Plan, out_dir: Path):
        from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer

        self.rate = plan.physics.rate_hz
        self.path = out_dir / "bag"
        if self.path.exists():  # a rerun into the same folder; rosbags never overwrites
            shutil.rmtree(self.path)
        self.writer = Writer(self.path, version=8, storage_plugin=StoragePlugin.MCAP)
        # zstd inside each MCAP chunk (as ros2 bag record's zstd storage presets do): ~12x
        # smaller for ~10 % of the bag's time; metadata.yaml names no compression, as readers
        # need no extra step.
        self.writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
        self.writer.open()
        self.clock = self.topic("/clock", CLOCK)
        self.tf = self.topic("/tf", TF)
        self.tf_static = self.topic("/tf_static", TF, latched=True)
        self.clock_packer = Layout().var("i").var("I").build()
        self.robots: dict[str, _RobotTopics] = {}  # by record name; kept after a delete for its topics
        self.arriving: dict[str, RobotPlan] = {}  # spawned, waiting for their first sample
        self.tf_packers: dict[tuple[str, ...], Packer] = {}  # the /tf shape for a set of robots
        self.pending: list = []  # samples, arrivals (key, plan) and readings (key, Reading), in order
        self.waiting = 0  # samples in ``pending``
        self.waiting_bytes = 0  # sensor data in ``pending``
        self.sensor_topics: dict[str, object] = {}  # topic name -> connection, added once
        self.clock_step = -1  # the step of the last /clock message

    def topic(self, name: str, msgtype: str, latched: bool = False):
        """Add a connection, with its message definition and type hash embedded."""
        msgdef, rihs01 = MESSAGES[msgtype] if msgtype in MESSAGES else SENSOR_MESSAGES[msgtype]
        return self.writer.add_connection(name, msgtype, msgdef=msgdef, rihs01=rihs01,
                                          offered_qos_profiles=_latched_qos() if latched else ())

    def spawned(self, step: int, key: str, robot: RobotPlan) -> None:
        self.pending.append((key, robot))

    def write(self, sample: Sample) -> None:
        # Samples wait and are recorded a chunk at a time: the same work runs ~2x faster in a
        # batch than spread between physics steps, which leave the CPU caches cold.
        self.pending.append(sample)
        self.waiting += 1
        if self.waiting >= CHUNK_EVERY_SAMPLES:
            self._record()

    def reading(self, key: str, reading: Reading) -> None:
        self.pending.append((key, reading))
        ranges = getattr(reading.data, "ranges", None)
        self.waiting_bytes += 64 if ranges is None else ranges.nbytes
        if self.waiting_bytes >= CHUNK_BYTES:
            self._record()

    def _record(self) -> None:
        """Record the waiting samples and readings and close their chunk."""
        for item in self.pending:
            if isinstance(item, Sample):
                self._record_one(item)
            elif isinstance(item[1], Reading):
                key, reading = item
                self.robots[key].write_reading(self.writer.write, reading, self.rate)
            else:
                key, robot = item
                self.arriving[key] = robot
        self.pending.clear()
        self.waiting = self.waiting_bytes = 0
        self._flush()

    def _record_one(self, sample: Sample) -> None:
        ns = sample.step * 1_000_000_000 // self.rate
        stamp = divmod(ns, 1_000_000_000)
        write = self.writer.write
        if sample.step != self.clock_step:  # a robot's own row may share its step with a log row
            self.clock_step = sample.step
            write(self.clock, ns, self.clock_packer.pack(stamp))
        names = tuple(sample.states)
        for name in names:
            if name in self.arriving:
                self._arrive(name, self.arriving.pop(name), sample.states[name], ns, stamp)
        tf_values: list[float] = []
        robots = self.robots
        for name, state in sample.states.items():
            robots[name].write(write, ns, stamp, state, tf_values)
        packer = self.tf_packers.get(names)
        if packer is None:
            packer = self.tf_packers[names] = _tf_layout([robots[name].frames for name in names])
        write(self.tf, ns, packer.pack(tf_values))

    def _arrive(self, name: str, plan: RobotPlan, state: RobotState, ns: int, stamp: tuple[int, int]) -> None:
        """A robot's first sample: its topics (reused for a name seen before), static frames and
        description."""
        same_ns = [r for r in self.robots.values() if r.plan.namespace == plan.namespace]
        robot = self.robots[name] = _RobotTopics(self, plan, state, reuse=same_ns[0] if same_ns else None)
        self.writer.write(robot.description, ns, robot.description_packer.pack(()))
        # The odom frame sits where odometry (0, 0, 0) is: the truth now, less the odometry so far.
        origin = odom_origin(state.true_x, state.true_y, state.true_yaw, state.odom_x, state.odom_y, state.odom_yaw)
        frames = robot.frames
        statics = [(WORLD_FRAME, frames.odom_frame, (origin.x, origin.y, state.true_z), yaw_quat(origin.yaw))]
        statics += [(t.parent, t.child, t.xyz, t.quat) for t in frames.static]
        statics += [(f.parent, f.frame, f.xyz, f.quat) for f in robot.sensor_frames.values() if f.parent]
        layout = Layout().u32(len(statics))
        values: list[float] = []
        for parent, child, xyz, quat in statics:
            layout.header(parent).string(child).var("d", 7)
            values.extend((*stamp, *xyz, *quat))
        self.writer.write(self.tf_static, ns, layout.build().pack(values))

    def _flush(self) -> None:
        """Close the open MCAP chunk and push it to the OS, so a killed run keeps it."""
        # rosbags closes chunks only at 1 MiB; its McapWriter has no public flush, so use its
        # chunk writer directly. Without it (another rosbags) a killed run keeps less, no harm.
        storage = getattr(self.writer, "storage", None)
        try:
            if storage.chunk.bio.tell():
                storage.close_chunk()
            storage.bio.flush()
        except AttributeError:
            pass

    def close(self) -> None:
        if self.writer.storage is not None:
            self._record()
            self.writer.close()


class _RobotTopics:
    """One robot's topics, frames and message layouts."""

    def __init__(self, sink: BagSink, plan: RobotPlan, state: RobotState, reuse: "_RobotTopics | None" = None):
        ns = plan.namespace.rstrip("/")
        self.plan = plan
        self.frames = RobotFrames(plan.urdf, plan.frame_prefix, plan.root_link)
        if reuse is not None:  # a topic is added once
            self.odom, self.cmd_vel = reuse.odom, reuse.cmd_vel
            self.joint_states, self.description = reuse.joint_states, reuse.description
        else:
            self.odom = sink.topic(f"{ns}/odom", ODOMETRY)
            self.cmd_vel = sink.topic(f"{ns}/cmd_vel", TWIST)
            self.joint_states = sink.topic(f"{ns}/joint_states", JOINT_STATE)
            self.description = sink.topic(f"{ns}/robot_description", STRING, latched=True)
        cov = self.frames.covariance
        self.odom_packer = (Layout().header(self.frames.odom_frame).string(self.frames.base_frame)
                            .var("d", 7).doubles(cov).var("d", 6).doubles(cov).build())
        self.twist_packer = Layout().var("d", 6).build()
        self.joints = list(state.joint_positions)
        n = len(self.joints)
        joints = Layout().header("").strings(self.joints)
        if n:
            joints.u32(n).var("d", n).u32(n).var("d", n)
        else:
            joints.u32(0).u32(0)
        self.joint_packer = joints.u32(0).build()  # effort: none
        self.description_packer = Layout().string(file_uris(plan.urdf)).build()
        self.sensor_frames = {spec.name: sensor_topics.sensor_frame(plan, spec) for spec in plan.sensors}
        self.sensor_connections = {spec.name: _sensor_topic(sink, plan, spec) for spec in plan.sensors}
        self.collision = {spec.name: f"{plan.name}::{spec.link}::{spec.collision or spec.link}"
                          for spec in plan.sensors if spec.kind == "contact"}

    def write_reading(self, write, reading: Reading, rate: int) -> None:
        """One sensor reading as its ROS message."""
        spec, data = reading.sensor, reading.data
        ns = reading.step * 1_000_000_000 // rate
        stamp = divmod(ns, 1_000_000_000)
        frame = self.sensor_frames[spec.name].frame
        if spec.kind == "lidar":
            if sensor_topics.is_3d(spec):
                message = sensor_cdr.point_cloud2(stamp, frame, data.ranges, data.beams)
            else:
                message = sensor_cdr.laser_scan(stamp, frame, spec, sensor_cdr.scan_row(data.ranges))
        elif spec.kind == "imu":
            message = sensor_cdr.imu(stamp, frame, spec, data.orientation, data.angular_velocity,
                                     data.linear_acceleration)
        else:  # in the world frame, as gazebo_ros_bumper without a <frame_name>
            message = sensor_cdr.contacts_state(stamp, WORLD_FRAME, self.collision[spec.name], data.contacts)
        write(self.sensor_connections[spec.name], ns, message)

    def write(self, write, ns: int, stamp: tuple[int, int], state: RobotState, tf_values: list[float]) -> None:
        """This robot's messages of one sample; its /tf transforms go to ``tf_values``."""
        # Runs at the log rate for every robot: plain tuples, one pack per message.
        sec, nsec = stamp
        half = state.odom_yaw / 2.0
        qz, qw = math.sin(half), math.cos(half)
        x, y = state.odom_x, state.odom_y
        write(self.odom, ns, self.odom_packer.pack(
            (sec, nsec, x, y, 0.0, 0.0, 0.0, qz, qw, state.odom_vx, 0.0, 0.0, 0.0, 0.0, state.odom_wz)))
        write(self.cmd_vel, ns, self.twist_packer.pack((state.cmd_linear, 0.0, 0.0, 0.0, 0.0, state.cmd_angular)))
        positions, velocities = state.joint_positions, state.joint_velocities
        if len(positions) == len(velocities) == len(self.joints):  # the same joints, in order
            values = (sec, nsec, *positions.values(), *velocities.values())
        else:
            values = (sec, nsec, *(positions.get(j, 0.0) for j in self.joints),
                      *(velocities.get(j, 0.0) for j in self.joints))
        write(self.joint_states, ns, self.joint_packer.pack(values))
        tf_values.extend((sec, nsec, x, y, 0.0, 0.0, 0.0, qz, qw))
        for joint in self.frames.moving:
            tf_values.extend((sec, nsec, *joint.transform(positions)))


def _sensor_topic(sink: BagSink, plan: RobotPlan, spec):
    """A sensor's connection, added once per topic name."""
    name = sensor_topics.topic(plan, spec)
    if name not in sink.sensor_topics:
        sink.sensor_topics[name] = sink.topic(name, sensor_topics.message_type(spec))
    return sink.sensor_topics[name]


def _tf_layout(robots: list[RobotFrames]) -> Packer:
    """The /tf message shape for this set of robots: odom -> base, then every moving joint."""
    pairs = []
    for frames in robots:
        pairs.append((frames.odom_frame, frames.base_frame))
        pairs.extend((joint.parent, joint.child) for joint in frames.moving)
    layout = Layout().u32(len(pairs))
    for parent, child in pairs:
        layout.header(parent).string(child).var("d", 7)
    return layout.build()
