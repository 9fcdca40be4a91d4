"""The controllers a robot's ros2_control plugin loads, read from its parameters files.

Modern ROS 2 robots say how they drive in a controller_manager parameters file, not in a
Gazebo drive plugin: a ``gz_ros2_control-system`` (``ign_ros2_control-system``,
``libgazebo_ros2_control.so``) plugin names it in ``<parameters>``, and the controller there
(``diff_drive_controller/DiffDriveController``, ``mecanum_drive_controller/...``) turns
``cmd_vel`` into wheel speeds. drive.py drives the robot as that controller does.

The files are read as ``ros2 run`` reads parameters files: node names are the keys above
``ros__parameters`` (``/**/name``, ``/ns/name`` and nested namespaces alike, ``/**`` for every
node), nested maps are dotted parameter names, and a controller's type is either
``controller_manager``'s ``<name>.type`` or the controller's own ``type``. Only YAML data is
read (safe_load); a file that cannot be read is named in a notice and the drive is detected
from the geometry, as without the plugin.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from mobot_cli.assets import sandbox
from mobot_cli.assets.resources import ResourceResolver
from mobot_cli.errors import Location, MobotError, Notice

# A parameters file larger than this is not read (they are a few kB).
MAX_BYTES = 1_000_000
# ros2_controllers' drive controllers mobot reads (drive.py) or refuses, by package.
KNOWN_PACKAGES = ("diff_drive_controller", "mecanum_drive_controller", "ackermann_steering_controller",
                  "tricycle_controller", "tricycle_steering_controller", "bicycle_steering_controller",
                  "omni_wheel_drive_controller")
# What a plugin's name or file name holds when it is ros2_control's Gazebo plugin.
PLUGIN_WORDS = ("ros2_control",)


@dataclass(frozen=True)
class Controller:
    """One controller controller_manager would load: its name, type and parameters."""

    name: str
    type: str  # as written, e.g. "diff_drive_controller/DiffDriveController"
    params: dict[str, Any] = field(default_factory=dict)  # dotted names -> values
    file: Path | None = None

    @property
    def package(self) -> str:
        """The plugin's package, lower case: "diff_drive_controller"."""
        return self.type.partition("/")[0].strip().lower()

    @property
    def kind(self) -> str:
        """The controller as ros2_controllers names its package, also for a vendor's fork of one
        (``clearpath_mecanum_drive_controller/MecanumDriveController``): the package when it is
        one of those mobot reads, else the class name in snake case ("mecanum_drive_controller")."""
        package, _, cls = self.type.partition("/")
        package = package.strip().lower()
        if package in KNOWN_PACKAGES or not cls.strip():
            return package
        return re.sub(r"(?<=[a-z0-9])(?=[A-Z])", "_", cls.strip().rpartition("::")[2]).lower()

    def location(self, parameter: str = "") -> Location:
        key = f"{self.name}.{parameter}" if parameter else self.name
        return Location(file=self.file, key=key)


def read(robot: ET.Element, resolver: ResourceResolver, source: Path,
         notices: list[Notice]) -> tuple[tuple[Controller, ...], dict[str, str | None]]:
    """Every controller the robot's ros2_control plugins load, in file order, and the files
    read (URI as written -> path, None where it leads nowhere: kept so a cached description
    goes stale when one changes)."""
    found: list[Controller] = []
    files: dict[str, str | None] = {}
    for uri in _parameter_uris(robot):
        path = _resolve(uri, resolver, source, notices)
        files[uri] = str(path) if path is not None else None
        if path is not None:
            found += _controllers(path, source, notices)
    return tuple(found), files


def _parameter_uris(robot: ET.Element) -> list[str]:
    uris = []
    for gazebo in robot.findall("gazebo"):
        for plugin in gazebo.findall("plugin"):
            words = f"{plugin.get('name', '')} {plugin.get('filename', '')}".lower()
            if any(w in words for w in PLUGIN_WORDS):
                uris += [(p.text or "").strip() for p in plugin.findall("parameters") if (p.text or "").strip()]
    return list(dict.fromkeys(uris))


def _resolve(uri: str, resolver: ResourceResolver, source: Path, notices: list[Notice]) -> Path | None:
    """The parameters file's path; None, with a notice, where it cannot be read."""
    written = uri
    if uri.startswith("$(find ") and ")" in uri:  # a URDF written out without xacro's expansion
        package, _, rest = uri[len("$(find "):].partition(")")
        uri = f"package://{package.strip()}/{rest.lstrip('/')}"
    why = ""
    try:
        path = resolver.resolve_uri(uri, source)
    except MobotError as exc:
        why = exc.message
    else:
        if not sandbox.allows(path):
            why = "it lies outside the folders this spawn may read"
        elif not path.is_file():
            why = f"{path} is not a file"
        elif path.stat().st_size > MAX_BYTES:
            why = f"{path} is larger than {MAX_BYTES // 1000} kB"
        else:
            return path
    notices.append(Notice(f"the ros2_control plugin's parameters file '{written}' cannot be read ({why}): "
                          "the drive is detected from the wheels' geometry instead, not from its "
                          "controller", Location(file=source)))
    return None


def _controllers(path: Path, source: Path, notices: list[Notice]) -> list[Controller]:
    try:
        document = yaml.load(path.read_text(encoding="utf-8"), Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as exc:
        mark = getattr(exc, "problem_mark", None)
        line = mark.line + 1 if mark else None
        notices.append(Notice(f"the ros2_control parameters file {path} is not readable YAML "
                              f"({getattr(exc, 'problem', None) or type(exc).__name__}): the drive is detected "
                              "from the wheels' geometry instead", Location(file=path, line=line)))
        return []
    nodes = _nodes(document)
    every = nodes.pop("**", {})
    types: dict[str, str] = {}
    for key, value in nodes.get("controller_manager", {}).items():
        name, dot, last = key.rpartition(".")
        if dot and last == "type" and isinstance(value, str):
            types[name] = value
    for name, params in nodes.items():
        if isinstance(params.get("type"), str) and name != "controller_manager":
            types.setdefault(name, params["type"])
    return [Controller(name, kind, {**every, **nodes.get(name, {})}, path) for name, kind in types.items()]


def _nodes(document: Any) -> dict[str, dict[str, Any]]:
    """Node name (the last part of its key, "**" for every node) -> its parameters, dotted."""
    out: dict[str, dict[str, Any]] = {}

    def walk(value: Any, path: list[str]) -> None:
        if not isinstance(value, dict):
            return
        for key, child in value.items():
            if key == "ros__parameters":
                if isinstance(child, dict):
                    out.setdefault(path[-1] if path else "**", {}).update(_dotted(child))
            elif isinstance(key, str):
                walk(child, path + [part for part in key.split("/") if part])

    walk(document, [])
    return out


def _dotted(params: dict, prefix: str = "") -> dict[str, Any]:
    flat: dict[str, Any] = {}
    for key, value in params.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            flat.update(_dotted(value, name + "."))
        else:
            flat[name] = value
    return flat


def names(controller: Controller, *keys: str) -> list[str]:
    """Joint names under the first of ``keys`` present: a list, or one name."""
    for key in keys:
        value = controller.params.get(key)
        if isinstance(value, str) and value.strip():
            return [value.strip()]
        if isinstance(value, list):
            return [str(v).strip() for v in value if str(v).strip()]
    return []


def number(controller: Controller, *keys: str) -> float | None:
    """The first of ``keys`` that holds a positive number."""
    for key in keys:
        value = controller.params.get(key)
        if isinstance(value, (int, float)) and not isinstance(value, bool) and value > 0:
            return float(value)
    return None
