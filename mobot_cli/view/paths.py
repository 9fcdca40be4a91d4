"""A robot's true path and odometry path in the page, as line segments just above its wheels.

Live, points come at the view's rate; a point closer than ``MIN_STEP`` to the last one is skipped,
and the lines are re-sent at most every ``every`` seconds, so a long run costs the page little.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

LIFT = 0.01  # m above the robot's root link
# m between two kept points: fat lines are costly to draw in software (no GPU), so a path keeps
# one point per 5 cm, which still follows a robot turning in place closely enough.
MIN_STEP = 0.05
THICKNESS = 0.015  # m


def _segments(points: np.ndarray) -> np.ndarray:
    return np.stack([points[:-1], points[1:]], axis=1).astype(np.float32)


def thin(points: np.ndarray) -> np.ndarray:
    """The points at least MIN_STEP apart (the first and the last always kept)."""
    if len(points) < 3:
        return points
    keep, last = [0], points[0]
    for i in range(1, len(points) - 1):
        if np.sum((points[i] - last) ** 2) >= MIN_STEP ** 2:
            keep.append(i)
            last = points[i]
    keep.append(len(points) - 1)
    return points[keep]


def draw_path(server: Any, name: str, points: np.ndarray, color: tuple[int, int, int], visible: bool = True) -> Any:
    """(n, 3) points as one polyline; None when fewer than two."""
    if len(points) < 2:
        return None
    return server.scene.add_line_segments(name, _segments(points), color, thickness=THICKNESS, visible=visible)


def lighter(color: tuple[int, int, int], amount: float = 0.55) -> tuple[int, int, int]:
    """The colour washed towards white (the odometry path of a robot)."""
    return tuple(int(c + (255 - c) * amount) for c in color)  # type: ignore[return-value]


class LivePath:
    """A path that grows as a robot moves; ``flush`` re-sends it when it changed."""

    def __init__(self, server: Any, name: str, color: tuple[int, int, int], every: float = 0.5):
        self.server, self.name, self.color, self.every = server, name, color, every
        self.points: list[tuple[float, float, float]] = []
        self._sent, self._last = 0, 0.0
        self._handle: Any = None

    def add(self, x: float, y: float, z: float) -> None:
        """Keep the point if it is far enough from the last one kept."""
        if self.points:
            px, py, pz = self.points[-1]
            if (x - px) ** 2 + (y - py) ** 2 + (z - pz) ** 2 < MIN_STEP ** 2:
                return
        self.points.append((x, y, z + LIFT))

    def flush(self, visible: bool = True, force: bool = False) -> None:
        """Re-send the line if points were added and ``every`` seconds passed."""
        now = time.monotonic()
        if len(self.points) == self._sent or (not force and now - self._last < self.every):
            return
        if self._handle is None:
            self._handle = draw_path(self.server, self.name, np.array(self.points), self.color, visible)
        else:  # an update of the node's points, cheaper than a new node
            self._handle.points = _segments(np.array(self.points))
        self._sent, self._last = len(self.points), now
