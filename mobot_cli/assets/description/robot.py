"""An expanded robot description (URDF text) to a checked RobotDescription, cached by content.

A cold load checks the URDF with yourdfpy, resolves meshes, fixes inertials and friction and
detects the drive; the result is cached on disk by content, so a warm load of the same
description reads one JSON file and never imports yourdfpy or trimesh.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from mobot_cli.assets import sandbox
from mobot_cli.assets.description import ros2_control
from mobot_cli.assets.description.check import check_geometry, check_tree, check_with_yourdfpy, parse_urdf
from mobot_cli.assets.description.drive import detect
from mobot_cli.assets.description.frames import LinkTree, floats
from mobot_cli.assets.description.grip import slipping_wheels
from mobot_cli.assets.description.joints import read_holds
from mobot_cli.assets.description.process import (
    apply_friction,
    collision_bounds,
    fix_inertials,
    inertial_values,
    mesh_path_or_none,
    readable_collisions,
    resolve_meshes,
)
from mobot_cli.assets.description.sanity import check_mesh_file, check_sanity
from mobot_cli.assets.description.sensors import DescribedSensor, collision_names, read_sensors, sensor_summary
from mobot_cli.assets.description.wheels import wheel_layout, why_not_wheels
from mobot_cli.assets.description.xacro import Expansion
from mobot_cli.assets.lenient import gazebo_xml
from mobot_cli.assets.resources import ResourceResolver
from mobot_cli.common import cache
from mobot_cli.errors import DescriptionError, Location, Notice
from mobot_cli.plan import DriveSpec, JointHold
from mobot_cli.sim.bullet.urdf_file import UnwritableURDF, pybullet_text

MAX_FINGERPRINTS = 16  # search paths an entry remembers agreeing with (folders run from)

# The notice for a robot without detected wheels; a scenario that names them drops it.
NO_DRIVE = "no drive wheels found: the robot will not move on commands"


@dataclass(frozen=True)
class LinkInfo:
    """A link's name and its mass as written in the file (0 without <inertial>)."""

    name: str
    mass: float
    has_inertial: bool
    collisions: tuple[str, ...] = ()  # Gazebo's names of its <collision>s (LINK_collision, ...)


@dataclass(frozen=True)
class JointInfo:
    """A joint as written in the file."""

    name: str
    type: str
    parent: str
    child: str
    axis: tuple[float, float, float]
    xyz: tuple[float, float, float]
    rpy: tuple[float, float, float]


@dataclass(frozen=True)
class RobotDescription:
    """A checked robot: the URDF text for PyBullet plus what `mobot inspect` shows."""

    source: Path
    name: str
    urdf: str  # meshes absolute, tiny inertials and PyBullet friction injected
    root_link: str
    links: tuple[LinkInfo, ...]
    joints: tuple[JointInfo, ...]
    total_mass: float  # kg, as written in the file
    footprint: tuple[float, float, float, float]  # xmin, xmax, ymin, ymax; root frame
    drive: DriveSpec | None
    notices: tuple[Notice, ...] = ()
    bottom_z: float = 0.0  # lowest collision point in the root frame, all joints at zero
    top_z: float = 0.0  # highest collision point in the root frame, all joints at zero
    files: tuple[Path, ...] = field(default=())  # the description and every file it included
    sensors: tuple[DescribedSensor, ...] = ()  # from its <gazebo><sensor> blocks
    holds: tuple[JointHold, ...] = ()  # springs and held joints (assets/description/joints.py)
    refused_drive: str = ""  # a drive mobot cannot simulate (tracks, ...), named; "" otherwise

    def tree(self) -> dict[str, Any]:
        """The link tree as nested dicts: {link, mass, children: [{joint, type, link...}]}."""
        masses = {link.name: link.mass for link in self.links}
        below: dict[str, list[JointInfo]] = {}
        for joint in self.joints:
            below.setdefault(joint.parent, []).append(joint)

        def node(link: str, seen: frozenset[str]) -> dict[str, Any]:
            children = [dict(joint=j.name, type=j.type, **node(j.child, seen | {link}))
                        for j in below.get(link, []) if j.child not in seen]
            return {"link": link, "mass": masses.get(link, 0.0), "children": children}

        return node(self.root_link, frozenset())


def describe_expansion(source: Path, expansion: Expansion, resolver: ResourceResolver,
                       skip_missing: bool = False) -> RobotDescription:
    """Check, cache and describe an expanded URDF text (from xacro or converted from SDF).

    The search paths (the scenario's folder among them) matter only through where the mesh
    URIs lead, so an entry serves any search paths under which each of its URIs leads to the
    same file (or to none) as when it was made: a scenario in a new folder does not check the
    description again (slow: the check imports yourdfpy). Search paths seen to agree are noted
    in the entry, so their next run skips the comparison."""
    key = cache.digest("robot", expansion.text, str(source), *(["skip_missing"] if skip_missing else []))
    document = cache.load("robot", key)
    loaded = _from_document(document)
    if loaded is not None and resolver.fingerprint() not in document["fingerprints"]:
        if _same_meshes(document["uris"], resolver, source):
            document["fingerprints"] = [*document["fingerprints"][1 - MAX_FINGERPRINTS:], resolver.fingerprint()]
            cache.store("robot", key, document)
        else:
            loaded = None
    if loaded is None:
        loaded, found = _build(source, expansion, resolver, skip_missing)
        cache.store("robot", key, _to_document(loaded, found, resolver.fingerprint()))
    return RobotDescription(**{**_fields(loaded), "notices": expansion.notices + loaded.notices,
                               "files": expansion.files})


def _same_meshes(uris: list, resolver: ResourceResolver, source: Path) -> bool:
    """Whether each mesh URI of a cached entry leads where it led (or still nowhere) under
    these search paths."""
    try:
        return all(mesh_path_or_none(uri, resolver, source) == path for uri, path in uris)
    except (TypeError, ValueError):  # an entry written by hand, or torn
        return False


def _build(source: Path, expansion: Expansion, resolver: ResourceResolver,
           skip_missing: bool = False) -> tuple[RobotDescription, dict[str, str | None]]:
    text = gazebo_xml(expansion.text)  # what Gazebo's parsers accept (assets/lenient.py)
    robot = parse_urdf(text, source)
    root_link = check_tree(robot, source)
    check_geometry(robot, source)
    check_with_yourdfpy(text, source)
    check_sanity(robot, source)
    notices: list[Notice] = []
    found = resolve_meshes(robot, resolver, source, skip_missing, notices)
    if not any(link.find("collision") is not None for link in robot.findall("link")):
        raise DescriptionError(
            "the robot has no collision geometry left: its collision meshes cannot be found and "
            "were left out (skip_missing), so nothing would hold it up", location=Location(file=source),
            hint="Make the collision meshes findable (MOBOT_RESOURCE_PATH), or add <collision> shapes.")
    for link in robot.findall("link"):
        for mesh in link.findall("collision/geometry/mesh"):
            check_mesh_file(Path(mesh.get("filename", "")), link.get("name", ""), source)
    for obj in readable_collisions(robot, source):  # an absolute path leads to itself under any search paths
        found[obj] = obj  # kept with the entry: a converted file removed since makes it stale
    links = tuple(_link_info(link) for link in robot.findall("link"))
    joints = tuple(_joint_info(joint) for joint in robot.findall("joint"))
    notices += fix_inertials(robot, source)
    sensors = read_sensors(robot, source, notices)
    friction = apply_friction(robot)
    bounds = collision_bounds(LinkTree(robot), source, notices)
    controllers, parameter_files = ros2_control.read(robot, resolver, source, notices)
    found.update(parameter_files)  # an edited parameters file makes the cached entry stale, as a mesh does
    detected = detect(robot, notices=notices, source=source, controllers=controllers)
    drive = detected.spec
    if drive is None and not detected.refused:  # a refused drive was named in its own notice
        why = why_not_wheels(LinkTree(robot))
        notices.append(Notice(f"{NO_DRIVE} ({why})" if why else NO_DRIVE, Location(file=source)))
    holds = read_holds(robot, drive, notices, source)
    notices += [n for n in (slipping_wheels(robot, drive, friction, source),) if n is not None]
    try:  # written once as PyBullet reads it whole, so `check` fails where `run` would
        urdf = pybullet_text('<?xml version="1.0"?>\n' + ET.tostring(robot, encoding="unicode"))
    except UnwritableURDF as exc:
        raise UnwritableURDF(exc.message, location=Location(file=source), hint=exc.hint) from None
    description = RobotDescription(
        source=source, name=robot.get("name", ""), urdf=urdf, root_link=root_link,
        links=links, joints=joints, total_mass=sum(link.mass for link in links),
        footprint=bounds[:4], drive=drive, notices=tuple(notices), bottom_z=bounds[4], top_z=bounds[5],
        sensors=sensors, holds=holds, refused_drive=detected.refused)
    return description, found


def _link_info(link: ET.Element) -> LinkInfo:
    inertial = link.find("inertial")
    return LinkInfo(name=link.get("name", ""), mass=inertial_values(inertial)[0],
                    has_inertial=inertial is not None, collisions=collision_names(link))


def _joint_info(joint: ET.Element) -> JointInfo:
    origin = joint.find("origin")
    axis = joint.find("axis")

    def get(element: ET.Element | None, attr: str, default: tuple[float, ...]):
        return floats(element.get(attr) if element is not None else None, 3, default)

    return JointInfo(
        name=joint.get("name", ""), type=joint.get("type", ""),
        parent=joint.find("parent").get("link", ""),  # type: ignore[union-attr]
        child=joint.find("child").get("link", ""),  # type: ignore[union-attr]
        axis=get(axis, "xyz", (1.0, 0.0, 0.0)), xyz=get(origin, "xyz", (0.0, 0.0, 0.0)),
        rpy=get(origin, "rpy", (0.0, 0.0, 0.0)))  # type: ignore[arg-type]


def _fields(description: RobotDescription) -> dict[str, Any]:
    return {name: getattr(description, name) for name in description.__dataclass_fields__}


def _to_document(description: RobotDescription, found: dict[str, str | None],
                 fingerprint: str) -> dict[str, Any]:
    document = asdict(description)
    document["source"] = str(description.source)
    document["files"] = []
    document["notices"] = [
        {"message": n.message,
         "location": {"file": str(n.location.file) if n.location.file is not None else None,
                      "line": n.location.line, "key": n.location.key}}
        for n in description.notices]
    document["meshes"] = [[path, *_stat(path)] for path in dict.fromkeys(p for p in found.values() if p is not None)]
    document["uris"] = [[uri, path] for uri, path in found.items()]  # checked under other search paths
    document["fingerprints"] = [fingerprint]  # search paths under which they lead there
    return document


def _stat(path: str) -> tuple[int, int]:
    try:
        info = os.stat(path)
    except OSError:
        return (-1, -1)
    return (info.st_size, info.st_mtime_ns)


def _from_document(document: dict[str, Any] | None) -> RobotDescription | None:
    """Rebuild a cached description; None when absent, stale or from another layout."""
    if not document:
        return None
    try:
        # A mesh edited or removed since the entry was written makes it stale.
        if any(list(_stat(path)) != [size, mtime] for path, size, mtime in document["meshes"]):
            return None
        if not all(sandbox.allows(path) for path, _, _ in document["meshes"]):  # live spawns
            return None
        if not isinstance(document["uris"], list) or not isinstance(document["fingerprints"], list):
            return None  # an entry from before URIs were kept
        drive = document["drive"]
        if drive is not None:
            drive = DriveSpec(**{key: _tuples(value) for key, value in drive.items()})
        return RobotDescription(
            source=Path(document["source"]), name=document["name"], urdf=document["urdf"],
            root_link=document["root_link"],
            links=tuple(LinkInfo(**{**link, "collisions": tuple(link["collisions"])})
                        for link in document["links"]),
            joints=tuple(JointInfo(**{k: tuple(v) if isinstance(v, list) else v
                                      for k, v in joint.items()})
                         for joint in document["joints"]),
            total_mass=document["total_mass"], footprint=tuple(document["footprint"]),
            drive=drive, bottom_z=document["bottom_z"], top_z=document["top_z"],
            refused_drive=document.get("refused_drive", ""),
            sensors=tuple(DescribedSensor(**{k: tuple(v) if isinstance(v, list) else v
                                             for k, v in sensor.items()})
                          for sensor in document["sensors"]),
            holds=tuple(JointHold(**hold) for hold in document.get("holds", ())),
            notices=tuple(Notice(n["message"], Location(**n["location"]))
                          for n in document["notices"]))
    except (KeyError, TypeError, ValueError):
        return None


def _wheels(desc: RobotDescription) -> list[dict[str, Any]]:
    drive = desc.drive
    if drive is None:
        return []
    tree = LinkTree(ET.fromstring(desc.urdf))
    return wheel_layout(tree, drive.left_joints, drive.right_joints, drive.wheel_radius)


def _tuples(value: Any) -> Any:
    """JSON lists back to the tuples they were (a DriveSpec holds tuples, some of pairs)."""
    return tuple(_tuples(v) for v in value) if isinstance(value, list) else value


def inspect_summary(desc: RobotDescription) -> dict[str, Any]:
    """What `mobot inspect` shows, as plain data: tree, mass, footprint, drive, sensors, notices."""
    xmin, xmax, ymin, ymax = desc.footprint
    return {
        "name": desc.name,
        "source": str(desc.source),
        "root_link": desc.root_link,
        "links": len(desc.links),
        "joints": len(desc.joints),
        "total_mass": desc.total_mass,
        "footprint": {"xmin": xmin, "xmax": xmax, "ymin": ymin, "ymax": ymax,
                      "length": round(xmax - xmin, 9), "width": round(ymax - ymin, 9)},
        "bottom_z": desc.bottom_z,
        "top_z": desc.top_z,
        "tree": desc.tree(),
        "drive": drive_summary(desc.drive),
        "drive_type": desc.drive.kind if desc.drive is not None else None,
        "refused_drive": desc.refused_drive or None,
        "wheels": _wheels(desc),
        "sensors": [sensor_summary(s) for s in desc.sensors],
        "notices": [str(n) for n in desc.notices],
    }


def drive_summary(drive: DriveSpec | None) -> dict[str, Any] | None:
    """A drive as `inspect` shows it: its fields, and a car's minimum turning radius (m)."""
    if drive is None:
        return None
    summary = asdict(drive)
    if drive.kind == "ackermann" and drive.max_steering_angle:
        from mobot_cli.sim.steering import min_turning_radius

        summary["min_turning_radius"] = round(min_turning_radius(drive.wheelbase, drive.max_steering_angle), 6)
    return summary
