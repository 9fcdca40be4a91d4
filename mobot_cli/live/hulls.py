"""A spawned robot's collision meshes as the convex hulls PyBullet would build, built in the loader.

PyBullet collides the mesh of a moving link as the convex hull of its vertices (one hull per
``o``/``g`` group of an OBJ, tested), and builds it on the world's thread when the robot is
loaded, at a cost that grows with every face, while a hull already built has few vertices and
costs it little. So the loader process computes the hulls and the robot
reaches the world with small OBJ files of them: the same collision shape, its cost paid off the
world's thread. A hull of more than MAX_HULL_VERTICES vertices (a finely tessellated sphere
keeps all of them) is the hull of an even subset of them, slightly inside the original.
Static (massless) and ``concave="yes"`` links collide as triangle meshes and keep theirs, as
do COLLADA files (bounded by ``mobot serve --max-faces`` like every mesh).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from mobot_cli.common import cache

MAX_HULL_VERTICES = 1000
_HULLS: dict[tuple[str, int, int], Path | None] = {}  # by path, mtime and size: a warm loader reuses them


def hulled(urdf: str) -> str:
    """The URDF with each moving link's OBJ/STL collision mesh replaced by a file of its hulls."""
    root = ET.fromstring(urdf)
    changed = False
    for link in root.findall("link"):
        if link.get("concave") == "yes" or not _moves(link):
            continue
        for mesh in link.findall("collision/geometry/mesh"):
            filename = mesh.get("filename", "").removeprefix("file://")
            if filename.lower().endswith((".obj", ".stl")):
                out = _hull_file(Path(filename))
                if out is not None:
                    mesh.set("filename", str(out))
                    changed = True
    return ET.tostring(root, encoding="unicode") if changed else urdf


def _moves(link: ET.Element) -> bool:
    mass = link.find("inertial/mass")
    try:
        return mass is not None and float(mass.get("value", "0")) > 0
    except ValueError:
        return False


def _hull_file(path: Path) -> Path | None:
    """A cached OBJ of the hulls of ``path``'s parts; None to keep the file (unreadable, flat, ...)."""
    try:
        stat = path.stat()
    except OSError:
        return None
    key = (str(path), stat.st_mtime_ns, stat.st_size)
    if key not in _HULLS:
        _HULLS[key] = _make(path)
    return _HULLS[key]


def _make(path: Path) -> Path | None:
    try:  # a loader at a low --load-memory may not fit scipy: the mesh goes as it is (within --max-faces)
        from scipy.spatial import ConvexHull, QhullError
    except (ImportError, MemoryError):
        return None
    try:
        parts = _obj_parts(path) if path.suffix.lower() == ".obj" else [_stl_points(path)]
        lines: list[str] = []
        base = 1
        for index, points in enumerate(parts):
            hull = ConvexHull(points)
            if len(hull.vertices) > MAX_HULL_VERTICES:
                keep = hull.vertices[np.linspace(0, len(hull.vertices) - 1, MAX_HULL_VERTICES).astype(int)]
                hull = ConvexHull(points[keep])
            ids = np.full(len(hull.points), -1)
            ids[hull.vertices] = np.arange(len(hull.vertices)) + base
            lines.append(f"o hull{index}")
            lines.extend(f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in hull.points[hull.vertices])
            lines.extend(f"f {a} {b} {c}" for a, b, c in ids[hull.simplices])
            base += len(hull.vertices)
    except (OSError, ValueError, IndexError, QhullError):
        return None  # PyBullet gets the file itself (the loader has already checked it is a mesh)
    data = ("\n".join(lines) + "\n").encode()
    return cache.store_file("hulls", f"{cache.digest(data)[:32]}.obj", data, bounded=True)


def _obj_parts(path: Path) -> list[np.ndarray]:
    """The vertices each part of an OBJ uses, parts split at ``o``/``g`` lines as PyBullet's loader does."""
    from mobot_cli.common.meshfile import obj_groups

    vertices, groups = obj_groups(path.read_text(encoding="utf-8", errors="replace"))
    if not groups:
        raise ValueError("no faces")
    return [vertices[np.unique(faces)] for faces in groups]


def _stl_points(path: Path) -> np.ndarray:
    from mobot_cli.common.meshfile import read_mesh

    vertices, faces = read_mesh(str(path))
    if not len(faces):
        raise ValueError("no faces")
    return np.unique(vertices, axis=0)
