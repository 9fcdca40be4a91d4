"""Camera images from PyBullet's own renderers, headless (docs/cameras.md).

* ``tiny``: PyBullet's TinyRenderer, a software rasteriser in the C module: always there, no
  display, no GPU. It draws the visual shapes of URDF bodies and, for bodies built from collision
  shapes only (the ground plane, SDF worlds' static models), those shapes. The static models are
  drawn by visual-only copies, smallest shapes first and large faces cut into tiles, which it
  draws faster (tiles.py).
* ``egl``: PyBullet's eglRendererPlugin (OpenGL through EGL: a GPU's driver, or Mesa's llvmpipe
  without one). It draws visual shapes only, so the world's collision-only bodies get visual twins
  without collision (``_visual_twins``) when it is chosen.

TinyRenderer draws the ground as a visual-only grid of FLOOR_CELLS x FLOOR_CELLS squares,
FLOOR_SIZE m across, centred near the world's origin, in place of the ground plane (whose own
drawing is made transparent): it draws PyBullet's infinite plane in ~40 ms a 320 x 240 frame (its
triangles reach behind the camera), the grid in ~5 ms (measured here); it is made after the
static world's copies, so that it is drawn last, under everything. EGL draws a flat box
there (a mesh body made after its plugin loaded crashes PyBullet 3.2.7). The rendering bodies have
no collision shape, so rays, contacts and physics never meet them.
* ``auto``: egl when a GPU's render node is there (/dev/dri/renderD*) and the plugin loads, else
  tiny, which needs nothing.

The EGL plugin draws only the bodies made after it loaded, so a World asking for it loads it
once its static world is built (``preload``; PyBullet 3.2.7 crashes making a body without a visual
shape while it is loaded), before any robot, and lets it go as it closes (``discard``); the
Renderer made at the first image takes it over.

The EGL plugin prints its GL versions and more on stdout from C; those prints are sent to
/dev/null (C's buffers flushed there) so that `--json` output stays JSON.

The camera looks along its sensor frame's +x with +z up, as Gazebo's; pixel (u, v) sees the ray
of the pinhole model with fx = fy = width / (2 tan(hfov / 2)), cx = (width - 1) / 2,
cy = (height - 1) / 2 (pixel centres at whole numbers, as sensor_msgs/CameraInfo's K). Depth is the
optical-axis distance z in metres (float32), from the depth buffer d as
z = far * near / (far - (far - near) * d); +inf where nothing is nearer than the far clip.
"""

from __future__ import annotations

import ctypes
import glob
import importlib.util
import math
from contextlib import contextmanager

import numpy as np

from mobot_cli.common.streams import silenced
from mobot_cli.common.transforms import quat_matrix
from mobot_cli.plan import SensorSpec, WorldPlan
from mobot_cli.sim.pb import p
from mobot_cli.sim.sensing import tiles

RENDERERS = ("auto", "tiny", "egl")
FLOOR_CELLS, FLOOR_SIZE = 16, 512.0  # m: the ground as cameras see it ends 256 m from the origin
FLOOR_RGBA = (0.6, 0.6, 0.6, 1.0)
# TinyRenderer drops the whole grid from a camera exactly above one of its vertices (measured): the
# grid is shifted off round coordinates, where robots are placed and move along the axes.
FLOOR_SHIFT = (0.3183099, 0.2718282)
# The depth buffer where nothing was drawn: 1 as float32 keeps it, less 2 ulps (TinyRenderer
# leaves 0.9999999); a surface just inside the far clip stays below (1 - d is ~1e-5 at 0.99 far).
CLEARED = float(np.float32(1.0) - 2 * np.finfo(np.float32).epsneg)
LUMA = np.array([0.299, 0.587, 0.114], dtype=np.float32)  # mono8 from RGB (ITU-R BT.601)


def intrinsics(spec: SensorSpec) -> tuple[float, float, float, float]:
    """fx, fy, cx, cy in pixels (pixel centres at whole numbers)."""
    fx = spec.width / (2.0 * math.tan(spec.field_of_view / 2.0))
    return fx, fx, (spec.width - 1) / 2.0, (spec.height - 1) / 2.0


def egl_ships() -> bool:
    """The eglRenderer module ships with this PyBullet (whether EGL works is known only on loading)."""
    return importlib.util.find_spec("eglRenderer") is not None


def gpu_present() -> bool:
    """A GPU's DRM render node is there."""
    return bool(glob.glob("/dev/dri/renderD*"))


@contextmanager
def _quiet():
    """stdout and stderr to /dev/null, C's stdio buffers flushed before they come back."""
    with silenced(1), silenced(2):
        try:
            yield
        finally:
            _fflush()


def _fflush() -> None:
    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError):
        pass


_PRELOADED: dict[int, int] = {}  # client -> the EGL plugin loaded for it, not yet taken by a Renderer


def preload(cid: int, wanted: str) -> None:
    """At a world's start: load the EGL plugin when ``wanted`` is egl, or auto with a GPU."""
    if wanted == "egl" or (wanted == "auto" and gpu_present()):
        _PRELOADED[cid] = _load_egl(cid)


def discard(cid: int) -> bool:
    """At a world's close: unload a plugin no Renderer took; whether one was loaded."""
    plugin = _PRELOADED.pop(cid, -1)
    if plugin >= 0:
        with _quiet():
            p.unloadPlugin(plugin, physicsClientId=cid)
    return plugin >= 0


def _load_egl(cid: int) -> int:
    spec = importlib.util.find_spec("eglRenderer")
    if spec is None or spec.origin is None:
        return -1
    with _quiet():  # the plugin prints its EGL and GL versions
        try:
            return p.loadPlugin(spec.origin, "_eglRendererPlugin", physicsClientId=cid)
        except p.error:
            return -1


class Renderer:
    """The renderer of one PyBullet client, chosen at its first image (``notice`` says which)."""

    def __init__(self, cid: int, wanted: str, world: WorldPlan, tile: float | None = tiles.TILE):
        self.cid, self.world = cid, world
        self.name = "tiny"
        self.plugin = -1
        why = "physics.renderer: tiny" if wanted == "tiny" else "no GPU found"
        if wanted == "egl" or (wanted == "auto" and gpu_present()):
            self.plugin = _PRELOADED.pop(cid, -1)
            why = "its EGL plugin did not load" + (", although physics.renderer asks for egl"
                                                   if wanted == "egl" else "")
        if self.plugin >= 0:
            self.name = "egl"
            _visual_twins(cid, world)
            self.notice = "cameras render with PyBullet's EGL plugin (OpenGL)"
        else:
            if tile is not None:
                tiles.retile(cid, world, tile)
            _floor(cid)  # after the copies: the ground is drawn last, under everything
            self.notice = f"cameras render with PyBullet's TinyRenderer (software; {why})"

    def close(self) -> None:
        """Unload the EGL plugin (it prints as it goes)."""
        if self.plugin >= 0:
            with _quiet():
                p.unloadPlugin(self.plugin, physicsClientId=self.cid)
            self.plugin = -1

    def image(self, spec: SensorSpec, position, quat) -> tuple[np.ndarray, np.ndarray]:
        """The RGB (H, W, 3 uint8) and depth (H, W float32 m, +inf beyond the far clip) seen from
        ``position`` with the sensor frame's orientation ``quat``."""
        w, h = spec.width, spec.height
        rotation = np.array(quat_matrix(quat))
        eye = np.array(position, dtype=float)
        view = p.computeViewMatrix(eye.tolist(), (eye + rotation[:, 0]).tolist(), rotation[:, 2].tolist(),
                                   physicsClientId=self.cid)
        vfov = 2.0 * math.atan(math.tan(spec.field_of_view / 2.0) * h / w)
        near, far = spec.range_min, spec.range_max
        projection = p.computeProjectionMatrixFOV(math.degrees(vfov), w / h, near, far, physicsClientId=self.cid)
        if self.name == "egl":
            with _quiet():
                out = p.getCameraImage(w, h, view, projection, shadow=0, renderer=p.ER_BULLET_HARDWARE_OPENGL,
                                       flags=p.ER_NO_SEGMENTATION_MASK, physicsClientId=self.cid)
        else:
            with _hidden(self.cid, _around(self.cid, position, near)):
                out = p.getCameraImage(w, h, view, projection, shadow=0, renderer=p.ER_TINY_RENDERER,
                                       flags=p.ER_NO_SEGMENTATION_MASK, physicsClientId=self.cid)
        rgb = np.asarray(out[2], dtype=np.uint8).reshape(h, w, 4)[:, :, :3]
        buffer = np.asarray(out[3], dtype=np.float64).reshape(h, w)
        with np.errstate(divide="ignore"):
            depth = far * near / (far - (far - near) * buffer)
        depth[(buffer >= CLEARED) | (depth > far)] = np.inf
        if spec.depth_clip is not None:  # the depth image's own clip (gz's <depth_camera><clip>)
            depth[depth > spec.depth_clip[1]] = np.inf
            depth[depth < spec.depth_clip[0]] = -np.inf
        return np.ascontiguousarray(rgb), depth.astype(np.float32)


def _around(cid: int, eye, near: float) -> list[tuple[int, int, int, tuple]]:
    """The visual shapes of robots' links whose boxes hold the camera (grown by its near clip):
    (body, link, shape index, colour) each. TinyRenderer does not clip triangles at the near
    plane: one whose corners lie on both sides of the camera is drawn across the image, and a
    housing round the camera (Robotnik's Orbbec Astra on the Summit XL) took it minutes a frame,
    in C, where Ctrl-C cannot stop it. Such a link is hidden from the camera inside it, as a
    renderer that clips shows little of it."""
    found = []
    lo, hi = [v - near for v in eye], [v + near for v in eye]
    for body, link in p.getOverlappingObjects(lo, hi, physicsClientId=cid) or ():
        if p.getDynamicsInfo(body, link, physicsClientId=cid)[0] <= 0.0:
            continue  # static world geometry: a camera under a table still sees it
        low, high = p.getAABB(body, link, physicsClientId=cid)
        if all(low[k] - near <= eye[k] <= high[k] + near for k in range(3)):
            shapes = [s for s in p.getVisualShapeData(body, physicsClientId=cid) if s[1] == link]
            found += [(body, link, k, tuple(s[7])) for k, s in enumerate(shapes)]
    return found


@contextmanager
def _hidden(cid: int, shapes: list[tuple[int, int, int, tuple]]):
    """Those visual shapes made transparent while the block runs, their colours put back after."""
    for body, link, k, rgba in shapes:
        p.changeVisualShape(body, link, shapeIndex=k, rgbaColor=(*rgba[:3], 0.0), physicsClientId=cid)
    try:
        yield
    finally:
        for body, link, k, rgba in shapes:
            p.changeVisualShape(body, link, shapeIndex=k, rgbaColor=rgba, physicsClientId=cid)


def encode(rgb: np.ndarray, encoding: str) -> np.ndarray:
    """An RGB image in a sensor_msgs/Image encoding: rgb8 (H, W, 3), bgr8 or mono8 (H, W)."""
    if encoding == "bgr8":
        return np.ascontiguousarray(rgb[:, :, ::-1])
    if encoding == "mono8":
        return np.clip(np.rint(rgb.astype(np.float32) @ LUMA), 0, 255).astype(np.uint8)
    return rgb


def image_noise(rgb: np.ndarray, mean: float, stddev: float, rng: np.random.Generator) -> np.ndarray:
    """Gazebo's gaussian image noise: one value per pixel, added to each of its channels in [0, 1],
    clamped."""
    noise = (rng.normal(mean, stddev, rgb.shape[:2]) * 255.0).astype(np.float32)
    noisy = rgb.astype(np.float32) + noise[:, :, None]
    return np.clip(np.rint(noisy), 0, 255).astype(np.uint8)


def depth_noise(depth: np.ndarray, mean: float, stddev: float, rng: np.random.Generator) -> np.ndarray:
    """Gaussian noise in metres on every finite depth (+inf stays)."""
    noise = rng.normal(mean, stddev, depth.shape).astype(np.float32)
    return np.where(np.isfinite(depth), depth + noise, depth).astype(np.float32)


def _visual_twins(cid: int, world: WorldPlan) -> None:
    """Visual-only bodies (no collision, so rays, contacts and physics never meet them) where the
    world has bodies of collision shapes, which the EGL renderer would not draw."""
    for body in world.bodies:
        for shape in body.shapes:
            args = _visual_args(shape)
            if args is None:
                continue
            try:
                visual = p.createVisualShape(physicsClientId=cid, rgbaColor=(0.75, 0.75, 0.75, 1.0), **args)
            except p.error:
                continue
            p.createMultiBody(0.0, -1, visual, basePosition=body.xyz, baseOrientation=body.quat,
                              useMaximalCoordinates=True, physicsClientId=cid)
    if world.ground_plane:
        floor = p.createVisualShape(p.GEOM_BOX, halfExtents=(500.0, 500.0, 0.001), rgbaColor=FLOOR_RGBA,
                                    visualFramePosition=(0.0, 0.0, -0.001), physicsClientId=cid)
        p.createMultiBody(0.0, -1, floor, physicsClientId=cid)


def _floor(cid: int) -> None:
    """Every horizontal plane body drawn as a grid (see the module) at its height."""
    for index in range(p.getNumBodies(physicsClientId=cid)):
        uid = p.getBodyUniqueId(index, physicsClientId=cid)
        try:
            with _quiet():  # PyBullet prints its failure on stdout
                shapes = p.getCollisionShapeData(uid, -1, physicsClientId=cid)
        except p.error:  # a robot's base without a collision shape
            continue
        if len(shapes) != 1 or shapes[0][2] != p.GEOM_PLANE:
            continue
        position, orientation = p.getBasePositionAndOrientation(uid, physicsClientId=cid)
        if abs(abs(p.getMatrixFromQuaternion(orientation)[8]) - 1.0) > 1e-9:
            continue  # a tilted plane keeps its own drawing
        p.changeVisualShape(uid, -1, rgbaColor=(0.0, 0.0, 0.0, 0.0), physicsClientId=cid)
        vertices, indices = _grid(FLOOR_CELLS, FLOOR_SIZE / FLOOR_CELLS)
        visual = p.createVisualShape(p.GEOM_MESH, vertices=vertices, indices=indices, rgbaColor=FLOOR_RGBA,
                                     physicsClientId=cid)
        p.createMultiBody(0.0, -1, visual, basePosition=(*FLOOR_SHIFT, position[2]), physicsClientId=cid)


def _grid(n: int, cell: float) -> tuple[list, list]:
    """A flat square mesh of n x n cells facing +z."""
    vertices = [[(i - n / 2) * cell, (j - n / 2) * cell, 0.0] for i in range(n + 1) for j in range(n + 1)]
    indices = []
    for i in range(n):
        for j in range(n):
            a = i * (n + 1) + j
            indices += [a, a + n + 1, a + 1, a + 1, a + n + 1, a + n + 2]
    return vertices, indices


def _visual_args(shape) -> dict | None:
    where = {"visualFramePosition": shape.xyz, "visualFrameOrientation": shape.quat}
    size = shape.size
    if shape.kind == "box":
        return {"shapeType": p.GEOM_BOX, "halfExtents": [s / 2.0 for s in size], **where}
    if shape.kind in ("cylinder", "capsule"):
        kind = p.GEOM_CYLINDER if shape.kind == "cylinder" else p.GEOM_CAPSULE
        return {"shapeType": kind, "radius": size[0], "length": size[1], **where}
    if shape.kind == "sphere":
        return {"shapeType": p.GEOM_SPHERE, "radius": size[0], **where}
    if shape.kind == "mesh":
        return {"shapeType": p.GEOM_MESH, "fileName": shape.mesh, "meshScale": list(size), **where}
    return None  # a plane: the ground's twin stands for it
