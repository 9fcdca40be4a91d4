"""Car-like robots and the drives mobot cannot simulate, found the way Gazebo finds them.

An Ackermann car comes from a plugin (gazebo_ros ``libgazebo_ros_ackermann_drive.so``, gz-sim's
``AckermannSteering`` system) or from its geometry: joints turning about the root's vertical axis
(limited revolute joints, or joints a ros2_control block commands by position) that carry wheels,
ahead of the wheels fixed to the body. Its DriveSpec has kind "ackermann": the driven wheels in
``left_joints``/``right_joints``, the steering joints in ``steering_joints`` and
``max_steering_angle`` as the bicycle model's largest angle (docs/ackermann.md).

Tracked vehicles, tricycle drives, other drive plugins and steered robots whose wheels have no
measurable radius are refused: one notice names the drive, and the robot is a passive body.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

from mobot_cli.assets.description.frames import JointRow, LinkTree, movable_joint
from mobot_cli.assets.description.wheels import PARALLEL, Wheel, carried_by_body, wheel, wheel_radius
from mobot_cli.common.transforms import mat_vec
from mobot_cli.errors import DescriptionError, Location, Notice
from mobot_cli.plan import DriveSpec
from mobot_cli.sim.steering import curvature

# gazebo_ros_ackermann_drive's default max_steer (rad): used when nothing gives a limit.
DEFAULT_MAX_STEER = 0.6
# gz-sim AckermannSteering's default steering_limit (rad).
GZ_STEERING_LIMIT = 0.5
# Plugins named like drives that mobot cannot simulate: (what the label holds, the drive type).
UNSUPPORTED = (("track", "tracked vehicle"), ("tricycle", "tricycle drive"))
# Drive plugins handled elsewhere (drive.py and the holonomic drives): never "unknown".
KNOWN = ("diff_drive", "diff-drive", "diffdrive", "skid_steer", "skidsteer", "ackermann", "mecanum",
         "planar_move", "omni", "holonomic")
DRIVE_WORDS = ("drive", "steer", "locomotion")


@dataclass(frozen=True)
class Detected:
    """What detection found: a drive, or the name of one mobot refuses ("" when it drives it)."""

    spec: DriveSpec | None
    refused: str = ""


CANNOT_DRIVE = "mobot cannot drive this robot's"  # how a refusal's notice begins


def refusal(what: str, label: str, notices: list[Notice], file: Path | None) -> Detected:
    """Refuse a drive in one notice that names it."""
    named = f"{what} ({label})" if label else what
    notices.append(Notice(f"{CANNOT_DRIVE} {named}: it is a passive body and refuses "
                          "velocity commands", Location(file=file)))
    return Detected(None, named)


def from_plugins(robot: ET.Element, tree: LinkTree, notices: list[Notice],
                 file: Path | None) -> Detected | None:
    """An Ackermann plugin's drive, or the refusal of a tracked or tricycle plugin; None without."""
    for gazebo in robot.findall("gazebo"):
        for plugin in gazebo.findall("plugin"):
            label, words = _label(plugin), _words(plugin)
            if "ackermann" in words:
                return _from_ackermann_plugin(plugin, label, tree, notices, file)
            for key, what in UNSUPPORTED:
                if key in words:
                    return refusal(what, label, notices, file)
    return None


def unknown_drive(robot: ET.Element, notices: list[Notice], file: Path | None) -> Detected | None:
    """Refuse a plugin named like a drive that mobot does not know (after the ones it does)."""
    for gazebo in robot.findall("gazebo"):
        for plugin in gazebo.findall("plugin"):
            words = _words(plugin)
            if any(w in words for w in DRIVE_WORDS) and not any(k in words for k in KNOWN):
                return refusal("drive plugin of a kind mobot does not know", _label(plugin), notices, file)
    return None


def _label(plugin: ET.Element) -> str:
    """How a plugin is named in messages: a classic plugin's library (its name is the user's),
    a gz-sim system's class name."""
    name, filename = plugin.get("name", ""), plugin.get("filename", "")
    return filename if filename.startswith("lib") or not name else name


def _words(plugin: ET.Element) -> str:
    """What a plugin is matched on: its name and file name, lower case."""
    return f"{plugin.get('name', '')} {plugin.get('filename', '')}".lower()


def _text(plugin: ET.Element, tag: str) -> str | None:
    child = plugin.find(tag)
    if child is None:
        return None
    return (child.text or "").strip() or child.get("value", "").strip() or None


def _number(plugin: ET.Element, tag: str) -> float | None:
    try:
        text = _text(plugin, tag)
        return float(text) if text is not None else None
    except ValueError:
        return None


def _joint(tree: LinkTree, plugin_label: str, name: str, tag: str, file: Path | None) -> JointRow:
    """The movable joint a plugin names, or a located DescriptionError."""
    return movable_joint(tree, name, f"the {plugin_label} plugin names {tag}",
                         Location(file=file, key=f"gazebo.plugin.{tag}"), "Name a movable joint of the robot.")


def _from_ackermann_plugin(plugin: ET.Element, label: str, tree: LinkTree, notices: list[Notice],
                           file: Path | None) -> Detected:
    """gazebo_ros_ackermann_drive (rear wheels driven, odometry = the model's world pose) or
    gz-sim AckermannSteering (its left/right joints driven, odometry from them and the steering)."""
    classic = "gazebo_ros" in _words(plugin) or plugin.find("rear_left_joint") is not None
    if classic:
        tags = {"left": ["rear_left_joint"], "right": ["rear_right_joint"]}
        defaults = {t: t for t in ("rear_left_joint", "rear_right_joint", "left_steering_joint",
                                   "right_steering_joint")}
    else:
        tags = {"left": ["left_joint"], "right": ["right_joint"]}
        defaults = {}
    driven: dict[str, list[str]] = {}
    for side, (tag,) in tags.items():
        names = [(c.text or "").strip() for c in plugin.findall(tag) if (c.text or "").strip()]
        driven[side] = names or ([defaults[tag]] if tag in defaults else [])
        if not driven[side]:
            raise DescriptionError(f"the {label} plugin names no {tag}",
                                   location=Location(file=file, key=f"gazebo.plugin.{tag}"),
                                   hint="Name the driven wheel joints, as Gazebo needs them.")
    steering = []
    for tag in ("left_steering_joint", "right_steering_joint"):
        name = _text(plugin, tag) or defaults.get(tag)
        if name is None:
            raise DescriptionError(f"the {label} plugin names no {tag}",
                                   location=Location(file=file, key=f"gazebo.plugin.{tag}"),
                                   hint="Name the steering joints, as Gazebo needs them.")
        steering.append(_joint(tree, label, name, tag, file))
    wheels = {side: [_wheel(tree, _joint(tree, label, n, f"{side} wheel joint", file))
                     for n in names] for side, names in driven.items()}
    if classic:
        wheelbase = None  # measured between the axles, as the plugin does
        limit = _number(plugin, "max_steer")
        limit = DEFAULT_MAX_STEER if limit is None else limit
        radius = separation = None
    else:
        wheelbase = _number(plugin, "wheel_base")
        radius, separation = _number(plugin, "wheel_radius"), _number(plugin, "wheel_separation")
        steering_limit = _number(plugin, "steering_limit")
        # The system keeps the turning radius at or above wheel_base / sin(steering_limit): the
        # bicycle angle at that radius is atan(sin(steering_limit)).
        limit = math.atan(math.sin(GZ_STEERING_LIMIT if steering_limit is None else steering_limit))
    return _car(wheels["left"], wheels["right"], steering, tree, notices, file, source="plugin",
                label=label, odometry="ground_truth" if classic else "encoder", wheelbase=wheelbase,
                radius=radius, separation=separation, limit=limit)


def from_geometry(tree: LinkTree, robot: ET.Element, notices: list[Notice],
                  file: Path | None) -> Detected | None:
    """A car found from its joints: steering joints ahead of wheels fixed to the body. None when
    the robot has no steering joint carrying a wheel."""
    positioned = _position_commanded(robot)
    steering = [j for j in tree.joints if _steers(tree, j, positioned)]
    if not steering:
        return None
    names = ", ".join(j.name for j in steering)
    fixed = [_wheel(tree, j) for j in tree.joints if _spins_on_body(tree, j)]
    if not fixed:
        return refusal("all-wheel steering", f"steering joints {names}", notices, file)
    rear_x = sum(w.x for w in fixed) / len(fixed)
    if any(tree.frame(j.child).pos[0] <= rear_x for j in steering):
        return refusal("rear-wheel steering", f"steering joints {names}", notices, file)
    if len(steering) > 2:
        return refusal(f"steering on {len(steering)} wheels", f"steering joints {names}", notices, file)
    steering.sort(key=lambda j: -tree.frame(j.child).pos[1])  # left first
    left = [w for w in fixed if w.y > 0]
    right = [w for w in fixed if w.y <= 0]
    if not left or not right:
        return refusal("steered drive with driven wheels on one side", f"steering joints {names}",
                       notices, file)
    return _car(left, right, steering, tree, notices, file, source="urdf", label="",
                odometry="encoder", wheelbase=None, radius=None, separation=None,
                limit=None)


def _position_commanded(robot: ET.Element) -> set[str]:
    """Joints a <ros2_control> block commands by position (a steering controller's)."""
    return {joint.get("name", "") for joint in robot.findall("ros2_control/joint")
            if any(c.get("name") == "position" for c in joint.findall("command_interface"))}


def _vertical(tree: LinkTree, joint: JointRow) -> float:
    """The joint axis' z component in the root frame."""
    return mat_vec(tree.frame(joint.child).rot, joint.axis)[2]


def _steers(tree: LinkTree, joint: JointRow, positioned: set[str]) -> bool:
    """A steering joint: about the vertical, on the body, a wheel below it, held by limits or by
    a position controller (a free vertical joint over a wheel is a caster's swivel)."""
    if joint.type not in ("revolute", "continuous") or abs(_vertical(tree, joint)) < PARALLEL:
        return False
    limited = (joint.type == "revolute" and joint.lower is not None and joint.upper is not None
               and 0.0 < joint.upper - joint.lower < 2 * math.pi)
    if not (limited or joint.name in positioned) or not carried_by_body(tree, joint.parent):
        return False
    return _steered_wheel(tree, joint) is not None


def _below(tree: LinkTree, link: str) -> list[JointRow]:
    """The joints hanging from ``link`` and from the links fixed to it (a knuckle and its parts)."""
    found, todo = [], [link]
    while todo:
        current = todo.pop()
        for joint in tree.joints:
            if joint.parent == current and joint not in found:
                found.append(joint)
                if joint.type == "fixed":
                    todo.append(joint.child)
    return found


def _spins(tree: LinkTree, joint: JointRow) -> bool:
    """A joint that rolls a wheel: spins without limit about a horizontal axis."""
    spins = joint.type == "continuous" or (
        joint.type == "revolute" and joint.lower is not None and joint.upper is not None
        and joint.upper - joint.lower >= 2 * math.pi)
    return spins and abs(_vertical(tree, joint)) < 1.0 - PARALLEL


def _spins_on_body(tree: LinkTree, joint: JointRow) -> bool:
    axis = mat_vec(tree.frame(joint.child).rot, joint.axis)
    return _spins(tree, joint) and abs(axis[1]) >= PARALLEL and carried_by_body(tree, joint.parent)


def _steered_wheel(tree: LinkTree, joint: JointRow) -> JointRow | None:
    """The wheel a steering joint turns: a spinning joint right below it (only fixed joints
    between), whose link collides. An arm's base joint carries no such thing."""
    for below in _below(tree, joint.child):
        link = tree.links.get(below.child)
        if _spins(tree, below) and link is not None and link.find("collision") is not None:
            return below
    return None


def _wheel(tree: LinkTree, joint: JointRow) -> Wheel:
    """The wheel on a joint, its radius from a cylinder, a sphere or a mesh (its farthest vertex from
    the spin axis, as a diff drive's wheels are measured)."""
    found = wheel(tree, joint.name, strict=False)
    frame = tree.frame(joint.child)
    axis = mat_vec(frame.rot, joint.axis)
    radius = wheel_radius(tree, joint.child, frame.pos, axis, meshes=True)
    return Wheel(joint=joint.name, x=found.x, y=found.y, radius=radius, sign=found.sign)  # type: ignore[union-attr]


def _car(left: list[Wheel], right: list[Wheel], steering: list[JointRow], tree: LinkTree,
         notices: list[Notice], file: Path | None, *, source: str, label: str, odometry: str,
         wheelbase: float | None, radius: float | None, separation: float | None,
         limit: float | None) -> Detected:
    """The Ackermann DriveSpec of these wheels and steering joints, or a refusal."""
    steered = [_steered_wheel(tree, j) for j in steering]
    if radius is None:
        radii = [w.radius for w in left + right]
        if not all(radii):
            return refusal("Ackermann steering with wheels of no measurable radius", label or "no cylinder, "
                           "sphere or mesh collision to measure a radius on " + ", ".join(w.joint for w in left + right
                                                                                         if not w.radius),
                           notices, file)
        radius = sum(radii) / len(radii)  # type: ignore[arg-type]
    if any(s is not None and _wheel(tree, s).radius is None for s in steered) and source == "urdf":
        return refusal("Ackermann steering with wheels of no measurable radius", "steered wheels " + ", ".join(
            s.name for s in steered if s is not None), notices, file)
    rear_x = sum(w.x for w in left + right) / len(left + right)
    rear_y = sum(w.y for w in left + right) / len(left + right)
    points = [(tree.frame(j.child).pos[0] - rear_x, tree.frame(j.child).pos[1] - rear_y) for j in steering]
    measured = sum(x for x, _ in points) / len(points)
    if wheelbase is None:
        wheelbase = measured
    elif abs(wheelbase - measured) > 0.02 * measured:
        notices.append(Notice(f"the {label} plugin says wheel_base {wheelbase:.3f} m, but its steering "
                              f"joints are {measured:.3f} m ahead of the driven wheels: mobot uses the "
                              "plugin's value, as Gazebo does", Location(file=file)))
    if wheelbase <= 0.0:
        return refusal("rear-wheel steering", label or "steering joints behind the driven wheels",
                       notices, file)
    if separation is None:
        separation = sum(w.y for w in left) / len(left) - sum(w.y for w in right) / len(right)
    joint_limit = _limit_from_joints(tree, steering, points, wheelbase)
    if limit is None:
        limit = joint_limit
        if limit is None:
            limit = DEFAULT_MAX_STEER
            notices.append(Notice(f"steering joints {', '.join(j.name for j in steering)} have no "
                                  f"limit: mobot steers at most {DEFAULT_MAX_STEER} rad (gazebo_ros "
                                  "ackermann_drive's default max_steer); set drive: max_steering_angle",
                                  Location(file=file)))
    elif joint_limit is not None and joint_limit < limit - 1e-6:
        notices.append(Notice(f"the {label} plugin steers up to {limit:.3f} rad but the steering joints' "
                              f"limits allow {joint_limit:.3f} rad: mobot uses the joints' limit",
                              Location(file=file)))
        limit = joint_limit
    signs = [(w.joint, w.sign) for w in left + right]
    signs += [(j.name, 1.0 if _vertical(tree, j) > 0 else -1.0) for j in steering]
    return Detected(DriveSpec(
        left_joints=tuple(w.joint for w in sorted(left, key=lambda w: -w.x)),
        right_joints=tuple(w.joint for w in sorted(right, key=lambda w: -w.x)),
        wheel_radius=radius, wheel_separation=abs(separation), odometry=odometry,
        twist_feedback=False, source=source, joint_signs=tuple(signs), kind="ackermann",
        wheelbase=wheelbase, steering_joints=tuple(j.name for j in steering),
        max_steering_angle=limit))


def _limit_from_joints(tree: LinkTree, steering: list[JointRow], points: list[tuple[float, float]],
                       wheelbase: float) -> float | None:
    """The bicycle angle at which the first steering joint reaches its <limit> (either way)."""
    tightest = math.inf
    for joint, (x, y) in zip(steering, points):
        if joint.type != "revolute" or joint.lower is None or joint.upper is None:
            return None
        sign = 1.0 if _vertical(tree, joint) > 0 else -1.0
        # its largest wheel angle turning left, and turning right (a right turn mirrors y)
        left_most, right_most = (joint.upper, -joint.lower) if sign > 0 else (-joint.lower, joint.upper)
        for steer, side in ((left_most, 1.0), (right_most, -1.0)):
            if steer <= 0.0:
                return None  # it cannot steer that way at all
            tightest = min(tightest, abs(curvature(steer, x, side * y)))
    return math.atan(tightest * wheelbase) if math.isfinite(tightest) and tightest > 0 else None
