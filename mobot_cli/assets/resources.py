"""Find packages, models and files the way ROS and Gazebo do, without a ROS install.

Search roots, in order (DESIGN.md, "Resources"): the scenario's folder, the bundled
``robots/`` and ``worlds/``, then ``MOBOT_RESOURCE_PATH``, ``ROS_PACKAGE_PATH``,
``AMENT_PREFIX_PATH`` (``<prefix>/share``), ``GZ_SIM_RESOURCE_PATH`` and ``GAZEBO_MODEL_PATH``.
Nothing is ever fetched from the network.
"""

from __future__ import annotations

import os
import threading
from pathlib import Path
from urllib.parse import unquote

from mobot_cli.assets import sandbox
from mobot_cli.errors import Location, ResourceError

# Environment variables holding extra search roots, in search order.
PATH_VARIABLES = ("MOBOT_RESOURCE_PATH", "ROS_PACKAGE_PATH", "AMENT_PREFIX_PATH",
                  "GZ_SIM_RESOURCE_PATH", "GAZEBO_MODEL_PATH")

# rospack crawls package roots recursively; a few levels is enough for a workspace's src/
# and keeps a root such as $HOME from turning into a crawl of the whole disk.
_CRAWL_DEPTH = 4
_CRAWL_MAX_DIRS = 5000
_IGNORE_MARKERS = ("CATKIN_IGNORE", "COLCON_IGNORE", "AMENT_IGNORE")

_PACKAGE_ROOT = Path(__file__).resolve().parent.parent  # mobot_cli/
_index_lock = threading.Lock()
_index_cache: dict[tuple[str, int], dict[str, Path]] = {}

HINT = "Add the folder holding it to MOBOT_RESOURCE_PATH (folders separated by '{sep}')."


def bundled_dir(kind: str) -> Path:
    """The folder of bundled ``robots`` or ``worlds``: in the wheel, else in the repository."""
    if kind not in ("robots", "worlds"):
        raise ValueError(f"unknown bundled kind {kind!r}")
    installed = _PACKAGE_ROOT / "_data" / kind
    if installed.is_dir():
        return installed
    return _PACKAGE_ROOT.parent / kind


def _package_name(package_xml: Path) -> str | None:
    """The <name> of a package.xml, read with a cheap scan (no XML parser needed)."""
    try:
        text = package_xml.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return None
    start = text.find("<name>")
    end = text.find("</name>", start)
    if start < 0 or end < 0:
        return None
    return text[start + len("<name>"):end].strip() or None


def _crawl(root: Path, depth: int) -> dict[str, Path]:
    """Map package name -> folder for every package.xml under root, like rospack."""
    found: dict[str, Path] = {}
    stack = [(root, 0)]
    visited = 0
    while stack and visited < _CRAWL_MAX_DIRS:
        folder, level = stack.pop()
        visited += 1
        try:
            entries = sorted(os.scandir(folder), key=lambda e: e.name)
        except OSError:
            continue
        names = {e.name for e in entries}
        if any(marker in names for marker in _IGNORE_MARKERS):
            continue
        if "package.xml" in names:
            name = _package_name(Path(folder) / "package.xml")
            if name and name not in found:
                found[name] = Path(folder)
            continue  # like rospack: packages do not nest
        if level >= depth:
            continue
        subdirs = [e for e in entries if not e.name.startswith(".") and _is_dir(e)]
        stack.extend((Path(e.path), level + 1) for e in reversed(subdirs))
    return found


def _is_dir(entry: os.DirEntry) -> bool:
    try:
        return entry.is_dir()
    except OSError:
        return False


def _package_index(root: Path, depth: int) -> dict[str, Path]:
    """The crawl of one root, done once per process."""
    key = (str(root), depth)
    with _index_lock:
        if key not in _index_cache:
            _index_cache[key] = _crawl(root, depth)
        return _index_cache[key]


def _split_env(name: str) -> list[Path]:
    value = os.environ.get(name, "")
    return [Path(part).expanduser() for part in value.split(os.pathsep) if part.strip()]


class ResourceResolver:
    """Resolves ``package://``, ``model://``, ``file://``, ``$(find)`` and relative paths."""

    def __init__(self, base_dir: Path | None = None):
        # (root, crawl depth): ament prefixes hold packages exactly one level below share/.
        roots: list[tuple[Path, int]] = []
        if base_dir is not None:
            roots.append((Path(base_dir), _CRAWL_DEPTH))
        roots.append((bundled_dir("robots"), _CRAWL_DEPTH))
        roots.append((bundled_dir("worlds"), _CRAWL_DEPTH))
        for var in PATH_VARIABLES:
            for path in _split_env(var):
                if var == "AMENT_PREFIX_PATH":
                    roots.append((path / "share", 1))
                else:
                    roots.append((path, _CRAWL_DEPTH))
        seen: set[str] = set()
        self._roots: list[tuple[Path, int]] = []
        for path, depth in roots:
            resolved = path.resolve()
            if str(resolved) not in seen:
                seen.add(str(resolved))
                self._roots.append((resolved, depth))

    @property
    def roots(self) -> tuple[Path, ...]:
        """Every search root, in search order."""
        return tuple(path for path, _ in self._roots)

    def fingerprint(self) -> str:
        """A string that changes whenever the search roots change (for cache keys)."""
        return os.pathsep.join(f"{path}#{depth}" for path, depth in self._roots)

    def find_package(self, name: str, referenced_from: Path | None = None) -> Path:
        """The folder of package NAME: a package.xml naming it, or a folder of that name."""
        return self._find_package(name, referenced_from, f"package '{name}'")

    def _find_package(self, name: str, referenced_from: Path | None, what: str) -> Path:
        for root, depth in self._roots:
            hit = _package_index(root, depth).get(name)
            if hit is not None:
                return hit
            if (root / name).is_dir():
                return root / name
        # Last resort: the package the referencing file itself lives in, so a description
        # naming its own package (package://my_robot/meshes/... from my_robot/urdf/) works
        # before any search path is set.
        own = None
        if referenced_from is not None:
            own = _enclosing_package(Path(referenced_from).resolve().parent)
        if own is not None and name in (_package_name(own / "package.xml"), own.name):
            return own
        raise self._missing(what, referenced_from)

    def find_model(self, name: str, referenced_from: Path | None = None) -> Path:
        """The folder of Gazebo model NAME: ``<root>/NAME`` or ``<root>/models/NAME``."""
        return self._find_model(name, referenced_from, f"model '{name}'")

    def _find_model(self, name: str, referenced_from: Path | None, what: str) -> Path:
        for root, _ in self._roots:
            for candidate in (root / name, root / "models" / name):
                if candidate.is_dir():
                    return candidate
        raise self._missing(what, referenced_from)

    def resolve_uri(self, uri: str, referenced_from: Path | None) -> Path:
        """The absolute path a resource URI or relative path names; ResourceError if absent."""
        uri = uri.strip()
        if uri.startswith("package://"):
            package, _, rest = uri[len("package://"):].partition("/")
            folder = self._find_package(package, referenced_from,
                                        f"package '{package}' (for '{uri}')")
            return self._existing(folder / unquote(rest), uri, referenced_from)
        if uri.startswith("model://"):
            model, _, rest = uri[len("model://"):].partition("/")
            folder = self._find_model(model, referenced_from, f"model '{model}' (for '{uri}')")
            return self._existing(folder / unquote(rest), uri, referenced_from)
        if uri.startswith("file://"):
            path = unquote(uri[len("file://"):])
        elif "://" in uri:
            raise ResourceError(
                f"cannot resolve '{uri}': only package://, model:// and file:// URIs and "
                "local paths are supported; nothing is fetched from the network",
                location=Location(file=referenced_from),
                hint="Download the resource and refer to it by a local path.")
        else:
            path = uri
        path = os.path.expanduser(path)
        if os.path.isabs(path):
            return self._existing(Path(path), uri, referenced_from)
        for folder in self._relative_bases(referenced_from):
            candidate = folder / path
            if candidate.exists() and sandbox.allows(candidate):  # live spawns: inside their roots
                return candidate.resolve()
        raise self._missing(f"'{uri}'", referenced_from, self._relative_bases(referenced_from))

    def _relative_bases(self, referenced_from: Path | None) -> list[Path]:
        # A relative path is relative to the referencing file, then to its package's root
        # (bookstore meshes use file://models/... from inside models/NAME/), then to the roots.
        bases: list[Path] = []
        if referenced_from is not None:
            folder = Path(referenced_from).resolve().parent
            bases.append(folder)
            package_root = _enclosing_package(folder)
            if package_root is not None and package_root != folder:
                bases.append(package_root)
        bases.extend(path for path, _ in self._roots if path not in bases)
        return bases

    def _existing(self, path: Path, uri: str, referenced_from: Path | None) -> Path:
        sandbox.check(path, f"'{uri}' names {path}, which")  # before looking: no existence oracle
        if path.exists():
            return path.resolve()
        raise ResourceError(
            f"'{uri}' points to {path}, which does not exist",
            location=Location(file=referenced_from),
            hint="The package was found but this file is not in it: check the file name "
                 "(case matters) and that the package is complete.")

    def _missing(self, what: str, referenced_from: Path | None,
                 searched: list[Path] | None = None) -> ResourceError:
        folders = searched if searched is not None else list(self.roots)
        listing = "; ".join(str(f) for f in folders) or "(none)"
        return ResourceError(
            f"{what} not found. Folders searched: {listing}.",
            location=Location(file=referenced_from),
            hint=HINT.format(sep=os.pathsep))


def model_sdf(model_dir: Path) -> Path:
    """The SDF file of a Gazebo model folder, as its model.config names it (newest version)."""
    import xml.etree.ElementTree as ET

    from mobot_cli.assets.lenient import gazebo_xml

    config = Path(model_dir) / "model.config"
    candidates: list[tuple[tuple[int, ...], str]] = []
    try:
        text = gazebo_xml(config.read_text(encoding="utf-8", errors="replace"))
        for sdf in ET.fromstring(text).findall("sdf"):
            version = tuple(int(p) for p in (sdf.get("version") or "0").split(".") if p.isdigit())
            if (sdf.text or "").strip():
                candidates.append((version, sdf.text.strip()))
    except (OSError, ET.ParseError):
        pass  # no or broken model.config: Gazebo falls back to model.sdf as well
    names = [name for _, name in sorted(candidates, key=lambda c: c[0], reverse=True)]
    for name in [*names, "model.sdf"]:
        if (Path(model_dir) / name).is_file():
            return (Path(model_dir) / name).resolve()
    raise ResourceError(f"model folder {model_dir} has no SDF file "
                        f"(model.config names: {', '.join(names) or 'none'})",
                        location=Location(file=config),
                        hint="A Gazebo model folder needs model.config and the SDF file it names.")


def _enclosing_package(folder: Path) -> Path | None:
    """The nearest folder at or above ``folder`` holding a package.xml, if any."""
    for candidate in (folder, *folder.parents):
        if (candidate / "package.xml").is_file():
            return candidate
    return None
