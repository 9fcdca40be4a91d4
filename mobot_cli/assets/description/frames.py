"""The link tree of a URDF and each link's pose in the root frame, in plain Python.

Drive detection and footprints only need a handful of 3x3 products at zero joint
positions (common.transforms), so this avoids both numpy and yourdfpy's scene graph (and
their import time).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

from mobot_cli.common.transforms import Frame, Vec, rpy_matrix
from mobot_cli.errors import DescriptionError, Location, did_you_mean


def floats(text: str | None, count: int, default: tuple[float, ...]) -> tuple[float, ...]:
    """Parse 'a b c'; the default when absent or malformed (the checks report those)."""
    if text is None:
        return default
    try:
        values = tuple(float(part) for part in text.split())
    except ValueError:
        return default
    return values if len(values) == count else default


def origin_frame(element: ET.Element | None) -> Frame:
    """The <origin xyz rpy> child of an element as a Frame (identity when absent)."""
    origin = element.find("origin") if element is not None else None
    if origin is None:
        return Frame()
    xyz = floats(origin.get("xyz"), 3, (0.0, 0.0, 0.0))
    rpy = floats(origin.get("rpy"), 3, (0.0, 0.0, 0.0))
    return Frame(rpy_matrix(*rpy), xyz)  # type: ignore[arg-type]


@dataclass(frozen=True)
class JointRow:
    """One <joint> as drive detection needs it."""

    name: str
    type: str
    parent: str
    child: str
    origin: Frame
    axis: Vec
    lower: float | None
    upper: float | None


class LinkTree:
    """The links and joints of a URDF <robot> element, with root-frame poses at zero."""

    def __init__(self, robot: ET.Element):
        self.robot = robot
        self.links: dict[str, ET.Element] = {}
        for link in robot.findall("link"):
            self.links.setdefault(link.get("name", ""), link)
        self.joints: list[JointRow] = [_joint_row(j) for j in robot.findall("joint")]
        self.parent_joint = {j.child: j for j in self.joints}
        roots = [name for name in self.links if name not in self.parent_joint]
        self.root = roots[0] if roots else None
        self._frames: dict[str, Frame] = {}

    def frame(self, link: str) -> Frame:
        """The pose of ``link`` in the root link's frame, all joints at zero."""
        if link in self._frames:
            return self._frames[link]
        chain = []
        current, seen = link, set()
        while current in self.parent_joint and current not in seen:
            seen.add(current)
            joint = self.parent_joint[current]
            chain.append(joint)
            current = joint.parent
        frame = Frame()
        for joint in reversed(chain):
            frame = frame.compose(joint.origin)
        self._frames[link] = frame
        return frame


def _joint_row(joint: ET.Element) -> JointRow:
    parent = joint.find("parent")
    child = joint.find("child")
    axis = floats(joint.find("axis").get("xyz") if joint.find("axis") is not None else None,
                  3, (1.0, 0.0, 0.0))  # URDF's default axis is x
    norm = math.sqrt(sum(a * a for a in axis)) or 1.0
    limit = joint.find("limit")
    lower = upper = None
    if limit is not None:
        lower = floats(limit.get("lower"), 1, (0.0,))[0]
        upper = floats(limit.get("upper"), 1, (0.0,))[0]
    return JointRow(
        name=joint.get("name", ""), type=joint.get("type", ""),
        parent=parent.get("link", "") if parent is not None else "",
        child=child.get("link", "") if child is not None else "",
        origin=origin_frame(joint),
        axis=(axis[0] / norm, axis[1] / norm, axis[2] / norm),
        lower=lower, upper=upper)


def movable_joint(tree: LinkTree, name: str, who: str, location: Location, hint: str,
                  place: str = "the URDF") -> JointRow:
    """The movable joint ``name`` that ``who`` names ("the X plugin names left_joint"), or a
    located DescriptionError saying it is fixed or not in ``place``, with the nearest movable name."""
    joints = {j.name: j for j in tree.joints}
    found = joints.get(name)
    if found is None or found.type == "fixed":
        problem = "is fixed" if found is not None else f"is not in {place}"
        raise DescriptionError(f"{who} '{name}', which {problem}", location=location,
                               hint=did_you_mean(name, [n for n, j in joints.items() if j.type != "fixed"]) or hint)
    return found
