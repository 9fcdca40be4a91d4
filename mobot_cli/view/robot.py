"""A robot in the page, drawn from its own URDF: one frame per link, its wheels turning with its joints.

yourdfpy reads the URDF text of the plan (mesh paths are absolute) into visual meshes; each
moving joint gets a frame whose transform is its origin times its motion, set from the joint
positions the run recorded. COLLADA meshes are drawn from mobot's converted OBJ, which applies
the file's <unit> as PyBullet does (yourdfpy would draw a centimetre mesh 100 times too big).
Updates send only what moved, so parked robots cost the page nothing.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from mobot_cli.view.geometry import axis_angle_wxyz, matrix_wxyz, quat_mul, rpy_wxyz

ROOT = "/robots"
MOVED = 1e-4  # m or rad: smaller changes are not sent
MARKER_SIZE = (0.3, 0.25, 0.15)
LABEL_Z = 0.6  # m above the root link: the name floats clear of the body  # m: the box drawn for a robot whose URDF is unknown


@dataclass
class _Joint:
    name: str
    kind: str  # revolute | continuous | prismatic
    handle: Any  # the child link's frame
    origin: np.ndarray  # 4x4 in the parent link's frame
    axis: np.ndarray
    last: float = math.nan


class RobotModel:
    """One robot's scene nodes under /robots/<name>; ``show`` moves it to a state."""

    def __init__(self, server: Any, name: str, urdf: str | None, color: tuple[int, int, int]):
        self.server, self.name = server, name
        self.path = f"{ROOT}/{_safe(name)}"
        self.color = color
        self.root = server.scene.add_frame(self.path, show_axes=False)
        self.label = server.scene.add_label(f"{self.path}/label", name, position=(0.0, 0.0, LABEL_Z),
                                            anchor="bottom-center", font_screen_scale=0.8)
        self.joints: list[_Joint] = []
        self.link_paths: dict[str, str] = {}
        self._pose = (math.nan,) * 6
        model = _load(urdf) if urdf else None
        if model is None:
            server.scene.add_box(f"{self.path}/marker", color=color, dimensions=MARKER_SIZE,
                                 position=(0.0, 0.0, MARKER_SIZE[2] / 2))
        else:
            self._build(model)

    def show(self, x: float, y: float, z: float, roll: float, pitch: float, yaw: float,
             joints: dict[str, float] | None = None) -> None:
        """Place the root link at a world pose and turn its joints (only what moved is sent)."""
        pose = (x, y, z, roll, pitch, yaw)
        if max(abs(a - b) for a, b in zip(pose, self._pose)) > MOVED or math.isnan(self._pose[0]):
            self.root.position = (x, y, z)
            self.root.wxyz = rpy_wxyz(roll, pitch, yaw)
            self._pose = pose
        if joints:
            for joint in self.joints:
                q = joints.get(joint.name)
                if q is not None and not abs(q - joint.last) <= MOVED:
                    self._turn(joint, q)

    def visible(self, shown: bool) -> None:
        """Show or hide the whole robot (a replay before its spawn or after its deletion)."""
        if self.root.visible != shown:
            self.root.visible = shown

    def remove(self) -> None:
        """Take the robot's nodes out of the page."""
        self.root.remove()

    def _turn(self, joint: _Joint, q: float) -> None:
        joint.last = q
        origin = joint.origin
        if joint.kind == "prismatic":
            joint.handle.position = tuple((origin[:3, 3] + origin[:3, :3] @ joint.axis * q).tolist())
        else:
            joint.handle.wxyz = quat_mul(matrix_wxyz(origin), axis_angle_wxyz(joint.axis, q))

    def _build(self, model: Any) -> None:
        scene = self.server.scene
        base = model.scene.graph.base_frame
        self.link_paths[base] = self.path
        for joint in _joints_in_order(model, base):
            parent = self.link_paths[joint.parent]
            path = self.link_paths[joint.child] = f"{parent}/{_safe(joint.child)}"
            origin = np.asarray(joint.origin if joint.origin is not None else np.eye(4), float)
            handle = scene.add_frame(path, show_axes=False, position=tuple(origin[:3, 3].tolist()),
                                     wxyz=matrix_wxyz(origin))
            if joint.type in ("revolute", "continuous", "prismatic"):
                axis = np.asarray(joint.axis if joint.axis is not None else (1.0, 0.0, 0.0), float)
                axis = axis / (np.linalg.norm(axis) or 1.0)
                self.joints.append(_Joint(joint.name, joint.type, handle, origin, axis))
        graph = model.scene.graph
        for node in graph.nodes_geometry:
            geometry = model.scene.geometry[graph[node][1]]
            link = graph.transforms.parents[node]
            local, _ = graph.get(frame_to=node, frame_from=link)
            mesh = geometry.copy()
            mesh.apply_transform(local)
            if link in self.link_paths:
                scene.add_mesh_trimesh(f"{self.link_paths[link]}/{_safe(node)}", mesh)


def _joints_in_order(model: Any, base: str) -> list[Any]:
    """Joints from the root outwards, so that every parent frame exists before its children."""
    children: dict[str, list[Any]] = {}
    for joint in model.robot.joints:
        children.setdefault(joint.parent, []).append(joint)
    ordered, todo = [], [base]
    while todo:
        link = todo.pop(0)
        for joint in children.get(link, ()):
            ordered.append(joint)
            todo.append(joint.child)
    return ordered


def _load(urdf: str) -> Any | None:
    """yourdfpy's model with visual meshes; None when the text cannot be drawn."""
    import yourdfpy

    try:
        return yourdfpy.URDF.load(io.StringIO(urdf), build_scene_graph=True, load_meshes=True,
                                  build_collision_scene_graph=False, load_collision_meshes=False,
                                  filename_handler=_mesh_file)
    except Exception:  # noqa: BLE001 - the robot ran, so the sim read it; draw a box instead
        return None


def _mesh_file(filename: str) -> str:
    """The file to draw for a mesh path: COLLADA through mobot's unit-aware conversion."""
    path = filename[len("file://"):] if filename.startswith("file://") else filename
    if path.lower().endswith(".dae"):
        from pathlib import Path

        from mobot_cli.assets.meshes import collision_mesh
        from mobot_cli.errors import Location, MobotError

        try:
            return collision_mesh(Path(path), Location(file=path)).path
        except MobotError:
            return path
    return path


def _safe(name: str) -> str:
    return name.replace("/", "_") or "_"
