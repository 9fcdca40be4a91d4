"""The Gymnasium env's camera observation (gym/env.py's ``camera=``): images as SB3 takes them."""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from mobot_cli.plan import SensorSpec


def camera_space(base: spaces.Space, camera: SensorSpec, normalize: bool, odom: np.ndarray,
                 goal: np.ndarray) -> spaces.Dict:
    """``base`` (a Box of odom and goal, or the lidar's Dict) with the camera's image and depth added."""
    parts = dict(base.spaces) if isinstance(base, spaces.Dict) else {
        "odom": spaces.Box(-odom, odom, dtype=np.float32), "goal": spaces.Box(-goal, goal, dtype=np.float32)}
    h, w = camera.height, camera.width
    if camera.kind != "depth":
        parts["image"] = spaces.Box(0, 255, (h, w, 1 if camera.encoding == "mono8" else 3), np.uint8)
    if camera.kind != "camera":
        top = np.float32(1.0) if normalize else np.float32(camera.range_max)
        parts["depth"] = spaces.Box(np.float32(0.0), top, (h, w, 1), np.float32)
    return spaces.Dict(parts)


def camera_observation(obs, image, camera: SensorSpec, normalize: bool) -> dict:
    """``obs`` as a Dict with the camera's latest frame (black, and far, before its first)."""
    out = dict(obs) if isinstance(obs, dict) else {"odom": obs[:5], "goal": obs[5:]}
    h, w, far = camera.height, camera.width, np.float32(camera.range_max)
    if camera.kind != "depth":
        rgb = None if image is None else image.rgb
        channels = 1 if camera.encoding == "mono8" else 3
        out["image"] = np.zeros((h, w, channels), np.uint8) if rgb is None else rgb.reshape(h, w, channels).copy()
    if camera.kind != "camera":
        depth = None if image is None else image.depth
        depth = np.full((h, w), far, np.float32) if depth is None else np.minimum(depth, far)
        out["depth"] = (depth / far if normalize else depth).astype(np.float32).reshape(h, w, 1)
    return out
