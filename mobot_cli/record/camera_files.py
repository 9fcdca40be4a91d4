"""``DIR/sensors/<robot>/<camera>/``: a camera's frames as PNG files, one per image (docs/cameras.md).

* ``rgb/NNNNNN.png``: the image (8-bit RGB; 8-bit grey for a mono8 camera; a bgr8 camera's
  frames are stored as RGB like the others);
* ``depth/NNNNNN.png``: depth as 16-bit grey in millimetres (0: nothing within the far clip,
  or farther than 65.535 m), as ROS's 16UC1 depth images and RGB-D datasets store it; the bag,
  the topics and the API give the float32 metres;
* ``frames.csv``: frame, step, t (s) of every frame, written as it comes;
* ``camera.json``: size, encoding, intrinsics (fx, fy, cx, cy), clip planes, frame and topics.

One PNG per frame streams (a killed run keeps every frame written), loads with any image
library, and is what image tools take; ``np.asarray(PIL.Image.open(path))`` gives the array.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from mobot_cli.common.numbers import number
from mobot_cli.plan import RobotPlan, SensorSpec
from mobot_cli.record.png import encode_array
from mobot_cli.ros import sensor_topics
from mobot_cli.sim.sensing.render import intrinsics

FLUSH_EVERY = 50  # frames between two flushes of frames.csv
MAX_MM = 65535


def depth_mm(depth: np.ndarray) -> np.ndarray:
    """float32 metres to uint16 millimetres (0: no reading, as 16UC1 depth images)."""
    mm = np.rint(np.where(np.isfinite(depth), depth, 0.0) * 1000.0)
    mm[(mm > MAX_MM) | (mm < 0)] = 0
    return mm.astype(np.uint16)


def describe(key: str, robot: RobotPlan, spec: SensorSpec, physics_rate_hz: int) -> dict:
    """What camera.json says."""
    fx, fy, cx, cy = intrinsics(spec)
    topics = sensor_topics.camera_topics(robot, spec)
    return {"robot": key, "sensor": spec.name, "kind": spec.kind, "link": spec.link,
            "frame_id": sensor_topics.sensor_frame(robot, spec).frame,
            "rate_hz": sensor_topics.rate_hz(spec, physics_rate_hz), "width": spec.width, "height": spec.height,
            "encoding": spec.encoding, "horizontal_fov": spec.field_of_view, "clip_near": spec.range_min,
            "clip_far": spec.range_max, **({"depth_clip": list(spec.depth_clip)} if spec.depth_clip else {}),
            "fx": fx, "fy": fy, "cx": cx, "cy": cy, "topics": topics,
            "rgb": "rgb/NNNNNN.png" if spec.kind != "depth" else None,
            "depth": "depth/NNNNNN.png (uint16 mm, 0: none)" if spec.kind != "camera" else None}


class CameraFrames:
    """A camera's folder, growing a frame at a time."""

    def __init__(self, folder: Path, about: dict):
        self.folder = folder
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "camera.json").write_text(json.dumps(about, indent=2) + "\n", encoding="utf-8")
        self._csv = (folder / "frames.csv").open("w", encoding="utf-8", newline="")
        self._csv.write("frame,step,t\n")
        self.frames = 0

    def append(self, step: int, t: float, data) -> None:
        """One ImageData (sim/sensing/camera.py), rendered here if nothing rendered it yet."""
        rgb, depth = data.rgb, data.depth
        if rgb is None and depth is None:
            return  # expired: read too late (not by this sink, which reads at the step)
        name = f"{self.frames:06d}.png"
        if rgb is not None:
            if data.spec.encoding == "bgr8":
                rgb = rgb[:, :, ::-1]
            _write(self.folder / "rgb" / name, encode_array(np.ascontiguousarray(rgb)))
        if depth is not None:
            _write(self.folder / "depth" / name, encode_array(depth_mm(depth)))
        self._csv.write(f"{self.frames},{step},{number(t)}\n")
        self.frames += 1
        if self.frames % FLUSH_EVERY == 0:
            self._csv.flush()

    def close(self) -> None:
        self._csv.close()


def _write(path: Path, data: bytes) -> None:
    try:
        path.write_bytes(data)
    except FileNotFoundError:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
