"""A world's floor plan: its static collision geometry projected from above, as polygons.

Only what a wheeled robot can meet is kept: geometry reaching into ``BAND`` (above the floor,
below a ceiling), measured from the floor under the robots (floorlevel.py), not from z = 0.
Boxes, cylinders, capsules and spheres become the outline of their shadow; meshes become their
triangles' shadows, and upright faces (seen edge-on) become segments, so a wall taller than the
band still shows as its outline. Bodies come
as StaticShape lists (SDF worlds) or, failing that, as URDF text with <collision> elements.
"""

from __future__ import annotations

import functools
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

from mobot_cli.assets.description.frames import LinkTree, floats, origin_frame
from mobot_cli.common.transforms import Quat, Vec, compose_poses, pose_point, quat_from_matrix, quat_matrix
from mobot_cli.plan import StaticShape, WorldPlan

Point = tuple[float, float]
Polygon = list[Point]


@dataclass(frozen=True, eq=False)
class MeshShadow:
    """A mesh's shadow as arrays, not polygons: a furnished world's meshes cast a million
    triangles, and Python lists of each one's points took seconds to make and to read."""

    triangles: object  # numpy (n, 3 corners, xy), read-only: the shadows of its faces
    segments: object  # numpy (m, 2 ends, xy), read-only: its upright faces seen edge-on

    def polygons(self) -> list[Polygon]:
        """The same shadow as polygons: triangles, then segments."""
        return [[tuple(p) for p in shape] for shape in self.triangles.tolist() + self.segments.tolist()]

    def __len__(self) -> int:
        """The shapes it holds."""
        return len(self.triangles) + len(self.segments)

    def extent(self) -> tuple[float, float, float, float] | None:
        """xmin, xmax, ymin, ymax of its shapes' corners (None when it holds none)."""
        corners = [shapes.reshape(-1, 2) for shapes in (self.triangles, self.segments) if len(shapes)]
        if not corners:
            return None
        low = min(float(c[:, 0].min()) for c in corners), min(float(c[:, 1].min()) for c in corners)
        high = max(float(c[:, 0].max()) for c in corners), max(float(c[:, 1].max()) for c in corners)
        return low[0], high[0], low[1], high[1]


Part = Polygon | MeshShadow  # what a shadow is made of

BAND = (0.02, 2.0)  # metres above the floor: lower is floor, higher is ceiling
ROUND = 24  # points on a projected circle
SLIVER = 1e-3  # m: a triangle's shadow thinner than this is drawn as its longest side
# and so is a face leaning less than this off upright (sin of 1 degree): a wall stood up by a
# rounded roll (Gazebo poses often give 1.57 for pi/2) casts a shadow a few millimetres wide,
# which holds no cell's centre, and would vanish from the map if it were filled
UPRIGHT = math.sin(math.radians(1.0))


def floor_plan(world: WorldPlan, starts: list[tuple[float, float, float]] = ()) -> list[Polygon]:
    """Every static body's shadow in the band above the floor under ``starts`` (each robot's
    root link x, y, z where it started; the band is measured from z = 0 without them)."""
    return [polygon for part in floor_parts(world, starts)
            for polygon in (part.polygons() if isinstance(part, MeshShadow) else [part])]


def floor_parts(world: WorldPlan, starts: list[tuple[float, float, float]] = ()) -> list[Part]:
    """``floor_plan`` with meshes' shadows kept as arrays (what trajectory.png draws)."""
    from mobot_cli.assets.world.floorlevel import floor_level

    floor = floor_level(world, list(starts), body_shapes) if starts else 0.0
    band = (floor + BAND[0], floor + BAND[1])
    return [part for _, parts in body_shadows(world, band) for part in parts]


@functools.lru_cache(maxsize=4)  # a run plans its goals, checks coverage and draws the same world
def body_shadows(world: WorldPlan, band: tuple[float, float] = BAND) -> tuple[tuple[str, tuple[Part, ...]], ...]:
    """Each static body that reaches into the band: how messages name it, and its shadow
    (polygons, and its meshes' shadows as arrays).

    Cached: treat the polygons and arrays as read-only."""
    out = []
    for body in world.bodies:
        polygons: list[Part] = []
        for shape in body_shapes(body):
            xyz, quat = compose_poses((body.xyz, body.quat), (shape.xyz, shape.quat))
            polygons.extend(shape_shadow(shape, xyz, quat, band))
        if polygons:
            out.append((body.label or f"static body '{body.name}'", tuple(polygons)))
    return tuple(out)


def body_shapes(body) -> list[StaticShape]:
    """A static body's collision shapes: its own, or read from its URDF text."""
    return list(body.shapes) or _urdf_shapes(body.urdf)


def shape_shadow(shape: StaticShape, xyz: Vec, quat: Quat,
                 band: tuple[float, float] = BAND) -> list[Part]:
    """The shadow of one shape posed in the world (none when it lies outside the band)."""
    if shape.kind == "mesh":
        return _mesh_shadow(shape.mesh, shape.size, xyz, quat, band)
    points = [pose_point(xyz, quat, p) for p in _outline_points(shape.kind, shape.size)]
    if not points or not _in_band(min(p[2] for p in points), max(p[2] for p in points), band):
        return []
    hull = convex_hull([(p[0], p[1]) for p in points])
    return [hull] if len(hull) >= 3 else []


def _outline_points(kind: str, size: tuple[float, ...]) -> list[Vec]:
    """Points whose convex hull is the shape (exact for boxes, 24-gons for round parts)."""
    if kind == "box":
        hx, hy, hz = (s / 2.0 for s in size[:3])
        return [(sx * hx, sy * hy, sz * hz) for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
    ring = [(math.cos(a), math.sin(a)) for a in (2 * math.pi * i / ROUND for i in range(ROUND))]
    if kind == "cylinder":
        r, half = size[0], size[1] / 2.0
        return [(r * c, r * s, z) for z in (-half, half) for c, s in ring]
    if kind in ("sphere", "capsule"):  # a capsule is two spheres and the hull between them
        r = size[0]
        centres = (0.0,) if kind == "sphere" else (-size[1] / 2.0, size[1] / 2.0)
        return [p for z in centres for c, s in ring
                for p in ((r * c, r * s, z), (r * c, 0.0, z + r * s), (0.0, r * c, z + r * s))]
    return []  # a plane is a floor or a wall of infinite extent: not drawn


def _mesh_shadow(path: str, scale: tuple[float, ...], xyz: Vec, quat: Quat,
                 band: tuple[float, float]) -> list[MeshShadow]:
    import numpy as np

    from mobot_cli.common.meshfile import read_mesh

    vertices, faces = read_mesh(path)
    if len(faces) == 0:
        return []
    rot = np.array(quat_matrix(quat))
    world = (vertices * np.array(scale[:3])) @ rot.T + np.array(xyz)
    tri = world[faces]  # (n, 3 corners, xyz)
    z = tri[:, :, 2]
    keep = (z.max(axis=1) >= band[0]) & (z.min(axis=1) <= band[1])
    tri = tri[keep]
    # twice each face's area in 3D; its shadow's (the normal's z) is ``area`` below
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    tri = tri[:, :, :2]
    area = np.abs(normal[:, 2])
    sides = np.stack([np.hypot(*(np.roll(tri, -1, axis=1) - tri)[:, k].T) for k in range(3)], axis=1)
    # the rest are upright faces seen edge-on: a wall's sides, drawn as lines; so are faces
    # within SLIVER of upright (exported walls lean by a few micrometres) or leaning less than
    # UPRIGHT, whose shadow is too thin to hold a cell's centre
    flat = (area > 1e-6) & (area > SLIVER * sides.max(axis=1, initial=0.0)) & \
        (area >= UPRIGHT * np.sqrt(np.einsum("ij,ij->i", normal, normal)))
    edge_on = tri[~flat]
    ends = np.stack([edge_on, np.roll(edge_on, -1, axis=1)], axis=2)  # (n, 3 edges, 2 ends, xy)
    length = np.hypot(*(ends[:, :, 1] - ends[:, :, 0]).transpose(2, 0, 1))
    longest = ends[np.arange(len(ends)), length.argmax(axis=1)] if len(ends) else ends[:, 0]
    longest = longest[length.max(axis=1) > 1e-3] if len(ends) else longest
    shadow = MeshShadow(tri[flat], longest)
    for array in (shadow.triangles, shadow.segments):
        array.flags.writeable = False  # kept by body_shadows' cache
    return [shadow] if len(shadow) else []


def _urdf_shapes(urdf: str) -> list[StaticShape]:
    """The collision shapes of a URDF's links, posed in the root link's frame (joints at zero)."""
    if not urdf.strip():
        return []
    try:
        tree = LinkTree(ET.fromstring(urdf))
    except ET.ParseError:
        return []
    shapes = []
    for name, link in tree.links.items():
        link_frame = tree.frame(name)
        for collision in link.findall("collision"):
            frame = link_frame.compose(origin_frame(collision))
            shape = _urdf_geometry(collision.find("geometry"))
            if shape is not None:
                kind, size, mesh = shape
                part = collision.get("name")
                shapes.append(StaticShape(kind=kind, size=size, mesh=mesh, xyz=frame.pos,
                                          quat=quat_from_matrix(frame.rot),
                                          name=f"{name}::{part}" if part else name))
    return shapes


def _urdf_geometry(geometry: ET.Element | None):
    if geometry is None or len(geometry) == 0:
        return None
    g = geometry[0]
    if g.tag == "box":
        return "box", floats(g.get("size"), 3, (0.0, 0.0, 0.0)), ""
    if g.tag == "cylinder":
        return "cylinder", (floats(g.get("radius"), 1, (0.0,))[0], floats(g.get("length"), 1, (0.0,))[0]), ""
    if g.tag == "sphere":
        return "sphere", floats(g.get("radius"), 1, (0.0,)), ""
    if g.tag == "mesh" and g.get("filename"):
        filename = g.get("filename", "").removeprefix("file://")
        return "mesh", floats(g.get("scale"), 3, (1.0, 1.0, 1.0)), filename
    return None


def convex_hull(points: list[Point]) -> Polygon:
    """Andrew's monotone chain: the hull counter-clockwise, without repeated points."""
    pts = sorted(set(points))
    if len(pts) <= 2:
        return pts

    def half(seq):
        out: list[Point] = []
        for p in seq:
            while len(out) >= 2 and _cross(out[-2], out[-1], p) <= 1e-12:
                out.pop()
            out.append(p)
        return out[:-1]

    return half(pts) + half(reversed(pts))


def _cross(o: Point, a: Point, b: Point) -> float:
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def _in_band(zmin: float, zmax: float, band: tuple[float, float]) -> bool:
    return zmax >= band[0] and zmin <= band[1]

