"""Passive joints Gazebo holds: springs, and joints a position controller keeps where they start.

Gazebo leaves no joint free that its description holds: a ``<gazebo reference="JOINT">`` with
``springStiffness`` (and ``springReference``; SDF's ``<axis><dynamics><spring_stiffness>`` comes
here through world/to_urdf.py) is a spring; a joint in a ``<ros2_control>`` block with a
position or velocity command interface is held by its controller (at the state interface's
``initial_value``, else 0), with the joint's ``<limit effort>``, except continuous joints
with only a velocity interface (wheels: a tricycle's traction wheel); a joint a model plugin
names (other than the drive and joint-state publishers) is held at 0 the same way, except a
continuous joint (a wheel) named by a plugin that is not a position controller: it spins; a
``<mimic>`` joint whose leader is held is held where the mimic puts it. Every other revolute
or prismatic joint that is not a drive wheel stays free and is named in one notice. Continuous
joints (casters, free wheels) spin freely in Gazebo too and are not named.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path

from mobot_cli.assets.description.frames import floats
from mobot_cli.errors import Location, Notice
from mobot_cli.plan import DriveSpec, JointHold

MOVABLE = ("revolute", "continuous", "prismatic")
LIMITED = ("revolute", "prismatic")
# A held joint whose URDF gives no effort limit (0) is held as SDF's unlimited effort is (1e6).
UNLIMITED_EFFORT = 1e6
# Plugins that name joints without holding them: they publish joint states or drive the wheels.
# Compared with the plugin's filename and name stripped of "-", "_" and spaces, in lower case.
_NOT_HOLDING = ("jointstate", "diffdrive", "skidsteer", "planarmove", "mecanum", "ackermann",
                "ros2control", "p3d", "imu", "ray", "lidar", "laser", "camera", "sonar", "range")


def read_holds(robot: ET.Element, drive: DriveSpec | None, notices: list[Notice],
               source: Path | None = None) -> tuple[JointHold, ...]:
    """The springs and held joints of a URDF, and one notice naming the joints left free."""
    joints = {j.get("name", ""): j for j in robot.findall("joint") if j.get("type") in MOVABLE}
    wheels = set()
    if drive is not None:
        wheels = {*drive.left_joints, *drive.right_joints, *getattr(drive, "steering_joints", ())}
    holds: dict[str, JointHold] = {}
    spinning: dict[str, list[str]] = {}  # plugin -> the continuous joints it names, left to spin
    for name, hold in (*_springs(robot), *_controlled(robot, joints), *_plugin_held(robot, joints, spinning)):
        if name in joints and name not in wheels and name not in holds:
            holds[name] = hold
    for name, hold in _mimics(joints, holds):
        if name not in wheels:
            holds[name] = hold
    for label, names in spinning.items():
        names = [n for n in dict.fromkeys(names) if n not in wheels and n not in holds]
        if names:
            notices.append(Notice(
                f"mobot does not know the {label} plugin: the continuous joints it names spin freely "
                f"({', '.join(names)}), as wheels it does not drive", Location(file=source)))
    free = [name for name, joint in joints.items()
            if name not in wheels and name not in holds and joint.get("type") in LIMITED]
    if free:
        notices.append(Notice(f"{FREE}{', '.join(free)}", Location(file=source)))
    return tuple(holds.values())


FREE = "joints left free (no spring, position controller or plugin holds them): "  # the notice's start


# m above the robot's lowest point: a continuous joint higher than this turns no wheel or caster
# (an arm's roll joint), and ``hold: all`` holds it too
WHEEL_HEIGHT = 0.3


def asked_holds(urdf: str, drive: DriveSpec | None, held: tuple[JointHold, ...], asked,
                bottom: float = 0.0) -> tuple[tuple[JointHold, ...], list[str], list[str], list[str]]:
    """A scenario's ``hold:`` ("all", or {joint: position}) added to the joints held already:
    (every hold, the names that are no joint a hold can take, the joints still left free, the
    joints a hold can take).
    Each asked joint is held by a position controller with its <limit effort>, as a vendor's
    plugin holds an arm in Gazebo. "all": every revolute or prismatic joint left free, and every
    continuous joint more than WHEEL_HEIGHT above ``bottom`` (the robot's lowest point, root
    frame): Fetch's arm rolls, not its casters."""
    from mobot_cli.assets.description.frames import LinkTree

    robot = ET.fromstring(urdf)
    joints = {j.get("name", ""): j for j in robot.findall("joint") if j.get("type") in MOVABLE}
    wheels = set() if drive is None else {*drive.left_joints, *drive.right_joints,
                                          *getattr(drive, "steering_joints", ())}
    holds = {h.joint: h for h in held}
    free = [n for n, joint in joints.items() if n not in wheels and n not in holds and joint.get("type") in LIMITED]
    wanted = dict(asked) if asked != "all" else {n: 0.0 for n in free}
    if asked == "all":
        tree = LinkTree(robot)
        for name, joint in joints.items():
            child = joint.find("child")
            if joint.get("type") == "continuous" and name not in wheels and name not in holds and \
                    child is not None and tree.frame(child.get("link", "")).pos[2] > bottom + WHEEL_HEIGHT:
                wanted[name] = 0.0
    unknown = [n for n in wanted if n not in joints or n in wheels]
    for name, position in wanted.items():
        if name not in unknown:
            holds[name] = JointHold(joint=name, kind="position", target=float(position),
                                    effort=_effort(joints[name]), source="hold")
    return tuple(holds.values()), unknown, [n for n in free if n not in wanted], [n for n in joints if n not in wheels]


def _springs(robot: ET.Element):
    for gazebo in robot.findall("gazebo"):
        stiffness = _number(gazebo.findtext("springStiffness"))
        if stiffness > 0.0:
            name = gazebo.get("reference", "")
            yield name, JointHold(joint=name, kind="spring", stiffness=stiffness,
                                  target=_number(gazebo.findtext("springReference")),
                                  source="springStiffness")


def _controlled(robot: ET.Element, joints: dict[str, ET.Element]):
    """Joints of <ros2_control> blocks that a position or velocity command interface drives."""
    for block in robot.iter("ros2_control"):
        for joint in block.findall("joint"):
            name = joint.get("name", "")
            commands = {c.get("name", "") for c in joint.findall("command_interface")}
            if name not in joints or "position" not in commands and (
                    "velocity" not in commands or joints[name].get("type") == "continuous"):
                continue
            initial = 0.0
            for interface in joint.findall("state_interface"):
                if interface.get("name") == "position":
                    initial = _number(interface.findtext("param[@name='initial_value']"))
            yield name, JointHold(joint=name, kind="position", target=initial,
                                  effort=_effort(joints[name]), source="ros2_control")


def _plugin_held(robot: ET.Element, joints: dict[str, ET.Element], spinning: dict[str, list[str]]):
    """Joints named in the parameters of a model plugin that controls joints.

    A continuous joint is held only by a position controller: one named by another plugin mobot
    does not know (a vendor's drive, ROS 1's ``libgazebo_ros_ackerman.so``) is a wheel that
    plugin would turn, and locking it would drag the robot; it goes to ``spinning`` instead."""
    for plugin in robot.iter("plugin"):
        label = re.sub(r"[-_ ]", "", plugin.get("filename", "") + plugin.get("name", "")).lower()
        if any(word in label for word in _NOT_HOLDING):
            continue
        positions = "position" in label
        initial = _number(plugin.findtext("initial_position"))  # gz-sim JointPositionController
        for element in plugin.iter():
            name = (element.text or "").strip()
            if element is not plugin and name in joints:
                if joints[name].get("type") == "continuous" and not positions:
                    spinning.setdefault(plugin.get("filename", "") or plugin.get("name", ""), []).append(name)
                    continue
                yield name, JointHold(joint=name, kind="position", target=initial, effort=_effort(joints[name]),
                                      source=plugin.get("filename", "") or plugin.get("name", ""))


def _mimics(joints: dict[str, ET.Element], holds: dict[str, JointHold]):
    """Free joints that mimic a held one, held at multiplier * its target + offset."""
    for name, joint in joints.items():
        mimic = joint.find("mimic")
        leader = holds.get(mimic.get("joint", "")) if mimic is not None else None
        if name in holds or leader is None or leader.kind != "position":
            continue
        multiplier = floats(mimic.get("multiplier"), 1, (1.0,))[0]
        offset = floats(mimic.get("offset"), 1, (0.0,))[0]
        yield name, JointHold(joint=name, kind="position", target=multiplier * leader.target + offset,
                              effort=_effort(joint), source=f"mimic of {leader.joint}")


def _effort(joint: ET.Element) -> float:
    limit = joint.find("limit")
    effort = _number(limit.get("effort") if limit is not None else None)
    return effort if effort > 0.0 else UNLIMITED_EFFORT


def _number(text: str | None) -> float:
    return floats(text.strip() if text else None, 1, (0.0,))[0]
