"""Wheels as drive detection sees them: a spinning joint, where it sits, how big its wheel is.

A drive wheel may hang anywhere in the tree, as long as what carries it moves with the body:
fixed joints, prismatic suspension or wheel-drop joints, and suspension arms that pivot about a
horizontal axis (a rocker). A joint that turns about a vertical axis (a caster's swivel, a
steering knuckle) above a wheel makes it a caster or a steered wheel, not a drive wheel.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

from mobot_cli.assets.description.frames import LinkTree, floats, origin_frame
from mobot_cli.common.meshfile import collada_unit_of
from mobot_cli.common.transforms import Vec, mat_vec

# |cos| above this counts as parallel: turtlebot3 rotates its wheels by -1.57, not -pi/2.
PARALLEL = 0.99


@dataclass(frozen=True)
class Wheel:
    """A wheel joint as seen from the root link at zero joint positions."""

    joint: str
    x: float
    y: float
    radius: float | None
    sign: float  # +1 when the joint axis points along +y of the root frame


def wheel(tree: LinkTree, joint_name: str, strict: bool) -> Wheel | None:
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
        if not spins or abs(axis) < PARALLEL or not carried_by_body(tree, joint.parent):
            return None
    radius = wheel_radius(tree, joint.child, frame.pos, axis_root, meshes=not strict)
    if strict and radius is None:
        return None
    y = tyre_y(tree, joint.child, frame.pos, axis_root, radius)
    return Wheel(joint=joint.name, x=frame.pos[0], y=frame.pos[1] if y is None else y, radius=radius,
                 sign=1.0 if axis >= 0 else -1.0)


def tyre_y(tree: LinkTree, link: str, centre: Vec, axis_root: Vec, radius: float | None) -> float | None:
    """Where along y (root frame) the wheel meets the floor: the centre of the cylinder or sphere
    that reaches ``radius``, when it sits off the joint along the axle (limo, whose tyres hang
    2 cm outboard of their joints). None when no such shape, or it is centred on the joint."""
    element = tree.links.get(link)
    if element is None or not radius:
        return None
    link_frame = tree.frame(link)
    for collision in element.findall("collision"):
        geometry = collision.find("geometry")
        shape = None if geometry is None else next(
            (g for g in (geometry.find("cylinder"), geometry.find("sphere")) if g is not None), None)
        if shape is None:
            continue
        frame = link_frame.compose(origin_frame(collision))
        if shape.tag == "cylinder" and abs(sum(
                a * b for a, b in zip(mat_vec(frame.rot, (0.0, 0.0, 1.0)), axis_root))) < PARALLEL:
            continue
        reach = _off_axis(frame.pos, centre, axis_root) + floats(shape.get("radius"), 1, (0.0,))[0]
        if abs(reach - radius) < 1e-9 and abs(frame.pos[1] - centre[1]) > 1e-6:
            return frame.pos[1]
    return None


def why_not_wheels(tree: LinkTree, limit: int = 4) -> str:
    """Why the spinning joints of a robot without drive wheels are none ("" without any), for
    the notice that says no drive wheels were found (scout_mini's wheels spin about x)."""
    reasons = []
    for joint in tree.joints:
        if joint.type != "continuous":
            continue
        frame = tree.frame(joint.child)
        axis = mat_vec(frame.rot, joint.axis)
        if abs(axis[1]) < PARALLEL:
            why = f"spins about ({axis[0]:+.2f}, {axis[1]:+.2f}, {axis[2]:+.2f}), not the root's y axis"
        elif not carried_by_body(tree, joint.parent):
            why = "hangs below a swivel or free joint"
        elif wheel_radius(tree, joint.child, frame.pos, axis) is None:
            why = "has no cylinder or sphere collision (a mesh wheel: name it in drive: left_joints / right_joints)"
        else:
            continue
        reasons.append(f"{joint.name} {why}")
    more = [f"{len(reasons) - limit} more"] if len(reasons) > limit else []
    return "; ".join(reasons[:limit] + more)


def wheel_layout(tree: LinkTree, left: tuple[str, ...], right: tuple[str, ...],
                 default_radius: float) -> list[dict]:
    """Each drive wheel as `mobot inspect --json` shows it: joint, side, centre (x, y, z in the
    root frame, all joints at zero) and radius (its own, else the drive's)."""
    out = []
    for side, joints in (("left", left), ("right", right)):
        for name in joints:
            joint = next((j for j in tree.joints if j.name == name), None)
            if joint is None:
                continue
            x, y, z = (round(v, 9) + 0.0 for v in tree.frame(joint.child).pos)
            found = wheel(tree, name, strict=False)
            radius = found.radius if found is not None and found.radius else default_radius
            out.append({"joint": name, "side": side, "x": x, "y": y, "z": z, "radius": radius})
    return out


def carried_by_body(tree: LinkTree, link: str) -> bool:
    """True when every joint between the root and ``link`` keeps it moving with the body.

    Fixed and prismatic joints do, and so do pivots about a horizontal axis (suspension arms);
    a pivot about a vertical axis (a swivel or steering joint) does not, nor does a floating or
    planar joint.
    """
    current, seen = link, set()
    while current in tree.parent_joint and current not in seen:
        seen.add(current)
        joint = tree.parent_joint[current]
        if joint.type in ("revolute", "continuous"):
            axis = mat_vec(tree.frame(joint.child).rot, joint.axis)
            if abs(axis[2]) >= PARALLEL:
                return False
        elif joint.type not in ("fixed", "prismatic"):
            return False
        current = joint.parent
    return True


def wheel_radius(tree: LinkTree, link: str, centre: Vec, axis_root: Vec,
                 meshes: bool = False) -> float | None:
    """The radius the wheel rolls on: the farthest any of the link's spheres, or cylinders along
    the spin axis, reaches from the spin axis through ``centre`` (a hub cylinder written before
    the tyre does not make the wheel smaller).

    With ``meshes``, a collision mesh counts too: its farthest vertex from the spin axis
    (exact for a meshed cylinder or tyre).
    """
    element = tree.links.get(link)
    if element is None:
        return None
    link_frame = tree.frame(link)
    reaches = []
    for collision in element.findall("collision"):
        geometry = collision.find("geometry")
        if geometry is None:
            continue
        frame = link_frame.compose(origin_frame(collision))
        sphere, cylinder, mesh = geometry.find("sphere"), geometry.find("cylinder"), geometry.find("mesh")
        if sphere is not None:
            reaches.append(_off_axis(frame.pos, centre, axis_root) + floats(sphere.get("radius"), 1, (0.0,))[0])
        elif cylinder is not None:
            along = mat_vec(frame.rot, (0.0, 0.0, 1.0))  # a URDF cylinder's axis is its local z
            if abs(sum(a * b for a, b in zip(along, axis_root))) >= PARALLEL:
                reaches.append(_off_axis(frame.pos, centre, axis_root)
                               + floats(cylinder.get("radius"), 1, (0.0,))[0])
        elif meshes and mesh is not None:
            reaches.append(_mesh_radius(mesh, frame, centre, axis_root) or 0.0)
    radius = round(max(reaches, default=0.0), 9)
    return radius or None


def _off_axis(point: Vec, centre: Vec, axis: Vec) -> float:
    """How far ``point`` is from the axis through ``centre`` along ``axis``."""
    d = [p - c for p, c in zip(point, centre)]
    norm = math.sqrt(sum(a * a for a in axis)) or 1.0
    along = sum(x * a for x, a in zip(d, axis)) / norm
    return math.sqrt(max(0.0, sum(x * x for x in d) - along * along))


def _mesh_radius(mesh: ET.Element, frame, centre: Vec, axis: Vec) -> float | None:
    """The farthest vertex of a mesh from the axis through ``centre`` (None when unreadable)."""
    import numpy as np

    from mobot_cli.common.meshfile import load_quietly  # trimesh: the cold load path only

    try:
        loaded = load_quietly(mesh.get("filename", ""), force="mesh")
        vertices = np.asarray(loaded.vertices, dtype=float)
    except Exception:  # noqa: BLE001 - an unreadable mesh simply gives no radius
        return None
    if len(vertices) == 0:
        return None
    unit = collada_unit_of(mesh.get("filename", ""))  # trimesh ignores a COLLADA <unit>
    scale = np.array(floats(mesh.get("scale"), 3, (1.0, 1.0, 1.0))) * unit
    points = (vertices * scale) @ np.array(frame.rot).T + np.array(frame.pos) - np.array(centre)
    direction = np.array(axis) / (np.linalg.norm(axis) or 1.0)
    off_axis = points - np.outer(points @ direction, direction)
    radius = float(np.linalg.norm(off_axis, axis=1).max())
    return round(radius, 9) or None
