"""Find a robot's drive wheels the way Gazebo's diff-drive plugins see them.

A ``<gazebo><plugin>`` diff-drive or skid-steer block wins (source "plugin"); values it
leaves out, and robots without one, are detected from the URDF (source "urdf"): wheels are
continuous joints whose axes lie along the root's y axis, whose child link has a cylinder
(along that axis) or sphere collision, and which move with the body (wheels.py: under fixed,
prismatic or suspension joints, anywhere in the tree). A plugin whose radius or separation
disagrees with that geometry is followed, as Gazebo follows it, with a warning.

Holonomic bases (holonomic.py) are found first: a gz-sim MecanumDrive plugin (kind "mecanum"),
a gazebo_ros planar_move or omni-drive plugin (kind "omni", ground-truth odometry, as the plugin
publishes the model's pose), or, without any drive plugin, two or more wheels a side whose
Gazebo friction is that of mecanum rollers (process.roller_links).

Without a Gazebo drive plugin, a ros2_control plugin's drive controller (ros2_control.py) comes
before the geometry (source "ros2_control"): diff_drive_controller drives its named wheels as a
diff or skid drive with its radius, separation and multipliers, mecanum_drive_controller as a
mecanum base; steering controllers need the car the geometry finds, and tricycle, bicycle and
omni-wheel controllers are refused, as their plugins are.
"""

from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from pathlib import Path

from mobot_cli.assets.description import holonomic, ros2_control, steering
from mobot_cli.assets.description.frames import LinkTree, movable_joint
from mobot_cli.assets.description.plugin_values import disagreement as _disagreement
from mobot_cli.assets.description.plugin_values import number as _number
from mobot_cli.assets.description.plugin_values import texts as _texts
from mobot_cli.assets.description.steering import Detected
from mobot_cli.assets.description.torque import with_torque
from mobot_cli.assets.description.wheels import Wheel, wheel
from mobot_cli.errors import Location, Notice
from mobot_cli.plan import DriveSpec

# the last two: gazebo classic's stock libSkidSteerDrivePlugin.so (osrf's pioneer3at)
_LEFT_TAGS = ("leftJoint", "left_joint", "leftFrontJoint", "leftRearJoint", "left_front", "left_rear")
_RIGHT_TAGS = ("rightJoint", "right_joint", "rightFrontJoint", "rightRearJoint", "right_front", "right_rear")


def detect_drive(urdf: ET.Element | str, *, notices: list[Notice] | None = None,
                 source: Path | None = None) -> DriveSpec | None:
    """The robot's drive, or None when it has none mobot can drive (``detect``)."""
    return detect(urdf, notices=notices, source=source).spec


def detect(urdf: ET.Element | str, *, notices: list[Notice] | None = None,
           source: Path | None = None, controllers: tuple[ros2_control.Controller, ...] = ()) -> Detected:
    """The robot's drive (diff, skid, mecanum, omni or Ackermann) with its wheel torque limit
    (torque.py), or the name of one mobot refuses.

    Plugins first, as Gazebo drives by them: Ackermann, then the ones mobot refuses (tracks,
    tricycles), then mecanum and planar-move, then diff-drive and skid-steer, then a drive
    controller of ``controllers`` (what the robot's ros2_control plugin loads:
    ros2_control.read), then other drive plugins (refused); without one, steering joints make a
    car (steering.py), wheels with roller friction a mecanum base (holonomic.py), and wheels
    fixed to the body a diff or skid drive.
    """
    robot = ET.fromstring(urdf) if isinstance(urdf, str) else urdf
    found = _detect(robot, notices if notices is not None else [], source, controllers)
    if found.spec is None:
        return found
    return dataclasses.replace(found, spec=with_torque(robot, found.spec))


def _detect(robot: ET.Element, notices: list[Notice], source: Path | None,
            controllers: tuple[ros2_control.Controller, ...]) -> Detected:
    tree = LinkTree(robot)
    if tree.root is None:
        return Detected(None)
    found = steering.from_plugins(robot, tree, notices, source)
    if found is not None:
        return found
    holonomic_plugin = holonomic.plugin(robot)
    if holonomic_plugin is not None:
        spec = holonomic.from_plugin(holonomic_plugin, robot, tree, notices, source)
        if spec is not None:
            return Detected(spec)
    plugin = _drive_plugin(robot)
    if plugin is not None:
        spec = _from_plugin(plugin, tree, notices, source)
        if spec is not None:
            holonomic.note_rollers(spec, robot, tree, f"the {_plugin_label(plugin)} plugin", notices, source)
            return Detected(spec)
    else:
        found = _from_controllers(controllers, robot, tree, notices, source)
        if found is None:
            found = steering.unknown_drive(robot, notices, source)
        if found is not None:
            return found
    found = steering.from_geometry(tree, robot, notices, source)
    if found is not None:
        return found
    wheels = [w for j in tree.joints if (w := wheel(tree, j.name, strict=True)) is not None]
    rolling = holonomic.from_rollers(wheels, robot, tree, notices, source)
    if rolling is not None:
        return Detected(rolling)
    return Detected(_spec(wheels, source="urdf", notices=notices, file=source))


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
    wheels = []
    for side, names in (("left", left), ("right", right)):
        for name in names:
            movable_joint(tree, name, f"drive names {side} wheel joint",
                          Location(file=source, key=f"drive.{side}_joints"), "Name continuous wheel joints.",
                          place="the description")
            wheels.append(wheel(tree, name, strict=False))
    sides = {**{n: "left" for n in left}, **{n: "right" for n in right}}
    return with_torque(robot, _spec(wheels, source="scenario", notices=notices, file=source,  # type: ignore[arg-type]
                                    sides=sides, radius=radius, separation=separation))


def _drive_plugin(robot: ET.Element) -> ET.Element | None:
    """The first diff-drive or skid-steer plugin in the robot's <gazebo> blocks."""
    for gazebo in robot.findall("gazebo"):
        for plugin in gazebo.findall("plugin"):
            label = (plugin.get("filename", "") + " " + plugin.get("name", "")).lower()
            if any(k in label for k in ("diff_drive", "diff-drive", "diffdrive", "skid_steer", "skidsteer")):
                return plugin
    return None


def _plugin_label(plugin: ET.Element) -> str:
    """How messages name a diff-drive plugin: its file name, else its name."""
    return plugin.get("filename") or plugin.get("name") or "diff-drive"


def _from_plugin(plugin: ET.Element, tree: LinkTree, notices: list[Notice],
                 file: Path | None) -> DriveSpec | None:
    label = _plugin_label(plugin)
    left, right = _texts(plugin, *_LEFT_TAGS), _texts(plugin, *_RIGHT_TAGS)
    if not left or not right:
        notices.append(Notice(f"the {label} plugin names no left or right joints; "
                              "detecting the wheels from the URDF instead", Location(file=file)))
        return None
    wheels = _named_wheels(f"the {label} plugin", {"left": left, "right": right}, tree, notices, file,
                           lambda side, _name: Location(file=file, key=f"gazebo.plugin.{side}_joint"))
    radius = _number(plugin, "wheel_radius")
    diameter = _number(plugin, "wheelDiameter", "wheel_diameter")
    if radius is None and diameter is not None:
        radius = diameter / 2.0
    torque = _number(plugin, "wheelTorque", "max_wheel_torque", "torque")
    accel = _number(plugin, "wheelAcceleration", "max_wheel_acceleration")
    separation = _number(plugin, "wheelSeparation", "wheel_separation")
    _disagreement(f"the {label} plugin", wheels, radius, separation, notices, file)
    return _spec([w for _, w in wheels], source="plugin", notices=notices, file=file,
                 sides={w.joint: s for s, w in wheels}, radius=radius,
                 separation=separation, torque=torque, rim_accel=accel)


def _named_wheels(who: str, named: dict[str, list[str]], tree: LinkTree, notices: list[Notice],
                  file: Path | None, where) -> list[tuple[str, Wheel]]:
    """(side, wheel) for each joint a plugin or controller names on a side ("left", "right"):
    a located error (``where(side, name)``) for a name that is no movable joint, a notice for
    one on the other side."""
    wheels: list[tuple[str, Wheel]] = []
    for side, names in named.items():
        for name in dict.fromkeys(names):
            movable_joint(tree, name, f"{who} names {side} wheel joint", where(side, name),
                          "Name a continuous wheel joint.")
            wheels.append((side, wheel(tree, name, strict=False)))  # type: ignore[arg-type]
    for side, found in wheels:
        if (side == "left") != (found.y > 0):
            notices.append(Notice(f"{who} drives '{found.joint}' as a {side} wheel "
                                  f"but it sits at y = {found.y:+.3f} m in the root frame",
                                  Location(file=file)))
    return wheels


# ros2_control drive controllers (the type's package) mobot refuses, with the drive they make.
REFUSED_CONTROLLERS = {"tricycle_controller": "tricycle drive", "tricycle_steering_controller": "tricycle drive",
                       "bicycle_steering_controller": "bicycle drive",
                       "omni_wheel_drive_controller": "omni-wheel drive"}
# mecanum_drive_controller's wheels: the side and corner of each (the corner names its parameter).
_MECANUM_JOINTS = (("left", "front_left"), ("right", "front_right"), ("left", "rear_left"), ("right", "rear_right"))


def _from_controllers(controllers: tuple[ros2_control.Controller, ...], robot: ET.Element, tree: LinkTree,
                      notices: list[Notice], source: Path | None) -> Detected | None:
    """The drive of the first drive controller the robot's ros2_control plugin loads; None
    without one (or when it names no wheels: the geometry decides, with a notice)."""
    for controller in controllers:
        package, label = controller.kind, f"the {controller.package} controller '{controller.name}'"
        if package in REFUSED_CONTROLLERS:
            return steering.refusal(REFUSED_CONTROLLERS[package], f"{controller.type}, {controller.file}",
                                    notices, source)
        if package == "ackermann_steering_controller":
            found = steering.from_geometry(tree, robot, notices, source)
            if found is not None and found.spec is not None and found.spec.kind == "ackermann":
                return Detected(dataclasses.replace(found.spec, source="ros2_control"))
            return steering.refusal("Ackermann steering whose steered wheels mobot cannot find",
                                    f"{controller.type}, {controller.file}", notices, source)
        if package == "diff_drive_controller":
            spec = _from_diff_controller(controller, label, tree, notices)
        elif package == "mecanum_drive_controller":
            spec = _from_mecanum_controller(controller, label, tree, notices)
        else:
            continue
        if spec is not None:
            if spec.kind != "mecanum":
                holonomic.note_rollers(spec, robot, tree, label, notices, source)
            return Detected(spec)
        return None
    return None


def _from_diff_controller(controller: ros2_control.Controller, label: str, tree: LinkTree,
                          notices: list[Notice]) -> DriveSpec | None:
    """diff_drive_controller: its wheels, radius, separation and multipliers, as it drives them."""
    named = {side: ros2_control.names(controller, f"{side}_wheel_names") for side in ("left", "right")}
    if not named["left"] or not named["right"]:
        notices.append(Notice(f"{label} names no left or right wheels; detecting the wheels from the "
                              "URDF instead", controller.location()))
        return None
    wheels = _named_wheels(label, named, tree, notices, controller.file,
                           lambda side, _name: controller.location(f"{side}_wheel_names"))
    radius = ros2_control.number(controller, "wheel_radius")
    separation = ros2_control.number(controller, "wheel_separation")
    _controller_disagreement(controller, wheels, radius, separation, notices)
    spec = _spec([w for _, w in wheels], source="ros2_control", notices=notices, file=controller.file,
                 sides={w.joint: s for s, w in wheels}, radius=radius, separation=separation)
    if spec is None:
        return None
    multipliers = {}
    given = ros2_control.number(controller, "wheel_separation_multiplier")
    if given is not None:  # as the controller turns; else mobot's skid-steer default
        multipliers["wheel_separation_multiplier"] = given
    left = ros2_control.number(controller, "left_wheel_radius_multiplier") or 1.0
    right = ros2_control.number(controller, "right_wheel_radius_multiplier") or 1.0
    if left != right:
        notices.append(Notice(f"{label} has left and right wheel radius multipliers {left:g} and {right:g}: "
                              f"mobot uses one for both, their mean {(left + right) / 2:g}", controller.location()))
    if left != 1.0 or right != 1.0:
        multipliers["wheel_radius_multiplier"] = (left + right) / 2
    return dataclasses.replace(spec, **multipliers)


def _from_mecanum_controller(controller: ros2_control.Controller, label: str, tree: LinkTree,
                             notices: list[Notice]) -> DriveSpec | None:
    """mecanum_drive_controller: its four wheels; radius and spacing from it where it gives them."""
    named: dict[str, list[str]] = {"left": [], "right": []}
    key_of: dict[str, str] = {}  # joint -> the parameter naming it, for errors
    for side, corner in _MECANUM_JOINTS:
        keys = (f"{corner}_wheel_command_joint_name", f"{corner}_wheel_name")
        found = ros2_control.names(controller, *keys)
        named[side] += found
        key_of.update(dict.fromkeys(found, next((k for k in keys if k in controller.params), keys[0])))
    if len(named["left"]) != 2 or len(named["right"]) != 2:
        notices.append(Notice(f"{label} does not name its four wheels; detecting the wheels from the URDF "
                              "instead", controller.location()))
        return None
    wheels = _named_wheels(label, named, tree, notices, controller.file,
                           lambda side, name: controller.location(key_of[name]))
    radius = ros2_control.number(controller, "kinematics.wheels_radius", "wheel_radius")
    separation = ros2_control.number(controller, "wheel_separation_y")
    _controller_disagreement(controller, wheels, radius, separation, notices, holonomic=True)
    spec = holonomic.holonomic_spec("mecanum", [w for _, w in wheels], {w.joint: s for s, w in wheels},
                                    odometry="encoder", source="ros2_control", notices=notices,
                                    file=controller.file, radius=radius, separation=separation,
                                    wheelbase=ros2_control.number(controller, "wheel_separation_x"))
    reach = ros2_control.number(controller, _REACH)
    if spec is None or reach is None or reach <= spec.wheel_separation / 2:
        return spec
    measured = (spec.wheel_separation + spec.wheelbase) / 2
    if abs(reach - measured) > 0.02 * measured:
        notices.append(Notice(f"the parameters of {controller.package} controller '{controller.name}' say {_REACH} "
                              f"{reach:.4f} m, but its wheels are {measured:.4f} m (lx + ly) from the centre: "
                              "mobot turns the wheels and integrates odometry with the controller's value, "
                              "as Gazebo does", controller.location(_REACH)))
    # The controller's inverse kinematics use only lx + ly: keep the track, fit the wheelbase.
    return dataclasses.replace(spec, wheelbase=2 * reach - spec.wheel_separation)


# mecanum_drive_controller's lx + ly: the wheels' distance from the centre along x plus along y.
_REACH = "kinematics.sum_of_robot_center_projection_on_X_Y_axis"


def _controller_disagreement(controller: ros2_control.Controller, wheels: list[tuple[str, Wheel]],
                             radius: float | None, separation: float | None, notices: list[Notice],
                             holonomic: bool = False) -> None:
    """plugin_values.disagreement, worded for a controller's parameters."""
    _disagreement(f"the parameters of {controller.package} controller '{controller.name}'", wheels, radius,
                  separation, notices, controller.file, says="say", whose="the controller's", holonomic=holonomic)


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
