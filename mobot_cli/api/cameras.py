"""Camera images from Python: ``Simulation.image(robot, camera)`` (docs/cameras.md).

A camera's image is rendered only when something reads it (sim/sensing/camera.py). Asking
``image`` for a camera makes the simulation render that camera's frames from then on, at the
camera's rate, as the timeline takes them; the first ask renders the camera's view now when
its latest frame was not rendered.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mobot_cli.errors import UsageError
from mobot_cli.plan import CAMERA_KINDS, SensorSpec
from mobot_cli.sim.sensing.render import intrinsics
from mobot_cli.timeline.records import Reading


@dataclass(frozen=True)
class CameraImage:
    """One camera frame as numpy arrays (read-only), with the pinhole that made it."""

    robot: str
    camera: str
    step: int  # taken after this many physics steps
    t: float  # s
    rgb: np.ndarray | None = field(repr=False)  # uint8 (H, W, 3) rgb8/bgr8 or (H, W) mono8; None: depth only
    depth: np.ndarray | None = field(repr=False)  # float32 (H, W) m along the optical axis, +inf: nothing
    encoding: str  # the rgb image's: "rgb8" | "bgr8" | "mono8"
    k: np.ndarray = field(repr=False)  # 3x3 intrinsics [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]
    frame: str  # the optical frame the image is stamped with


def pick_camera(name: str, sensors: tuple[SensorSpec, ...], camera: str | None) -> SensorSpec:
    """The camera called ``camera``, or the robot's only camera; UsageError otherwise."""
    cameras = [s for s in sensors if s.kind in CAMERA_KINDS]
    names = ", ".join(s.name for s in cameras) or "none"
    if camera is not None:
        for spec in cameras:
            if spec.name == camera:
                return spec
        raise UsageError(f"robot '{name}' has no camera named '{camera}'", hint=f"Its cameras: {names}.")
    if len(cameras) != 1:
        raise UsageError(f"robot '{name}' has {len(cameras)} cameras: name the one you mean" if cameras
                         else f"robot '{name}' has no camera",
                         hint=f"Its cameras: {names}." if cameras else
                         "Add one in the scenario: sensors: {camera: {type: camera, link: base_link}}.")
    return cameras[0]


def image_of(robot: str, spec: SensorSpec, step: int, data, rate_hz: int, frame: str) -> CameraImage:
    """An ImageData (rendered now if it was not) as a CameraImage."""
    rgb, depth = data.rgb, data.depth
    for array in (rgb, depth):
        if array is not None:
            array.flags.writeable = False  # shared with the records of the same frame
    fx, fy, cx, cy = intrinsics(spec)
    k = np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])
    return CameraImage(robot, spec.name, step, step / rate_hz, rgb, depth, spec.encoding, k, frame)


class Wanted:
    """The cameras asked for (a timeline consumer): their frames are rendered as they pass."""

    def __init__(self) -> None:
        self.cameras: set[tuple[str, str]] = set()

    def __call__(self, record) -> None:
        if isinstance(record, Reading) and (record.robot, record.sensor.name) in self.cameras:
            record.data.rgb  # noqa: B018 - rendering is what reading it does
