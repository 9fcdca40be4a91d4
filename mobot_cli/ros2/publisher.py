"""What the ROS 2 node publishes, from the timeline's records (ros2/bridge.py hands them over).

The same bytes as the bag (ros/messages.py): ``/clock`` and ``/tf`` every sample,
``/tf_static`` (every robot's fixed frames in one message, re-sent when a robot arrives or
leaves, as tf2's static broadcaster does), per robot ``<ns>/odom`` and ``<ns>/joint_states``
every sample, ``<ns>/odom/ground_truth`` (ros2/ground_truth.py) every sample while read, and
``<ns>/robot_description`` once. Each robot's ``<ns>/cmd_vel`` reader is made
here too, so that the node's endpoints in the graph are always the ones that exist.

Every sensor's readings go out on its bag topic (``<ns>/scan``, ``<ns>/points``, ``<ns>/range``, ``<ns>/imu``,
``<ns>/bumper``, a camera's ``<ns>/<camera>/image_raw``, ``depth/image_raw`` and ``camera_info``:
ros/sensor_topics.py), at the sensor's rate, the bag's bytes
(``RobotMessages.reading``), reliable, volatile, keep last 10 as ros_gz_bridge publishes
them (a reliable writer also serves the best-effort readers nav2 and slam_toolbox make);
their writers exist from the robot's arrival, so the graph lists them before the first reading.

More topics plug in through ``Topics.publish(name, msgtype, cdr)``: a writer is made on first
use with ROS's default QoS. A record type the timeline does not make yet gets a handler with
``register(record_type, handler)``; the handler turns it into publishes.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from typing import Callable

from mobot_cli.errors import MobotError
from mobot_cli.plan import CAMERA_KINDS, RobotPlan
from mobot_cli.ros import sensor_topics
from mobot_cli.ros.cdr import Packer
from mobot_cli.ros.definitions import CAMERA_INFO, IMAGE, MESSAGES
from mobot_cli.ros.messages import (
    CLOCK,
    CLOCK_PACKER,
    JOINT_STATE,
    ODOMETRY,
    STRING,
    TF,
    TWIST,
    TWIST_STAMPED,
    RobotMessages,
    stamp_of,
    tf_layout,
    tf_static,
)
from mobot_cli.ros.tf import mover_transforms
from mobot_cli.ros2 import dds, graph, ground_truth, idl, names
from mobot_cli.sim.state import RobotState
from mobot_cli.timeline.records import Deleted, Reading, Record, Sample, Spawned

TWIST_FIELDS = struct.Struct("<4x6d")  # encapsulation header, linear xyz, angular xyz
Handler = Callable[["Topics", Record], None]
_HANDLERS: dict[type, Handler] = {}


def register(record_type: type, handler: Handler) -> None:
    """Publish records of ``record_type`` with ``handler(topics, record)`` (sensor readings)."""
    _HANDLERS[record_type] = handler


def type_hash(msgtype: str) -> str:
    """The RIHS01 hash ROS 2 Jazzy and later expect in an endpoint's USER_DATA."""
    return MESSAGES[msgtype][1]


def twist(data: bytes) -> tuple[float, float]:
    """(linear.x, angular.z) of a geometry_msgs/Twist in CDR; ValueError if it is not one."""
    # Little-endian plain CDR only, as ROS 2 sends; a writer may pad it to 4 or 8 bytes, no more.
    if not TWIST_FIELDS.size <= len(data) <= TWIST_FIELDS.size + 4 or data[1] != 1:
        raise ValueError("not a little-endian CDR geometry_msgs/Twist")
    lx, _, _, _, _, az = TWIST_FIELDS.unpack_from(data)
    return lx, az


def unstamped(data: bytes) -> bytes:
    """The geometry_msgs/Twist (CDR) inside a TwistStamped (CDR); b'' when it is not one (the
    bridge then drops it as malformed). The header (stamp, frame) is not used: a command holds
    from when it arrives, as a Twist's does."""
    if len(data) < 16 or data[1] != 1:
        return b""
    (length,) = struct.unpack_from("<I", data, 12)  # after the header's stamp: the frame_id's length
    start = 16 + length
    start += -(start - 4) % 8  # the twist's doubles align to 8 from the end of the encapsulation header
    body = data[start:start + 48]
    return data[:4] + body if len(body) == 48 and len(data) <= start + 52 else b""


def planar_twist(data: bytes) -> tuple[float, float, float]:
    """(linear.x, linear.y, angular.z) of a geometry_msgs/Twist in CDR; ValueError if it is not one."""
    linear, angular = twist(data)
    return linear, TWIST_FIELDS.unpack_from(data)[1], angular


class Topics:
    """The node's writers and readers by ROS topic name; every change re-announces the node."""

    def __init__(self, participant: dds.Participant, node: str, namespace: str, gid_size: int):
        self.participant = participant
        self.node, self.namespace, self.gid_size = node, namespace, gid_size
        self.writers: dict[str, dds.Writer] = {}
        self.readers: dict[tuple[str, str], dds.Reader] = {}  # (topic, type): cmd_vel takes two types
        self.sent = 0  # messages written
        self.unsent = 0  # messages a stalled reliable reader kept from being written
        self.held = self.changed = False  # announcements wait while held (a fleet's arrivals: one, not N)
        self._announcer = participant.writer(graph.TOPIC, idl.ParticipantEntitiesInfo if gid_size == 16
                                             else idl.ParticipantEntitiesInfo24, dds.DISCOVERY,
                                             dds.ros_topic_userdata(graph.RIHS01))
        self.announce()

    def writer(self, name: str, msgtype: str, profile: dds.QosProfile = dds.DEFAULT) -> dds.Writer:
        """The writer of ROS topic ``name``, made on first use."""
        writer = self.writers.get(name)
        if writer is None:
            writer = self.writers[name] = self.participant.writer(
                names.topic(name), idl.TYPES[msgtype], profile, dds.ros_topic_userdata(type_hash(msgtype)))
            self.announce()
        return writer

    def publish(self, name: str, msgtype: str, data: bytes, profile: dds.QosProfile = dds.DEFAULT) -> None:
        """Send one message (CDR bytes) on ROS topic ``name``; a volatile one only when read."""
        writer = self.writer(name, msgtype, profile)
        if not (writer.readers or profile.transient_local):
            return
        if writer.write(data):
            self.sent += 1
        else:
            self.unsent += 1

    def wanted(self, name: str, msgtype: str) -> bool:
        """Whether anyone reads ROS topic ``name`` now (build the message only then)."""
        return self.writer(name, msgtype).readers > 0

    def subscribe(self, name: str, msgtype: str, on_data: Callable[[bytes], None]) -> None:
        """Take ROS topic ``name`` of type ``msgtype`` (reliable, volatile, keep last 10); ``on_data``
        runs on Cyclone's thread. One topic may be read as several types: each matches its writers."""
        self.readers[(name, msgtype)] = self.participant.reader(
            names.topic(name), idl.TYPES[msgtype], dds.DEFAULT, on_data, dds.ros_topic_userdata(type_hash(msgtype)))
        self.announce()

    def drop(self, *topics: str) -> None:
        """Remove these topics' writers and readers from the graph."""
        for name in topics:
            if name in self.writers:
                self.writers.pop(name).delete()
            for key in [key for key in self.readers if key[0] == name]:
                self.readers.pop(key).delete()
        self.announce()

    def announce(self) -> None:
        """Tell the ROS graph this node's name and endpoints (ros_discovery_info); while ``held``,
        once when it ends."""
        if self.held:
            self.changed = True
            return
        self._announcer.write(graph.participant_entities_info(
            self.participant.gid, self.namespace, self.node, [r.gid for r in self.readers.values()],
            [w.gid for w in self.writers.values()], self.gid_size))


@dataclass
class _Robot:
    """A robot's message shapes and the writers its every sample goes to."""

    messages: RobotMessages
    namespace: str
    odom: dds.Writer
    joint_states: dds.Writer
    sensors: dict[str, dds.Writer]  # sensor name -> the writer of its topic
    cameras: dict[str, dict[str, dds.Writer]] = field(default_factory=dict)  # camera -> role -> writer
    truth: dds.Writer | None = None  # <ns>/odom/ground_truth (ros2/ground_truth.py)
    truth_packer: object = None


class RecordPublisher:
    """Turns records into messages: robots get their topics with their first sample."""

    def __init__(self, topics: Topics, rate_hz: int, on_cmd_vel: Callable[[str, str, bytes], None],
                 world_frame: bool = True):
        self.topics, self.rate = topics, rate_hz
        self.world_frame = world_frame  # publish world -> <prefix>odom (off: a localizer owns the odom's parent)
        self.on_cmd_vel = on_cmd_vel  # (robot, topic, CDR bytes as they came), called on Cyclone's thread
        self.arriving: dict[str, RobotPlan] = {}
        self.robots: dict[str, _Robot] = {}
        self.left_out: list[str] = []  # robots with no ROS 2 topics, and why
        self.statics: dict[str, list] = {}  # name -> its fixed transforms
        self.tf_packers: dict[tuple[str, ...], Packer] = {}
        self.clock_step = -1
        self.clock = topics.writer("/clock", CLOCK)  # in the graph from the start
        self.tf = topics.writer("/tf", TF)
        topics.writer("/tf_static", TF, dds.LATCHED)

    def __call__(self, record: Record) -> None:
        if isinstance(record, Sample):
            self.sample(record)
        elif isinstance(record, Spawned):
            self.arriving[record.robot.name] = record.robot
        elif isinstance(record, Reading):
            self.reading(record)
        elif isinstance(record, Deleted):
            self.leave(record.name)
        elif type(record) in _HANDLERS:
            _HANDLERS[type(record)](self.topics, record)

    def sample(self, sample: Sample) -> None:
        """/clock, each robot's odom and joint_states, and one /tf for all of them; a message
        is built only for a topic that some reader matches."""
        # Runs at the log rate: writers are looked up once per robot, not per message.
        stamp = stamp_of(sample.step, self.rate)[1]
        write = self._write
        if sample.step != self.clock_step:
            self.clock_step = sample.step
            if self.clock.readers:
                write(self.clock, CLOCK_PACKER.pack(stamp))
        tf_values: list[float] | None = [] if self.tf.readers else None
        arriving = [name for name in sample.states if name in self.arriving]
        if arriving:
            self._arrive_all(arriving, sample, stamp)
        robots = self.robots
        for name, state in sample.states.items():
            robot = robots.get(name)
            if robot is None:  # a robot that was in the world before the bridge opened
                continue
            messages = robot.messages
            if robot.odom.readers:
                write(robot.odom, messages.odom(stamp, state))
            if robot.joint_states.readers:
                write(robot.joint_states, messages.joint_states(stamp, state))
            if robot.truth.readers:
                write(robot.truth, ground_truth.message(robot.truth_packer, stamp, state))
            if tf_values is not None:
                messages.tf_values(stamp, state, tf_values)
        if tf_values is not None:
            present = tuple(name for name in sample.states if name in robots)
            if present:
                packer = self.tf_packers.get(present)
                if packer is None:
                    packer = self.tf_packers[present] = tf_layout([robots[n].messages.frames for n in present])
                write(self.tf, packer.pack(tf_values))
        if sample.movers and tf_values is not None:  # the movers' frames, in a message of their own
            write(self.tf, tf_static(stamp, mover_transforms(sample.movers)))

    def _arrive_all(self, arriving: list[str], sample: Sample, stamp: tuple[int, int]) -> None:
        """The robots new in this sample, the node announced and /tf_static sent once for all of
        them (a fleet's first sample: once, not once per robot with every robot so far)."""
        topics = self.topics
        topics.held = True
        try:
            for name in arriving:
                self.arrive(self.arriving.pop(name), sample.states[name], stamp, statics=False)
        finally:
            topics.held = False
            if topics.changed:
                topics.changed = False
                topics.announce()
        self.publish_statics(stamp)

    def reading(self, reading: Reading) -> None:
        """A sensor reading on its bag topic, built only while someone reads it (a camera's image
        is rendered only then: sim/sensing/camera.py)."""
        robot = self.robots.get(reading.robot)
        if robot is not None and reading.sensor.name in robot.cameras:
            self._camera(robot, reading)
            return
        writer = robot.sensors.get(reading.sensor.name) if robot is not None else None
        if writer is not None and writer.readers:
            self._write(writer, robot.messages.reading(stamp_of(reading.step, self.rate)[1], reading))

    def wants_image(self, reading: Reading) -> bool:
        """A camera reading whose image or depth topic has a reader now (it must be rendered at its step)."""
        robot = self.robots.get(reading.robot)
        writers = robot.cameras.get(reading.sensor.name) if robot is not None else None
        return bool(writers) and any(w.readers for role, w in writers.items() if role != "camera_info")

    def _camera(self, robot: _Robot, reading: Reading) -> None:
        from mobot_cli.ros import camera_cdr

        writers = {role: w for role, w in robot.cameras[reading.sensor.name].items() if w.readers}
        if set(writers) - {"camera_info"}:  # camera_info alone needs no image
            frame = robot.messages.sensor_frames[reading.sensor.name].frame
            stamp = stamp_of(reading.step, self.rate)[1]
            for role, data in camera_cdr.messages(stamp, frame, reading.sensor, reading.data,
                                                  {role: role for role in robot.cameras[reading.sensor.name]}):
                if role in writers:
                    self._write(writers[role], data)
        elif writers:
            from mobot_cli.ros.camera_cdr import camera_info

            frame = robot.messages.sensor_frames[reading.sensor.name].frame
            stamp = stamp_of(reading.step, self.rate)[1]
            self._write(writers["camera_info"], camera_info(stamp, frame, reading.sensor))

    def _write(self, writer: dds.Writer, data: bytes) -> None:
        if writer.write(data):
            self.topics.sent += 1
        else:
            self.topics.unsent += 1

    def arrive(self, plan: RobotPlan, state: RobotState, stamp: tuple[int, int], statics: bool = True) -> None:
        """A robot's topics, description and fixed frames (sent now unless ``statics`` is False),
        and its /cmd_vel reader if it drives; a robot whose namespace ROS 2 cannot take (a live
        spawn's) is left out, and said so."""
        namespace = plan.namespace
        try:
            names.check_namespace(namespace)
        except MobotError as exc:
            self.left_out.append(f"robot '{plan.name}' is not on ROS 2: {exc}")
            return
        messages = RobotMessages(plan, state)
        sensors = {spec.name: self.topics.writer(sensor_topics.topic(plan, spec), sensor_topics.message_type(spec))
                   for spec in plan.sensors if spec.kind not in CAMERA_KINDS}
        cameras = {spec.name: {role: self.topics.writer(name, CAMERA_INFO if role == "camera_info" else IMAGE)
                               for role, name in sensor_topics.camera_topics(plan, spec).items()}
                   for spec in plan.sensors if spec.kind in CAMERA_KINDS}
        self.robots[plan.name] = _Robot(messages, namespace,
                                        self.topics.writer(names.join(namespace, "odom"), ODOMETRY),
                                        self.topics.writer(names.join(namespace, "joint_states"), JOINT_STATE), sensors,
                                        cameras,
                                        self.topics.writer(names.join(namespace, ground_truth.TOPIC), ODOMETRY),
                                        ground_truth.packer(messages.frames.base_frame))
        self.topics.publish(names.join(namespace, "robot_description"), STRING, messages.description(), dds.LATCHED)
        frames = messages.statics(state)
        self.statics[plan.name] = frames if self.world_frame else frames[1:]
        if statics:
            self.publish_statics(stamp)
        if plan.drive is not None:
            name, topic = plan.name, names.join(namespace, "cmd_vel")
            # The bytes go to the bridge as they came: it checks them (ros2/inputs.py) and counts what it drops.
            self.topics.subscribe(topic, TWIST, lambda data: self.on_cmd_vel(name, topic, data))
            # nav2 sends TwistStamped from Kilted on (enable_stamped_cmd_vel): both drive the robot alike.
            self.topics.subscribe(topic, TWIST_STAMPED,
                                  lambda data: self.on_cmd_vel(name, topic, unstamped(data)))

    def leave(self, name: str) -> None:
        """A robot left: its topics leave the graph, its frames leave /tf_static."""
        self.arriving.pop(name, None)
        if name not in self.robots:
            return
        robot = self.robots.pop(name)
        namespace = robot.namespace
        self.statics.pop(name, None)
        plan = robot.messages.plan
        cameras = CAMERA_KINDS
        sensors = {sensor_topics.topic(plan, spec) for spec in plan.sensors if spec.kind not in cameras}
        sensors |= {name for spec in plan.sensors if spec.kind in cameras
                    for name in sensor_topics.camera_topics(plan, spec).values()}
        self.topics.drop(*(names.join(namespace, t) for t in ("odom", "joint_states", "robot_description", "cmd_vel",
                                                              ground_truth.TOPIC)),
                         *sensors)
        self.publish_statics(stamp_of(self.clock_step if self.clock_step >= 0 else 0, self.rate)[1])

    def publish_statics(self, stamp: tuple[int, int]) -> None:
        """Every robot's fixed transforms in one latched message (a late joiner gets them all)."""
        transforms = [t for robot in self.statics.values() for t in robot]
        self.topics.publish("/tf_static", TF, tf_static(stamp, transforms), dds.LATCHED)
