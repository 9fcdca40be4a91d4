"""What mobot's ROS 2 node puts on the wire, checked without a network: CDR bytes against two
independent serializers (rosbags, cyclonedds' IDL), golden bytes, names, hashes and settings."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.errors import UsageError
from mobot_cli.plan import RobotPlan, SpawnPose
from mobot_cli.ros import messages as rm
from mobot_cli.ros.cdr import ENCAPSULATION
from mobot_cli.ros.definitions import MESSAGES
from mobot_cli.ros2 import graph, names
from mobot_cli.sim.state import RobotState

pytest.importorskip("cyclonedds")
from mobot_cli.ros2 import idl  # noqa: E402 - needs cyclonedds
from mobot_cli.ros2.publisher import twist, type_hash  # noqa: E402

GOLDEN = Path(__file__).parents[1] / "golden" / "ros2_messages.json"
URDF = """<robot name="r"><link name="base_link"/><link name="wheel"/><link name="lidar"/>
<joint name="wheel_joint" type="continuous"><parent link="base_link"/><child link="wheel"/>
<origin xyz="0 0.1 0.05" rpy="-1.5708 0 0"/><axis xyz="0 0 1"/></joint>
<joint name="lidar_joint" type="fixed"><parent link="base_link"/><child link="lidar"/>
<origin xyz="0.05 0 0.2"/></joint></robot>"""
finite = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False)


def discovery_store(gid_size: int):
    """rmw_dds_common's messages (Gid is char[16] from Iron on, char[24] before)."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    typestore = get_typestore(Stores.EMPTY)
    types = get_types_from_msg(f"uint8[{gid_size}] data", "rmw_dds_common/msg/Gid")  # ROS 2 IDL: char is uint8
    types.update(get_types_from_msg("string<=256 node_namespace\nstring<=256 node_name\nGid[] reader_gid_seq\n"
                                    "Gid[] writer_gid_seq", "rmw_dds_common/msg/NodeEntitiesInfo"))
    types.update(get_types_from_msg("Gid gid\nNodeEntitiesInfo[] node_entities_info_seq",
                                    "rmw_dds_common/msg/ParticipantEntitiesInfo"))
    typestore.register(types)
    return typestore


@pytest.fixture(scope="module")
def store():
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_JAZZY)


def robot(**values) -> tuple[rm.RobotMessages, RobotState]:
    plan = RobotPlan(name="r1", namespace="/r1", frame_prefix="r1/", urdf=URDF, root_link="base_link",
                     pose=SpawnPose(), drive=None)
    fields = dict(true_x=1.5, true_y=-2.0, true_z=0.1, true_roll=0.0, true_pitch=0.0, true_yaw=0.3,
                  true_vx=0.2, true_wz=0.1, odom_x=0.5, odom_y=0.25, odom_yaw=0.2, odom_vx=0.2, odom_wz=0.1,
                  cmd_linear=0.2, cmd_angular=0.1, joint_positions={"wheel_joint": 1.25},
                  joint_velocities={"wheel_joint": 4.0})
    fields.update(values)
    state = RobotState(**{k: v for k, v in fields.items() if k in RobotState.__dataclass_fields__})
    return rm.RobotMessages(plan, state), state


def header(store, stamp, frame):
    Time, Header = store.types["builtin_interfaces/msg/Time"], store.types["std_msgs/msg/Header"]
    return Header(stamp=Time(sec=stamp[0], nanosec=stamp[1]), frame_id=frame)


def rosbags_odom(store, stamp, state, cov):
    import numpy as np

    t = store.types
    V, P, Q = t["geometry_msgs/msg/Vector3"], t["geometry_msgs/msg/Point"], t["geometry_msgs/msg/Quaternion"]
    half = state.odom_yaw / 2
    pose = t["geometry_msgs/msg/PoseWithCovariance"](
        pose=t["geometry_msgs/msg/Pose"](position=P(x=state.odom_x, y=state.odom_y, z=0.0),
                                         orientation=Q(x=0.0, y=0.0, z=math.sin(half), w=math.cos(half))),
        covariance=np.array(cov))
    tw = t["geometry_msgs/msg/TwistWithCovariance"](
        twist=t["geometry_msgs/msg/Twist"](linear=V(x=state.odom_vx, y=0.0, z=0.0),
                                           angular=V(x=0.0, y=0.0, z=state.odom_wz)),
        covariance=np.array(cov))
    msg = t["nav_msgs/msg/Odometry"](header=header(store, stamp, "r1/odom"), child_frame_id="r1/base_link",
                                     pose=pose, twist=tw)
    return bytes(store.serialize_cdr(msg, rm.ODOMETRY))


@settings(max_examples=40, deadline=None)
@given(x=finite, y=finite, yaw=finite, vx=finite, wz=finite, sec=st.integers(0, 2**31 - 1),
       nsec=st.integers(0, 999_999_999))
def test_odometry_bytes_equal_rosbags_and_cyclonedds(store, x, y, yaw, vx, wz, sec, nsec):
    messages, state = robot(odom_x=x, odom_y=y, odom_yaw=yaw, odom_vx=vx, odom_wz=wz)
    ours = messages.odom((sec, nsec), state)
    assert ours == rosbags_odom(store, (sec, nsec), state, messages.frames.covariance)
    half = yaw / 2
    cov = list(messages.frames.covariance)
    theirs = idl.Odometry(
        idl.Header(idl.Time(sec, nsec), "r1/odom"), "r1/base_link",
        idl.PoseWithCovariance(idl.Pose(idl.Point(x, y, 0.0),
                                        idl.Quaternion(0.0, 0.0, math.sin(half), math.cos(half))), cov),
        idl.TwistWithCovariance(idl.Twist(idl.Vector3(vx, 0.0, 0.0), idl.Vector3(0.0, 0.0, wz)), cov)).serialize()
    assert ours == theirs


@settings(max_examples=40, deadline=None)
@given(linear=finite, angular=finite)
def test_cmd_vel_bytes_and_their_decoding(store, linear, angular):
    messages, state = robot(cmd_linear=linear, cmd_angular=angular)
    ours = messages.cmd_vel(state)
    t = store.types
    V = t["geometry_msgs/msg/Vector3"]
    msg = t["geometry_msgs/msg/Twist"](linear=V(x=linear, y=0.0, z=0.0), angular=V(x=0.0, y=0.0, z=angular))
    assert ours == bytes(store.serialize_cdr(msg, rm.TWIST))
    message = idl.Twist(idl.Vector3(linear, 5.0, 6.0), idl.Vector3(7.0, 8.0, angular))
    assert twist(message.serialize()) == (linear, angular)


def test_twist_that_is_not_little_endian_cdr_is_refused():
    with pytest.raises(ValueError):
        twist(b"\x00\x00\x00\x00" + bytes(48))  # big-endian CDR
    with pytest.raises(ValueError):
        twist(ENCAPSULATION + bytes(8))  # too short


def test_clock_joint_states_tf_description_and_scan_bytes_equal_rosbags(store):
    import numpy as np

    t = store.types
    messages, state = robot()
    stamp = (12, 500_000_000)
    clock = t["rosgraph_msgs/msg/Clock"](clock=t["builtin_interfaces/msg/Time"](sec=12, nanosec=500_000_000))
    assert rm.CLOCK_PACKER.pack(stamp) == bytes(store.serialize_cdr(clock, rm.CLOCK))
    joints = t["sensor_msgs/msg/JointState"](header=header(store, stamp, ""), name=["wheel_joint"],
                                             position=np.array([1.25]), velocity=np.array([4.0]),
                                             effort=np.array([], dtype=np.float64))
    assert messages.joint_states(stamp, state) == bytes(store.serialize_cdr(joints, rm.JOINT_STATE))
    description = t["std_msgs/msg/String"](data=URDF)
    assert messages.description() == bytes(store.serialize_cdr(description, rm.STRING))
    values: list[float] = []
    messages.tf_values(stamp, state, values)
    ours = rm.tf_layout([messages.frames]).pack(values)
    decoded = store.deserialize_cdr(ours, rm.TF)
    assert [(x.header.frame_id, x.child_frame_id) for x in decoded.transforms] == [
        ("r1/odom", "r1/base_link"), ("r1/base_link", "r1/wheel")]
    assert bytes(store.serialize_cdr(decoded, rm.TF)) == ours
    statics = rm.tf_static(stamp, messages.statics(state))
    decoded = store.deserialize_cdr(statics, rm.TF)
    assert [(x.header.frame_id, x.child_frame_id) for x in decoded.transforms] == [
        ("world", "r1/odom"), ("r1/base_link", "r1/lidar")]
    scan = rm.laser_scan_layout("r1/lidar", 4, intensities=True).pack(
        (*stamp, -1.5, 1.5, 1.0, 0.0, 0.1, 0.1, 8.0, 1.0, 2.0, 3.0, float("inf"), 9.0, 8.0, 7.0, 6.0))
    msg = t["sensor_msgs/msg/LaserScan"](
        header=header(store, stamp, "r1/lidar"), angle_min=-1.5, angle_max=1.5, angle_increment=1.0,
        time_increment=0.0, scan_time=0.1, range_min=0.1, range_max=8.0,
        ranges=np.array([1.0, 2.0, 3.0, np.inf], dtype=np.float32),
        intensities=np.array([9.0, 8.0, 7.0, 6.0], dtype=np.float32))
    assert scan == bytes(store.serialize_cdr(msg, rm.LASER_SCAN))


@pytest.mark.parametrize("gid_size", [16, 24])
def test_discovery_info_bytes_equal_rosbags(gid_size):
    import numpy as np

    store = discovery_store(gid_size)
    t = store.types
    participant, readers, writers = bytes(range(16)), [bytes([7] * 16)], [bytes([1] * 16), bytes([2] * 16)]
    ours = graph.participant_entities_info(participant, "/sim", "mobot", readers, writers, gid_size)

    def gid(guid: bytes):  # the GUID, zero-padded to Humble's 24 bytes
        return t["rmw_dds_common/msg/Gid"](data=np.frombuffer(guid + bytes(gid_size - 16), dtype=np.uint8))

    msg = t["rmw_dds_common/msg/ParticipantEntitiesInfo"](
        gid=gid(participant), node_entities_info_seq=[t["rmw_dds_common/msg/NodeEntitiesInfo"](
            node_namespace="/sim", node_name="mobot", reader_gid_seq=[gid(g) for g in readers],
            writer_gid_seq=[gid(g) for g in writers])])
    assert ours == bytes(store.serialize_cdr(msg, graph.MSGTYPE))
    if gid_size == 16:
        theirs = idl.ParticipantEntitiesInfo(idl.Gid(list(participant)), [idl.NodeEntitiesInfo(
            "/sim", "mobot", [idl.Gid(list(g)) for g in readers], [idl.Gid(list(g)) for g in writers])]).serialize()
        assert ours == theirs
        assert store.hash_rihs01(graph.MSGTYPE) == graph.RIHS01  # the hash rmw_dds_common 3.1.0 ships


def test_type_hashes_are_rosbags_rihs01(store):
    for msgtype in idl.TYPES:
        # rmw_dds_common and gazebo_msgs are checked with their own definitions (above, test_sensor_wire.py)
        if msgtype not in (graph.MSGTYPE, "gazebo_msgs/msg/ContactsState"):
            assert type_hash(msgtype) == store.hash_rihs01(msgtype), msgtype
    assert set(idl.TYPES) == set(MESSAGES)  # a struct for every type in the table


def test_dds_type_names_are_ros2s():
    assert names.topic("/mobot/odom") == "rt/mobot/odom"
    assert names.dds_type("nav_msgs/msg/Odometry") == "nav_msgs::msg::dds_::Odometry_"
    for msgtype, struct in idl.TYPES.items():
        assert struct.__idl__.idl_transformed_typename == names.dds_type(msgtype)
        assert names.ros_type(names.dds_type(msgtype)) == msgtype
    assert names.join("/", "clock") == "/clock" and names.join("/r1", "odom") == "/r1/odom"


def test_golden_messages():
    """The bytes of one fixed robot state; a change here changes what ROS nodes receive."""
    messages, state = robot()
    stamp = (3, 250_000_000)
    values: list[float] = []
    messages.tf_values(stamp, state, values)
    got = {
        "clock": rm.CLOCK_PACKER.pack(stamp).hex(),
        "odom": messages.odom(stamp, state).hex(),
        "joint_states": messages.joint_states(stamp, state).hex(),
        "tf": rm.tf_layout([messages.frames]).pack(values).hex(),
        "tf_static": rm.tf_static(stamp, messages.statics(state)).hex(),
        "ros_discovery_info": graph.participant_entities_info(bytes(range(16)), "/", "mobot", [bytes(16)],
                                                              [bytes([1] * 16)]).hex(),
    }
    assert got == json.loads(GOLDEN.read_text())


@pytest.mark.parametrize("name, namespace, message", [
    ("1mobot", "/", "'1mobot' is not a valid ROS 2 node name"),
    ("mo-bot", "/", "'mo-bot' is not a valid ROS 2 node name"),
    ("mobot", "sim", "'sim' is not a valid ROS 2 namespace"),
    ("mobot", "/sim/", "'/sim/' is not a valid ROS 2 namespace"),
    ("mobot", "/" + "n" * 230, "namespace '/nnnnnnnnnnnnnnnnnnnnnnn...' is too long for ROS 2"),
    ("mobot", "/2d", "'/2d' is not a valid ROS 2 namespace"),
])
def test_bad_node_names_are_usage_errors(name, namespace, message):
    with pytest.raises(UsageError, match=message):
        names.check_node(name, namespace)
    names.check_node("mobot", "/")
    names.check_node("sim_1", "/fleet/a")


@pytest.mark.parametrize("value, expected", [("", 0), ("7", 7), (" 42 ", 42), ("232", 232)])
def test_domain_from_the_environment(value, expected):
    assert names.domain_id(None, {"ROS_DOMAIN_ID": value}) == expected
    assert names.domain_id(3, {"ROS_DOMAIN_ID": value}) == 3


@pytest.mark.parametrize("value", ["abc", "-1", "233", "1.5"])
def test_bad_domain_in_the_environment(value):
    with pytest.raises(UsageError, match=f"ROS_DOMAIN_ID='{value.strip()}' is not a ROS 2 domain id"):
        names.domain_id(None, {"ROS_DOMAIN_ID": value})


def test_discovery_config_follows_ros_environment():
    plain = names.discovery_config({}, True)
    assert plain == ("<CycloneDDS><Domain><Compatibility><IgnoreTypeInformation>1.15</IgnoreTypeInformation>"
                     "</Compatibility></Domain></CycloneDDS>")
    assert "IgnoreTypeInformation" not in names.discovery_config({}, False)
    local = names.discovery_config({"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "ROS_STATIC_PEERS": "10.0.0.2"}, True)
    assert "<AllowMulticast>false</AllowMulticast>" in local
    assert '<Peer address="localhost"/><Peer address="10.0.0.2"/>' in local
    assert names.discovery_config({"ROS_LOCALHOST_ONLY": "1"}, True) == names.discovery_config(
        {"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}, True)
    assert names.discovery_config({"CYCLONEDDS_URI": "file:///etc/dds.xml"}, True).endswith(",file:///etc/dds.xml")
    with pytest.raises(UsageError, match="ROS_AUTOMATIC_DISCOVERY_RANGE='LAN'"):
        names.discovery_config({"ROS_AUTOMATIC_DISCOVERY_RANGE": "lan"}, True)
    assert names.gid_size({"ROS_DISTRO": "humble"}) == 24 and names.gid_size({"ROS_DISTRO": "jazzy"}) == 16
