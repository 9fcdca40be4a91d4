"""The local controller's free-space distances: how far the goal is through free space, on a
square grid around the robot, when the path ahead runs into something the map did not have
(timeline/local.py; nav2 propagates such distances through its costmap).

The lidar points are grown by the robot's radius, and a wavefront from the goal's cell relaxes
over the free cells (eight neighbours, diagonal steps sqrt(2) cells long) until nothing changes.
"""

from __future__ import annotations

import math

import numpy as np

WAVE_CELL = 0.1  # m: the grid's cell
WAVE_REACH = 2.5  # m: its half width around the robot


class Wavefront:
    """Distances (m) to the goal through free space on a square grid around the robot."""

    def __init__(self, goal, points: np.ndarray, radius: float):
        n = int(round(2 * WAVE_REACH / WAVE_CELL))
        self.n, self.origin = n, -WAVE_REACH
        blocked = np.zeros((n, n), dtype=bool)
        if len(points):
            ij = np.floor((points - self.origin) / WAVE_CELL).astype(int)
            inside = ((ij >= 0) & (ij < n)).all(axis=1)
            blocked[ij[inside, 1], ij[inside, 0]] = True
            blocked = _dilate(blocked, radius / WAVE_CELL)
        gx, gy = (np.clip(np.floor((np.asarray(goal) - self.origin) / WAVE_CELL).astype(int), 0, n - 1))
        seed_d = math.hypot(goal[0] - (self.origin + (gx + 0.5) * WAVE_CELL),
                            goal[1] - (self.origin + (gy + 0.5) * WAVE_CELL))
        dist = np.full((n, n), np.inf)
        free = ~blocked
        free[gy, gx] = True
        dist[gy, gx] = seed_d
        diag = math.sqrt(2.0) * WAVE_CELL
        moves = [(0, 1, WAVE_CELL), (0, -1, WAVE_CELL), (1, 0, WAVE_CELL), (-1, 0, WAVE_CELL),
                 (1, 1, diag), (1, -1, diag), (-1, 1, diag), (-1, -1, diag)]
        for _ in range(4 * n):  # relax until nothing changes
            before = dist.copy()
            for dy, dx, step in moves:
                src = dist[max(0, -dy):n - max(0, dy), max(0, -dx):n - max(0, dx)] + step
                dst = dist[max(0, dy):n - max(0, -dy), max(0, dx):n - max(0, -dx)]
                np.minimum(dst, src, out=dst)
            dist[~free] = np.inf
            if np.array_equal(dist, before):
                break
        # Cells nothing reaches (inside obstacles, walled off) cost as far as the grid is wide.
        dist[~np.isfinite(dist)] = 2 * n * WAVE_CELL
        self.dist = dist

    def at(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The distance at each point (the grid's edge value beyond it)."""
        ix = np.clip(np.floor((x - self.origin) / WAVE_CELL).astype(int), 0, self.n - 1)
        iy = np.clip(np.floor((y - self.origin) / WAVE_CELL).astype(int), 0, self.n - 1)
        return self.dist[iy, ix]


def _dilate(mask: np.ndarray, cells: float) -> np.ndarray:
    reach = int(math.ceil(cells))
    out = mask.copy()
    ny, nx = mask.shape
    for dy in range(-reach, reach + 1):
        for dx in range(-reach, reach + 1):
            if (dx or dy) and dx * dx + dy * dy <= (cells + 0.5) ** 2:
                src = mask[max(0, -dy):ny - max(0, dy), max(0, -dx):nx - max(0, dx)]
                out[max(0, dy):ny - max(0, -dy), max(0, dx):nx - max(0, -dx)] |= src
    return out
