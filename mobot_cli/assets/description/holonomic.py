"""Holonomic bases (mecanum and omni) as Gazebo's plugins and wheel surfaces describe them.

* gz-sim's MecanumDrive system (``gz-sim-mecanum-drive-system``, the ``ignition-gazebo`` one
  before it): ``front_left_joint``, ``front_right_joint``, ``back_left_joint``,
  ``back_right_joint``, ``wheel_separation``, ``wheelbase``, ``wheel_radius``. Kind "mecanum";
  odometry from the wheel encoders, as the plugin integrates them. Values it leaves out are
  measured from the wheels, as for the diff-drive plugins.
* gazebo_ros's planar_move (and omni-drive plugins like it): it sets the body's planar twist and
  publishes the model's pose, so kind "omni" with ground-truth odometry. Its wheels, if any, are
  found from the URDF as for a robot without a plugin.
* No drive plugin, two or more wheels a side, every one with roller friction (<fdir1> and one mu
  near 0, process.roller_links): a mecanum base driven by something mobot does not read (a
  ros2_control mecanum controller): kind "mecanum", encoder odometry.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from mobot_cli.assets.description.frames import LinkTree, movable_joint
from mobot_cli.assets.description.plugin_values import disagreement, number, texts
from mobot_cli.assets.description.process import roller_links
from mobot_cli.assets.description.wheels import Wheel, wheel
from mobot_cli.errors import Location, Notice
from mobot_cli.plan import DriveSpec

MECANUM_LABELS = ("mecanum-drive", "mecanum_drive", "mecanumdrive")
OMNI_LABELS = ("planar_move", "planar-move", "planarmove", "omni_drive", "omni-drive", "omnidrive",
               "omni_steering", "omni-steering")
CORNERS = (("left", "front_left_joint"), ("left", "back_left_joint"),
           ("right", "front_right_joint"), ("right", "back_right_joint"))


def plugin(robot: ET.Element) -> ET.Element | None:
    """The first mecanum or planar-move plugin in the robot's <gazebo> blocks."""
    for gazebo in robot.findall("gazebo"):
        for element in gazebo.findall("plugin"):
            if kind_of(element) is not None:
                return element
    return None


def kind_of(element: ET.Element) -> str | None:
    """"mecanum", "omni" or None for a <plugin> element."""
    label = (element.get("filename", "") + " " + element.get("name", "")).lower()
    if any(k in label for k in MECANUM_LABELS):
        return "mecanum"
    if any(k in label for k in OMNI_LABELS):
        return "omni"
    return None


def from_plugin(element: ET.Element, robot: ET.Element, tree: LinkTree, notices: list[Notice],
                file: Path | None) -> DriveSpec | None:
    """The drive a mecanum or planar-move plugin describes."""
    kind = kind_of(element)
    label = element.get("filename") or element.get("name") or f"{kind} drive"
    if kind == "omni":
        found = [w for j in tree.joints if (w := wheel(tree, j.name, strict=True)) is not None]
        sides = {w.joint: "left" if w.y > 0 else "right" for w in found}
        return holonomic_spec("omni", found, sides, odometry="ground_truth", source="plugin",
                              notices=notices, file=file)
    found, sides = [], {}
    for side, tag in CORNERS:
        names = texts(element, tag)
        if not names:
            notices.append(Notice(f"the {label} plugin gives no <{tag}>; detecting the wheels from the "
                                  "URDF instead", Location(file=file)))
            return None
        for name in names:
            movable_joint(tree, name, f"the {label} plugin names {tag}",
                          Location(file=file, key=f"gazebo.plugin.{tag}"), "Name a continuous wheel joint.",
                          place="the description")
            found.append(wheel(tree, name, strict=False))
            sides[name] = side
    radius = number(element, "wheel_radius")
    separation = number(element, "wheel_separation")
    wheelbase = number(element, "wheelbase", "wheel_base")
    disagreement(f"the {label} plugin", [(sides[w.joint], w) for w in found], radius, separation, notices, file,
                 holonomic=True)
    return holonomic_spec("mecanum", found, sides, odometry="encoder", source="plugin", notices=notices,
                          file=file, radius=radius, separation=separation, wheelbase=wheelbase)


def from_rollers(found: list[Wheel], robot: ET.Element, tree: LinkTree, notices: list[Notice],
                 file: Path | None) -> DriveSpec | None:
    """A mecanum drive when every detected wheel has roller friction and each side has two or more."""
    rollers = roller_links(robot)
    children = {j.name: j.child for j in tree.joints}
    if not found or not all(children.get(w.joint) in rollers for w in found):
        return None
    sides = {w.joint: "left" if w.y > 0 else "right" for w in found}
    if min(list(sides.values()).count("left"), list(sides.values()).count("right")) < 2:
        return None
    return holonomic_spec("mecanum", found, sides, odometry="encoder", source="urdf", notices=notices,
                          file=file)


def note_rollers(spec: DriveSpec, robot: ET.Element, tree: LinkTree, who: str,
                 notices: list[Notice], file: Path | None) -> None:
    """One notice when a diff or skid plugin or controller (``who``: "the X plugin") drives
    wheels that have roller friction."""
    rollers = roller_links(robot)
    children = {j.name: j.child for j in tree.joints}
    rolling = [j for j in spec.left_joints + spec.right_joints if children.get(j) in rollers]
    if rolling:
        notices.append(Notice(f"wheels {', '.join(rolling)} have roller friction (mecanum), but "
                              f"{who} drives them as a diff drive: so does mobot, with their "
                              "larger mu along the rolling direction", Location(file=file)))


def holonomic_spec(kind: str, found: list[Wheel], sides: dict[str, str], *, odometry: str, source: str,
                   notices: list[Notice], file: Path | None, radius: float | None = None,
                   separation: float | None = None, wheelbase: float | None = None) -> DriveSpec | None:
    """A mecanum or omni DriveSpec; wheels front first on each side. A mecanum base needs a
    radius (given or measured); an omni base may have no wheels at all (planar_move)."""
    left = sorted((w for w in found if sides[w.joint] == "left"), key=lambda w: -w.x)
    right = sorted((w for w in found if sides[w.joint] == "right"), key=lambda w: -w.x)
    if radius is None:
        radii = [w.radius for w in found if w.radius]
        radius = sum(radii) / len(radii) if radii else None
    if radius is None and found:
        notices.append(Notice(f"{kind} drive wheels {', '.join(w.joint for w in found)} have no "
                              "cylinder or sphere collision to measure a radius from: their joints "
                              "are not turned (set drive: wheel_radius)", Location(file=file)))
    if separation is None:
        separation = (_mean([w.y for w in left]) - _mean([w.y for w in right])) if left and right else 0.0
    if wheelbase is None:
        wheelbase = _wheelbase(left, right)
    return DriveSpec(
        left_joints=tuple(w.joint for w in left), right_joints=tuple(w.joint for w in right),
        wheel_radius=radius or 0.0, wheel_separation=abs(separation), odometry=odometry,
        twist_feedback=False, source=source, joint_signs=tuple((w.joint, w.sign) for w in left + right),
        kind=kind, wheelbase=abs(wheelbase))


def _wheelbase(left: list[Wheel], right: list[Wheel]) -> float:
    """Front-half wheels' mean x minus the back half's (0 with one wheel a side)."""
    fronts, backs = [], []
    for side in (left, right):
        half = len(side) // 2
        if half:
            fronts += [w.x for w in side[:half]]
            backs += [w.x for w in side[-half:]]
    return _mean(fronts) - _mean(backs) if fronts else 0.0


def _mean(values: list[float]) -> float:
    return sum(values) / len(values) if values else 0.0


def wheelbase_of(urdf: str, left: tuple[str, ...], right: tuple[str, ...]) -> float:
    """The wheelbase of these wheel joints (front first on each side) as holonomic_spec measures it."""
    tree = LinkTree(ET.fromstring(urdf))
    found = {name: wheel(tree, name, strict=False) for name in left + right}
    return abs(_wheelbase([found[n] for n in left if found[n] is not None],
                          [found[n] for n in right if found[n] is not None]))
