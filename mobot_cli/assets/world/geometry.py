"""The <geometry> of an SDF collision or visual: primitives, planes and meshes."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from mobot_cli.assets.world import paths as sdf_paths
from mobot_cli.assets.world.frames import is_number, key_of
from mobot_cli.assets.world.pose import IDENTITY, Matrix
from mobot_cli.errors import Location, MobotError, WorldError

# Geometry mobot cannot collide with: warned about and left out (collisions only).
UNSUPPORTED = ("heightmap", "image")
# Shapes PyBullet has no primitive for: made meshes (world/solids.py)
SOLIDS = ("cone", "ellipsoid", "polyline")


@dataclass
class Shape:
    """One collision or visual geometry; ``pose`` is relative to its link."""

    kind: str  # box | cylinder | capsule | sphere | plane | mesh
    size: tuple[float, ...]  # box: x y z; cylinder, capsule: radius length; sphere: radius;
    #                          plane: normal; mesh: scale
    name: str
    location: Location
    mesh: Path | None = None  # the resolved mesh file
    uri: str = ""
    pose: Matrix = field(default_factory=lambda: IDENTITY.copy())
    friction: float | None = None  # min(mu, mu2) when the surface gives them
    # (mu, mu2, fdir1 text) when the surface gives both mu and an <fdir1>: anisotropic friction,
    # which the robot path keeps as written (description/process.py reads rollers from it)
    anisotropic: tuple[float, float, str] | None = None
    extent: tuple[float, float] | None = None  # a plane's <size>: it is finite (build.py)


def parse_shape(reader, element, file: Path, collision: bool) -> Shape | None:
    """The shape of a <collision> or <visual>; None for empty, unsupported or skipped ones."""
    where = key_of(element, file)
    geometry = element.find("geometry")
    kind_el = next((c for c in (geometry if geometry is not None else ()) if isinstance(c.tag, str)),
                   None)
    if kind_el is None or kind_el.tag == "empty":
        return None
    kind = kind_el.tag
    what = f"{element.tag} '{element.get('name', '')}'"
    if kind in SOLIDS:
        return _solid(reader, element, geometry, kind_el, file, collision, what)
    if kind in UNSUPPORTED or kind not in ("box", "cylinder", "capsule", "sphere", "plane", "mesh"):
        if collision:
            reader.warn(f"{what} uses <{kind}> geometry, which mobot does not simulate: it is "
                        "left out", key_of(kind_el, file))
            reader.ignored[f"{kind} geometry"] += 1
        return None
    shape = Shape(kind=kind, size=(), name=element.get("name", ""), location=where)
    if kind == "box":
        shape.size = reader.vector(kind_el, "size", file, (1.0, 1.0, 1.0))
    elif kind in ("cylinder", "capsule"):
        shape.size = (reader.number(kind_el, "radius", file, 0.5),
                      reader.number(kind_el, "length", file, 1.0))
    elif kind == "sphere":
        shape.size = (reader.number(kind_el, "radius", file, 1.0),)
    elif kind == "plane":
        shape.size = reader.vector(kind_el, "normal", file, (0.0, 0.0, 1.0))
        extent = reader.vector(kind_el, "size", file, (0.0, 0.0))
        if min(extent) > 0.0:
            shape.extent = extent  # type: ignore[assignment]
    else:
        if not _mesh(reader, shape, kind_el, file, collision, what):
            return None
    if kind != "plane" and any(v <= 0.0 for v in shape.size):
        raise WorldError(f"{what} has a <{kind}> with a size of zero or less: {shape.size}",
                         location=key_of(kind_el, file), hint="Sizes must be positive.")
    if kind == "plane" and sum(v * v for v in shape.size) < 1e-12:
        raise WorldError(f"{what} has a plane with a zero normal", location=key_of(kind_el, file),
                         hint="Give <normal> a direction, e.g. 0 0 1.")
    shape.friction = _friction(reader, element, file)
    shape.anisotropic = _anisotropic(reader, element, file)
    return shape


def _solid(reader, element, geometry, kind_el, file: Path, collision: bool, what: str) -> Shape | None:
    """A cone, ellipsoid or polyline as a mesh shape (its OBJ in the cache)."""
    from mobot_cli.assets.world import solids
    from mobot_cli.common import cache
    from mobot_cli.common.meshfile import obj_text

    kind = kind_el.tag
    where = key_of(kind_el, file)
    if kind == "cone":
        size = (reader.number(kind_el, "radius", file, 0.5), reader.number(kind_el, "length", file, 1.0))
    elif kind == "ellipsoid":
        size = reader.vector(kind_el, "radii", file, (1.0, 1.0, 1.0))
    else:
        outlines = [[_point(point, file) for point in line.findall("point")] for line in geometry.findall("polyline")]
        size = (reader.number(kind_el, "height", file, 1.0),)
    if any(v <= 0.0 for v in size):
        raise WorldError(f"{what} has a <{kind}> with a size of zero or less: {size}", location=where,
                         hint="Sizes must be positive.")
    if kind == "cone":
        vertices, faces = solids.cone(*size)
    elif kind == "ellipsoid":
        vertices, faces = solids.ellipsoid(size)
    else:
        vertices, faces, nested = solids.polyline(outlines, size[0])
        if not len(faces):
            if collision:
                reader.warn(f"{what} has a <polyline> without three distinct points: it is left out", where)
            return None
        if nested and collision:
            reader.warn(f"{what}: a <polyline> outline lies inside another; Gazebo makes it a hole, "
                        "mobot a solid of its own", where)
    text = obj_text(vertices, faces, f"SDF <{kind}> {size}").encode("utf-8")
    try:
        path = cache.store_file("meshes", f"{cache.digest(kind, text)}.obj", text)
    except OSError as exc:
        raise WorldError(f"cannot write the mesh of {what}'s <{kind}>: {exc.strerror}", location=where,
                         hint="Free some disk space or set TMPDIR.") from None
    shape = Shape(kind="mesh", size=(1.0, 1.0, 1.0), name=element.get("name", ""), location=key_of(element, file),
                  mesh=path, uri=f"<{kind}>")
    shape.friction = _friction(reader, element, file)
    shape.anisotropic = _anisotropic(reader, element, file)
    return shape


def _point(element, file: Path) -> tuple[float, float]:
    """A polyline's <point>: x y."""
    parts = (element.text or "").split()
    if len(parts) != 2 or not all(is_number(v) for v in parts):
        raise WorldError(f"<point> '{(element.text or '').strip()}' is not 2 numbers", location=key_of(element, file),
                         hint="Write x and y in metres, separated by a space.")
    return float(parts[0]), float(parts[1])


def _mesh(reader, shape: Shape, mesh, file: Path, collision: bool, what: str) -> bool:
    """Fill in a mesh shape; False when it is missing and may be skipped."""
    uri_el = mesh.find("uri")
    uri = (uri_el.text or "").strip() if uri_el is not None else ""
    where = key_of(uri_el if uri_el is not None else mesh, file)
    if not uri:
        raise WorldError(f"{what} has a <mesh> without <uri>", location=where,
                         hint="Add <uri>model://NAME/meshes/FILE</uri>.")
    shape.uri = uri
    shape.size = reader.vector(mesh, "scale", file, (1.0, 1.0, 1.0))
    if 0.0 in shape.size:  # Gazebo loads it flat; nothing can collide with a flat mesh
        if collision:
            scale = " ".join(f"{v:g}" for v in shape.size)
            reader.warn(f"{what}: mesh '{uri}' has a zero in its <scale> ({scale}), which "
                        "flattens it: left out", key_of(mesh.find("scale"), file))
        return False
    try:
        shape.mesh = reader.paths.mesh_path(uri, file, where)
    except MobotError as exc:
        if collision and not reader.skip_missing:
            raise
        if collision:
            reader.left_out.append(sdf_paths.LeftOut(uri, f"{what} left out: {exc.message}", where))
        else:
            reader.missing_visuals.append((uri, where))
        return False
    if shape.mesh.suffix.lower() not in (".dae", ".stl", ".obj"):
        if collision:
            raise WorldError(f"{what}: mesh '{uri}' is a {shape.mesh.suffix} file; mobot reads "
                             "COLLADA (.dae), STL and OBJ", location=where,
                             hint="Convert the mesh to one of those formats.")
        reader.missing_visuals.append((uri, where))
        return False
    if mesh.find("submesh") is not None and collision:
        _submesh(reader, shape, mesh.find("submesh"), uri, what, where)
    return True


def _submesh(reader, shape: Shape, element, uri: str, what: str, where: Location) -> None:
    """A collision <submesh>: the part of the mesh file it names (world/meshes.py), as Gazebo cuts
    it; the whole mesh, with a warning, when the file has no part of that name."""
    from mobot_cli.assets.world import meshes

    part = (element.findtext("name") or "").strip()
    center = (element.findtext("center") or "").strip().lower() in ("true", "1")
    cut, parts = meshes.submesh(shape.mesh, part, center, where)
    if cut is None:
        shown = ", ".join(repr(p) for p in parts[:8]) + (", ..." if len(parts) > 8 else "")
        reader.warn(f"{what} selects <submesh> {part!r} of '{uri}', which has no part of that name "
                    f"(its parts: {shown or 'none named'}): mobot collides with the whole mesh", where)
        return
    reader.paths.files[cut] = None  # a dependency of the cached world: made again when it is gone
    shape.mesh = cut


def _friction(reader, element, file: Path) -> float | None:
    ode = element.find("surface/friction/ode")
    if ode is None:
        return None
    values = [reader.number(ode, tag, file, -1.0) for tag in ("mu", "mu2")]
    values = [v for v in values if v >= 0.0]
    return min(values) if values else None


def _anisotropic(reader, element, file: Path) -> tuple[float, float, str] | None:
    ode = element.find("surface/friction/ode")
    fdir = ode.find("fdir1") if ode is not None else None
    if fdir is None or not (fdir.text or "").strip():
        return None
    mu, mu2 = (reader.number(ode, tag, file, 1.0) for tag in ("mu", "mu2"))  # SDF's defaults
    return mu, mu2, " ".join(fdir.text.split())
