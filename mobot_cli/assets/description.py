"""Load a robot description (bundled name, URDF or xacro) into a checked RobotDescription.

A cold load expands the xacro, checks the URDF with yourdfpy, resolves meshes, fixes
inertials and friction and detects the drive; the result is cached on disk by content, so a
warm load of the same description reads one JSON file and never imports yourdfpy or trimesh.
"""

from __future__ import annotations

import os
import re
import xml.etree.ElementTree as ET
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Mapping

from mobot_cli.assets import cache, sandbox
from mobot_cli.assets.drive_detect import detect_drive
from mobot_cli.assets.frames import LinkTree, floats
from mobot_cli.assets.resources import ResourceResolver, bundled_dir, model_sdf
from mobot_cli.assets.urdf_check import check_geometry, check_tree, check_with_yourdfpy, \
    parse_urdf
from mobot_cli.assets.urdf_process import apply_friction, collision_bounds, fix_inertials, \
    inertial_values, resolve_meshes
from mobot_cli.assets.xacro_expand import Expansion, expand_file
from mobot_cli.errors import Location, Notice, ResourceError, did_you_mean
from mobot_cli.sim.plan import DriveSpec

_SUFFIXES = (".urdf", ".xacro", ".sdf")
_MESH_ATTR = re.compile(r"(<mesh\b[^>]*?\bfilename\s*=\s*)([\"'])(.*?)\2", re.DOTALL)


@dataclass(frozen=True)
class LinkInfo:
    """A link's name and its mass as written in the file (0 without <inertial>)."""

    name: str
    mass: float
    has_inertial: bool


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
    files: tuple[Path, ...] = field(default=())  # the description and every file it included

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


def bundled_robot_names() -> tuple[str, ...]:
    """Names usable as `description:`, one per folder of the bundled robots/."""
    root = bundled_dir("robots")
    if not root.is_dir():
        return ()
    return tuple(sorted(p.name for p in root.iterdir() if _bundled_file(p) is not None))


def _bundled_file(folder: Path) -> Path | None:
    for suffix in (".urdf.xacro", ".xacro", ".urdf"):
        candidate = folder / "urdf" / f"{folder.name}{suffix}"
        if candidate.is_file():
            return candidate
    return None


def resolve_description(description: str, base_dir: Path | None,
                        resolver: ResourceResolver) -> Path:
    """The file a `description:` value names: a bundled name, a path or a package:// URI."""
    text = str(description).strip()
    if "://" in text:
        return _model_file(resolver.resolve_uri(text, None))
    if text.endswith(_SUFFIXES) or "/" in text or os.sep in text:
        path = Path(text).expanduser()
        if not path.is_absolute():
            path = Path(base_dir or Path.cwd()) / path
        path = _model_file(path)
        if not path.is_file():
            raise ResourceError(f"robot description file {path} does not exist",
                                location=Location(file=path),
                                hint="Relative paths are relative to the scenario's folder.")
        return path.resolve()
    names = bundled_robot_names()
    if text in names:
        return _bundled_file(bundled_dir("robots") / text).resolve()  # type: ignore[union-attr]
    raise ResourceError(
        f"'{text}' is neither a bundled robot nor a .urdf/.xacro file",
        hint=(did_you_mean(text, names) + " " if names else "")
        + "Give a bundled name or a path to a .urdf, .urdf.xacro or .xacro file.")


def load_robot(description: str, args: Mapping[str, str] | None = None,
               base_dir: Path | None = None) -> RobotDescription:
    """Load, check and cache a robot description for the simulation."""
    resolver = ResourceResolver(base_dir)
    source = resolve_description(description, base_dir, resolver)
    if source.suffix == ".sdf":  # a Gazebo model: converted to URDF, then the same path
        from mobot_cli.assets.sdf_description import expand_sdf

        expansion = expand_sdf(source, resolver)
    else:
        expansion = expand_file(source, args or {}, resolver)
    return describe_expansion(source, expansion, resolver)


def describe_expansion(source: Path, expansion: Expansion,
                       resolver: ResourceResolver) -> RobotDescription:
    """Check, cache and describe an expanded URDF text (from xacro or converted from SDF)."""
    key = cache.digest("robot", expansion.text, resolver.fingerprint(), str(source))
    loaded = _from_document(cache.load("robot", key))
    if loaded is None:
        loaded, meshes = _build(source, expansion, resolver)
        cache.store("robot", key, _to_document(loaded, meshes))
    return RobotDescription(**{**_fields(loaded), "notices": expansion.notices + loaded.notices,
                               "files": expansion.files})


def _model_file(path: Path) -> Path:
    """A Gazebo model folder stands for the SDF file its model.config names."""
    if Path(path).is_dir() and (Path(path) / "model.config").is_file():
        return model_sdf(Path(path))
    return Path(path)


def _build(source: Path, expansion: Expansion,
           resolver: ResourceResolver) -> tuple[RobotDescription, list[str]]:
    robot = parse_urdf(expansion.text, source)
    root_link = check_tree(robot, source)
    check_geometry(robot, source)
    check_with_yourdfpy(expansion.text, source)
    meshes = resolve_meshes(robot, resolver, source)
    links = tuple(_link_info(link) for link in robot.findall("link"))
    joints = tuple(_joint_info(joint) for joint in robot.findall("joint"))
    notices = fix_inertials(robot, source)
    apply_friction(robot)
    bounds = collision_bounds(LinkTree(robot), source, notices)
    drive = detect_drive(robot, notices=notices, source=source)
    if drive is None:
        notices.append(Notice("no drive wheels found: the robot will not move on commands",
                              Location(file=source)))
    urdf = '<?xml version="1.0"?>\n' + ET.tostring(robot, encoding="unicode")
    description = RobotDescription(
        source=source, name=robot.get("name", ""), urdf=urdf, root_link=root_link,
        links=links, joints=joints, total_mass=sum(link.mass for link in links),
        footprint=bounds[:4], drive=drive, notices=tuple(notices), bottom_z=bounds[4])
    return description, meshes


def _link_info(link: ET.Element) -> LinkInfo:
    inertial = link.find("inertial")
    return LinkInfo(name=link.get("name", ""), mass=inertial_values(inertial)[0],
                    has_inertial=inertial is not None)


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


def _to_document(description: RobotDescription, meshes: list[str]) -> dict[str, Any]:
    document = asdict(description)
    document["source"] = str(description.source)
    document["files"] = []
    document["notices"] = [
        {"message": n.message,
         "location": {"file": str(n.location.file) if n.location.file is not None else None,
                      "line": n.location.line, "key": n.location.key}}
        for n in description.notices]
    document["meshes"] = [[path, *_stat(path)] for path in dict.fromkeys(meshes)]
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
        drive = document["drive"]
        if drive is not None:
            drive = DriveSpec(**{**drive, "left_joints": tuple(drive["left_joints"]),
                                 "right_joints": tuple(drive["right_joints"]),
                                 "joint_signs": tuple(tuple(s) for s in drive["joint_signs"])})
        return RobotDescription(
            source=Path(document["source"]), name=document["name"], urdf=document["urdf"],
            root_link=document["root_link"],
            links=tuple(LinkInfo(**link) for link in document["links"]),
            joints=tuple(JointInfo(**{k: tuple(v) if isinstance(v, list) else v
                                      for k, v in joint.items()})
                         for joint in document["joints"]),
            total_mass=document["total_mass"], footprint=tuple(document["footprint"]),
            drive=drive, bottom_z=document["bottom_z"],
            notices=tuple(Notice(n["message"], Location(**n["location"]))
                          for n in document["notices"]))
    except (KeyError, TypeError, ValueError):
        return None


def expand_to_text(description: str, args: Mapping[str, str] | None = None,
                   base_dir: Path | None = None) -> str:
    """The expanded URDF as `mobot xacro` prints it: xacro output, mesh paths made absolute."""
    resolver = ResourceResolver(base_dir)
    source = resolve_description(description, base_dir, resolver)
    text = expand_file(source, args or {}, resolver).text

    def absolute(match: re.Match) -> str:
        path = resolver.resolve_uri(match.group(3), source)
        return f"{match.group(1)}{match.group(2)}{path}{match.group(2)}"

    return _MESH_ATTR.sub(absolute, text)


def inspect_summary(desc: RobotDescription) -> dict[str, Any]:
    """What `mobot inspect` shows, as plain data: tree, mass, footprint, drive, notices."""
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
        "tree": desc.tree(),
        "drive": asdict(desc.drive) if desc.drive is not None else None,
        "notices": [str(n) for n in desc.notices],
    }
