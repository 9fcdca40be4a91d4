"""A world's static collision geometry in the page: meshes as meshes, every surface coloured by height.

All static bodies are merged into one triangle mesh in the world frame (one draw call, however
many models a world has) whose vertices are coloured by their height: floors dark, walls and
furniture shading up to warm tops, so a house reads from any angle. A ground plane becomes a grid.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from typing import Any

import numpy as np

from mobot_cli.plan import StaticBody, StaticShape, WorldPlan
from mobot_cli.view.geometry import matrix

# Height colours (m -> RGB), from the floor to above a door: slate, teal, sand, coral.
STOPS = ((0.0, (70, 80, 100)), (0.3, (60, 140, 150)), (1.0, (220, 200, 140)), (2.2, (235, 120, 90)))
GRID_MARGIN = 2.0  # m of grid around the world's extent


@dataclass(frozen=True)
class WorldMesh:
    """The world's triangles, their vertex colours and the extent worth looking at."""

    vertices: np.ndarray  # (n, 3) world frame
    faces: np.ndarray  # (m, 3)
    colors: np.ndarray  # (n, 3) uint8
    lo: tuple[float, float, float]  # the robust extent (outliers such as a book 300 km up left out)
    hi: tuple[float, float, float]


def world_mesh(world: WorldPlan) -> WorldMesh:
    """Every static body's collision shapes as one coloured triangle mesh."""
    parts = [mesh for body in world.bodies for mesh in _body_meshes(body)]
    if not parts:
        empty = np.zeros((0, 3))
        return WorldMesh(empty, empty.astype(np.int64), empty.astype(np.uint8), (-5, -5, 0), (5, 5, 0))
    vertices, faces, offset = [], [], 0
    for v, f in parts:
        vertices.append(v)
        faces.append(f + offset)
        offset += len(v)
    v, f = np.concatenate(vertices), np.concatenate(faces)
    lo, hi = np.percentile(v, 1, axis=0), np.percentile(v, 99, axis=0)
    return WorldMesh(v, f, height_colors(v[:, 2]), tuple(lo.tolist()), tuple(hi.tolist()))


def height_colors(z: np.ndarray) -> np.ndarray:
    """RGB (uint8) for each height, interpolated between STOPS."""
    heights = [h for h, _ in STOPS]
    return np.stack([np.interp(z, heights, [c[i] for _, c in STOPS]) for i in range(3)], axis=1).astype(np.uint8)


def draw_world(server: Any, world: WorldPlan, mesh: WorldMesh | None = None) -> WorldMesh:
    """Add the world under /world (replacing what was there); returns the mesh drawn."""
    import trimesh

    mesh = mesh or world_mesh(world)
    scene = server.scene
    if len(mesh.faces):
        tri = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
        tri.visual.vertex_colors = np.concatenate([mesh.colors, np.full((len(mesh.colors), 1), 255, np.uint8)], 1)
        scene.add_mesh_trimesh("/world/geometry", tri, cast_shadow=False, receive_shadow=False)
    if world.ground_plane:
        (x0, y0, _), (x1, y1, _) = mesh.lo, mesh.hi
        size = max(x1 - x0, y1 - y0, 8.0) + 2 * GRID_MARGIN
        scene.add_grid("/world/ground", width=size, height=size, cell_size=1.0, section_size=5.0,
                       position=((x0 + x1) / 2, (y0 + y1) / 2, 0.0), plane="xy")
    return mesh


def _body_meshes(body: StaticBody) -> list[tuple[np.ndarray, np.ndarray]]:
    pose = matrix(body.xyz, body.quat)
    if not body.shapes:
        return [_moved(v, f, pose) for v, f in _urdf_collisions(body.urdf)]
    out = []
    for shape in body.shapes:
        part = _shape_mesh(shape)
        if part is not None:
            out.append(_moved(*part, pose @ matrix(shape.xyz, shape.quat)))
    return out


def _shape_mesh(shape: StaticShape) -> tuple[np.ndarray, np.ndarray] | None:
    """One shape's triangles in its own frame (None: a plane, drawn as the grid, or no file)."""
    import trimesh

    from mobot_cli.common.meshfile import load_quietly

    size = shape.size
    if shape.kind == "box":
        m = trimesh.creation.box(extents=size[:3])
    elif shape.kind == "cylinder":
        m = trimesh.creation.cylinder(radius=size[0], height=size[1], sections=24)
    elif shape.kind == "capsule":
        m = trimesh.creation.capsule(radius=size[0], height=size[1], count=[12, 12])
    elif shape.kind == "sphere":
        m = trimesh.creation.icosphere(subdivisions=2, radius=size[0])
    elif shape.kind == "mesh":
        try:
            m = load_quietly(shape.mesh, force="mesh", process=False)
        except Exception:  # noqa: BLE001 - the world loader vetted it; draw the rest anyway
            return None
        return np.asarray(m.vertices, float) * np.asarray(size[:3], float), np.asarray(m.faces, np.int64)
    else:
        return None
    return np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)


def _urdf_collisions(urdf: str) -> list[tuple[np.ndarray, np.ndarray]]:
    """A single-link URDF body's collision geometry, in its root frame."""
    import yourdfpy

    try:
        model = yourdfpy.URDF.load(io.StringIO(urdf), build_scene_graph=False, load_meshes=False,
                                   build_collision_scene_graph=True, load_collision_meshes=True)
        dumped = model.collision_scene.dump(concatenate=True)
    except Exception:  # noqa: BLE001 - PyBullet loaded it; the view draws what it can
        return []
    if dumped is None or not len(getattr(dumped, "faces", ())):
        return []
    return [(np.asarray(dumped.vertices, float), np.asarray(dumped.faces, np.int64))]


def _moved(vertices: np.ndarray, faces: np.ndarray, pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return vertices @ pose[:3, :3].T + pose[:3, 3], faces
