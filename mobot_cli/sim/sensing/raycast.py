"""The static world as a ray-casting scene: Embree (through embreex) on its triangles.

A lidar's rays meet two kinds of things: the static world, which never moves, and robots,
which do. PyBullet's ``rayTestBatch`` answers both but spends 3-8 us a ray in the bundled
house (its broadphase walk and the Python tuples it returns), so a 360-beam scan at 10 Hz
would cost more than the physics. Embree traces the same static triangles at about 9 M
rays/s (bench/bench_sensors.py), so the static world is cast here, and the robots as a small
scene of their own made at each cast (sim/sensing/robot_scene.py, from ``shape_triangles`` too).

Shapes become triangles as PyBullet collides with them: boxes exactly, cylinders, capsules
and spheres as polygons whose faces lie within ``ROUND_TOLERANCE`` of the true surface,
meshes as their triangles. Planes (the ground, SDF ``<plane>``) are intersected exactly.
Embree works in float32: a few micrometres at 100 m.

A level 2D lidar's rays stay within millimetres of its height, and most of a house's triangles
(table tops, shelves, roofs) lie above or below that. Rays that all keep to a narrow band of
heights are cast at a slice of the scene, the triangles that reach into the band (a margin
around it, so that one slice serves a robot driving on): a smaller BVH, about 20 % less of
Embree's work in the bundled house and 25 % in the AWS small house. A ray can meet only a triangle that reaches
its height, so the answers are those of the whole scene, bit for bit
(tests/sim/sensing/test_scene_slices.py).

A scene depends on the world plan alone, so the last world's scene is kept (``static_scene``)
for the next World of that plan: a sweep worker's runs, a Gymnasium environment's episodes
and the benchmark's runs follow one another in one process, and building the triangles and
their BVHs again would cost every run a good part of what its lidar adds.
"""

from __future__ import annotations

import math
import os
import threading

import numpy as np

from mobot_cli.common.polygon import circle_sides
from mobot_cli.common.transforms import compose_poses, quat_matrix
from mobot_cli.plan import StaticShape, WorldPlan

SLICE_BAND = 0.5  # m: rays spanning more height than this are cast at the whole scene
SLICE_MARGIN = 0.05  # m added below and above the rays' heights when a slice is cut
SLICE_SHARE = 0.8  # a slice holding more of the triangles than this is not worth its BVH
MAX_SLICES = 4  # slices kept per scene (a robot on a ramp cuts new ones as it climbs)
FLOAT_SLACK = 0.001  # m: a slice also keeps triangles this close to its band (Embree rounds in float32)
_BOX = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                 [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])


_kept: list[tuple[tuple, "StaticScene"]] = []  # the last world's scene, for the next World of it
_kept_lock = threading.Lock()  # Worlds may be made in several threads


def static_scene(world: WorldPlan) -> "StaticScene":
    """The ray scene of ``world``: the one the last World of an equal plan used, its mesh files
    unchanged on disk, else a new one."""
    key = (world, _mesh_files(world))
    with _kept_lock:
        if _kept and _kept[0][0] == key:
            return _kept[0][1].again()
    scene = StaticScene(world)
    with _kept_lock:
        _kept[:] = [(key, scene)]
    return scene


def forget_kept() -> None:
    """Drop the kept scene: the next World builds its own, as a fresh process's first does."""
    with _kept_lock:
        _kept.clear()


def _mesh_files(world: WorldPlan) -> tuple:
    """Each mesh file a world's shapes read, as it is now (size, modification time): a file
    rewritten between two Worlds of one process (the Python API's) is read again."""
    files = []
    for mesh in sorted({shape.mesh for body in world.bodies for shape in body.shapes if shape.mesh}):
        try:
            stat = os.stat(mesh)
            files.append((mesh, stat.st_size, stat.st_mtime_ns))
        except OSError:
            files.append((mesh, None, None))
    return tuple(files)


def embree_available() -> bool:
    """True when embreex imports (a declared dependency; without it PyBullet casts every ray)."""
    try:
        import embreex.rtcore_scene  # noqa: F401
    except ImportError:
        return False
    return True


class StaticScene:
    """Every static shape of a world, ready to cast rays at; ``complete`` is False when some
    static body (a URDF-only one) could not be turned into triangles. Safe to cast at from
    several threads (a kept scene may serve Worlds in two threads)."""

    def __init__(self, world: WorldPlan):
        triangles: list[np.ndarray] = []
        self.planes: list[tuple[np.ndarray, np.ndarray]] = []  # (point, unit normal) in the world
        if world.ground_plane:
            self.planes.append((np.zeros(3), np.array([0.0, 0.0, 1.0])))
        self.complete = True
        for body in world.bodies:
            if not body.shapes:
                self.complete = False
                continue
            for shape in body.shapes:
                xyz, quat = compose_poses((body.xyz, body.quat), (shape.xyz, shape.quat))
                rot = np.array(quat_matrix(quat))
                if shape.kind == "plane":
                    normal = rot @ np.array(shape.size[:3], dtype=float)
                    self.planes.append((np.array(xyz, dtype=float), normal / np.linalg.norm(normal)))
                    continue
                local = shape_triangles(shape)
                if len(local):
                    triangles.append(local @ rot.T + np.array(xyz))
        self.triangles = np.concatenate(triangles) if triangles else np.zeros((0, 3, 3))
        self._planes32 = [(point.astype(np.float32), normal.astype(np.float32)) for point, normal in self.planes]
        self._heights = (self.triangles[:, :, 2].min(axis=1), self.triangles[:, :, 2].max(axis=1))
        self._slices: list[tuple[float, float, object]] = []  # (low, high, Embree scene), newest last
        self._cut: list[tuple[float, float, object]] = []  # every slice cut, shared with the copies (again)
        self._lock = threading.Lock()  # guards _cut
        self._scene = _embree(self.triangles) if len(self.triangles) else None

    def again(self) -> "StaticScene":
        """This scene for another World: the triangles and BVHs shared, no slice in use yet (a
        band it casts at takes a slice cut before when one holds it)."""
        copy = object.__new__(StaticScene)
        copy.__dict__.update(self.__dict__)
        copy._slices = []
        return copy

    def cast(self, origins: np.ndarray, directions: np.ndarray, lengths: np.ndarray,
             heights: tuple[float, float] | None = None) -> np.ndarray:
        """Distance (float32) along each ray (unit ``directions``) to the first static surface
        within its length; +inf where there is none. ``heights``: (low, high) z that every
        ray stays within, when the caller knows it (else it is found from the rays)."""
        origins = np.ascontiguousarray(origins, dtype=np.float32)
        directions = np.ascontiguousarray(directions, dtype=np.float32)
        lengths = np.ascontiguousarray(lengths, dtype=np.float32)
        if self._scene is not None and len(origins):
            # DISTANCE answers the ray's own length where it meets nothing.
            scene = self._scene_for(heights or _heights(origins, directions, lengths))
            out = scene.run(origins, directions, dists=lengths.copy(), query="DISTANCE")
            np.putmask(out, out >= lengths, np.inf)  # twice as fast as out[out >= lengths] = inf
        else:
            out = np.full(len(origins), np.inf, dtype=np.float32)
        for point, normal in self._planes32:
            along = directions @ normal
            if not along.any():  # every ray parallel to it (level rays and the floor): no hit
                continue
            t = np.full(len(origins), np.inf, dtype=np.float32)
            np.divide((point - origins) @ normal, along, out=t, where=along != 0.0)  # parallel: no hit
            np.putmask(t, (t < 0.0) | (t >= lengths), np.inf)
            np.minimum(out, t, out=out)
        return out

    def _scene_for(self, heights: tuple[float, float]):
        """The Embree scene to cast rays within these heights at: a slice of the triangles that
        reach into them, when they span little, else the whole scene."""
        low, high = heights
        if high - low > SLICE_BAND:
            return self._ready(self._scene)
        for lo, hi, scene in self._slices:
            if lo <= low and high <= hi:
                return self._ready(scene)
        with self._lock:
            cut = next((kept for kept in reversed(self._cut) if kept[0] <= low and high <= kept[1]), None)
            if cut is None:
                lo, hi = low - SLICE_MARGIN, high + SLICE_MARGIN
                bottom, top = self._heights
                keep = (top >= lo - FLOAT_SLACK) & (bottom <= hi + FLOAT_SLACK)
                # Not worth a BVH of its own: the whole scene is kept for this band too.
                cut = (lo, hi, self._scene if keep.sum() > SLICE_SHARE * len(keep) else _embree(self.triangles[keep]))
                self._cut[:] = [*self._cut[1 - 2 * MAX_SLICES:], cut]  # in place: the copies share it
        self._slices = [*self._slices[1 - MAX_SLICES:], cut]
        return self._ready(cut[2])

    def _ready(self, scene):
        """``scene`` with its BVH built: embreex builds it at the first cast, which two threads
        casting at a kept scene must not both do."""
        if not scene.is_committed:
            with self._lock:
                if not scene.is_committed:
                    scene.run(np.zeros((1, 3), np.float32), np.array([[0.0, 0.0, 1.0]], np.float32),
                              dists=np.ones(1, np.float32), query="DISTANCE")
        return scene


def _heights(origins: np.ndarray, directions: np.ndarray, lengths: np.ndarray) -> tuple[float, float]:
    """The lowest and highest z the rays reach (from their origins to their ends)."""
    z = origins[:, 2]
    end = z + directions[:, 2] * lengths
    return float(min(z.min(), end.min())), float(max(z.max(), end.max()))


def _embree(triangles: np.ndarray):
    """An Embree scene of triangles (n, 3, 3); an empty slice is a scene no ray meets."""
    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh

    scene = rtcore_scene.EmbreeScene()
    if len(triangles):
        TriangleMesh(scene, np.ascontiguousarray(triangles, dtype=np.float32))
    return scene  # its BVH is built at its first cast (_ready): a level lidar never builds the whole scene's


def shape_triangles(shape: StaticShape) -> np.ndarray:
    """The shape's surface as triangles (n, 3 corners, xyz) in its own frame."""
    kind, size = shape.kind, shape.size
    if kind == "box":
        half = np.array(size[:3], dtype=float) / 2.0
        corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * half
        return corners[_BOX]
    if kind == "cylinder":
        return _lathe(size[0], [(-size[1] / 2.0, size[0]), (size[1] / 2.0, size[0])], caps=True)
    if kind == "sphere":
        return _lathe(size[0], _arc(size[0], 0.0, -1.0) + _arc(size[0], 0.0, 1.0)[1:], caps=False)
    if kind == "capsule":
        r, half = size[0], size[1] / 2.0
        return _lathe(r, _arc(r, -half, -1.0) + _arc(r, half, 1.0), caps=False)
    if kind == "mesh":
        from mobot_cli.common.meshfile import read_mesh

        vertices, faces = read_mesh(shape.mesh)
        return (vertices * np.array(size[:3], dtype=float))[faces] if len(faces) else np.zeros((0, 3, 3))
    return np.zeros((0, 3, 3))


def _arc(radius: float, z0: float, side: float) -> list[tuple[float, float]]:
    """A quarter circle of (z, r) from the pole (side -1: bottom, +1: top) to the equator at z0,
    ordered bottom to top."""
    n = max(2, circle_sides(radius) // 4)
    angles = [math.pi / 2.0 * k / n for k in range(n + 1)]  # 0 at the equator
    points = [(z0 + side * radius * math.sin(a), radius * math.cos(a)) for a in angles]
    return points[::-1] if side < 0 else points


def _lathe(radius: float, profile: list[tuple[float, float]], caps: bool) -> np.ndarray:
    """A surface of revolution about z from a (z, r) profile, bottom to top."""
    n = circle_sides(radius)
    a = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    ring = np.stack([np.cos(a), np.sin(a)], axis=1)
    rings = [np.column_stack([ring * r, np.full(n, z)]) for z, r in profile]
    tris = []
    nxt = np.roll(np.arange(n), -1)
    for lo, hi in zip(rings, rings[1:]):
        tris.append(np.stack([lo, lo[nxt], hi[nxt]], axis=1))
        tris.append(np.stack([lo, hi[nxt], hi], axis=1))
    if caps:
        for r, z in ((rings[0], profile[0][0]), (rings[-1], profile[-1][0])):
            centre = np.broadcast_to([0.0, 0.0, z], (n, 3))
            tris.append(np.stack([centre, r, r[nxt]], axis=1))
    return np.concatenate(tris)
