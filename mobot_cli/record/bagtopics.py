"""A run folder's bag, per robot namespace: joint_states, robot_description, scans and clouds.

Read with rosbags (a base dependency), whose typestore decodes the CDR the run wrote. The bag
folder reaches here only through RunFolder.bag_folder (regular files inside the run folder,
within the size limit); a message that does not decode ends the read with a BagError.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mobot_cli.errors import MobotError

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


class BagError(MobotError):
    """The bag does not read (truncated, damaged or not a rosbag2 folder)."""


def read_topics(bag: Path, namespaces: set[str]) -> dict[str, Found]:
    """Each namespace's joint states, description and readings (LaserScan, PointCloud2 messages)."""
    try:
        return _read(bag, namespaces)
    except MobotError:
        raise
    except Exception as exc:  # noqa: BLE001 - rosbags and the CDR decoder raise many kinds on damaged bytes
        raise BagError(str(exc)[:300] or type(exc).__name__) from None


def _read(bag: Path, namespaces: set[str]) -> dict[str, Found]:
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


def scan_points(ranges: Any, angle_min: float, angle_increment: float, range_min: float,
                range_max: float) -> np.ndarray:
    """A sensor_msgs/LaserScan's hits in its own frame."""
    r = np.asarray(ranges, float)
    a = angle_min + angle_increment * np.arange(len(r))
    keep = np.isfinite(r) & (r >= range_min) & (r <= range_max)
    r = np.where(keep, r, 0.0)
    return np.stack([r * np.cos(a), r * np.sin(a), np.zeros_like(r)], axis=1)[keep]


def cloud_points(msg: Any) -> np.ndarray:
    """A sensor_msgs/PointCloud2's x, y, z (float32 fields) in its own frame."""
    fields = {f.name: f.offset for f in msg.fields if f.datatype == 7}  # 7: FLOAT32
    if not {"x", "y", "z"} <= fields.keys() or msg.point_step == 0:
        return np.zeros((0, 3))
    count = msg.width * msg.height
    dtype = np.dtype({"names": ["x", "y", "z"], "formats": ["<f4"] * 3,
                      "offsets": [fields["x"], fields["y"], fields["z"]], "itemsize": msg.point_step})
    data = np.frombuffer(bytes(msg.data), dtype=dtype, count=count)
    points = np.stack([data["x"], data["y"], data["z"]], axis=1).astype(float)
    return points[np.isfinite(points).all(axis=1)]
