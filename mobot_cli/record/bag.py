"""``DIR/bag/``: a rosbag2 folder (metadata.yaml + one MCAP file) that ROS tools open as is.

Written with rosbags: storage plugin mcap with zstd chunks, metadata version 8 (Iron's; Jazzy
reads it, and its QoS profiles are YAML strings as Humble's reader expects), CDR encoded, every
message definition embedded. Its connections and metadata.yaml are written as its Writer writes
them, without ruamel.yaml (ros/bag_metadata.py), and messages go into its open MCAP chunk
directly (ros/mcap_records.py). Topics, per sample at the log rate unless noted:

* ``/clock`` (rosgraph_msgs/Clock): the sim time;
* ``/tf`` (tf2_msgs/TFMessage): per robot ``<prefix>odom -> <prefix><root link>`` from its
  odometry, and every moving joint from the joint positions, as robot_state_publisher does;
  With movers (docs/movers.md), each mover as ``world -> movers/<name>`` (at its foot, facing
  its heading) on the rows after they moved;
* ``/tf_static`` (transient local): every robot's static frames in one message, written again
  when robots arrive (once for those arriving in one sample) or one leaves, so the latest
  message holds them all, as the live topic does: ``world -> <prefix>odom`` at the pose the
  robot's odometry starts from, so every robot shows in one view, and every fixed joint;
* ``<ns>/odom`` (nav_msgs/Odometry), ``<ns>/cmd_vel`` (geometry_msgs/Twist),
  ``<ns>/joint_states`` (sensor_msgs/JointState) and, once, ``<ns>/robot_description``
  (std_msgs/String, transient local; mesh paths as file:// URIs);
* per sensor, at its own rate: ``<ns>/scan`` (LaserScan), ``<ns>/points`` (PointCloud2),
  ``<ns>/imu`` (Imu), ``<ns>/bumper`` (gazebo_msgs/ContactsState), named and framed as
  ros/sensor_topics.py says, each sensor frame on /tf_static.

Message log times and header stamps are both sim time (nanoseconds from the start), so the
same run gives the same bytes. Samples are recorded ``CHUNK_EVERY_SAMPLES`` at a time, each
batch closed as one MCAP chunk and flushed, so a killed run leaves an MCAP file that a reader
scanning it reads up to its last chunk (metadata.yaml is written only when the bag closes).
"""

from __future__ import annotations

import contextlib
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

from mobot_cli.plan import CAMERA_KINDS, Plan, RobotPlan
from mobot_cli.record.sinks import named
from mobot_cli.ros import bag_metadata, sensor_topics
from mobot_cli.ros.definitions import MESSAGES
from mobot_cli.ros.mcap_records import Records, Row
from mobot_cli.ros.messages import (
    CLOCK,
    CLOCK_LAYOUT,
    CLOCK_PACKER,
    JOINT_STATE,
    ODOMETRY,
    STAMP_SOURCES,
    STRING,
    TF,
    TWIST,
    RobotMessages,
    file_uris,
    stamp_of,
    tf_shape,
    tf_static,
)
from mobot_cli.ros.tf import mover_transforms
from mobot_cli.sim.state import RobotState
from mobot_cli.timeline.records import Reading, Sample, Sink

__all__ = ["BagSink", "file_uris"]
CHUNK_EVERY_SAMPLES = 50  # as the CSV's flush: about one second at the default log rate
CHUNK_BYTES = 8 << 20  # sensor data waiting before a chunk is closed anyway (3D lidars)


class BagSink(Sink):
    """Records samples into ``DIR/bag``; a robot's topics open with its first sample."""

    def __init__(self, plan: Plan, out_dir: Path, direct: bool = True):
        """``direct=False`` sends every message through rosbags' Writer.write: the same bytes,
        slower (the reference the tests compare the direct records with)."""
        from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer

        self.rate = plan.physics.rate_hz
        self.images = plan.images  # cameras' images: raw, png or jpeg (CompressedImage)
        self.path = out_dir / "bag"
        if self.path.exists():  # a rerun into the same folder; rosbags never overwrites
            shutil.rmtree(self.path)
        self.writer = Writer(self.path, version=8, storage_plugin=StoragePlugin.MCAP)
        # zstd inside each MCAP chunk (as ros2 bag record's zstd storage presets do): far
        # smaller for a small share of the bag's time; metadata.yaml names no compression, as
        # readers need no extra step.
        self.writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
        self.writer.open()
        self.records = Records(self.writer, direct)
        self.broken = False  # a write failed: the file ends torn, as a killed run's (mobot check --repair)
        self.clock = self.topic("/clock", CLOCK)
        self.tf = self.topic("/tf", TF)
        self.tf_static = self.topic("/tf_static", TF, latched=True)
        self.robots: dict[str, _RobotTopics] = {}  # by record name; kept after a delete for its topics
        self.arriving: dict[str, RobotPlan] = {}  # spawned, waiting for their first sample
        # Rows by the robots in them and whether /clock is in: the row, and each robot's row_values.
        self.rows: dict[tuple[tuple[str, ...], bool], tuple[Row, list]] = {}
        self.pending: list = []  # samples, arrivals (key, plan) and readings (key, Reading), in order
        self.waiting = 0  # samples in ``pending``
        self.waiting_bytes = 0  # sensor data in ``pending``
        self.sensor_topics: dict[str, object] = {}  # topic name -> connection, added once
        self.clock_step = -1  # the step of the last /clock message
        self.statics: dict[str, list] = {}  # each present robot's static transforms, in order of arrival

    def topic(self, name: str, msgtype: str, latched: bool = False):
        """Add a connection, with its message definition and type hash embedded."""
        msgdef, rihs01 = MESSAGES[msgtype]
        return bag_metadata.add_connection(self.writer, name, msgtype, msgdef, rihs01,
                                           bag_metadata.latched_qos() if latched else ())

    def spawned(self, step: int, key: str, robot: RobotPlan) -> None:
        self.pending.append((key, robot))

    def deleted(self, step: int, key: str) -> None:
        self.pending.append(_Left(step, key))

    def write(self, sample: Sample) -> None:
        # Samples wait and are recorded a chunk at a time: the same work runs ~2x faster in a
        # batch than spread between physics steps, which leave the CPU caches cold.
        self.pending.append(sample)
        self.waiting += 1
        if self.waiting >= CHUNK_EVERY_SAMPLES:
            self._record()

    def reading(self, key: str, reading: Reading) -> None:
        self.pending.append((key, reading))
        if reading.sensor.kind in CAMERA_KINDS:  # rendered now, while the world is where it was
            images = (reading.data.rgb, reading.data.depth)
            self.waiting_bytes += sum(a.nbytes for a in images if a is not None)
        else:
            self.waiting_bytes += getattr(reading.data, "nbytes", 64)  # a scan's ranges are cast when written
        if self.waiting_bytes >= CHUNK_BYTES:
            self._record()

    def _record(self) -> None:
        """Record the waiting samples and readings and close their chunk."""
        try:
            for item in self.pending:
                if isinstance(item, Sample):
                    self._record_one(item)
                elif isinstance(item, _Left):
                    self._leave(item)
                elif isinstance(item[1], Reading):
                    key, reading = item
                    self.robots[key].write_reading(self.records, reading, self.rate)
                else:
                    key, robot = item
                    self.arriving[key] = robot
            self.pending.clear()
            self.waiting = self.waiting_bytes = 0
            self._flush()
        except OSError as exc:
            self.broken = True
            raise named(exc, self.writer.storage.path) from None

    def _record_one(self, sample: Sample) -> None:
        ns, stamp = stamp_of(sample.step, self.rate)
        clock = sample.step != self.clock_step  # a robot's own row may share its step with a log row
        self.clock_step = sample.step
        names = tuple(sample.states)
        if self.arriving and not self.arriving.keys().isdisjoint(names):
            if clock:  # before the arrivals: their connections go into the open chunk after it
                self.records.write(ns, [(self.clock, CLOCK_PACKER.pack(stamp))])
                clock = False
            for name in names:
                if name in self.arriving:
                    self.records.write(ns, self._arrive(name, self.arriving.pop(name), sample.states[name], stamp))
            self.records.write(ns, [self._statics_message(stamp)])
        row, fills = self.rows.get((names, clock)) or self._row(names, clock)
        values = [ns, *stamp]
        for fill, state in zip(fills, sample.states.values()):
            fill(state, values)
        self.records.write_row(ns, row, values)
        if sample.movers:
            self.records.write(ns, [(self.tf, tf_static(stamp, mover_transforms(sample.movers)))])

    def _row(self, names: tuple[str, ...], clock: bool) -> tuple[Row, list]:
        """The row of a sample of these robots, and the functions that give its values."""
        robots = [self.robots[name] for name in names]
        row = log_row(self.clock if clock else None,
                      [((r.odom, r.cmd_vel, r.joint_states), r.messages) for r in robots], self.tf)
        self.rows[names, clock] = row, [r.messages.row_values for r in robots]
        return self.rows[names, clock]

    def _arrive(self, name: str, plan: RobotPlan, state: RobotState,
                stamp: tuple[int, int]) -> list[tuple[object, bytes]]:
        """A robot's first sample: its topics (reused for a name seen before), then its
        description and static frames, the messages returned."""
        same_ns = [r for r in self.robots.values() if r.plan.namespace == plan.namespace]
        self.rows = {key: row for key, row in self.rows.items() if name not in key[0]}  # a name seen before
        robot = self.robots[name] = _RobotTopics(self, plan, state, reuse=same_ns[0] if same_ns else None)
        self.statics[name] = robot.messages.statics(state)
        return [(robot.description, robot.messages.description())]

    def _statics_message(self, stamp: tuple[int, int]) -> tuple[object, bytes]:
        """/tf_static with every present robot's static frames (a late-joining player gets them all)."""
        return self.tf_static, tf_static(stamp, [t for transforms in self.statics.values() for t in transforms])

    def _leave(self, left: "_Left") -> None:
        """A robot left: its frames leave /tf_static (nothing to write if it never had a sample)."""
        self.arriving.pop(left.key, None)
        if self.statics.pop(left.key, None) is not None:
            ns, stamp = stamp_of(left.step, self.rate)
            self.records.write(ns, [self._statics_message(stamp)])

    def _flush(self) -> None:
        """Close the open MCAP chunk and push it to the OS, so a killed run keeps it."""
        # rosbags closes chunks only at 1 MiB; its McapWriter has no public flush, so use its
        # chunk writer directly. Without it (another rosbags) a killed run keeps less, no harm.
        storage = getattr(self.writer, "storage", None)
        try:
            if storage.chunk.bio.tell():
                self.records.close_chunk()
            storage.bio.flush()
        except AttributeError:
            pass

    def close(self) -> None:
        storage = self.writer.storage
        if storage is None:
            return
        try:
            if not self.broken:  # else writing more would fail again; what is on disk can be repaired
                self._record()
                bag_metadata.close(self.writer)  # the MCAP summary and footer, then metadata.yaml
        except OSError as exc:
            failed = storage.path if self.writer.storage is not None else self.path / "metadata.yaml"
            with contextlib.suppress(OSError):
                (self.path / "metadata.yaml.tmp").unlink(missing_ok=True)
            raise named(exc, failed) from None
        finally:
            if self.writer.storage is not None:
                self._abandon(storage)

    def _abandon(self, storage) -> None:
        """Let go of the MCAP file without its summary: it stays as a killed run leaves it."""
        self.broken, self.writer.storage = True, None
        try:
            storage.bio.close()  # may still add pending bytes: they continue the file, in order
        except (OSError, ValueError):
            pass


@dataclass(frozen=True)
class _Left:
    """A robot's delete, waiting in order with the samples."""

    step: int
    key: str


class _RobotTopics:
    """One robot's bag connections and message shapes."""

    def __init__(self, sink: BagSink, plan: RobotPlan, state: RobotState, reuse: "_RobotTopics | None" = None):
        ns = plan.namespace.rstrip("/")
        self.plan = plan
        self.messages = RobotMessages(plan, state)
        if reuse is not None:  # a topic is added once
            self.odom, self.cmd_vel = reuse.odom, reuse.cmd_vel
            self.joint_states, self.description = reuse.joint_states, reuse.description
        else:
            self.odom = sink.topic(f"{ns}/odom", ODOMETRY)
            self.cmd_vel = sink.topic(f"{ns}/cmd_vel", TWIST)
            self.joint_states = sink.topic(f"{ns}/joint_states", JOINT_STATE)
            self.description = sink.topic(f"{ns}/robot_description", STRING, latched=True)
        self.sensor_connections = {spec.name: _sensor_topic(sink, plan, spec) for spec in plan.sensors
                                   if spec.kind not in CAMERA_KINDS}
        self.cameras = {spec.name: _camera_topics(sink, plan, spec) for spec in plan.sensors
                        if spec.kind in CAMERA_KINDS}
        self.images = sink.images

    def write_reading(self, records: Records, reading: Reading, rate: int) -> None:
        """One sensor reading as its ROS message (a camera's: image, depth image, camera info)."""
        ns, stamp = stamp_of(reading.step, rate)
        if reading.sensor.name in self.cameras:
            from mobot_cli.ros import camera_cdr

            spec, connections = reading.sensor, self.cameras[reading.sensor.name]
            frame = self.messages.sensor_frames[spec.name].frame
            records.write(ns, [(connections[topic], data) for topic, data in camera_cdr.messages(
                stamp, frame, spec, reading.data, {role: role for role in connections}, self.images)])
            return
        records.write(ns, [(self.sensor_connections[reading.sensor.name], self.messages.reading(stamp, reading))])


def log_row(clock, robots: Sequence[tuple[Sequence, RobotMessages]], tf) -> Row:
    """The messages of one sample: /clock (unless ``clock`` is None), each robot's odom,
    cmd_vel and joint_states (to its three connections), then one /tf. Its values: the log
    time (ns), the stamp, then each robot's ``row_values``."""
    row = Row()
    if clock is not None:
        row.add(clock, CLOCK_LAYOUT, STAMP_SOURCES)
    at, tf_sources = len(STAMP_SOURCES) + 1, []
    for connections, messages in robots:
        for connection, (layout, sources) in zip(connections, messages.row_messages(at)):
            row.add(connection, layout, sources)
        tf_sources += messages.tf_sources(at)
        at += messages.row_width
    return row.add(tf, tf_shape([messages.frames for _, messages in robots]), tf_sources).build()


def _sensor_topic(sink: BagSink, plan: RobotPlan, spec):
    """A sensor's connection, added once per topic name."""
    name = sensor_topics.topic(plan, spec)
    if name not in sink.sensor_topics:
        sink.sensor_topics[name] = sink.topic(name, sensor_topics.message_type(spec))
    return sink.sensor_topics[name]


def _camera_topics(sink: BagSink, plan: RobotPlan, spec) -> dict:
    """A camera's connections by role (image, depth, camera_info), each added once per topic name;
    the image on image_raw/compressed when the bag compresses images (image_transport's name)."""
    from mobot_cli.ros.definitions import CAMERA_INFO, COMPRESSED_IMAGE, IMAGE

    out = {}
    for role, name in sensor_topics.camera_topics(plan, spec).items():
        kind = CAMERA_INFO if role == "camera_info" else IMAGE
        if role == "image" and sink.images != "raw":
            name, kind = f"{name}/compressed", COMPRESSED_IMAGE
        if name not in sink.sensor_topics:
            sink.sensor_topics[name] = sink.topic(name, kind)
        out[role] = sink.sensor_topics[name]
    return out
