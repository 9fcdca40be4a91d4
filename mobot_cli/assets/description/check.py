"""Reject URDFs that PyBullet would load wrongly or not at all, with messages that say why."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from mobot_cli.errors import DescriptionError, Location, did_you_mean

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")


def parse_urdf(text: str, source: Path) -> ET.Element:
    """Parse URDF text into its <robot> element; XML errors name the file and line."""
    try:
        robot = ET.fromstring(text)
    except ET.ParseError as exc:
        line = exc.position[0] if exc.position else None
        raise DescriptionError(f"XML syntax error in the robot description: {exc}",
                               location=Location(file=source, line=line),
                               hint="Check that every tag is closed and every attribute value "
                                    "is quoted.") from None
    if robot.tag != "robot":
        raise DescriptionError(f"the top element is <{robot.tag}>, not <robot>",
                               location=Location(file=source),
                               hint="A URDF file holds one <robot name=...> element; for SDF "
                                    "models use a world file instead.")
    return robot


def check_tree(robot: ET.Element, source: Path) -> str:
    """Check links and joints form one tree; return the root link's name."""
    def fail(message: str, hint: str, key: str | None = None) -> DescriptionError:
        return DescriptionError(message, location=Location(file=source, key=key), hint=hint)

    links = [link.get("name") for link in robot.findall("link")]
    if not links:
        raise fail("the robot has no <link> elements", "A URDF needs at least one <link name=...>.")
    if any(not name for name in links):
        raise fail("a <link> has no name attribute", "Give every <link> a unique name.")
    duplicates = sorted({n for n in links if links.count(n) > 1})
    if duplicates:
        raise fail(f"link name(s) used more than once: {', '.join(duplicates)}",
                   "Link names must be unique (xacro prefixes help).")
    known = set(links)
    parents: dict[str, str] = {}
    joint_names: set[str] = set()
    for joint in robot.findall("joint"):
        name = joint.get("name") or "(unnamed)"
        key = f"joint.{name}"
        if name in joint_names:
            raise fail(f"joint name '{name}' is used more than once", "Joint names must be unique.",
                       key)
        joint_names.add(name)
        kind = joint.get("type")
        if kind not in JOINT_TYPES:
            raise fail(f"joint '{name}' has type '{kind}'",
                       "Use one of " + ", ".join(JOINT_TYPES) + ". "
                       + did_you_mean(str(kind), JOINT_TYPES), key)
        ends = {}
        for end in ("parent", "child"):
            element = joint.find(end)
            link = element.get("link") if element is not None else None
            if not link:
                raise fail(f"joint '{name}' has no <{end} link=...>",
                           f"Add <{end} link=\"...\"/> to the joint.", key)
            if link not in known:
                raise fail(f"joint '{name}' names {end} link '{link}', which does not exist",
                           did_you_mean(link, known) or "Add the link or fix the name.", key)
            ends[end] = link
        if ends["child"] in parents:
            raise fail(f"link '{ends['child']}' is the child of two joints "
                       f"('{parents[ends['child']]}' and '{name}')",
                       "A URDF is a tree: every link has at most one parent joint.", key)
        parents[ends["child"]] = name
    roots = [n for n in links if n not in parents]
    if len(roots) != 1:
        detail = (f"links {', '.join(repr(r) for r in roots)} have no parent joint" if roots
                  else "every link has a parent joint (the joints form a loop)")
        raise fail(f"the links do not form one tree: {detail}",
                   "Connect every link to the root with exactly one chain of joints.")
    _check_reachable(robot, roots[0], known, source)
    return roots[0]


def _check_reachable(robot: ET.Element, root: str, links: set[str], source: Path) -> None:
    children: dict[str, list[str]] = {}
    for joint in robot.findall("joint"):  # check_tree made sure both ends exist
        parent = joint.find("parent").get("link")  # type: ignore[union-attr]
        children.setdefault(parent, []).append(joint.find("child").get("link"))  # type: ignore
    seen, stack = {root}, [root]
    while stack:
        for child in children.get(stack.pop(), []):
            if child not in seen:
                seen.add(child)
                stack.append(child)
    lost = sorted(links - seen)
    if lost:
        raise DescriptionError(f"links in a loop, not connected to root '{root}': "
                               + ", ".join(lost), location=Location(file=source),
                               hint="A URDF is a tree: remove the joint that closes the loop.")


_SHAPES = {"box": ("size", 3), "cylinder": ("radius", 1), "sphere": ("radius", 1),
           "mesh": ("filename", 0)}


def check_geometry(robot: ET.Element, source: Path) -> None:
    """Every <visual>/<collision> has exactly one shape with its size attributes."""
    for link in robot.findall("link"):
        name = link.get("name")
        for kind in ("visual", "collision"):
            for element in link.findall(kind):
                geometry = element.find("geometry")
                shapes = [c for c in (geometry if geometry is not None else []) if c.tag in _SHAPES]
                if len(shapes) != 1:
                    raise DescriptionError(
                        f"a <{kind}> of link '{name}' has {len(shapes)} shapes in its <geometry>",
                        location=Location(file=source, key=f"link.{name}"),
                        hint="Put exactly one of <box>, <cylinder>, <sphere>, <mesh> in it.")
                shape = shapes[0]
                attr, count = _SHAPES[shape.tag]
                needed = [(attr, count)] + ([("length", 1)] if shape.tag == "cylinder" else [])
                for attr, count in needed:
                    if not _valid(shape.get(attr), count):
                        raise DescriptionError(
                            f"the <{shape.tag}> of a <{kind}> of link '{name}' has "
                            f"{attr}={shape.get(attr)!r}",
                            location=Location(file=source, key=f"link.{name}"),
                            hint=f"Give <{shape.tag}> a valid {attr}.")


def _valid(value: str | None, count: int) -> bool:
    if value is None or not value.strip():
        return False
    if count == 0:
        return True
    try:
        numbers = [float(v) for v in value.split()]
    except ValueError:
        return False
    return len(numbers) == count and all(n >= 0 for n in numbers)


def check_with_yourdfpy(text: str, source: Path) -> None:
    """Run yourdfpy's own validation (geometry, limits, attributes) on the text."""
    import yourdfpy
    from lxml import etree  # lazy, with yourdfpy: only a cold load pays for them

    try:
        parser = etree.XMLParser(remove_blank_text=True, remove_comments=True)
        element = etree.fromstring(text.encode("utf-8"), parser=parser)
        robot = yourdfpy.URDF._parse_robot(xml_element=element)  # noqa: SLF001 - no public hook in yourdfpy
        model = yourdfpy.URDF(robot=robot, build_scene_graph=False, load_meshes=False)
        valid = model.validate(validation_fn=lambda errors: not errors)
    except DescriptionError:
        raise
    except Exception as exc:  # noqa: BLE001 - yourdfpy raises bare KeyError/AttributeError
        raise DescriptionError(f"the URDF is malformed: {type(exc).__name__}: {exc}",
                               location=Location(file=source),
                               hint="Check required attributes (name, size, radius, length, "
                                    "filename) and elements (<geometry>, <mass>).") from None
    if not valid:
        messages = "; ".join(dict.fromkeys(str(e) for e in model.errors))
        raise DescriptionError(f"the URDF is incomplete: {messages}",
                               location=Location(file=source),
                               hint="Fix the elements named above.")
