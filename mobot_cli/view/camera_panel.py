"""The selected robot's camera in the side panel (`run --view`, `serve --view`; docs/cameras.md).

On the simulation's thread, ``CameraFeed.take`` renders a camera reading of the selected robot
(sim/sensing/camera.py renders only what is read) while a browser is connected, at most
``rate_hz`` frames a second; the view's thread shows the latest frame as an image in the panel.
A depth-only camera is shown as grey levels, near bright, nothing within the far clip black.
"""

from __future__ import annotations

import threading
import time
from typing import Any

import numpy as np


def picture(data, far: float) -> np.ndarray | None:
    """A frame as RGB uint8 for the page."""
    rgb = data.rgb
    if rgb is not None:
        if rgb.ndim == 2:
            return np.repeat(rgb[:, :, None], 3, axis=2)
        return rgb[:, :, ::-1] if data.spec.encoding == "bgr8" else rgb
    depth = data.depth
    if depth is None:
        return None
    grey = np.where(np.isfinite(depth), 255.0 * (1.0 - np.clip(depth / far, 0.0, 1.0)), 0.0).astype(np.uint8)
    return np.repeat(grey[:, :, None], 3, axis=2)


class CameraFeed:
    """The latest frame of the selected robot's camera, and the panel image that shows it."""

    def __init__(self, server: Any, rate_hz: float = 5.0):
        self.server, self.period = server, 1.0 / rate_hz
        self._next = 0.0
        self._frame: tuple[str, np.ndarray] | None = None
        self._lock = threading.Lock()
        self.image = None  # the panel's image handle, made with the first frame
        self.shown = 0  # frames shown: for tests

    def take(self, record, selected: str | None) -> None:
        """A camera reading (simulation thread): rendered and kept when it is the selected robot's,
        someone watches and the last frame is old enough."""
        if record.robot != selected or time.monotonic() < self._next or not self.server.get_clients():
            return
        frame = picture(record.data, record.sensor.range_max)
        if frame is not None:
            self._next = time.monotonic() + self.period
            with self._lock:
                self._frame = (f"{record.robot}: {record.sensor.name}", np.ascontiguousarray(frame))

    def draw(self) -> None:
        """Show the kept frame (view thread)."""
        with self._lock:
            frame, self._frame = self._frame, None
        if frame is None:
            return
        label, pixels = frame
        if self.image is None:
            self.image = self.server.gui.add_image(pixels, label=label, format="jpeg")
        else:
            self.image.image = pixels
        self.shown += 1
