"""Checks that keep an untrusted robot description from failing deep inside PyBullet.

Every number a URDF gives (origins, sizes, scales, masses, inertias, axes, limits) must be
finite; masses and inertia diagonals must not be negative; its collision meshes must be meshes;
it may have at most MAX_LINKS links, and at least one of them a collision shape (with none,
nothing holds it up: it falls through the floor). Each refusal names the file, the link or
joint and the element.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

from mobot_cli.errors import DescriptionError, Location

# PyBullet loads a multibody link by link and checks nothing on the way: a robot of thousands
# of links takes half a minute to fail with a bare "cannot load". Real robots have tens.
MAX_LINKS = 512

# The numeric attributes of a URDF, per element tag: (attribute, how many numbers).
_NUMBERS = {
    "origin": (("xyz", 3), ("rpy", 3)), "box": (("size", 3),), "cylinder": (("radius", 1), ("length", 1)),
    "sphere": (("radius", 1),), "mesh": (("scale", 3),), "mass": (("value", 1),),
    "inertia": tuple((name, 1) for name in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")),
    "axis": (("xyz", 3),), "limit": (("lower", 1), ("upper", 1), ("effort", 1), ("velocity", 1)),
    "dynamics": (("damping", 1), ("friction", 1)),
}


def check_sanity(robot: ET.Element, source: Path) -> None:
    """Refuse what PyBullet would choke on or silently drop; see the module docstring."""
    links = robot.findall("link")
    if len(links) > MAX_LINKS:
        raise DescriptionError(f"the robot has {len(links)} links, more than mobot's limit of {MAX_LINKS}",
                               location=Location(file=source),
                               hint="Merge links joined by fixed joints, or split the model.")
    if links and not any(link.find("collision") is not None for link in links):
        raise DescriptionError("the robot has no collision geometry: nothing would hold it up and it "
                               "would fall through the floor", location=Location(file=source),
                               hint="Add <collision> to its links (a box the size of its body will do).")
    for element in (*links, *robot.findall("joint")):
        _check_numbers(element, source)
    for link in links:
        _check_inertial(link, source)


def check_mesh_file(path: Path, link: str, source: Path) -> None:
    """A collision mesh that is not a mesh (empty, garbage, no triangles) is an error."""
    from mobot_cli.common.meshfile import load_quietly  # trimesh: cold loads only (then cached)

    where = f"collision mesh {path} of link '{link}'"
    try:
        loaded = load_quietly(path, force="mesh")
        faces = len(loaded.faces)
        finite = bool(faces) and bool(abs(loaded.vertices).max() < math.inf)
    except Exception as exc:  # noqa: BLE001 - trimesh raises whatever its parsers raise
        raise DescriptionError(f"{where} cannot be read as a mesh: {type(exc).__name__}: {str(exc).strip()}",
                               location=Location(file=source, key=f"link.{link}"),
                               hint="Check that the file is a valid STL, OBJ or COLLADA mesh.") from None
    if not finite:
        raise DescriptionError(f"{where} has no triangles (or non-finite vertices)",
                               location=Location(file=source, key=f"link.{link}"),
                               hint="Check that the file is a valid STL, OBJ or COLLADA mesh.")


def _check_numbers(element: ET.Element, source: Path) -> None:
    owner = f"{element.tag} '{element.get('name', '')}'"
    for child in element.iter():
        for attr, count in _NUMBERS.get(child.tag, ()):
            text = child.get(attr)
            if text is None:
                continue
            try:
                values = [float(v) for v in text.split()]
            except ValueError:
                values = None
            if values is None or len(values) != count or not all(math.isfinite(v) for v in values):
                raise DescriptionError(f"<{child.tag} {attr}=\"{text[:40]}\"> in {owner} is not "
                                       f"{count} finite number{'s' if count > 1 else ''}",
                                       location=Location(file=source, key=f"{element.tag}.{element.get('name', '')}"),
                                       hint="Give finite numbers (no nan, inf or text).")


def _check_inertial(link: ET.Element, source: Path) -> None:
    inertial = link.find("inertial")
    if inertial is None:
        return
    name = link.get("name", "")
    mass = inertial.find("mass")
    if mass is not None and float(mass.get("value", "0")) < 0:
        raise DescriptionError(f"link '{name}' has a negative mass ({mass.get('value')} kg)",
                               location=Location(file=source, key=f"link.{name}"),
                               hint="Masses are positive: give the link's mass in kilograms.")
    inertia = inertial.find("inertia")
    if inertia is None:
        return
    negative = [f"{k}={inertia.get(k)}" for k in ("ixx", "iyy", "izz") if float(inertia.get(k, "0")) < 0]
    if negative:
        raise DescriptionError(f"link '{name}' has a negative moment of inertia ({', '.join(negative)})",
                               location=Location(file=source, key=f"link.{name}"),
                               hint="The diagonal of an inertia tensor is positive (kg*m^2).")
