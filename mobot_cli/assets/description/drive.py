"""Find a robot's drive wheels the way Gazebo's diff-drive plugins see them.

A ``<gazebo><plugin>`` diff-drive or skid-steer block wins (source "plugin"); values it
leaves out, and robots without one, are detected from the URDF (source "urdf"): wheels are
continuous joints whose axes lie along the root's y axis, whose child link has a cylinder
(along that axis) or sphere collision, and which move with the body (wheels.py: under fixed,
prismatic or suspension joints, anywhere in the tree). A plugin whose radius or separation
disagrees with that geometry is followed, as Gazebo follows it, with a warning.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from mobot_cli.assets.description.frames import LinkTree
from mobot_cli.assets.description.torque import with_torque
from mobot_cli.assets.description.wheels import Wheel, wheel
from mobot_cli.errors import DescriptionError, Location, Notice, did_you_mean
from mobot_cli.plan import DriveSpec

_LEFT_TAGS = ("leftJoint", "left_joint", "leftFrontJoint", "leftRearJoint")
_RIGHT_TAGS = ("rightJoint", "right_joint", "rightFrontJoint", "rightRearJoint")
# Plugin values farther than this from the wheel geometry get a warning.
DISAGREEMENT = 0.02


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
            return with_torque(robot, spec)
    wheels = [w for j in tree.joints if (w := wheel(tree, j.name, strict=True)) is not None]
    return with_torque(robot, _spec(wheels, source="urdf", notices=notices, file=source))


def drive_from_joints(urdf: ET.Element | str, left: tuple[str, ...], right: tuple[str, ...], *,
                      notices: list[Notice] | None = None, source: Path | None = None,
                      radius: float | None = None,
                      separation: float | None = None) -> DriveSpec | None:
    """The drive on the named wheel joints, radius and separation from their geometry.

    For a `drive:` that names the joints: anything that spins counts, wherever it hangs, and
    a mesh wheel gives its radius too. ``radius`` and ``separation``, when given, win. None
    when no radius can be measured (the caller asks for one). A name that is not a movable
    joint is a DescriptionError.
    """
    robot = ET.fromstring(urdf) if isinstance(urdf, str) else urdf
    tree = LinkTree(robot)
    notices = notices if notices is not None else []
    joint_types = {j.name: j.type for j in tree.joints}
    wheels = []
    for side, names in (("left", left), ("right", right)):
        for name in names:
            if joint_types.get(name) in (None, "fixed"):
                problem = "is fixed" if name in joint_types else "is not in the description"
                raise DescriptionError(
                    f"drive names {side} wheel joint '{name}', which {problem}",
                    location=Location(file=source, key=f"drive.{side}_joints"),
                    hint=did_you_mean(name, [n for n, t in joint_types.items() if t != "fixed"])
                    or "Name continuous wheel joints.")
            wheels.append(wheel(tree, name, strict=False))
    sides = {**{n: "left" for n in left}, **{n: "right" for n in right}}
    return with_torque(robot, _spec(wheels, source="scenario", notices=notices, file=source,  # type: ignore[arg-type]
                                    sides=sides, radius=radius, separation=separation))


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
            wheels.append((side, wheel(tree, name, strict=False)))  # type: ignore[arg-type]
    for side, found in wheels:
        if (side == "left") != (found.y > 0):
            notices.append(Notice(f"the {label} plugin drives '{found.joint}' as a {side} wheel "
                                  f"but it sits at y = {found.y:+.3f} m in the root frame",
                                  Location(file=file)))
    radius = _number(plugin, "wheel_radius")
    diameter = _number(plugin, "wheelDiameter", "wheel_diameter")
    if radius is None and diameter is not None:
        radius = diameter / 2.0
    torque = _number(plugin, "wheelTorque", "max_wheel_torque", "torque")
    accel = _number(plugin, "wheelAcceleration", "max_wheel_acceleration")
    separation = _number(plugin, "wheelSeparation", "wheel_separation")
    _disagreement(label, wheels, radius, separation, notices, file)
    return _spec([w for _, w in wheels], source="plugin", notices=notices, file=file,
                 sides={w.joint: s for s, w in wheels}, radius=radius,
                 separation=separation, torque=torque, rim_accel=accel)


def _disagreement(label: str, wheels: list[tuple[str, Wheel]], radius: float | None,
                  separation: float | None, notices: list[Notice], file: Path | None) -> None:
    """One warning when the plugin's radius or separation is > 2 % off the wheel geometry."""
    parts, effects = [], []
    left = [w.y for side, w in wheels if side == "left"]
    right = [w.y for side, w in wheels if side == "right"]
    if separation and left and right:
        apart = abs(sum(left) / len(left) - sum(right) / len(right))
        if apart > 0 and abs(separation - apart) > DISAGREEMENT * apart:
            parts.append(f"wheel_separation {separation:.3f} m, but its wheel joints are "
                         f"{apart:.3f} m apart")
            effects.append(f"turns {_percent(separation / apart)} than commanded")
    radii = [w.radius for _, w in wheels if w.radius]
    if radius and radii:
        measured = sum(radii) / len(radii)
        if abs(radius - measured) > DISAGREEMENT * measured:
            parts.append(f"wheel_radius {radius:.3f} m, but its wheels' collisions have radius "
                         f"{measured:.3f} m")
            effects.append(f"drives {_percent(measured / radius)} than commanded")
    if parts:
        notices.append(Notice(
            f"the {label} plugin says {'; and '.join(parts)}: mobot uses the plugin's values, "
            f"as Gazebo does, so the robot {' and '.join(effects)} (set drive: wheel_radius / "
            "wheel_separation to use the geometry)", Location(file=file)))


def _percent(ratio: float) -> str:
    """'11 % more' or '9 % less' for a ratio of achieved to commanded motion."""
    return f"{abs(ratio - 1) * 100:.0f} % {'more' if ratio > 1 else 'less'}"


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
    extra: dict = {}
    if torque is not None and torque > 0:
        extra.update(max_wheel_torque=torque, torque_source="plugin")
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
