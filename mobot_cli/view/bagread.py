"""The bag topics the view draws, per robot namespace: joint_states, robot_description, scans, clouds.

Read with rosbags (a base dependency), whose typestore decodes the CDR the run wrote.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mobot_cli.view.readings import cloud_points, scan_points

JOINT_STATE, STRING = "sensor_msgs/msg/JointState", "std_msgs/msg/String"
LASER_SCAN, POINT_CLOUD = "sensor_msgs/msg/LaserScan", "sensor_msgs/msg/PointCloud2"


@dataclass
class Joints:
    """One robot's joint positions over time, from its joint_states topic."""

    t: np.ndarray  # (k,) seconds
    names: list[str]
    positions: np.ndarray  # (k, len(names))

    def at(self, t: float) -> dict[str, float]:
        """The last positions at or before ``t``."""
        i = max(0, int(np.searchsorted(self.t, t, side="right")) - 1)
        return dict(zip(self.names, self.positions[i].tolist())) if len(self.t) else {}


@dataclass
class Found:
    """What one namespace's topics hold."""

    joints: Joints | None = None
    description: str | None = None
    readings: list[tuple[float, str, str, np.ndarray]] = field(default_factory=list)  # t, sensor, frame, points


def read_topics(bag: Path, namespaces: set[str]) -> dict[str, Found]:
    """Each namespace's joint states, description and readings (LaserScan, PointCloud2)."""
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore


    store = get_typestore(Stores.ROS2_HUMBLE)
    found: dict[str, Found] = {}
    joint_rows: dict[str, tuple[list[float], list[str], list[list[float]]]] = {}
    with Reader(bag) as reader:
        wanted = [c for c in reader.connections if _namespace(c.topic, namespaces) is not None
                  and c.msgtype in (JOINT_STATE, STRING, LASER_SCAN, POINT_CLOUD)]
        for conn, stamp, raw in reader.messages(connections=wanted):
            ns = _namespace(conn.topic, namespaces)
            entry = found.setdefault(ns, Found())
            msg = store.deserialize_cdr(raw, conn.msgtype)
            t = stamp / 1e9
            if conn.msgtype == JOINT_STATE:
                times, names, rows = joint_rows.setdefault(ns, ([], list(msg.name), []))
                if list(msg.name) == names:
                    times.append(t)
                    rows.append([float(v) for v in msg.position])
            elif conn.msgtype == STRING and conn.topic.endswith("/robot_description"):
                entry.description = entry.description or msg.data.replace('filename="file://', 'filename="')
            else:
                points = (scan_points(msg.ranges, msg.angle_min, msg.angle_increment, msg.range_min, msg.range_max)
                          if conn.msgtype == LASER_SCAN else cloud_points(msg))
                sensor = conn.topic[len(ns):].strip("/") or "scan"
                entry.readings.append((t, sensor, msg.header.frame_id, points.astype(np.float32)))
    for ns, (times, names, rows) in joint_rows.items():
        found[ns].joints = Joints(np.array(times), names, np.array(rows).reshape(len(times), len(names)))
    return found


def _namespace(topic: str, namespaces: set[str]) -> str | None:
    """The robot namespace a topic belongs to (the longest that prefixes it)."""
    best = None
    for ns in namespaces:
        if ns and topic.startswith(ns.rstrip("/") + "/") and (best is None or len(ns) > len(best)):
            best = ns
    return best
