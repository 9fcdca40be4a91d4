"""Where a robot's sensor readings are published: topic, message type and TF frame.

Topics sit in the robot's namespace: ``<ns>/<topic>``, the topic defaulting to ``scan`` for a
2D lidar (sensor_msgs/LaserScan), ``points`` for a 3D lidar (sensor_msgs/PointCloud2),
``range`` (sensor_msgs/Range), ``imu`` (sensor_msgs/Imu) and ``bumper``
(gazebo_msgs/ContactsState, as gazebo_ros_bumper). A camera publishes under its topic (default:
its name) as gazebo_ros_camera does: ``image_raw`` (sensor_msgs/Image), ``depth/image_raw``
(32FC1) and ``camera_info``.

Readings are stamped with the sensor's frame, prefixed as every frame of the robot. Its
frame is ``frame_id`` (or the link); when that frame is not a link of the URDF, it is added to
/tf_static below the link at the sensor's pose. A sensor with a pose inside its link and no
frame of its own gets the frame ``<link>_<sensor>`` (also on /tf_static), so that the
readings always agree with TF (Gazebo stamps them with the link's frame, which is off by the
sensor's pose).

Camera images are in an optical frame (REP 103: z forward, x right, y down): a camera's
``frame_id`` that is a URDF link is used as it is (as Gazebo does: the description's optical
link); otherwise the frame (named ``frame_id``, or ``<link>_<sensor>_optical``) is added to
/tf_static at the sensor's pose turned by OPTICAL.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from functools import lru_cache

from mobot_cli.common.transforms import quat_mul
from mobot_cli.plan import CAMERA_KINDS, RobotPlan, SensorSpec
from mobot_cli.ros.definitions import CONTACTS_STATE, IMAGE, IMU, LASER_SCAN, POINT_CLOUD2, RANGE

_UNSAFE = re.compile(r"[^A-Za-z0-9_]")
IDENTITY = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
OPTICAL = (-0.5, 0.5, -0.5, 0.5)  # rpy (-pi/2, 0, -pi/2): the sensor frame (x forward, z up) to the optical frame


def is_3d(spec: SensorSpec) -> bool:
    """A lidar with more than one vertical beam."""
    return spec.kind == "lidar" and spec.vertical is not None and spec.vertical.samples > 1


def message_type(spec: SensorSpec) -> str:
    """The ROS message type of a sensor's readings."""
    if spec.kind == "lidar":
        return POINT_CLOUD2 if is_3d(spec) else LASER_SCAN
    if spec.kind in CAMERA_KINDS:
        return IMAGE
    return {"range": RANGE, "imu": IMU}.get(spec.kind, CONTACTS_STATE)


def topic(robot: RobotPlan, spec: SensorSpec) -> str:
    """``<ns>/<topic>`` of a sensor."""
    default = "points" if is_3d(spec) else {"lidar": "scan", "range": "range", "imu": "imu", "camera": "camera",
                                             "depth": "camera", "rgbd": "camera"}.get(spec.kind, "bumper")
    return f"{robot.namespace.rstrip('/')}/{spec.topic.strip('/') or default}"


def camera_topics(robot: RobotPlan, spec: SensorSpec) -> dict[str, str]:
    """A camera's topics: image (none for a depth-only camera), depth (none for an RGB one), camera_info."""
    base = topic(robot, spec)
    out = {"image": f"{base}/image_raw", "depth": f"{base}/depth/image_raw", "camera_info": f"{base}/camera_info"}
    if spec.kind == "camera":
        del out["depth"]
    elif spec.kind == "depth":
        del out["image"]
    return out


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
    if spec.kind in CAMERA_KINDS:
        if name in links and name != spec.link:
            return SensorFrame(prefix + name)
        own = spec.frame_id if spec.frame_id and spec.frame_id != spec.link else \
            f"{spec.link}_{_UNSAFE.sub('_', spec.name)}_optical"
        return SensorFrame(prefix + own, prefix + spec.link, spec.xyz, quat_mul(spec.quat, OPTICAL))
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

