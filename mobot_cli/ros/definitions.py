"""ROS 2 message definitions and type hashes of the topics mobot records (generated).

The same in Humble, Jazzy and Kilted. Generated once from rosbags' typestore and kept here so
that a run does not build a typestore (~0.1 s); tests/record/test_bag.py checks them against it.
"""

from __future__ import annotations

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
}
