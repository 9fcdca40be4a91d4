"""Collision meshes of static worlds, ready for PyBullet: COLLADA converted to OBJ once.

PyBullet cannot build a concave triangle mesh from COLLADA, and trimesh ignores COLLADA's
``<unit>`` (the AWS worlds are in centimetres). A .dae file is therefore loaded with trimesh
+ pycollada, its node transforms applied, scaled by its unit, and written as a plain OBJ in
the cache, keyed by the .dae file's content. ``<up_axis>`` is ignored, as Gazebo ignores it.
STL and OBJ files are used as they are, unless some of their triangles lie farther than
``FAR`` from the mesh's origin: exporters leave debris there (a SketchUp node at 8e17 m), which
no robot meets but which would stretch the world's extent and every map. Those triangles are
left out (counted in ``MeshFile.dropped`` for a warning) and the rest is written as an OBJ.
"""

from __future__ import annotations

import hashlib
import warnings
from dataclasses import dataclass
from pathlib import Path

from mobot_cli.common import cache
from mobot_cli.common.meshfile import collada_unit, obj_text
from mobot_cli.errors import Location, WorldError


@dataclass(frozen=True)
class MeshFile:
    """A mesh PyBullet can load, with what the world summary reports about it."""

    path: str  # what PyBullet loads: a cached OBJ for COLLADA, else the file itself
    source: str  # the file the SDF names
    triangles: int
    bounds: tuple[tuple[float, float, float], tuple[float, float, float]]  # in the mesh frame
    converted: bool  # a COLLADA file turned into OBJ
    dropped: int = 0  # triangles left out for lying farther than FAR from the mesh's origin
    farthest: float = 0.0  # m: the farthest vertex of those, for the warning


FAR = 10_000.0  # m from the mesh's origin: beyond, a triangle is exporter debris


def collision_mesh(source: Path, where: Location) -> MeshFile:
    """The PyBullet-ready version of a collision mesh (converted and cached when COLLADA)."""
    source = Path(source)
    try:
        data = source.read_bytes()
    except OSError as exc:
        raise WorldError(f"cannot read mesh {source}: {exc.strerror}", location=where,
                         hint="Check the file's permissions.") from None
    collada = source.suffix.lower() == ".dae"
    key = cache.digest("mesh", data)
    meta = cache.load("meshes", key)
    obj = None
    if isinstance(meta, dict) and collada:  # the OBJ is used only if its bytes are the ones noted
        obj = cache.load_file("meshes", f"{key}.obj", str(meta.get("obj_sha256")))
    if isinstance(meta, dict) and meta.get("dropped"):  # a cleaned STL or OBJ
        obj = cache.load_file("meshes", f"{key}.obj", str(meta.get("obj_sha256")))
        rewritten = True
    else:
        rewritten = collada
    hit = _from_meta(meta, source, obj if rewritten else source, collada) \
        if meta is not None and (obj is not None or not rewritten) else None
    if hit is not None:
        return hit
    vertices, faces = _load(source, data, collada, where)
    vertices, faces, dropped, farthest = _near(vertices, faces, source, where)
    meta = {"triangles": int(len(faces)), "dropped": dropped, "farthest": farthest,
            "bounds": [[float(v) for v in vertices.min(axis=0)],
                       [float(v) for v in vertices.max(axis=0)]]}
    rewritten = collada or dropped > 0
    if rewritten:
        text = obj_text(vertices, faces, f"collision mesh from {source.name}").encode("utf-8")
        meta["obj_sha256"] = hashlib.sha256(text).hexdigest()
        try:
            obj = cache.store_file("meshes", f"{key}.obj", text)
        except OSError as exc:
            raise WorldError(f"cannot write the converted mesh of {source.name}: {exc.strerror}",
                             location=where, hint="Free some disk space or set TMPDIR.") from None
    cache.store("meshes", key, meta)
    return _from_meta(meta, source, obj if rewritten else source, collada)  # type: ignore[return-value]


def _near(vertices, faces, source: Path, where: Location):
    """The triangles within FAR of the mesh's origin, their vertices renumbered; how many were
    left out and how far the farthest vertex of those lies (m)."""
    import numpy as np

    distance = np.linalg.norm(vertices, axis=1)
    far = ~np.isfinite(distance) | (distance > FAR)
    if not far.any():
        return vertices, faces, 0, 0.0
    bad = far[faces].any(axis=1)
    if bad.all():
        raise WorldError(f"mesh {source.name}: all of its {len(faces)} triangles lie more than "
                         f"{FAR / 1000:g} km from its origin", location=where,
                         hint="Re-export the mesh in metres, near its origin.")
    farthest = float(np.nan_to_num(distance[far], nan=np.inf, posinf=np.inf).max())
    kept = faces[~bad]
    used = np.unique(kept)
    renumber = np.full(len(vertices), -1, dtype=np.int64)
    renumber[used] = np.arange(len(used))
    return vertices[used], renumber[kept], int(bad.sum()), farthest


def _from_meta(meta, source: Path, path, collada: bool) -> MeshFile | None:
    """A MeshFile from cached facts, or None when they are not what this code writes."""
    try:
        (lo, hi), triangles = meta["bounds"], int(meta["triangles"])
        bounds = (tuple(float(v) for v in lo), tuple(float(v) for v in hi))
        if len(bounds[0]) != 3 or len(bounds[1]) != 3:
            return None
    except (KeyError, TypeError, ValueError):
        return None
    if "dropped" not in meta:
        return None
    return MeshFile(path=str(path), source=str(source), triangles=triangles,
                    bounds=bounds, converted=collada, dropped=int(meta["dropped"]),
                    farthest=float(meta.get("farthest", 0.0)))  # type: ignore[arg-type]


def _load(source: Path, data: bytes, collada: bool, where: Location):
    """Vertices (metres) and triangle indices of a mesh file."""
    import numpy as np

    loaded = _scene(source, where)
    try:
        with warnings.catch_warnings():  # trimesh's merging casts debris at 1e17 m to int64
            warnings.simplefilter("ignore", RuntimeWarning)
            merged = loaded.to_geometry() if hasattr(loaded, "to_geometry") else loaded.dump(concatenate=True)
    except Exception as exc:  # noqa: BLE001 - any parser failure is a broken mesh to the user
        raise WorldError(f"cannot read mesh {source.name}: {type(exc).__name__}: {exc}",
                         location=where, hint="Open and re-export the mesh (COLLADA, STL or OBJ).") \
            from None
    vertices = np.asarray(getattr(merged, "vertices", np.zeros((0, 3))), dtype=float)
    faces = np.asarray(getattr(merged, "faces", np.zeros((0, 3))), dtype=np.int64)
    if len(faces) == 0 or len(vertices) == 0:
        raise WorldError(f"mesh {source.name} has no triangles", location=where,
                         hint="A collision mesh needs triangles; check the exported file.")
    if collada:
        vertices = vertices * collada_unit(data)
    return vertices, faces


def submesh(source: Path, name: str, center: bool, where: Location) -> tuple[Path | None, list[str]]:
    """The part of a mesh file an SDF ``<submesh><name>`` selects, as Gazebo cuts it: the
    geometry of that name (or of the node of that name), its node transforms and the COLLADA
    unit applied, moved so its box's centre is the origin when ``center``; written once as an
    OBJ in the cache, keyed by the file's content, the name and ``center``. (None, the parts'
    names) when the file holds no part of that name."""
    import numpy as np

    source = Path(source)
    data = source.read_bytes()
    key = cache.digest("submesh", data, name, "centred" if center else "")
    meta = cache.load("meshes", key)
    if isinstance(meta, dict):
        kept = cache.load_file("meshes", f"{key}.obj", str(meta.get("obj_sha256")))
        if kept is not None:
            return Path(kept), []
    scene = _scene(source, where)
    named = _collada_names(data) if source.suffix.lower() == ".dae" else {}
    parts, names = [], []
    for node in scene.graph.nodes_geometry:
        transform, geometry = scene.graph[node]
        mesh = scene.geometry[geometry]
        # trimesh keys COLLADA parts by their ids; a <submesh> may give the id or the name
        called = {node, geometry, geometry.removeprefix("geom-"), named.get(node, ""), named.get(geometry, "")}
        names.append(named.get(geometry) or geometry.removeprefix("geom-"))
        if name in called:
            vertices = np.asarray(mesh.vertices, dtype=float) @ transform[:3, :3].T + transform[:3, 3]
            parts.append((vertices, np.asarray(mesh.faces, dtype=np.int64)))
    if not parts:
        return None, sorted(set(names))
    offsets = np.cumsum([0] + [len(v) for v, _ in parts[:-1]])
    vertices = np.vstack([v for v, _ in parts])
    faces = np.vstack([f + o for (_, f), o in zip(parts, offsets)])
    if source.suffix.lower() == ".dae":
        vertices = vertices * collada_unit(data)
    if center:
        vertices = vertices - (vertices.min(axis=0) + vertices.max(axis=0)) / 2.0
    text = obj_text(vertices, faces, f"<submesh> {name} of {source.name}").encode("utf-8")
    try:
        path = cache.store_file("meshes", f"{key}.obj", text)
    except OSError as exc:
        raise WorldError(f"cannot write the <submesh> {name} of {source.name}: {exc.strerror}",
                         location=where, hint="Free some disk space or set TMPDIR.") from None
    cache.store("meshes", key, {"obj_sha256": hashlib.sha256(text).hexdigest()})
    return Path(path), []


def _collada_names(data: bytes) -> dict[str, str]:
    """The name attribute of each <geometry> and <node> of a COLLADA document, by its id."""
    from lxml import etree

    try:
        root = etree.fromstring(data, etree.XMLParser(resolve_entities=False, no_network=True, huge_tree=True))
    except etree.XMLSyntaxError:
        return {}
    return {e.get("id"): e.get("name") for e in root.iter("{*}geometry", "{*}node") if e.get("id") and e.get("name")}


def _scene(source: Path, where: Location):
    """The mesh file as a trimesh scene; a located error when it cannot be parsed."""
    from mobot_cli.common.meshfile import load_quietly

    try:
        with warnings.catch_warnings():  # trimesh's merging casts debris at 1e17 m to int64
            warnings.simplefilter("ignore", RuntimeWarning)
            return load_quietly(source, force="scene")
    except Exception as exc:  # noqa: BLE001 - any parser failure is a broken mesh to the user
        raise WorldError(f"cannot read mesh {source.name}: {type(exc).__name__}: {exc}",
                         location=where, hint="Open and re-export the mesh (COLLADA, STL or OBJ).") from None
