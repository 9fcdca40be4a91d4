"""Find a robot's drive wheels the way Gazebo's diff-drive plugins see them.

A ``<gazebo><plugin>`` diff-drive or skid-steer block wins (source "plugin"); values it
leaves out, and robots without one, are detected from the URDF (source "urdf"): wheels are
continuous joints fixed to the root whose axes lie along the root's y axis and whose child
link has a cylinder (along that axis) or sphere collision.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

from mobot_cli.assets.description.frames import LinkTree, floats, origin_frame
from mobot_cli.common.transforms import mat_vec
from mobot_cli.errors import DescriptionError, Location, Notice, did_you_mean
from mobot_cli.sim.plan import DriveSpec

# |cos| above this counts as parallel: turtlebot3 rotates its wheels by -1.57, not -pi/2.
_PARALLEL = 0.99

_LEFT_TAGS = ("leftJoint", "left_joint", "leftFrontJoint", "leftRearJoint")
_RIGHT_TAGS = ("rightJoint", "right_joint", "rightFrontJoint", "rightRearJoint")


@dataclass(frozen=True)
class Wheel:
    """A wheel joint as seen from the root link at zero joint positions."""

    joint: str
    x: float
    y: float
    radius: float | None
    sign: float  # +1 when the joint axis points along +y of the root frame


def detect_drive(urdf: ET.Element | str, *, notices: list[Notice] | None = None,
                 source: Path | None = None) -> DriveSpec | None:
    """The robot's differential / skid-steer drive, or None when it has no drive wheels."""
    robot = ET.fromstring(urdf) if isinstance(urdf, str) else urdf
    notices = notices if notices is not None else []
    tree = LinkTree(robot)
    if tree.root is None:
        return None
    plugin = _drive_plugin(robot)
    if plugin is not None:
        spec = _from_plugin(plugin, tree, notices, source)
        if spec is not None:
            return spec
    wheels = [w for j in tree.joints if (w := _wheel(tree, j.name, strict=True)) is not None]
    return _spec(wheels, source="urdf", notices=notices, file=source)


def _wheel(tree: LinkTree, joint_name: str, strict: bool) -> Wheel | None:
    """The wheel on ``joint_name``; with ``strict``, None unless it looks like a drive wheel."""
    joint = next((j for j in tree.joints if j.name == joint_name), None)
    if joint is None:
        return None
    frame = tree.frame(joint.child)
    axis_root = mat_vec(frame.rot, joint.axis)
    axis = axis_root[1]  # how much the spin axis points along +y of the root
    if strict:
        spins = joint.type == "continuous" or (
            joint.type == "revolute" and joint.lower is not None and joint.upper is not None
            and joint.upper - joint.lower >= 2 * math.pi)
        if not spins or abs(axis) < _PARALLEL or not tree.fixed_to_root(joint.parent):
            return None
    radius = _wheel_radius(tree, joint.child, axis_root)
    if strict and radius is None:
        return None
    return Wheel(joint=joint.name, x=frame.pos[0], y=frame.pos[1], radius=radius,
                 sign=1.0 if axis >= 0 else -1.0)


def _wheel_radius(tree: LinkTree, link: str, axis_root) -> float | None:
    """Radius of the first sphere, or cylinder along the spin axis, in the link's collisions."""
    element = tree.links.get(link)
    if element is None:
        return None
    link_frame = tree.frame(link)
    for collision in element.findall("collision"):
        geometry = collision.find("geometry")
        if geometry is None:
            continue
        sphere, cylinder = geometry.find("sphere"), geometry.find("cylinder")
        if sphere is not None:
            return floats(sphere.get("radius"), 1, (0.0,))[0] or None
        if cylinder is not None:
            rot = link_frame.compose(origin_frame(collision)).rot
            along = mat_vec(rot, (0.0, 0.0, 1.0))  # a URDF cylinder's axis is its local z
            if abs(sum(a * b for a, b in zip(along, axis_root))) >= _PARALLEL:
                return floats(cylinder.get("radius"), 1, (0.0,))[0] or None
    return None


def _drive_plugin(robot: ET.Element) -> ET.Element | None:
    """The first diff-drive or skid-steer plugin in the robot's <gazebo> blocks."""
    for gazebo in robot.findall("gazebo"):
        for plugin in gazebo.findall("plugin"):
            label = (plugin.get("filename", "") + " " + plugin.get("name", "")).lower()
            if any(k in label for k in ("diff_drive", "diff-drive", "diffdrive", "skid_steer")):
                return plugin
    return None


def _texts(plugin: ET.Element, *tags: str) -> list[str]:
    """Values of the children named ``tags``, as <t>v</t> or <t value="v"/>, in tag order."""
    values = []
    for tag in tags:
        for child in plugin.findall(tag):
            value = (child.text or "").strip() or child.get("value", "").strip()
            if value:
                values.append(value)
    return values


def _number(plugin: ET.Element, *tags: str) -> float | None:
    for text in _texts(plugin, *tags):
        try:
            return float(text)
        except ValueError:
            continue
    return None


def _from_plugin(plugin: ET.Element, tree: LinkTree, notices: list[Notice],
                 file: Path | None) -> DriveSpec | None:
    label = plugin.get("filename") or plugin.get("name") or "diff-drive"
    left, right = _texts(plugin, *_LEFT_TAGS), _texts(plugin, *_RIGHT_TAGS)
    if not left or not right:
        notices.append(Notice(f"the {label} plugin names no left or right joints; "
                              "detecting the wheels from the URDF instead", Location(file=file)))
        return None
    joint_types = {j.name: j.type for j in tree.joints}
    wheels: list[tuple[str, Wheel]] = []
    for side, names in (("left", left), ("right", right)):
        for name in dict.fromkeys(names):
            if joint_types.get(name) in (None, "fixed"):
                problem = "is fixed" if name in joint_types else "is not in the URDF"
                raise DescriptionError(
                    f"the {label} plugin names {side} wheel joint '{name}', which {problem}",
                    location=Location(file=file, key=f"gazebo.plugin.{side}_joint"),
                    hint=did_you_mean(name, [n for n, t in joint_types.items() if t != "fixed"])
                    or "Name a continuous wheel joint.")
            wheels.append((side, _wheel(tree, name, strict=False)))  # type: ignore[arg-type]
    for side, wheel in wheels:
        if (side == "left") != (wheel.y > 0):
            notices.append(Notice(f"the {label} plugin drives '{wheel.joint}' as a {side} wheel "
                                  f"but it sits at y = {wheel.y:+.3f} m in the root frame",
                                  Location(file=file)))
    radius = _number(plugin, "wheel_radius")
    diameter = _number(plugin, "wheelDiameter", "wheel_diameter")
    if radius is None and diameter is not None:
        radius = diameter / 2.0
    torque = _number(plugin, "wheelTorque", "max_wheel_torque", "torque")
    accel = _number(plugin, "wheelAcceleration", "max_wheel_acceleration")
    return _spec([w for _, w in wheels], source="plugin", notices=notices, file=file,
                 sides={w.joint: s for s, w in wheels}, radius=radius,
                 separation=_number(plugin, "wheelSeparation", "wheel_separation"),
                 torque=torque, rim_accel=accel)


def _spec(wheels: list[Wheel], *, source: str, notices: list[Notice], file: Path | None,
          sides: dict[str, str] | None = None, radius: float | None = None,
          separation: float | None = None, torque: float | None = None,
          rim_accel: float | None = None) -> DriveSpec | None:
    """Merge wheels and explicit values into a DriveSpec (None without wheels on both sides)."""
    def side_of(w: Wheel) -> str:
        return sides[w.joint] if sides else ("left" if w.y > 0 else "right")

    left = sorted((w for w in wheels if side_of(w) == "left"), key=lambda w: -w.x)
    right = sorted((w for w in wheels if side_of(w) == "right"), key=lambda w: -w.x)
    if not left or not right:
        return None
    if radius is None:
        radii = [w.radius for w in wheels if w.radius]
        if not radii:
            notices.append(Notice("drive wheels found but no wheel radius: none of "
                                  f"{', '.join(w.joint for w in wheels)} has a cylinder or "
                                  "sphere collision", Location(file=file)))
            return None
        radius = sum(radii) / len(radii)
        if max(radii) - min(radii) > 0.01 * radius:
            notices.append(Notice(f"drive wheels have different radii {sorted(set(radii))}; "
                                  f"using their mean {radius:.4f} m", Location(file=file)))
    if separation is None:
        separation = (sum(w.y for w in left) / len(left)) - (sum(w.y for w in right) / len(right))
    multiplier = 1.0
    if len(left) > 1 or len(right) > 1:
        wheelbase = max(w.x for w in wheels) - min(w.x for w in wheels)
        multiplier = _separation_multiplier(abs(separation), wheelbase)
    extra = {}
    if torque is not None and torque > 0:
        extra["max_wheel_torque"] = torque
    if rim_accel is not None and rim_accel > 0:
        # gazebo_ros limits the change of rim speed (m/s^2); DriveSpec wants rad/s^2.
        extra["max_wheel_acceleration"] = rim_accel / radius
    return DriveSpec(
        left_joints=tuple(w.joint for w in left), right_joints=tuple(w.joint for w in right),
        wheel_radius=radius, wheel_separation=abs(separation),
        wheel_separation_multiplier=multiplier, source=source,
        joint_signs=tuple((w.joint, w.sign) for w in left + right), **extra)


def _separation_multiplier(track: float, wheelbase: float) -> float:
    if track <= 0.0 or wheelbase <= 0.0:
        return 1.0
    from mobot_cli.sim.drive import default_separation_multiplier  # owned by the sim layer

    return default_separation_multiplier(track, wheelbase)
