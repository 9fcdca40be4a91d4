"""An SDF model with joints (dolly, the turtlebot3 SDF models) as URDF text for the robot path.

The URDF's root link frame is the model frame, every other link's frame is its joint's frame
(URDF has no separate joint pose), and shapes and inertials are re-expressed accordingly.
Joint axes come out in the joint frame. Ball joints become fixed: the caster sphere then
slides with mobot's low caster friction (sim/bullet/world.py), which is how URDF robots model
casters too. The diff-drive <plugin> is kept as a <gazebo><plugin> block so drive detection
reads it exactly as it reads gazebo_ros plugins in URDF; each link's <sensor>s likewise become
<gazebo reference="LINK"><sensor> blocks, their <pose> re-expressed in the URDF link frame.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from mobot_cli.assets.description.process import is_roller
from mobot_cli.assets.world.model import Link, Model
from mobot_cli.assets.world.pose import IDENTITY, inverse, rpy
from mobot_cli.errors import DescriptionError, Location, Notice

# Revolute limits this wide (SDF's default is +-1e16) mean "turns freely": continuous.
CONTINUOUS_SPAN = 1e6
UNSUPPORTED_JOINTS = ("ball", "universal", "revolute2", "screw", "gearbox")


def model_to_urdf(model: Model, source: Path) -> tuple[str, list[Notice]]:
    """URDF text for a model with joints, plus notices about what changed on the way."""
    notices: list[Notice] = []
    where = Location(file=source)
    links = {link.name: link for link in model.links}
    if not links:
        raise DescriptionError(f"model '{model.name}' has no links", location=model.location,
                               hint="A robot needs at least one <link>.")
    joints = [j for j in model.joints if j.parent != "world"]
    for joint in model.joints:
        if joint.parent == "world":
            notices.append(Notice(f"joint '{joint.name}' to the world is left out: a spawned "
                                  "robot is free", joint.location))
    children = {}
    for joint in joints:
        for end in (joint.parent, joint.child):
            if end not in links:
                raise DescriptionError(f"joint '{joint.name}' names link '{end}', which the model "
                                       "does not have", location=joint.location,
                                       hint="Links of nested models are named MODEL::LINK.")
        if joint.child in children:
            # SDF allows a closed loop; a URDF is a tree. A second joint that cannot move (fixed,
            # or limits both 0: osrf's turtlebot holds its rack by two) adds nothing: left out.
            first = children[joint.child]
            if joint.moves and first.moves:
                raise DescriptionError(f"link '{joint.child}' is the child of two joints that move "
                                       f"('{first.name}' and '{joint.name}'): a closed loop",
                                       location=joint.location,
                                       hint="mobot simulates links that form a tree: fix one of the joints.")
            dropped, children[joint.child] = (first, joint) if first.moves is False and joint.moves else \
                (joint, first)
            notices.append(Notice(f"joint '{dropped.name}' also holds link '{joint.child}', which joint "
                                  f"'{children[joint.child].name}' holds: it cannot move, so it is left out "
                                  "(links form a tree in mobot)", dropped.location))
            continue
        children[joint.child] = joint
    joints = list(children.values())
    roots = [name for name in links if name not in children]
    if not roots:
        raise DescriptionError(f"the joints of model '{model.name}' form a loop",
                               location=model.location, hint="Links must form a tree.")
    root = roots[0]
    frames = {root: IDENTITY.copy()}  # the root link's URDF frame is the model frame
    robot = ET.Element("robot", name=model.name)
    for extra in roots[1:]:  # SDF lets links float free; a robot keeps them on its root
        notices.append(Notice(f"link '{extra}' has no joint: it is fixed to '{root}'", where))
    order = _tree_order(root, roots[1:], joints)
    for name in order:
        joint = children.get(name)
        frames[name] = joint.pose if joint is not None else links[name].pose
    for name in [root, *order]:
        _link(robot, links[name], frames[name], notices)
    for extra in roots[1:]:
        _fixed(robot, f"{extra}_fixed", root, extra, inverse(frames[root]) @ frames[extra])
    for name in order:
        joint = children.get(name)
        if joint is not None:
            _joint(robot, joint, frames, notices)
    _plugins(robot, model)
    return '<?xml version="1.0"?>\n' + ET.tostring(robot, encoding="unicode"), notices


def _tree_order(root: str, extra_roots: list[str], joints) -> list[str]:
    """Every link but the root, parents before children."""
    below: dict[str, list[str]] = {}
    for joint in joints:
        below.setdefault(joint.parent, []).append(joint.child)
    order, stack = [], [*reversed(extra_roots), root]
    while stack:
        name = stack.pop()
        if name != root:
            order.append(name)
        stack.extend(reversed(below.get(name, [])))
    return order


def _origin(parent: ET.Element, m) -> None:
    x, y, z = (round(float(v), 12) + 0.0 for v in m[:3, 3])
    r, p, yaw = rpy(m)
    ET.SubElement(parent, "origin", xyz=f"{x:.12g} {y:.12g} {z:.12g}", rpy=f"{r:.12g} {p:.12g} {yaw:.12g}")


def _link(robot: ET.Element, link: Link, frame, notices: list[Notice]) -> None:
    """A URDF link in ``frame`` (the link's URDF frame, in the model frame)."""
    element = ET.SubElement(robot, "link", name=link.name)
    to_urdf = inverse(frame) @ link.pose  # SDF link frame expressed in the URDF link frame
    inertial = link.inertial
    if not inertial.given:
        notices.append(Notice(f"link '{link.name}' has no <inertial>: SDF's default of 1 kg and "
                              "1 kg*m^2 applies, as in Gazebo", link.location))
    block = ET.SubElement(element, "inertial")
    _origin(block, to_urdf @ inertial.pose)
    ET.SubElement(block, "mass", value=f"{inertial.mass:.12g}")
    ixx, ixy, ixz, iyy, iyz, izz = inertial.inertia
    ET.SubElement(block, "inertia", ixx=f"{ixx:.12g}", ixy=f"{ixy:.12g}", ixz=f"{ixz:.12g}",
                  iyy=f"{iyy:.12g}", iyz=f"{iyz:.12g}", izz=f"{izz:.12g}")
    for kind, shapes in (("visual", link.visuals), ("collision", link.collisions)):
        for shape in shapes:
            _shape(element, kind, shape, to_urdf, link.name, notices)
    for sensor, pose in link.sensors:  # description.sensors reads them as from URDF
        _sensor(robot, link.name, sensor, to_urdf @ pose)
    frictions = [s.friction for s in link.collisions if s.friction is not None]
    rollers = [s.anisotropic for s in link.collisions if s.anisotropic is not None
               and is_roller({"mu1": s.anisotropic[0], "mu2": s.anisotropic[1]}, True)]
    if rollers:  # kept as written: description.process reads mecanum rollers from mu, mu2, fdir1
        gazebo = ET.SubElement(robot, "gazebo", reference=link.name)
        mu, mu2, fdir = rollers[0]
        ET.SubElement(gazebo, "mu1").text = f"{mu:.12g}"
        ET.SubElement(gazebo, "mu2").text = f"{mu2:.12g}"
        ET.SubElement(gazebo, "fdir1").text = fdir
    elif frictions:  # description.process.apply_friction turns this into PyBullet's lateral_friction
        gazebo = ET.SubElement(robot, "gazebo", reference=link.name)
        ET.SubElement(gazebo, "mu1").text = f"{min(frictions):.12g}"
        ET.SubElement(gazebo, "mu2").text = f"{min(frictions):.12g}"


def _sensor(robot: ET.Element, link_name: str, sensor, pose) -> None:
    """A copy of an SDF link's <sensor> in <gazebo reference>, posed in the URDF link frame."""
    copy = _copy(sensor)
    for old in copy.findall("pose"):
        copy.remove(old)
    x, y, z = (round(float(v), 12) + 0.0 for v in pose[:3, 3])
    ET.SubElement(copy, "pose").text = " ".join(f"{v:.12g}" for v in (x, y, z, *rpy(pose)))
    ET.SubElement(robot, "gazebo", reference=link_name).append(copy)


def _copy(element) -> ET.Element:
    """An lxml element as an ElementTree one, comments and processing instructions left out."""
    copy = ET.Element(element.tag, dict(element.attrib))
    copy.text = element.text
    for child in element:
        if isinstance(child.tag, str):
            inner = _copy(child)
            inner.tail = child.tail
            copy.append(inner)
    return copy


def _shape(link: ET.Element, kind: str, shape, to_urdf, link_name: str,
           notices: list[Notice]) -> None:
    pose = to_urdf @ shape.pose
    if shape.kind == "plane":
        notices.append(Notice(f"a plane {kind} of link '{link_name}' is left out: a robot cannot "
                              "carry an infinite plane", shape.location))
        return
    if shape.kind == "capsule":  # URDF has no capsule: a cylinder with a sphere at each end
        radius, length = shape.size
        for dz, geometry in ((0.0, ("cylinder", {"radius": radius, "length": length})),
                             (length / 2, ("sphere", {"radius": radius})),
                             (-length / 2, ("sphere", {"radius": radius}))):
            offset = IDENTITY.copy()
            offset[2, 3] = dz
            _element(link, kind, pose @ offset, *geometry, name=shape.name)
        return
    if shape.kind == "box":
        attrs = {"size": " ".join(f"{v:.12g}" for v in shape.size)}
    elif shape.kind == "cylinder":
        attrs = {"radius": shape.size[0], "length": shape.size[1]}
    elif shape.kind == "sphere":
        attrs = {"radius": shape.size[0]}
    else:
        attrs = {"filename": str(shape.mesh), "scale": " ".join(f"{v:.12g}" for v in shape.size)}
    _element(link, kind, pose, shape.kind, attrs, name=shape.name)


def _element(link: ET.Element, kind: str, pose, geometry: str, attrs: dict, name: str = "") -> None:
    # Collisions keep their SDF name: a contact sensor's <collision> names one.
    element = ET.SubElement(link, kind, name=name) if name and kind == "collision" else \
        ET.SubElement(link, kind)
    _origin(element, pose)
    shape = ET.SubElement(ET.SubElement(element, "geometry"), geometry)
    for key, value in attrs.items():
        shape.set(key, value if isinstance(value, str) else f"{value:.12g}")


def _fixed(robot: ET.Element, name: str, parent: str, child: str, m) -> None:
    joint = ET.SubElement(robot, "joint", name=name, type="fixed")
    _origin(joint, m)
    ET.SubElement(joint, "parent", link=parent)
    ET.SubElement(joint, "child", link=child)


def _joint(robot: ET.Element, joint, frames: dict, notices: list[Notice]) -> None:
    origin = inverse(frames[joint.parent]) @ frames[joint.child]
    kind = joint.type
    lower, upper, effort, velocity = joint.limits
    if kind in UNSUPPORTED_JOINTS:
        notices.append(Notice(f"{kind} joint '{joint.name}' becomes fixed: mobot simulates "
                              "revolute, continuous, prismatic and fixed joints", joint.location))
        kind = "fixed"
    elif kind == "revolute" and (upper - lower >= CONTINUOUS_SPAN or lower >= upper):
        kind = "continuous"
    elif kind not in ("revolute", "continuous", "prismatic", "fixed"):
        raise DescriptionError(f"joint '{joint.name}' has unknown type '{joint.type}'",
                               location=joint.location,
                               hint="Use revolute, continuous, prismatic, fixed or ball.")
    if kind == "fixed":
        _fixed(robot, joint.name, joint.parent, joint.child, origin)
        return
    element = ET.SubElement(robot, "joint", name=joint.name, type=kind)
    _origin(element, origin)
    ET.SubElement(element, "parent", link=joint.parent)
    ET.SubElement(element, "child", link=joint.child)
    rotation = frames[joint.child][:3, :3]
    axis = rotation.T @ joint.axis  # model frame -> joint (child) frame
    ET.SubElement(element, "axis", xyz=" ".join(f"{round(float(v), 12) + 0.0:.12g}" for v in axis))
    effort = effort if effort > 0 else 1e6  # SDF's -1 means unlimited
    velocity = velocity if velocity > 0 else 1e6
    limit = ET.SubElement(element, "limit", effort=f"{effort:.12g}", velocity=f"{velocity:.12g}")
    if kind != "continuous":
        limit.set("lower", f"{max(lower, -1e6):.12g}")
        limit.set("upper", f"{min(upper, 1e6):.12g}")
    damping, friction = joint.dynamics
    if damping or friction:
        ET.SubElement(element, "dynamics", damping=f"{damping:.12g}", friction=f"{friction:.12g}")
    stiffness, reference = joint.spring
    if stiffness > 0.0:  # as a URDF writes a spring for Gazebo (assets/description/joints.py)
        gazebo = ET.SubElement(robot, "gazebo", reference=joint.name)
        ET.SubElement(gazebo, "springStiffness").text = f"{stiffness:.12g}"
        ET.SubElement(gazebo, "springReference").text = f"{reference:.12g}"


def _plugins(robot: ET.Element, model: Model) -> None:
    """Copy model plugins (their name, filename and simple children) into <gazebo> blocks."""
    for plugin in model.plugins:
        gazebo = ET.SubElement(robot, "gazebo")
        copy = ET.SubElement(gazebo, "plugin", name=plugin.get("name", ""),
                             filename=plugin.get("filename", ""))
        for child in plugin:
            if isinstance(child.tag, str) and len(child) == 0:
                ET.SubElement(copy, child.tag).text = (child.text or "").strip()
