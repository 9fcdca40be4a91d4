"""Where a robot's sensor readings are published: topic, message type and TF frame.

Topics sit in the robot's namespace: ``<ns>/<topic>``, the topic defaulting to ``scan`` for a
2D lidar (sensor_msgs/LaserScan), ``points`` for a 3D lidar (sensor_msgs/PointCloud2),
``range`` (sensor_msgs/Range), ``imu`` (sensor_msgs/Imu) and ``bumper``
(gazebo_msgs/ContactsState, as gazebo_ros_bumper).

Readings are stamped with the sensor's frame, prefixed as every frame of the robot. Its
frame is ``frame_id`` (or the link); when that frame is not a link of the URDF, it is added to
/tf_static below the link at the sensor's pose. A sensor with a pose inside its link and no
frame of its own gets the frame ``<link>_<sensor>`` (also on /tf_static), so that the
readings always agree with TF (Gazebo stamps them with the link's frame, which is off by the
sensor's pose).
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from functools import lru_cache

from mobot_cli.plan import RobotPlan, SensorSpec
from mobot_cli.ros.definitions import CONTACTS_STATE, IMU, LASER_SCAN, POINT_CLOUD2, RANGE

_UNSAFE = re.compile(r"[^A-Za-z0-9_]")
IDENTITY = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))


def is_3d(spec: SensorSpec) -> bool:
    """A lidar with more than one vertical beam."""
    return spec.kind == "lidar" and spec.vertical is not None and spec.vertical.samples > 1


def message_type(spec: SensorSpec) -> str:
    """The ROS message type of a sensor's readings."""
    if spec.kind == "lidar":
        return POINT_CLOUD2 if is_3d(spec) else LASER_SCAN
    return {"range": RANGE, "imu": IMU}.get(spec.kind, CONTACTS_STATE)


def topic(robot: RobotPlan, spec: SensorSpec) -> str:
    """``<ns>/<topic>`` of a sensor."""
    default = "points" if is_3d(spec) else {"lidar": "scan", "range": "range", "imu": "imu"}.get(spec.kind, "bumper")
    return f"{robot.namespace.rstrip('/')}/{spec.topic.strip('/') or default}"


@dataclass(frozen=True)
class SensorFrame:
    """The frame readings are stamped with, and its static transform when it is a new frame."""

    frame: str  # prefixed
    parent: str | None = None  # prefixed link, None when the frame is a URDF link itself
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    quat: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)


def sensor_frame(robot: RobotPlan, spec: SensorSpec) -> SensorFrame:
    """Where a sensor's readings live in the robot's TF tree."""
    prefix, links = robot.frame_prefix, link_names(robot.urdf)
    name = spec.frame_id or spec.link
    at_link = (spec.xyz, spec.quat) == IDENTITY
    if name in links and (name != spec.link or at_link):
        return SensorFrame(prefix + name)
    if name in links:  # a pose inside the link: a frame of its own
        name = f"{spec.link}_{_UNSAFE.sub('_', spec.name)}"
    return SensorFrame(prefix + name, prefix + spec.link, spec.xyz, spec.quat)


@lru_cache(maxsize=64)
def link_names(urdf: str) -> frozenset[str]:
    """The links of a URDF text."""
    try:
        return frozenset(link.get("name", "") for link in ET.fromstring(urdf).findall("link"))
    except ET.ParseError:
        return frozenset()


def rate_hz(spec: SensorSpec, physics_rate_hz: int) -> float:
    """Readings per simulated second."""
    return physics_rate_hz / max(1, spec.every)
