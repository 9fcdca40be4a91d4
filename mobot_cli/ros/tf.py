"""A robot's TF frames as robot_state_publisher publishes them, in plain Python.

Every joint gives one parent -> child transform: fixed joints once on /tf_static, moving
joints (revolute, continuous, prismatic) on /tf from the joint positions. Floating and
planar joints are published as fixed at their origin, as robot_state_publisher does. Mimic
joints follow their leader (``multiplier * leader + offset``). Frame names carry the robot's
frame prefix (``mobot/base_link``), so two robots never share a frame.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

from mobot_cli.assets.description.frames import LinkTree, floats
from mobot_cli.common.transforms import Frame, Quat, Vec, quat_from_matrix, quat_mul

MOVING = ("revolute", "continuous", "prismatic")
# What gazebo_ros_diff_drive puts on the diagonal of both covariances unless the plugin's
# covariance_x / covariance_y / covariance_yaw say otherwise; z, roll and pitch are "unknown".
DEFAULT_COVARIANCE = {"covariance_x": 0.00001, "covariance_y": 0.00001, "covariance_yaw": 0.001}
UNKNOWN_VARIANCE = 1e12


@dataclass(frozen=True)
class Transform:
    """One parent -> child transform with prefixed frame names."""

    parent: str
    child: str
    xyz: Vec
    quat: Quat


@dataclass(frozen=True)
class MovingJoint:
    """A joint whose transform depends on its position."""

    name: str
    parent: str
    child: str
    prismatic: bool
    xyz: Vec  # origin translation
    quat: Quat  # origin rotation
    axis: Vec  # unit axis in the joint frame
    moved_axis: Vec  # origin rotation * axis: a prismatic joint's direction in the parent frame
    leader: str  # the joint whose position drives this one (itself unless mimic)
    multiplier: float = 1.0
    offset: float = 0.0

    def transform(self, positions: dict[str, float]) -> tuple[float, ...]:
        """(x, y, z, qx, qy, qz, qw) of the child in the parent frame at these positions."""
        q = positions.get(self.leader, 0.0) * self.multiplier + self.offset
        x, y, z = self.xyz
        if self.prismatic:
            mx, my, mz = self.moved_axis
            return (x + mx * q, y + my * q, z + mz * q, *self.quat)
        s, c = math.sin(q / 2.0), math.cos(q / 2.0)
        ax, ay, az = self.axis
        if self.quat == (0.0, 0.0, 0.0, 1.0):  # most wheel joints: no origin rotation
            return (x, y, z, ax * s, ay * s, az * s, c)
        return (x, y, z, *quat_mul(self.quat, (ax * s, ay * s, az * s, c)))


def mover_transforms(movers: dict) -> list[Transform]:
    """``world -> movers/<name>`` of each mover (name -> x, y, yaw; docs/movers.md), at its foot."""
    return [Transform("world", f"movers/{name}", (x, y, 0.0), (0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0)))
            for name, (x, y, yaw) in movers.items()]


class RobotFrames:
    """The TF tree of one robot's URDF under a frame prefix, and its odometry settings."""

    def __init__(self, urdf: str, prefix: str, root_link: str | None = None):
        robot = ET.fromstring(urdf)
        tree = LinkTree(robot)
        self.prefix = prefix
        self.root = root_link or tree.root or "base_link"
        self.links = list(tree.links)
        self.odom_frame = prefix + "odom"
        self.base_frame = prefix + self.root
        self.static: list[Transform] = []
        self.moving: list[MovingJoint] = []
        mimics = {j.get("name", ""): j.find("mimic") for j in robot.findall("joint")}
        for joint in tree.joints:
            quat = quat_from_matrix(joint.origin.rot)
            parent, child = prefix + joint.parent, prefix + joint.child
            if joint.type not in MOVING:
                self.static.append(Transform(parent, child, joint.origin.pos, quat))
                continue
            mimic = mimics.get(joint.name)
            leader, multiplier, offset = joint.name, 1.0, 0.0
            if mimic is not None and mimic.get("joint"):
                leader = mimic.get("joint", "")
                multiplier = floats(mimic.get("multiplier"), 1, (1.0,))[0]
                offset = floats(mimic.get("offset"), 1, (0.0,))[0]
            self.moving.append(MovingJoint(
                joint.name, parent, child, joint.type == "prismatic", joint.origin.pos, quat,
                joint.axis, Frame(joint.origin.rot).point(joint.axis), leader, multiplier, offset))
        self.covariance = odometry_covariance(robot)


def odometry_covariance(robot: ET.Element) -> tuple[float, ...]:
    """The 36 covariance values gazebo_ros_diff_drive sets, with the URDF plugin's overrides."""
    values = dict(DEFAULT_COVARIANCE)
    for gazebo in robot.findall("gazebo"):
        for plugin in gazebo.findall("plugin"):
            label = (plugin.get("filename", "") + " " + plugin.get("name", "")).lower()
            if "diff" not in label and "skid" not in label:
                continue
            for key in values:
                text = plugin.findtext(key)
                if text is not None:
                    values[key] = floats(text, 1, (values[key],))[0]
    diagonal = (values["covariance_x"], values["covariance_y"], UNKNOWN_VARIANCE,
                UNKNOWN_VARIANCE, UNKNOWN_VARIANCE, values["covariance_yaw"])
    return tuple(diagonal[i // 6] if i % 7 == 0 else 0.0 for i in range(36))
