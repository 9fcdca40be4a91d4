"""A real ROS 2 node (rclpy) that checks what `mobot serve --ros2` offers; run by bench/ros2_real.py.

It runs in the throwaway venv that holds rclpy and its RMW (never mobot's own), so it imports
nothing of mobot. It prints one JSON document with what it saw.

    python ros2_probe.py ROBOT SECONDS
"""

import json
import math
import sys
import time

import rclpy
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu, JointState, LaserScan
from std_msgs.msg import String

try:
    from tf2_msgs.msg import TFMessage  # no community wheel of tf2_msgs exists for every distro
except ImportError:
    TFMessage = None


def stamp(msg) -> float:
    if isinstance(msg, Clock):
        s = msg.clock
    else:
        s = msg.header.stamp if hasattr(msg, "header") else msg.transforms[0].header.stamp
    return s.sec + s.nanosec * 1e-9


def spin_for(node: Node, seconds: float, until=lambda: False) -> None:
    end = time.monotonic() + seconds
    while time.monotonic() < end and not until():
        rclpy.spin_once(node, timeout_sec=0.02)


def rates(node: Node, robot: str, seconds: float) -> dict:
    """Messages per simulated second on each topic, from header stamps."""
    seen: dict[str, list[float]] = {}
    topics = {"/clock": Clock, f"/{robot}/odom": Odometry, f"/{robot}/joint_states": JointState}
    listed = dict(node.get_topic_names_and_types())
    for name, kind in (("scan", LaserScan), ("imu", Imu)):
        if f"/{robot}/{name}" in listed:
            topics[f"/{robot}/{name}"] = kind
    if TFMessage is not None:
        topics["/tf"] = TFMessage
    last: dict[str, object] = {}
    subs = []
    for topic, kind in topics.items():
        # /clock and the sensors as their usual readers take them (rclpy's clock, nav2, slam_toolbox:
        # best effort, which a reliable publisher also serves); the rest as rclpy's default
        best_effort = topic == "/clock" or kind in (LaserScan, Imu)
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT) if best_effort else 10
        seen[topic] = []
        subs.append(node.create_subscription(kind, topic, lambda m, t=topic: (seen[t].append(stamp(m)),
                                                                             last.__setitem__(t, m)), qos))
    started = time.monotonic()
    spin_for(node, seconds)
    wall = time.monotonic() - started
    out = {}
    for topic, stamps in seen.items():
        span = stamps[-1] - stamps[0] if len(stamps) > 1 else 0.0
        out[topic] = {"count": len(stamps), "hz": (len(stamps) - 1) / span if span > 0 else 0.0,
                      "wall_hz": len(stamps) / wall}  # received per wall second (the world runs in real time)
    for topic, msg in last.items():  # what rclpy decoded of the sensors' messages
        if isinstance(msg, LaserScan):
            out[topic]["decoded"] = {"frame_id": msg.header.frame_id, "ranges": len(msg.ranges),
                                     "finite": sum(map(math.isfinite, msg.ranges)), "range_max": msg.range_max}
        elif isinstance(msg, Imu):
            out[topic]["decoded"] = {"frame_id": msg.header.frame_id, "az": msg.linear_acceleration.z}
    for sub in subs:
        node.destroy_subscription(sub)
    return out


def graph(node: Node, robot: str) -> dict:
    """What the ROS graph says of node /mobot: its topics, types and type hashes."""
    def nodes_now():
        return [f"{ns.rstrip('/')}/{name}" for name, ns in node.get_node_names_and_namespaces()]

    started = time.monotonic()
    def found():
        infos = node.get_publishers_info_by_topic(f"/{robot}/odom")
        return "/mobot" in nodes_now() and any(i.node_name == "mobot" for i in infos)

    spin_for(node, 10.0, until=found)
    spin_for(node, 0.5)
    nodes = nodes_now()
    pubs = node.get_publisher_names_and_types_by_node("mobot", "/") if "/mobot" in nodes else []
    subs = node.get_subscriber_names_and_types_by_node("mobot", "/") if "/mobot" in nodes else []
    hashes = {}
    for topic in (f"/{robot}/odom", f"/{robot}/scan", f"/{robot}/imu"):
        hashes[topic] = [{"node": i.node_name, "namespace": i.node_namespace, "type": i.topic_type,
                          "hash": str(getattr(i, "topic_type_hash", ""))}
                         for i in node.get_publishers_info_by_topic(topic)]
    return {"seconds_to_discover": time.monotonic() - started, "nodes": nodes,
            "publishers": {t: types for t, types in pubs}, "subscribers": {t: types for t, types in subs},
            "odom_publishers": hashes[f"/{robot}/odom"], "endpoints": hashes}


def late_description(robot: str) -> dict:
    """A node that joins now still gets the transient-local robot_description."""
    node = rclpy.create_node("late_joiner")
    got = []
    qos = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE)
    node.create_subscription(String, f"/{robot}/robot_description", lambda m: got.append(m.data), qos)
    spin_for(node, 8.0, until=lambda: bool(got))
    node.destroy_node()
    return {"received": len(got), "is_urdf": bool(got) and "<robot" in got[0], "bytes": len(got[0]) if got else 0}


def drive(node: Node, robot: str, metres: float, speed: float) -> dict:
    """Drive forward with /cmd_vel until the robot's own /odom says ``metres``, then stop."""
    odom = []
    node.create_subscription(Odometry, f"/{robot}/odom", lambda m: odom.append(m.pose.pose.position), 10)
    pub = node.create_publisher(Twist, f"/{robot}/cmd_vel", 10)
    spin_for(node, 5.0, until=lambda: bool(odom) and pub.get_subscription_count() > 0)
    if not odom:
        return {"error": "no odometry"}
    start = odom[-1]
    go, stop = Twist(), Twist()
    moved = 0.0
    end = time.monotonic() + 4 * metres / speed + 20
    while moved < metres - 0.002 and time.monotonic() < end:
        go.linear.x = min(speed, max(0.02, 1.5 * (metres - moved)))  # slow down near the goal, as nav2 would
        pub.publish(go)
        spin_for(node, 0.05)
        moved = math.hypot(odom[-1].x - start.x, odom[-1].y - start.y)
    for _ in range(20):
        pub.publish(stop)
        spin_for(node, 0.05)
    spin_for(node, 1.0)
    return {"odom_moved": math.hypot(odom[-1].x - start.x, odom[-1].y - start.y),
            "subscribers": pub.get_subscription_count()}


def main() -> None:
    robot, seconds = sys.argv[1], float(sys.argv[2])
    rclpy.init()
    node = Node("probe", parameter_overrides=[Parameter("use_sim_time", value=True)])
    result = {"tf2_msgs": TFMessage is not None}
    result["graph"] = graph(node, robot)
    result["rates"] = rates(node, robot, seconds)
    result["late"] = late_description(robot)
    result["drive"] = drive(node, robot, 1.0, 0.25)
    result["sim_time"] = node.get_clock().now().nanoseconds * 1e-9
    node.destroy_node()
    rclpy.shutdown()
    print(json.dumps(result, default=str))


if __name__ == "__main__":
    main()
