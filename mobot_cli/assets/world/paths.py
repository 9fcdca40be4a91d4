"""Where SDF files and meshes are: model://, file://, relative URIs and Gazebo Fuel's cache.

``model://NAME`` is looked up beside the world first (the world's folder, its package root
and that package's ``models/``, and the folder holding every model read so far), then in
mobot's resource roots (DESIGN.md, "Resources"), which include ``GZ_SIM_RESOURCE_PATH`` and
``GAZEBO_MODEL_PATH``. ``https://`` URIs (Gazebo Fuel) are never downloaded: a model already
in Fuel's local cache (``gz fuel download``) is used, anything else is an error or, with
``--skip-missing``, a warning.

A live spawn of an SDF model reads only what its confinement allows (assets/sandbox.py): each
file and folder is checked before it is looked at, so a refusal says nothing of what is there.
"""

from __future__ import annotations

import os
import re
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import unquote, urlparse

from lxml import etree

from mobot_cli.assets import sandbox
from mobot_cli.assets.lenient import gazebo_xml_bytes
from mobot_cli.assets.resources import ResourceResolver, model_sdf
from mobot_cli.errors import Location, MobotError, Notice, WorldError

FUEL_CACHES = ("~/.gz/fuel", "~/.ignition/fuel")
SKIP_HINT = "Pass --skip-missing (or set skip_missing: true) to leave it out with a warning."
# More includes or meshes left out than this are reported in one notice, not one each.
GROUP_LEFT_OUT = 3


@dataclass(frozen=True)
class LeftOut:
    """An include or mesh left out under --skip-missing."""

    uri: str
    message: str  # the notice it gets on its own
    where: Location


def left_out_notices(items: list[LeftOut], roots: list[Path], file: Path) -> list[Notice]:
    """A notice per item, or, for many, one naming each model or file once and the folders once."""
    if len(items) <= GROUP_LEFT_OUT:
        return [Notice(item.message, item.where) for item in items]
    fuel: Counter = Counter()
    models: Counter = Counter()
    files: Counter = Counter()
    for item in items:
        if item.uri.startswith(("http://", "https://")):
            parts = [unquote(p) for p in urlparse(item.uri).path.split("/") if p]
            fuel[parts[-2] if len(parts) > 1 and parts[-1].isdigit() else parts[-1]] += 1
        elif item.uri.startswith("model://") and "not found. Folders searched" in item.message:
            models[unquote(item.uri[len("model://"):].partition("/")[0])] += 1
        else:
            files[item.uri] += 1

    def named(counter: Counter) -> str:
        return ", ".join(f"{k} x{n}" if n > 1 else k for k, n in sorted(counter.items()))

    parts = []
    if fuel:
        parts.append(f"{sum(fuel.values())} from Gazebo Fuel without a local copy (mobot never "
                     f"downloads; `gz fuel download -u URL` fills ~/.gz/fuel): {named(fuel)}")
    if models:
        parts.append(f"{sum(models.values())} models not found: {named(models)}. Folders searched: "
                     + "; ".join(str(r) for r in roots))
    if files:
        parts.append(f"{sum(files.values())} files not found: {named(files)}")
    return [Notice(f"{len(items)} includes and meshes left out (skip_missing): "
                   + "; ".join(parts), Location(file=file))]


class SdfPaths:
    """Resolves and parses the files of one world (or model) and remembers every file read."""

    def __init__(self, top: Path, resolver: ResourceResolver, xacro_args: dict[str, str] | None = None):
        self.resolver = resolver
        self.xacro_args = xacro_args or {}  # for a top file written as xacro (.sdf.xacro, .world.xacro)
        self.notices: list[Notice] = []  # xacro's, for the reader to pass on
        self.files: dict[Path, None] = {}  # every file read, in order (cache dependencies)
        self._trees: dict[Path, object] = {}
        self.local: list[Path] = []
        folder = Path(top).resolve().parent
        package = _package_root(folder)
        for root in (folder, folder.parent, package, package / "models" if package else None):
            self._add_local(root)

    def _add_local(self, root: Path | None) -> None:
        if root is not None and root not in self.local:
            self.local.append(root)

    @property
    def roots(self) -> list[Path]:
        """Every folder searched for model://NAME, in order."""
        return [*self.local, *(r for r in self.resolver.roots if r not in self.local)]

    def parse(self, path: Path):
        """The root element of an SDF file, parsed once; WorldError with the line when broken."""
        path = Path(path).resolve()
        if path in self._trees:
            return self._trees[path]
        parser = etree.XMLParser(remove_comments=True, remove_pis=True, resolve_entities=False)
        from mobot_cli.assets.description.xacro import is_xacro

        expanded = False
        sandbox.check(path, str(path))
        try:
            data = path.read_bytes()
            # by its name or its content, as a robot description: nav2's depot.sdf is xacro inside
            expanded = is_xacro(path, data.decode("utf-8", errors="replace"))
            data = self._expanded(path) if expanded else data
            root = etree.fromstring(gazebo_xml_bytes(declaration_first(data)), parser, base_url=str(path))
        except OSError as exc:
            raise WorldError(f"cannot read {path}: {exc}", location=Location(file=path),
                             hint="Check the path and the file's permissions.") from None
        except etree.XMLSyntaxError as exc:
            raise WorldError(f"malformed XML: {exc.msg}", location=Location(file=path, line=exc.lineno),
                             hint="Fix the XML (an unclosed tag or a stray '<' is typical).") from None
        if expanded:  # lines of the expansion are not the file's: name none
            for element in root.iter():
                element.sourceline = 0
        entity = next(root.iter(etree.Entity), None)  # left unexpanded (resolve_entities=False)
        if entity is not None:  # silently it would be no text: a <size> of nothing, a default box
            raise WorldError(f"the XML entity {entity.text} is not expanded: Gazebo's SDF reader does not "
                             "expand a DOCTYPE's entities", location=Location(file=path, line=entity.sourceline),
                             hint="Write the value itself where the entity stands.")
        if root.tag != "sdf":
            raise WorldError(f"the root element is <{root.tag}>, not <sdf>",
                             location=Location(file=path, line=root.sourceline),
                             hint="A URDF file is a robot description, not a world."
                             if root.tag == "robot" else "Gazebo files start with <sdf version=...>.")
        self.files[path] = None
        self._trees[path] = root
        return root

    def _expanded(self, path: Path) -> bytes:
        """An SDF file written as xacro (nav2's sandbox and depot worlds are), expanded as a robot
        description is."""
        from mobot_cli.assets.description.xacro import expand_file

        expansion = expand_file(path, self.xacro_args if not self.files else {}, self.resolver)
        for file in expansion.files[1:]:
            self.files[Path(file).resolve()] = None
        self.notices.extend(expansion.notices)
        return expansion.text.encode("utf-8")

    def find_model(self, name: str, where: Location) -> Path:
        """The folder of model NAME: ROOT/NAME or ROOT/models/NAME for the first root that has it."""
        for root in self.roots:
            for candidate in (root / name, root / "models" / name):
                if sandbox.allows(candidate) and candidate.is_dir():  # live spawns: inside their roots
                    self._add_local(candidate.parent)
                    return candidate
        listing = "; ".join(str(r) for r in self.roots if sandbox.allows(r))
        raise WorldError(f"model '{name}' not found. Folders searched: {listing}", location=where,
                         hint="Add the folder holding it to GAZEBO_MODEL_PATH, GZ_SIM_RESOURCE_PATH "
                              f"or MOBOT_RESOURCE_PATH (separated by '{os.pathsep}').")

    def include_file(self, uri: str, file: Path, where: Location, reader) -> Path | None:
        """The SDF file an include URI names; None when it is missing and skipping is on."""
        try:
            if uri.startswith(("http://", "https://")):
                folder = _fuel_cache(uri)
                if folder is None:
                    raise WorldError(
                        f"'{uri}' is on Gazebo Fuel and mobot never downloads: it needs a local copy",
                        location=where, hint="Run `gz fuel download -u \"URI\"` (mobot reads Fuel's "
                        "cache in ~/.gz/fuel), or copy the model into a folder on GAZEBO_MODEL_PATH "
                        f"and include it as model://NAME. {SKIP_HINT}")
            elif uri.startswith("model://"):
                name, _, rest = uri[len("model://"):].partition("/")
                folder = self.find_model(unquote(name), where) / unquote(rest)
            else:
                folder = self.local_file(uri, file, where)
            sandbox.check(folder, f"'{uri}' names {folder}, which")  # a Fuel cache, a model's subfolder
            target = model_sdf(folder) if folder.is_dir() else folder
        except MobotError as exc:
            if not reader.skip_missing:
                if isinstance(exc, WorldError):
                    raise
                raise WorldError(exc.message, location=where, hint=exc.hint) from None
            reader.left_out.append(LeftOut(uri, f"include left out: {exc.message}", where))
            return None
        if folder.is_dir() and (folder / "model.config").is_file():
            self.files[(folder / "model.config").resolve()] = None
        return target.resolve()

    def local_file(self, uri: str, file: Path, where: Location) -> Path:
        """A file:// URI, absolute path or path relative to ``file``, its package or the roots."""
        text = unquote(uri[len("file://"):] if uri.startswith("file://") else uri)
        text = os.path.expanduser(text)
        if "://" in text:
            raise WorldError(f"cannot resolve '{uri}': only model://, file://, package:// and "
                             "paths are supported", location=where,
                             hint="Nothing is fetched from the network; use a local copy.")
        if os.path.isabs(text):
            sandbox.check(text, f"'{uri}' names {text}, which")  # before looking: no existence oracle
            bases, rel = [Path("/")], text.lstrip("/")
        else:
            folder = Path(file).resolve().parent
            bases = [folder, _package_root(folder), *self.roots]
            bases = list(dict.fromkeys(b for b in bases if b is not None))
            rel = text
        bases = [base for base in bases if sandbox.allows(base / rel)]  # live spawns: inside their roots
        for base in bases:
            if (base / rel).exists():
                return (base / rel).resolve()
        for base in bases:
            real = case_variant(base / rel)
            if real is not None:
                raise WorldError(
                    f"'{uri}' not found: {real.parent} has '{real.name}', which differs only in "
                    f"case from '{Path(rel).name}'", location=where,
                    hint="File names are case-sensitive here: rename the file or fix the URI. "
                         + SKIP_HINT)
        raise WorldError(f"'{uri}' not found. Folders searched: "
                         + "; ".join(str(b) for b in bases), location=where,
                         hint="Check the file name; relative URIs are relative to the file that "
                              "names them or to its package.")

    def mesh_path(self, uri: str, file: Path, where: Location) -> Path:
        """The file of a <mesh><uri>; a located WorldError when it cannot be found."""
        if uri.startswith("model://"):
            name, _, rest = uri[len("model://"):].partition("/")
            path = self.find_model(unquote(name), where) / unquote(rest)
            sandbox.check(path, f"mesh '{uri}' names {path}, which")  # before looking
            if path.is_file():
                return path.resolve()
            real = case_variant(path)
            if real is not None:
                raise WorldError(f"mesh '{uri}' not found: {real.parent} has '{real.name}', which "
                                 f"differs only in case from '{path.name}'", location=where,
                                 hint="File names are case-sensitive here: rename the file or fix "
                                      "the URI. " + SKIP_HINT)
            raise WorldError(f"mesh '{uri}' not found: {path} does not exist", location=where,
                             hint="Check the file name and that the model folder is complete. "
                                  + SKIP_HINT)
        if uri.startswith("package://"):
            try:
                return self.resolver.resolve_uri(uri, file)
            except MobotError as exc:
                raise WorldError(exc.message, location=where, hint=exc.hint) from None
        if uri.startswith(("http://", "https://")):
            raise WorldError(f"mesh '{uri}' is on the network and mobot never downloads",
                             location=where, hint="Use a local copy of the mesh. " + SKIP_HINT)
        try:
            return self.local_file(uri, file, where)
        except WorldError as exc:
            hint = exc.hint if SKIP_HINT in (exc.hint or "") else f"{exc.hint} {SKIP_HINT}"
            raise WorldError(f"mesh {exc.message}", location=exc.location, hint=hint) from None


# Comments, whitespace or a byte-order mark before the <?xml ...?> declaration. XML forbids them
# (libxml2 refuses the file); Gazebo's parser, tinyxml2, reads on, and Gazebo's own cafe.world
# starts with a comment.
_LATE_DECLARATION = re.compile(rb"^((?:\xef\xbb\xbf)?(?:\s|<!--.*?-->)+)(<\?xml\b[^>]*\?>)", re.DOTALL)


def declaration_first(data: bytes) -> bytes:
    """The file's bytes with a late <?xml?> declaration moved to the front, lines kept."""
    match = _LATE_DECLARATION.match(data)
    if match is None:
        return data
    declaration = match.group(2)
    newlines = b"\n" * declaration.count(b"\n")  # every element keeps its line number
    return declaration.replace(b"\n", b" ") + match.group(1).replace(b"\xef\xbb\xbf", b"") \
        + newlines + data[match.end():]


def case_variant(path: Path) -> Path | None:
    """The existing path that matches ``path`` when case is ignored, if there is one."""
    path = Path(path)
    current = Path(path.anchor or ".")
    for part in path.parts[1:] if path.anchor else path.parts:
        exact = current / part
        if exact.exists():
            current = exact
            continue
        try:
            matches = [e for e in os.listdir(current) if e.lower() == part.lower()]
        except OSError:
            return None
        if not matches:
            return None
        current = current / sorted(matches)[0]
    return current if current != path else None


def _package_root(folder: Path) -> Path | None:
    for candidate in (folder, *folder.parents):
        if (candidate / "package.xml").is_file():
            return candidate
    return None


def _fuel_cache(uri: str) -> Path | None:
    """The newest local copy of a Fuel model URL in Gazebo's cache, if one was downloaded."""
    url = urlparse(uri)
    parts = [unquote(p) for p in url.path.split("/") if p]
    if len(parts) >= 2 and parts[0][:1].isdigit():  # ".../1.0/OWNER/models/NAME[/VERSION]"
        parts = parts[1:]
    if len(parts) < 3 or parts[1].lower() != "models":
        return None
    owner, name = parts[0].lower(), parts[2].lower()
    version = parts[3] if len(parts) > 3 and parts[3].isdigit() else None
    caches = [os.environ.get("GZ_FUEL_CACHE_PATH", ""), *FUEL_CACHES]
    for cache in filter(None, caches):
        folder = Path(cache).expanduser() / url.netloc / owner / "models" / name
        if not folder.is_dir():
            continue
        versions = sorted((p for p in folder.iterdir() if p.name.isdigit()),
                          key=lambda p: int(p.name))
        chosen = folder / version if version else (versions[-1] if versions else None)
        if chosen is not None and chosen.is_dir():
            return chosen
    return None
