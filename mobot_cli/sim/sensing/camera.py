"""Camera readings: an image is rendered only when something reads it (docs/cameras.md).

A camera due at a step gives an ``ImageData`` that knows where the camera is; its pixels are
rendered (sim/sensing/render.py) the first time ``rgb`` or ``depth`` is read, as long as the
world has not stepped since: the run folder, the bag, a subscribed ROS 2 topic, the API and the
view read them as the reading passes, and a camera nobody reads costs nothing. Read after the
world moved on, an image that was never rendered is gone (``expired``): ``rgb`` and ``depth``
are None. Noise comes from the camera's own generator, drawn as its images are rendered, so the
same inputs and seed that render the same images give the same bytes.
"""

from __future__ import annotations

import threading
from typing import Callable

import numpy as np

from mobot_cli.plan import SensorSpec
from mobot_cli.sim.sensing import render


class Cameras:
    """The renderer of one world and what renders a camera's image."""

    def __init__(self, cid: int, world, wanted: str, notices: list[str], step_now: Callable[[], int]):
        self.cid, self.world, self.wanted = cid, world, wanted
        self.notices, self.step_now = notices, step_now
        self._renderer: render.Renderer | None = None
        self.lock = threading.Lock()  # a live world's clients may read an image from another thread
        self.rendered = 0  # images rendered so far

    @property
    def changed_scene(self) -> bool:
        """The renderer added its rendering bodies to the world (sim/sensing/render.py)."""
        return self._renderer is not None

    def renderer(self, spec: SensorSpec | None = None) -> render.Renderer:
        """The world's renderer, made (and said, once per world) at the first image."""
        if self._renderer is None:
            self._renderer = render.Renderer(self.cid, self.wanted, self.world)
            first = f" (the first: '{spec.name}', {spec.width} x {spec.height})" if spec else ""
            self.notices.append(f"{self._renderer.notice}; every image costs CPU time{first}: "
                                "`sensors: {NAME: off}` in a scenario leaves a camera out")
        return self._renderer

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()

    def take(self, spec: SensorSpec, rng: np.random.Generator, position, quat) -> tuple:
        """(rgb in the camera's encoding or None, depth or None), rendered now."""
        rgb, depth = self.renderer(spec).image(spec, position, quat)
        self.rendered += 1
        noisy = spec.noise_stddev > 0.0 or spec.noise_mean != 0.0
        if spec.kind == "depth":
            if noisy:
                depth = render.depth_noise(depth, spec.noise_mean, spec.noise_stddev, rng)
            return None, depth
        if noisy:
            rgb = render.image_noise(rgb, spec.noise_mean, spec.noise_stddev, rng)
        rgb = render.encode(rgb, spec.encoding)
        return rgb, (depth if spec.kind == "rgbd" else None)


class ImageData:
    """One camera reading: rendered when first read at the step it was taken (see the module)."""

    __slots__ = ("spec", "step", "position", "quat", "_cameras", "_rng", "_images", "expired")

    def __init__(self, cameras: Cameras, spec: SensorSpec, rng: np.random.Generator, step: int, position, quat):
        self.spec, self.step, self.position, self.quat = spec, step, position, quat
        self._cameras, self._rng = cameras, rng
        self._images: tuple | None = None
        self.expired = False

    def _render(self) -> tuple:
        if self._images is None and not self.expired:
            cameras = self._cameras
            with cameras.lock:
                if self._images is None:
                    if cameras.step_now() != self.step:
                        self.expired = True
                        return (None, None)
                    self._images = cameras.take(self.spec, self._rng, self.position, self.quat)
                    self._cameras = None  # the world is no longer needed
        return self._images or (None, None)

    @property
    def rgb(self) -> np.ndarray | None:
        """uint8 (H, W, 3) in rgb8 or bgr8, (H, W) in mono8; None for a depth-only camera."""
        return self._render()[0]

    @property
    def depth(self) -> np.ndarray | None:
        """float32 (H, W), metres along the optical axis, +inf beyond the far clip; None for an
        RGB-only camera."""
        return self._render()[1]

    @property
    def rendered(self) -> bool:
        return self._images is not None
