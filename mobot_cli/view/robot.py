"""The robots in the page, each drawn from its own URDF, their wheels turning with their joints.

yourdfpy reads a robot's URDF text (mesh paths are absolute) once into a template: its joints from
the root outwards and each link's visual meshes as GLB. Robots that share a URDF (a fleet) share
one instanced node per link mesh (viser's batched GLB): a frame computes every instance's pose
with numpy, forward kinematics included, and sends a few arrays, however many robots there are.
COLLADA meshes are drawn from mobot's converted OBJ, which applies the file's <unit> as PyBullet
does (yourdfpy would draw a centimetre mesh 100 times too big).
"""

from __future__ import annotations

import io
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mobot_cli.view.geometry import axis_rotations, matrices_wxyz, rpy_matrices

ROOT = "/robots"
MARKER_SIZE = (0.3, 0.25, 0.15)  # m: the box drawn for a robot whose URDF is unknown
LABEL_Z = 0.6  # m above the root link: the name floats clear of the body
LABEL_EVERY = 0.2  # s between two moves of the name labels
# Above this many robots only the selected one is named: each label is a text sprite that a
# software-rendered page (no GPU) draws at a real cost (25 labels halved its frame rate).
NAMED_MAX = 12
MOVING = ("revolute", "continuous", "prismatic")


@dataclass(frozen=True)
class _JointSpec:
    name: str
    kind: str
    parent: str
    child: str
    origin: np.ndarray  # 4x4 in the parent link's frame
    axis: np.ndarray  # unit vector in the joint frame


@dataclass(frozen=True)
class Template:
    """What a URDF draws as: its joints from the root outwards and each link's meshes as GLB."""

    base: str
    joints: tuple[_JointSpec, ...]
    meshes: tuple[tuple[str, bytes], ...]  # link, GLB bytes in the link's frame

    @property
    def moving(self) -> list[str]:
        """The names of the joints that move, in the order of a group's joint columns."""
        return [j.name for j in self.joints if j.kind in MOVING]


@dataclass
class _Group:
    """The robots drawn from one template: one batched node per link mesh."""

    key: str
    index: int  # names its nodes
    template: Template
    names: list[str] = field(default_factory=list)
    root: np.ndarray = field(default_factory=lambda: np.zeros((0, 4, 4)))  # world pose of each root link
    q: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # joint positions, template.moving order
    shown: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    links: dict[str, np.ndarray] = field(default_factory=dict)  # link -> (n, 4, 4) world poses
    handles: list[Any] = field(default_factory=list)
    dirty: bool = True
    rebuild: bool = True


class Robots:
    """Every robot on the page; ``place`` them, then ``flush`` sends one frame."""

    def __init__(self, server: Any):
        self.server = server
        self.groups: dict[str, _Group] = {}
        self.member: dict[str, _Group] = {}  # robot name -> its group
        self.labels: dict[str, Any] = {}
        self.selected: str | None = None  # always named
        self._labels_at = 0.0

    def add(self, name: str, urdf: str | None) -> None:
        """A robot enters the page (hidden until placed)."""
        template = template_of(urdf)
        key = urdf if template is not None and urdf else "<marker>"
        group = self.groups.get(key) or self.groups.setdefault(key, _Group(key, len(self.groups),
                                                                         template or _marker()))
        group.names.append(name)
        group.root = np.concatenate([group.root, np.eye(4)[None]])
        group.q = np.concatenate([group.q.reshape(len(group.names) - 1, len(group.template.moving)),
                                  np.zeros((1, len(group.template.moving)))])
        group.shown = np.append(group.shown, False)
        group.rebuild = group.dirty = True
        self.member[name] = group
        self.labels[name] = self.server.scene.add_label(f"/labels/{_safe(name)}", name, anchor="bottom-center",
                                                        font_screen_scale=0.8, visible=False)

    def remove(self, name: str) -> None:
        """A robot leaves the page."""
        group = self.member.pop(name)
        i = group.names.index(name)
        group.names.pop(i)
        group.root, group.q, group.shown = (np.delete(a, i, axis=0) for a in (group.root, group.q, group.shown))
        group.rebuild = group.dirty = True
        self.labels.pop(name).remove()

    def place(self, name: str, pose: tuple[float, ...], joints: dict[str, float] | None = None) -> None:
        """Put a robot's root link at (x, y, z, roll, pitch, yaw) with these joint positions, and show it."""
        group = self.member[name]
        i = group.names.index(name)
        m = np.eye(4)
        m[:3, :3] = rpy_matrices(np.array([pose[3:6]]))[0]
        m[:3, 3] = pose[:3]
        group.root[i] = m
        if joints:
            for j, joint in enumerate(group.template.moving):
                group.q[i, j] = joints.get(joint, group.q[i, j])
        group.shown[i] = True
        group.dirty = True

    def hide(self, name: str) -> None:
        """Hide a robot (a replay before its spawn or after its deletion)."""
        group = self.member[name]
        i = group.names.index(name)
        if group.shown[i]:
            group.shown[i] = False
            group.dirty = True

    def link_pose(self, name: str, link: str) -> np.ndarray | None:
        """A link's world pose as of the last flush (the root's for an unknown link)."""
        group = self.member.get(name)
        if group is None or not group.links:
            return None
        i = group.names.index(name)
        poses = group.links.get(link, group.links[group.template.base])
        return poses[i]

    def flush(self) -> None:
        """Send the poses that changed since the last flush."""
        for group in self.groups.values():
            if group.dirty:
                self._send(group)
        now = time.monotonic()
        if now - self._labels_at >= LABEL_EVERY:
            self._labels_at = now
            every_one = len(self.member) <= NAMED_MAX
            for group in self.groups.values():
                for i, name in enumerate(group.names):
                    label = self.labels[name]
                    shown = bool(group.shown[i]) and (every_one or name == self.selected)
                    if label.visible != shown:
                        label.visible = shown
                    position = tuple((group.root[i, :3, 3] + (0.0, 0.0, LABEL_Z)).tolist())
                    if shown and np.abs(np.subtract(label.position, position)).max() > 0.01:
                        label.position = position

    def _send(self, group: _Group) -> None:
        group.dirty = False
        group.links = _forward(group)
        scales = group.shown.astype(np.float32)
        if group.rebuild:
            for handle in group.handles:
                handle.remove()
            group.handles, group.rebuild = [], False
            if not group.names:
                return
            for k, (link, glb) in enumerate(group.template.meshes):
                poses = group.links[link]
                group.handles.append(self.server.scene.add_batched_glb(
                    f"{ROOT}/{group.index}/{k}", glb, matrices_wxyz(poses[:, :3, :3]),
                    poses[:, :3, 3], batched_scales=scales, lod="off"))
            return
        for handle, (link, _) in zip(group.handles, group.template.meshes):
            poses = group.links[link]
            handle.batched_positions = poses[:, :3, 3].astype(np.float32)
            handle.batched_wxyzs = matrices_wxyz(poses[:, :3, :3]).astype(np.float32)
            if not np.array_equal(handle.batched_scales, scales):
                handle.batched_scales = scales


def _forward(group: _Group) -> dict[str, np.ndarray]:
    """Every link's world pose for every robot of the group: (n, 4, 4) per link."""
    template = group.template
    links = {template.base: group.root}
    column = {name: j for j, name in enumerate(template.moving)}
    for joint in template.joints:
        parent = links.get(joint.parent)
        if parent is None:
            continue
        motion = np.broadcast_to(np.eye(4), (len(group.names), 4, 4)).copy()
        if joint.kind in ("revolute", "continuous"):
            motion[:, :3, :3] = axis_rotations(joint.axis, group.q[:, column[joint.name]])
        elif joint.kind == "prismatic":
            motion[:, :3, 3] = joint.axis * group.q[:, column[joint.name], None]
        links[joint.child] = parent @ joint.origin @ motion
    return links


_TEMPLATES: dict[str, Template | None] = {}  # URDF text -> template: a fleet's robot loads once


def template_of(urdf: str | None) -> Template | None:
    """The template of a URDF text; None when there is none or it cannot be drawn."""
    if not urdf:
        return None
    if urdf not in _TEMPLATES:
        if len(_TEMPLATES) > 64:
            _TEMPLATES.clear()
        model = _load(urdf)
        _TEMPLATES[urdf] = None if model is None else _make_template(model)
    return _TEMPLATES[urdf]


def _make_template(model: Any) -> Template:
    base = model.scene.graph.base_frame
    children: dict[str, list[Any]] = {}
    for joint in model.robot.joints:
        children.setdefault(joint.parent, []).append(joint)
    joints, todo = [], [base]
    while todo:  # from the root outwards: every parent's pose is known before its children's
        for joint in children.get(todo.pop(0), ()):
            origin = np.asarray(joint.origin if joint.origin is not None else np.eye(4), float)
            axis = np.asarray(joint.axis if joint.axis is not None else (1.0, 0.0, 0.0), float)
            joints.append(_JointSpec(joint.name, joint.type, joint.parent, joint.child, origin,
                                     axis / (np.linalg.norm(axis) or 1.0)))
            todo.append(joint.child)
    graph, meshes = model.scene.graph, []
    for node in graph.nodes_geometry:
        link = graph.transforms.parents[node]
        local, _ = graph.get(frame_to=node, frame_from=link)
        mesh = model.scene.geometry[graph[node][1]].copy()
        mesh.apply_transform(local)
        meshes.append((link, _glb(mesh)))
    return Template(base, tuple(joints), tuple(meshes))


def _marker() -> Template:
    import trimesh

    box = trimesh.creation.box(extents=MARKER_SIZE)
    box.apply_translation((0.0, 0.0, MARKER_SIZE[2] / 2))
    box.visual.face_colors = (150, 150, 150, 255)
    return Template("base", (), (("base", _glb(box)),))


def _glb(mesh: Any) -> bytes:
    with io.BytesIO() as data:
        mesh.export(data, file_type="glb")
        return data.getvalue()


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

        from mobot_cli.assets.world.meshes import collision_mesh
        from mobot_cli.errors import Location, MobotError

        try:
            return collision_mesh(Path(path), Location(file=path)).path
        except MobotError:
            return path
    return path


def _safe(name: str) -> str:
    return name.replace("/", "_") or "_"
