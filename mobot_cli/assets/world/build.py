"""The cold path of world loading: read the SDF, convert meshes, make static bodies."""

from __future__ import annotations

import math
from collections import Counter
from pathlib import Path

import numpy as np

from mobot_cli.assets.resources import ResourceResolver
from mobot_cli.assets.world import meshes
from mobot_cli.assets.world.loaded import LoadedWorld, WorldRobot
from mobot_cli.assets.world.model import Model
from mobot_cli.assets.world.paths import SdfPaths
from mobot_cli.assets.world.pose import xyz_quat
from mobot_cli.assets.world.reader import SdfReader
from mobot_cli.assets.world.to_urdf import model_to_urdf
from mobot_cli.plan import StaticBody, StaticShape, WorldPlan

# A model placed farther than this from the origin is a typo (the AWS bookstore has a book
# at z = 343 km): it is left out with a warning rather than stretching the world.
ABSURD_DISTANCE = meshes.FAR  # m
# A plane with a <size> is a box this thick behind its surface: Gazebo's physics makes every
# plane infinite, which turns a poster on a wall into an endless wall across the world.
THIN_PLANE = 0.01  # m


class _Builder:
    """Accumulates bodies, robots and the summary while walking a world's models."""

    def __init__(self, reader: SdfReader):
        self.reader = reader
        self.bodies: list[StaticBody] = []
        self.robots: list[WorldRobot] = []
        self.static_models: list[str] = []
        self.ground = False
        self.shapes: Counter = Counter()
        self.meshes: dict[str, meshes.MeshFile] = {}
        self.lo = np.full(3, math.inf)
        self.hi = np.full(3, -math.inf)
        self.held_fixed: list[str] = []
        self.anchored: list[str] = []  # models hung from the world by a joint that moves, held still
        self.skipped: list[str] = []

    def model(self, model: Model) -> None:
        position = model.pose[:3, 3]
        if float(np.linalg.norm(position)) > ABSURD_DISTANCE:
            x, y, z = position
            self.reader.warn(f"model '{model.name}' is placed at ({x:.1f}, {y:.1f}, {z:.1f}), more "
                             f"than {ABSURD_DISTANCE / 1000:g} km from the origin: left out as a "
                             "typo", model.location)
            self.skipped.append(model.name)
            return
        moving = [joint for joint in model.joints if joint.moves]
        if not model.static and moving and not any(joint.parent == "world" for joint in moving):
            self.robot(model)
            return
        if not model.static:  # nothing in it moves (a wall hung from `world`), or it hangs from the
            # world by a joint that moves (a door on its hinge): scenery, held where it starts
            (self.anchored if moving else self.held_fixed).append(model.name)
        self.static_models.append(model.name)
        self.static(model)

    def robot(self, model: Model) -> None:
        file = Path(str(model.location.file))
        urdf, notices = model_to_urdf(model, file)
        xyz, quat = xyz_quat(model.pose)
        self.robots.append(WorldRobot(name=model.name, urdf=urdf, xyz=xyz, quat=quat,
                                      source=str(file), notices=tuple(str(n) for n in notices)))

    def static(self, model: Model) -> None:
        shapes, frictions = [], []
        xyz, quat = xyz_quat(model.pose)
        label = f"world model '{model.name}' at ({_cm(xyz[0])}, {_cm(xyz[1])}, {_cm(xyz[2])})"
        for link in model.links:
            for shape in link.collisions:
                local = link.pose @ shape.pose
                self.shapes[shape.kind] += 1
                if shape.friction is not None:
                    frictions.append(min(1.0, shape.friction))
                if shape.kind == "plane":
                    local = self.plane(model, local, shape.size, shape.extent, label)
                    if local is None:
                        continue
                    shape_kind, size = "box", (*shape.extent, THIN_PLANE)  # type: ignore[misc]
                else:
                    shape_kind, size = shape.kind, shape.size
                path = str(shape.mesh or "")
                if shape.kind == "mesh":
                    mesh = meshes.collision_mesh(shape.mesh, shape.location)
                    if mesh.dropped and mesh.source not in self.meshes:
                        self.reader.warn(
                            f"mesh {Path(mesh.source).name}: {mesh.dropped} of its "
                            f"{mesh.triangles + mesh.dropped} triangles lie more than "
                            f"{meshes.FAR / 1000:g} km from its origin (up to {mesh.farthest:.3g} m): "
                            "left out, as no robot reaches them", shape.location)
                    self.meshes[mesh.source] = mesh
                    path = mesh.path
                    self.extend(model.pose @ local, _box_corners(mesh.bounds, size))
                else:
                    self.extend(model.pose @ local, _corners(shape_kind, size))
                s_xyz, s_quat = xyz_quat(local)
                shapes.append(StaticShape(kind=shape_kind, size=tuple(float(v) for v in size),
                                          mesh=path, xyz=s_xyz, quat=s_quat,
                                          name=f"{link.name}::{shape.name}"))
        if shapes:
            self.bodies.append(StaticBody(name=model.name, xyz=xyz, quat=quat, shapes=tuple(shapes),
                                          friction=min(frictions) if frictions else None,
                                          label=label))

    def plane(self, model: Model, local, normal, extent, label: str):
        """Place a plane: the ground plane, an infinite plane body, or (with a <size>) the pose
        of the thin box that stands for it, returned for the model's own body."""
        world = model.pose @ local
        n = world[:3, :3] @ (np.array(normal) / np.linalg.norm(normal))
        offset = float(n @ world[:3, 3])
        if not self.ground and n[2] > 1.0 - 1e-9 and abs(offset) < 1e-9:
            self.ground = True  # Gazebo's ground_plane: the simulation's own ground plane
            return None
        if extent is not None:
            return local @ _plane_box(np.array(normal, dtype=float))
        xyz, quat = xyz_quat(world)
        self.bodies.append(StaticBody(
            name=model.name, xyz=xyz, quat=quat, label=label,
            shapes=(StaticShape(kind="plane", size=tuple(float(v) for v in normal)),)))
        return None

    def extend(self, pose, corners: np.ndarray) -> None:
        points = corners @ pose[:3, :3].T + pose[:3, 3]
        self.lo = np.minimum(self.lo, points.min(axis=0))
        self.hi = np.maximum(self.hi, points.max(axis=0))


def _plane_box(normal: np.ndarray) -> np.ndarray:
    """Where the box of a finite plane sits in the plane's pose: its top face on the plane.

    The plane's own axes are Gazebo's (common::MeshManager::CreatePlane): y = normal x X (or
    normal x Y when the normal is along X), x = y x normal. An upward plane keeps the pose's
    axes; on an upright plane <size>'s first value is its horizontal width.
    """
    z = normal / np.linalg.norm(normal)
    y = np.cross(z, [1.0, 0.0, 0.0])
    if np.linalg.norm(y) < 1e-6:
        y = np.cross(z, [0.0, 1.0, 0.0])
    y /= np.linalg.norm(y)
    frame = np.eye(4)
    frame[:3, :3] = np.column_stack([np.cross(y, z), y, z])
    frame[:3, 3] = -z * THIN_PLANE / 2.0
    return frame


def _box_corners(bounds, scale) -> np.ndarray:
    lo, hi = np.array(bounds[0]) * scale, np.array(bounds[1]) * scale
    return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                     for z in (lo[2], hi[2])])


def _corners(kind: str, size) -> np.ndarray:
    if kind == "box":
        half = np.array(size) / 2
    elif kind == "sphere":
        half = np.array([size[0]] * 3)
    elif kind == "capsule":
        half = np.array([size[0], size[0], size[1] / 2 + size[0]])
    else:  # cylinder
        half = np.array([size[0], size[0], size[1] / 2])
    return _box_corners((-half, half), (1.0, 1.0, 1.0))


def build_world(path: Path, resolver: ResourceResolver,
                skip_missing: bool) -> tuple[LoadedWorld, list[str]]:
    """Read and convert a world; returns it and the files it depends on."""
    paths = SdfPaths(path, resolver)
    reader = SdfReader(path, paths, skip_missing)
    world = reader.world()
    builder = _Builder(reader)
    for model in world.models:
        builder.model(model)
    line = ignored_line(str(path), dict(world.ignored), world.max_step_size)
    notices = [*(str(n) for n in reader.notices), *([line] if line else [])]
    if not builder.bodies and not builder.ground:
        left = sorted(kind for kind in world.ignored if kind.endswith(" geometry"))  # a heightmap floor
        notices.append(f"{path.name} has no collision geometry and no ground plane: robots have "
                       "nothing to stand on" + (f" ({', '.join(left)} left out)" if left else ""))
    if builder.anchored:
        notices.append(f"{path.name}: {len(builder.anchored)} model(s) hang from the world by a joint that moves "
                       f"(a door on its hinge, a pendulum) and are held still where they start, as mobot's worlds "
                       f"are static: {', '.join(builder.anchored[:5])}"
                       + (", ..." if len(builder.anchored) > 5 else ""))
    if builder.held_fixed:
        notices.append(f"{path.name}: {len(builder.held_fixed)} non-static model(s) without joints that "
                       f"move are held fixed, as the world is static: {', '.join(builder.held_fixed[:5])}"
                       + (", ..." if len(builder.held_fixed) > 5 else ""))
    bounds = None
    if np.isfinite(builder.lo).all():
        lo = [round(float(v), 4) + 0.0 for v in builder.lo]
        hi = [round(float(v), 4) + 0.0 for v in builder.hi]
        bounds = {"min": lo, "max": hi, "size": [round(b - a, 4) for a, b in zip(lo, hi)]}
    converted = [m for m in builder.meshes.values() if m.converted]
    summary = {
        "kind": "world", "name": world.name, "path": str(path), "models": len(world.models),
        "static_models": len(builder.static_models), "held_fixed": len(builder.held_fixed),
        "robots": [r.name for r in builder.robots], "skipped_models": builder.skipped,
        "links": sum(len(m.links) for m in world.models),
        "shapes": count(builder.shapes), "ground_plane": builder.ground,
        "meshes": {"files": len(builder.meshes), "converted": len(converted),
                   "triangles": sum(m.triangles for m in builder.meshes.values())},
        "ignored": count(world.ignored), "state_poses": world.state_poses,
        "max_step_size": world.max_step_size, "bounds": bounds,
    }
    plan = WorldPlan(name=path.stem, ground_plane=builder.ground, bodies=tuple(builder.bodies),
                     source=str(path), robot_models=tuple(r.name for r in builder.robots),
                     actors=tuple(world.actors))
    loaded = LoadedWorld(plan=plan, robots=tuple(builder.robots),
                         static_models=tuple(builder.static_models), summary=summary,
                         notices=tuple(dict.fromkeys(notices)))
    deps = [*(str(p) for p in paths.files), *(m.source for m in builder.meshes.values()),
            *(m.path for m in builder.meshes.values() if m.path != m.source)]
    return loaded, deps


def _cm(value: float) -> str:
    """A coordinate for messages, to the centimetre, never '-0.00'."""
    return f"{round(value, 2) + 0.0:.2f}"


def ignored_line(file: str, ignored: dict[str, int], max_step: float | None) -> str | None:
    """The one summary line naming what the world holds that mobot does not simulate."""
    parts = []
    for tag, count in sorted(ignored.items(), key=lambda kv: (-kv[1], kv[0])):
        if tag.endswith(" geometry"):
            continue  # each of those has its own warning
        label = {"light": "light", "plugin": "plugin", "actor": "actor"}.get(tag)
        text = f"{count} {label}{'s' if count > 1 else ''}" if label else tag
        if tag == "physics" and max_step:
            text += f" (max_step_size {max_step:g} s; mobot steps at physics.rate_hz)"
        if tag == "gravity":
            text += " (physics.gravity applies)"
        parts.append(text)
    if not parts:
        return None
    return f"{Path(file).name}: ignored {', '.join(parts)} (mobot simulates collision geometry)"


def count(counter: Counter) -> dict[str, int]:
    """A Counter as a plain dict sorted by key (stable JSON)."""
    return {k: counter[k] for k in sorted(counter)}
