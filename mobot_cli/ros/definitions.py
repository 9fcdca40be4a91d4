"""Every ROS 2 message type mobot records, publishes or takes: one table, and how to read it.

``MESSAGES`` maps a type to its message definition as rosbag2 embeds it (the .msg text of
the type, then each type it uses after a line of '=') and its RIHS01 type description hash.
The bag embeds both (record/bag.py), the ROS 2 node announces the hash (ros2/publisher.py),
and ros2/idl.py builds the cyclonedds structs that describe the topics on DDS from the texts
(``structs``). Generated once from rosbags' typestore, the same in Humble, Jazzy and Kilted,
so that a run does not build a typestore (slow, and the same every time): tests/ros/test_definitions.py checks every
text and hash against rosbags and the .msg files of gazebo_msgs and rmw_dds_common.
gazebo_msgs/ContactsState is what gazebo_ros_bumper publishes. rmw_dds_common's Gid is Jazzy's
``char[16]``, Humble's is ``char[24]`` (ros2/idl.py); its hash is the one rmw_dds_common ships,
which reads ``char`` as ``uint8`` as ROS 2's IDL does (rosbags hashes it as a char).
sensor_msgs/Range is Jazzy's (and Kilted's): Humble's lacks the last field, ``variance``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

LASER_SCAN, POINT_CLOUD2 = "sensor_msgs/msg/LaserScan", "sensor_msgs/msg/PointCloud2"
IMU, CONTACTS_STATE = "sensor_msgs/msg/Imu", "gazebo_msgs/msg/ContactsState"
RANGE = "sensor_msgs/msg/Range"
IMAGE, CAMERA_INFO = "sensor_msgs/msg/Image", "sensor_msgs/msg/CameraInfo"  # cameras (docs/cameras.md)
COMPRESSED_IMAGE = "sensor_msgs/msg/CompressedImage"  # the bag's images with log.images png or jpeg
OCCUPANCY_GRID = "nav_msgs/msg/OccupancyGrid"  # /map (ros2/map_topic.py)
PARTICIPANT_ENTITIES_INFO = "rmw_dds_common/msg/ParticipantEntitiesInfo"
SEPARATOR = "=" * 80 + "\n"

# msgtype -> (message definition as rosbag2 embeds it, RIHS01 type description hash)
MESSAGES: dict[str, tuple[str, str]] = {
    "rosgraph_msgs/msg/Clock": (
        "builtin_interfaces/Time clock\n"
        "================================================================================\n"
        "MSG: builtin_interfaces/Time\n"
        "int32 sec\n"
        "uint32 nanosec\n",
        "RIHS01_692f7a66e93a3c83e71765d033b60349ba68023a8c689a79e48078bcb5c58564"),
    "tf2_msgs/msg/TFMessage": (
        "geometry_msgs/TransformStamped[] transforms\n"
        "================================================================================\n"
        "MSG: geometry_msgs/TransformStamped\n"
        "std_msgs/Header header\n"
        "string child_frame_id\n"
        "geometry_msgs/Transform transform\n"
        "================================================================================\n"
        "MSG: std_msgs/Header\n"
        "builtin_interfaces/Time stamp\n"
        "string frame_id\n"
        "================================================================================\n"
        "MSG: builtin_interfaces/Time\n"
        "int32 sec\n"
        "uint32 nanosec\n"
        "================================================================================\n"
        "MSG: geometry_msgs/Transform\n"
        "geometry_msgs/Vector3 translation\n"
        "geometry_msgs/Quaternion rotation\n"
        "================================================================================\n"
        "MSG: geometry_msgs/Vector3\n"
        "float64 x\n"
        "float64 y\n"
        "float64 z\n"
        "================================================================================\n"
        "MSG: geometry_msgs/Quaternion\n"
        "float64 x\n"
        "float64 y\n"
        "float64 z\n"
        "float64 w\n",
        "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087"),
    "nav_msgs/msg/Odometry": (
        "std_msgs/Header header\n"
        "string child_frame_id\n"
        "geometry_msgs/PoseWithCovariance pose\n"
        "geometry_msgs/TwistWithCovariance twist\n"
        "================================================================================\n"
        "MSG: std_msgs/Header\n"
        "builtin_interfaces/Time stamp\n"
        "string frame_id\n"
        "================================================================================\n"
        "MSG: builtin_interfaces/Time\n"
        "int32 sec\n"
        "uint32 nanosec\n"
        "================================================================================\n"
        "MSG: geometry_msgs/PoseWithCovariance\n"
        "geometry_msgs/Pose pose\n"
        "float64[36] covariance\n"
        "================================================================================\n"
        "MSG: geometry_msgs/Pose\n"
        "geometry_msgs/Point position\n"
        "geometry_msgs/Quaternion orientation\n"
        "================================================================================\n"
        "MSG: geometry_msgs/Point\n"
        "float64 x\n"
        "float64 y\n"
        "float64 z\n"
        "================================================================================\n"
        "MSG: geometry_msgs/Quaternion\n"
        "float64 x\n"
        "float64 y\n"
        "float64 z\n"
        "float64 w\n"
        "================================================================================\n"
        "MSG: geometry_msgs/TwistWithCovariance\n"
        "geometry_msgs/Twist twist\n"
        "float64[36] covariance\n"
        "================================================================================\n"
        "MSG: geometry_msgs/Twist\n"
        "geometry_msgs/Vector3 linear\n"
        "geometry_msgs/Vector3 angular\n"
        "================================================================================\n"
        "MSG: geometry_msgs/Vector3\n"
        "float64 x\n"
        "float64 y\n"
        "float64 z\n",
        "RIHS01_3cc97dc7fb7502f8714462c526d369e35b603cfc34d946e3f2eda2766dfec6e0"),
    "geometry_msgs/msg/Twist": (
        "geometry_msgs/Vector3 linear\n"
        "geometry_msgs/Vector3 angular\n"
        "================================================================================\n"
        "MSG: geometry_msgs/Vector3\n"
        "float64 x\n"
        "float64 y\n"
        "float64 z\n",
        "RIHS01_9c45bf16fe0983d80e3cfe750d6835843d265a9a6c46bd2e609fcddde6fb8d2a"),
    "geometry_msgs/msg/TwistStamped": (  # cmd_vel as nav2 sends it from Kilted on
        "std_msgs/Header header\n"
        "geometry_msgs/Twist twist\n"
        "================================================================================\n"
        "MSG: std_msgs/Header\n"
        "builtin_interfaces/Time stamp\n"
        "string frame_id\n"
        "================================================================================\n"
        "MSG: builtin_interfaces/Time\n"
        "int32 sec\n"
        "uint32 nanosec\n"
        "================================================================================\n"
        "MSG: geometry_msgs/Twist\n"
        "geometry_msgs/Vector3 linear\n"
        "geometry_msgs/Vector3 angular\n"
        "================================================================================\n"
        "MSG: geometry_msgs/Vector3\n"
        "float64 x\n"
        "float64 y\n"
        "float64 z\n",
        "RIHS01_5f0fcd4f81d5d06ad9b4c4c63e3ea51b82d6ae4d0558f1d475229b1121db6f64"),
    "sensor_msgs/msg/JointState": (
        "std_msgs/Header header\n"
        "string[] name\n"
        "float64[] position\n"
        "float64[] velocity\n"
        "float64[] effort\n"
        "================================================================================\n"
        "MSG: std_msgs/Header\n"
        "builtin_interfaces/Time stamp\n"
        "string frame_id\n"
        "================================================================================\n"
        "MSG: builtin_interfaces/Time\n"
        "int32 sec\n"
        "uint32 nanosec\n",
        "RIHS01_a13ee3a330e346c9d87b5aa18d24e11690752bd33a0350f11c5882bc9179260e"),
    "std_msgs/msg/String": (
        "string data\n",
        "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"),
    "sensor_msgs/msg/LaserScan": (
        "std_msgs/Header header\n"
        "float32 angle_min\n"
        "float32 angle_max\n"
        "float32 angle_increment\n"
        "float32 time_increment\n"
        "float32 scan_time\n"
        "float32 range_min\n"
        "float32 range_max\n"
        "float32[] ranges\n"
        "float32[] intensities\n"
        "================================================================================\n"
        "MSG: std_msgs/Header\n"
        "builtin_interfaces/Time stamp\n"
        "string frame_id\n"
        "================================================================================\n"
        "MSG: builtin_interfaces/Time\n"
        "int32 sec\n"
        "uint32 nanosec\n",
        "RIHS01_64c191398013af96509d518dac71d5164f9382553fce5c1f8cca5be7924bd828"),
    "sensor_msgs/msg/PointCloud2": (
        "std_msgs/Header header\n"
        "uint32 height\n"
        "uint32 width\n"
        "sensor_msgs/PointField[] fields\n"
        "bool is_bigendian\n"
        "uint32 point_step\n"
        "uint32 row_step\n"
        "uint8[] data\n"
        "bool is_dense\n"
        "================================================================================\n"
        "MSG: std_msgs/Header\n"
        "builtin_interfaces/Time stamp\n"
        "string frame_id\n"
        "================================================================================\n"
        "MSG: builtin_interfaces/Time\n"
        "int32 sec\n"
        "uint32 nanosec\n"
        "================================================================================\n"
        "MSG: sensor_msgs/PointField\n"
        "uint8 INT8=1\n"
        "uint8 UINT8=2\n"
        "uint8 INT16=3\n"
        "uint8 UINT16=4\n"
        "uint8 INT32=5\n"
        "uint8 UINT32=6\n"
        "uint8 FLOAT32=7\n"
        "uint8 FLOAT64=8\n"
        "string name\n"
        "uint32 offset\n"
        "uint8 datatype\n"
        "uint32 count\n",
        "RIHS01_9198cabf7da3796ae6fe19c4cb3bdd3525492988c70522628af5daa124bae2b5"),
    "sensor_msgs/msg/Imu": (
        "std_msgs/Header header\n"
        "geometry_msgs/Quaternion orientation\n"
        "float64[9] orientation_covariance\n"
        "geometry_msgs/Vector3 angular_velocity\n"
        "float64[9] angular_velocity_covariance\n"
        "geometry_msgs/Vector3 linear_acceleration\n"
        "float64[9] linear_acceleration_covariance\n"
        "================================================================================\n"
        "MSG: std_msgs/Header\n"
        "builtin_interfaces/Time stamp\n"
        "string frame_id\n"
        "================================================================================\n"
        "MSG: builtin_interfaces/Time\n"
        "int32 sec\n"
        "uint32 nanosec\n"
        "================================================================================\n"
        "MSG: geometry_msgs/Quaternion\n"
        "float64 x\n"
        "float64 y\n"
        "float64 z\n"
        "float64 w\n"
        "================================================================================\n"
        "MSG: geometry_msgs/Vector3\n"
        "float64 x\n"
        "float64 y\n"
        "float64 z\n",
        "RIHS01_7d9a00ff131080897a5ec7e26e315954b8eae3353c3f995c55faf71574000b5b"),
    "sensor_msgs/msg/Range": (
        "uint8 ULTRASOUND=0\n"
        "uint8 INFRARED=1\n"
        "std_msgs/Header header\n"
        "uint8 radiation_type\n"
        "float32 field_of_view\n"
        "float32 min_range\n"
        "float32 max_range\n"
        "float32 range\n"
        "float32 variance\n"
        "================================================================================\n"
        "MSG: std_msgs/Header\n"
        "builtin_interfaces/Time stamp\n"
        "string frame_id\n"
        "================================================================================\n"
        "MSG: builtin_interfaces/Time\n"
        "int32 sec\n"
        "uint32 nanosec\n",
        "RIHS01_b42b62562e93cbfe9d42b82fe5994dfa3d63d7d5c90a317981703f7388adff3a"),
    "gazebo_msgs/msg/ContactsState": (
        "std_msgs/Header header\n"
        "gazebo_msgs/ContactState[] states\n"
        "================================================================================\n"
        "MSG: std_msgs/Header\n"
        "builtin_interfaces/Time stamp\n"
        "string frame_id\n"
        "================================================================================\n"
        "MSG: builtin_interfaces/Time\n"
        "int32 sec\n"
        "uint32 nanosec\n"
        "================================================================================\n"
        "MSG: gazebo_msgs/ContactState\n"
        "string info\n"
        "string collision1_name\n"
        "string collision2_name\n"
        "geometry_msgs/Wrench[] wrenches\n"
        "geometry_msgs/Wrench total_wrench\n"
        "geometry_msgs/Vector3[] contact_positions\n"
        "geometry_msgs/Vector3[] contact_normals\n"
        "float64[] depths\n"
        "================================================================================\n"
        "MSG: geometry_msgs/Wrench\n"
        "geometry_msgs/Vector3 force\n"
        "geometry_msgs/Vector3 torque\n"
        "================================================================================\n"
        "MSG: geometry_msgs/Vector3\n"
        "float64 x\n"
        "float64 y\n"
        "float64 z\n",
        "RIHS01_1dc585e627c16551e50102b983ec513212ef81bad3b9e9f2423f549df190a40c"),
    "nav_msgs/msg/OccupancyGrid": (
        "std_msgs/Header header\n"
        "nav_msgs/MapMetaData info\n"
        "int8[] data\n"
        "================================================================================\n"
        "MSG: std_msgs/Header\n"
        "builtin_interfaces/Time stamp\n"
        "string frame_id\n"
        "================================================================================\n"
        "MSG: builtin_interfaces/Time\n"
        "int32 sec\n"
        "uint32 nanosec\n"
        "================================================================================\n"
        "MSG: nav_msgs/MapMetaData\n"
        "builtin_interfaces/Time map_load_time\n"
        "float32 resolution\n"
        "uint32 width\n"
        "uint32 height\n"
        "geometry_msgs/Pose origin\n"
        "================================================================================\n"
        "MSG: geometry_msgs/Pose\n"
        "geometry_msgs/Point position\n"
        "geometry_msgs/Quaternion orientation\n"
        "================================================================================\n"
        "MSG: geometry_msgs/Point\n"
        "float64 x\n"
        "float64 y\n"
        "float64 z\n"
        "================================================================================\n"
        "MSG: geometry_msgs/Quaternion\n"
        "float64 x\n"
        "float64 y\n"
        "float64 z\n"
        "float64 w\n",
        "RIHS01_8d348150c12913a31ee0ec170fbf25089e4745d17035792a1ba94d6f0bc0cfc7"),
    "sensor_msgs/msg/CompressedImage": (
        'std_msgs/Header header\n'
        'string format\n'
        'uint8[] data\n'
        '================================================================================\n'
        'MSG: std_msgs/Header\n'
        'builtin_interfaces/Time stamp\n'
        'string frame_id\n'
        '================================================================================\n'
        'MSG: builtin_interfaces/Time\n'
        'int32 sec\n'
        'uint32 nanosec\n',
        "RIHS01_15640771531571185e2efc8a100baf923961a4d15d5569652e6cb6691e8e371a"),
    "sensor_msgs/msg/Image": (
        'std_msgs/Header header\n'
        'uint32 height\n'
        'uint32 width\n'
        'string encoding\n'
        'uint8 is_bigendian\n'
        'uint32 step\n'
        'uint8[] data\n'
        '================================================================================\n'
        'MSG: std_msgs/Header\n'
        'builtin_interfaces/Time stamp\n'
        'string frame_id\n'
        '================================================================================\n'
        'MSG: builtin_interfaces/Time\n'
        'int32 sec\n'
        'uint32 nanosec\n',
        "RIHS01_d31d41a9a4c4bc8eae9be757b0beed306564f7526c88ea6a4588fb9582527d47"),
    "sensor_msgs/msg/CameraInfo": (
        'std_msgs/Header header\n'
        'uint32 height\n'
        'uint32 width\n'
        'string distortion_model\n'
        'float64[] d\n'
        'float64[9] k\n'
        'float64[9] r\n'
        'float64[12] p\n'
        'uint32 binning_x\n'
        'uint32 binning_y\n'
        'sensor_msgs/RegionOfInterest roi\n'
        '================================================================================\n'
        'MSG: std_msgs/Header\n'
        'builtin_interfaces/Time stamp\n'
        'string frame_id\n'
        '================================================================================\n'
        'MSG: builtin_interfaces/Time\n'
        'int32 sec\n'
        'uint32 nanosec\n'
        '================================================================================\n'
        'MSG: sensor_msgs/RegionOfInterest\n'
        'uint32 x_offset\n'
        'uint32 y_offset\n'
        'uint32 height\n'
        'uint32 width\n'
        'bool do_rectify\n',
        "RIHS01_b3dfd68ff46c9d56c80fd3bd4ed22c7a4ddce8c8348f2f59c299e73118e7e275"),
    "rmw_dds_common/msg/ParticipantEntitiesInfo": (
        "rmw_dds_common/Gid gid\n"
        "rmw_dds_common/NodeEntitiesInfo[] node_entities_info_seq\n"
        "================================================================================\n"
        "MSG: rmw_dds_common/Gid\n"
        "char[16] data\n"
        "================================================================================\n"
        "MSG: rmw_dds_common/NodeEntitiesInfo\n"
        "string<=256 node_namespace\n"
        "string<=256 node_name\n"
        "rmw_dds_common/Gid[] reader_gid_seq\n"
        "rmw_dds_common/Gid[] writer_gid_seq\n",
        "RIHS01_91a0593bacdcc50ea9bdcf849a938b128412cc1ea821245c663bcd26f83c295e"),
}

_FIELD = re.compile(r"(?P<type>[A-Za-z_][\w/]*)(?:<=(?P<bound>\d+))?(?:\[(?P<length>\d*)\])?")


@dataclass(frozen=True)
class Field:
    """One field of a message: a primitive ('float64', 'string', ...) or a message 'pkg/Name'."""

    name: str
    type: str
    length: int | None = None  # T[N]: a fixed-length array
    sequence: bool = False  # T[]: an unbounded sequence
    bound: int | None = None  # string<=N


def structs(msgtype: str, definition: str | None = None) -> dict[str, tuple[Field, ...]]:
    """Each message type in ``msgtype``'s definition ('pkg/Name' -> its fields), the ones a
    type uses before it, ``msgtype`` last. Constants are left out: they are not on the wire."""
    parts = (MESSAGES[msgtype][0] if definition is None else definition).split(SEPARATOR)
    package, _, name = msgtype.split("/")
    texts = {f"{package}/{name}": parts[0]}
    for part in parts[1:]:
        head, _, body = part.partition("\n")
        texts[head.removeprefix("MSG: ")] = body
    ordered: dict[str, tuple[Field, ...]] = {}

    def visit(key: str) -> None:
        if key not in ordered:
            fields = tuple(_fields(key, texts[key]))
            for field in fields:
                if "/" in field.type:
                    visit(field.type)
            ordered[key] = fields

    visit(f"{package}/{name}")
    return ordered


def _fields(key: str, text: str):
    for line in text.splitlines():
        words = line.split()
        if not words or "=" in "".join(words[1:2]):  # a constant: 'uint8 FLOAT32=7'
            continue
        match = _FIELD.fullmatch(words[0])
        if len(words) != 2 or match is None:
            raise ValueError(f"{key}: cannot read the field {line!r}")
        length = match["length"]
        yield Field(words[1], match["type"], int(length) if length else None, length == "",
                    int(match["bound"]) if match["bound"] else None)
