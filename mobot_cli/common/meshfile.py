"""Vertices and triangles of OBJ and STL files, read with numpy alone.

The floor plan and the lidar's world scene need only triangles; importing trimesh is slow,
slower than drawing a whole house. World meshes reach the plan as OBJ (COLLADA is
converted to OBJ by the world loader) or STL, which these readers cover; anything else goes
to trimesh.
"""

from __future__ import annotations

import functools
import re
from pathlib import Path

import numpy as np

# <triangles count="N">, <polylist count="N">, ...: polygons of a COLLADA geometry
_DAE_COUNT = re.compile(rb'<(?:triangles|polylist|polygons|trifans|tristrips)\b[^>]*?\bcount="(\d{1,12})"')
_STL_TRIANGLE = np.dtype([("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])


def read_mesh(path: str) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (n, 3) and triangle indices (m, 3); empty arrays when the file is unreadable.

    The arrays are read-only: the last files read are kept (by path, size and modification
    time), since a world's floor, floor plan and lidar scene read each of its meshes, and a
    furnished world places one mesh file dozens of times."""
    try:
        stat = Path(path).stat()
        key = (str(path), stat.st_size, stat.st_mtime_ns)
    except OSError:
        return _read(str(path))
    return _kept(key)


@functools.lru_cache(maxsize=256)
def _kept(key: tuple[str, int, int]) -> tuple[np.ndarray, np.ndarray]:
    vertices, faces = _read(key[0])
    vertices.flags.writeable = False
    faces.flags.writeable = False
    return vertices, faces


def load_quietly(path, **options):
    """``trimesh.load`` with trimesh's logging held back: it logs a whole traceback for every
    texture or material it cannot read (rmf_demos' Caddy: "unable to load bumpmap"), which looks
    like a crash to a user, and collisions need no textures."""
    import logging

    import trimesh

    logger = logging.getLogger("trimesh")  # its modules' loggers inherit the level
    level = logger.level
    logger.setLevel(logging.CRITICAL + 1)
    try:
        return trimesh.load(str(path), **options)
    finally:
        logger.setLevel(level)


def _read(path: str) -> tuple[np.ndarray, np.ndarray]:
    suffix = Path(path).suffix.lower()
    try:
        if suffix == ".obj":
            return _obj(Path(path).read_text(encoding="utf-8", errors="replace"))
        if suffix == ".stl":
            return _stl(Path(path).read_bytes())
        mesh = load_quietly(path, force="mesh", process=False)
        return np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces, dtype=int)
    except Exception:  # noqa: BLE001 - the world loader already vetted it; the plan is drawn anyway
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=int)


def _obj(text: str) -> tuple[np.ndarray, np.ndarray]:
    fast = _plain_obj(text)
    if fast is not None:
        return fast
    vertices, groups = obj_groups(text)
    return vertices, np.concatenate(groups) if groups else np.zeros((0, 3), dtype=int)


def _plain_obj(text: str) -> tuple[np.ndarray, np.ndarray] | None:
    """An OBJ of "v x y z" and "f a b c" lines only (as mobot writes converted meshes), read by
    numpy at once; None for anything else (texture or normal indices, polygons, negative
    indices, vertex colours), which obj_groups reads line by line."""
    lines = text.splitlines()
    v = [line[2:] for line in lines if line.startswith("v ")]
    f = [line[2:] for line in lines if line.startswith("f ")]
    if any("/" in line or "-" in line for line in f):
        return None
    try:
        vertices = np.array(" ".join(v).split(), dtype=float)
        faces = np.array(" ".join(f).split(), dtype=np.int64)
    except ValueError:
        return None
    if vertices.size != 3 * len(v) or faces.size != 3 * len(f):
        return None
    vertices, faces = vertices.reshape(-1, 3), faces.reshape(-1, 3) - 1
    return vertices, faces[(faces >= 0).all(axis=1) & (faces < len(vertices)).all(axis=1)]


def obj_groups(text: str) -> tuple[np.ndarray, list[np.ndarray]]:
    """Vertices (n, 3) and the triangles of each part, parts split at ``o``/``g`` lines as
    PyBullet's OBJ loader splits them; a part without faces is left out."""
    vertices: list[list[float]] = []
    groups: list[list[tuple[int, int, int]]] = [[]]
    for line in text.splitlines():
        if line.startswith("v "):
            vertices.append([float(v) for v in line.split()[1:4]])
        elif line.startswith("f "):
            # "f 1 2 3", "f 1/1/1 2/2/2 3/3/3", negative = from the end; polygons become fans
            idx = [int(part.split("/")[0]) for part in line.split()[1:]]
            idx = [i - 1 if i > 0 else len(vertices) + i for i in idx]
            groups[-1].extend((idx[0], idx[k], idx[k + 1]) for k in range(1, len(idx) - 1))
        elif (line.startswith(("o ", "g ")) or line in ("o", "g")) and groups[-1]:
            groups.append([])
    v = np.array(vertices, dtype=float).reshape(-1, 3)
    out = []
    for faces in groups:
        f = np.array(faces, dtype=int).reshape(-1, 3)
        f = f[(f >= 0).all(axis=1) & (f < len(v)).all(axis=1)]
        if len(f):
            out.append(f)
    return v, out


def _stl(data: bytes) -> tuple[np.ndarray, np.ndarray]:
    count = int.from_bytes(data[80:84], "little") if len(data) >= 84 else -1
    if count >= 0 and len(data) == 84 + 50 * count:  # binary
        tri = np.frombuffer(data, dtype=_STL_TRIANGLE, count=count, offset=84)["v"].astype(float)
    else:  # ASCII: "vertex x y z" lines, three per facet
        rows = [line.split()[1:4] for line in data.decode("utf-8", "replace").splitlines()
                if line.strip().startswith("vertex")]
        tri = np.array(rows, dtype=float).reshape(-1, 3, 3)
    vertices = tri.reshape(-1, 3)
    return vertices, np.arange(len(vertices)).reshape(-1, 3)


def count_faces(path: str) -> int:
    """Triangles a mesh file holds, counted without building it (OBJ, STL, COLLADA); 0 for others.

    A live spawn's loader counts them before the world's thread, which loads every mesh into
    PyBullet at a few microseconds a face, ever sees the robot. Polygons count as their fans.
    """
    suffix = Path(path).suffix.lower()
    if suffix == ".obj":
        with open(path, "rb") as obj:
            return sum(max(len(line.split()) - 3, 0) for line in obj if line.startswith(b"f "))
    if suffix == ".stl":
        with open(path, "rb") as stl:
            head = stl.read(84)
            size = Path(path).stat().st_size
            count = int.from_bytes(head[80:84], "little") if len(head) == 84 else -1
            if count >= 0 and size == 84 + 50 * count:
                return count
            stl.seek(0)
            return sum(chunk.count(b"endfacet") for chunk in iter(lambda: stl.read(1 << 20), b""))
    if suffix == ".dae":
        with open(path, "rb") as dae:
            text = dae.read()
        return sum(int(n) for n in _DAE_COUNT.findall(text))
    return 0


def obj_text(vertices: np.ndarray, faces: np.ndarray, what: str) -> str:
    """A minimal OBJ of the shape (what it is, in a comment)."""
    lines = [f"# mobot: {what}, in metres\n"]
    lines.extend(f"v {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in vertices.tolist())
    lines.extend(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces.tolist())
    return "".join(lines)


# A COLLADA file's <asset> comes first: a file lxml cannot parse (which trimesh may still read)
# has its unit looked for in the first bytes.
_UNIT_HEAD = 65536
_UNIT = re.compile(rb"<unit\b[^>]*\bmeter\s*=\s*[\"']([^\"']+)[\"']")


def collada_unit(data: bytes) -> float:
    """The metres per unit of a COLLADA document's <asset><unit meter=...> (1 when absent or not
    a positive number). trimesh ignores it; PyBullet and Gazebo apply it."""
    from lxml import etree

    try:
        root = etree.fromstring(data, etree.XMLParser(resolve_entities=False, huge_tree=True))
        unit = root.find("{*}asset/{*}unit")
        text = unit.get("meter", "1") if unit is not None else "1"
    except etree.XMLSyntaxError:
        found = _UNIT.search(data[:_UNIT_HEAD])
        text = found.group(1).decode("ascii", "replace") if found else "1"
    try:
        meter = float(text)
    except ValueError:
        return 1.0
    return meter if 0.0 < meter < float("inf") else 1.0


def collada_unit_of(path: str) -> float:
    """``collada_unit`` of a .dae file; 1 for other files, or when it cannot be read."""
    if not path.lower().endswith(".dae"):
        return 1.0
    try:
        return collada_unit(Path(path).read_bytes())
    except OSError:
        return 1.0
