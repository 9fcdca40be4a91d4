"""A robot's lidar points and its path as the local controller (timeline/local.py) reads them:
scans as world points, kept ready to be put in the robot's frame each control tick."""

from __future__ import annotations

import math

import numpy as np


class Cloud:
    """Lidar points (world x, y), kept as rows x, y, 1, x^2 + y^2 (4, n): put in a robot's frame
    with their distances from it by one small matrix product per control tick."""

    def __init__(self, points: np.ndarray):
        points = np.asarray(points, dtype=float).reshape(-1, 2)
        self.lifted = np.empty((4, len(points)))
        self.lifted[:2] = points.T
        self.lifted[2] = 1.0
        self.lifted[3] = np.einsum("ij,ij->i", points, points)

    def seen_from(self, pose) -> np.ndarray:
        """(3, n): each point's x and y in the frame of a robot at ``pose`` (world x, y, yaw) and
        its squared distance from the robot."""
        x, y, yaw = pose
        c, s = math.cos(yaw), math.sin(yaw)
        frame = np.array([[c, s, -c * x - s * y, 0.0],
                          [-s, c, s * x - c * y, 0.0],
                          [-2.0 * x, -2.0 * y, x * x + y * y, 1.0]])
        return frame @ self.lifted


def level_points(scan) -> np.ndarray:
    """A lidar scan's returns as world (x, y) points (n, 2): a 3D lidar gives its beam row
    nearest the horizontal (its floor and ceiling returns are not obstacles)."""
    beams = scan.beams
    row = 0 if len(beams.vertical) == 1 else int(np.argmin(np.abs(beams.vertical)))
    count = len(beams.horizontal)
    ranges = scan.ranges[row]
    x, y, z, w = scan.quat
    # The beams' directions in the world's x and y (the lidar may be tilted), times their ranges.
    rotation = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y + z * w)],
                         [2 * (x * y - z * w), 1 - 2 * (x * x + z * z)],
                         [2 * (x * z + y * w), 2 * (y * z - x * w)]])
    keep = np.isfinite(ranges)
    points = beams.directions[row * count:(row + 1) * count][keep] @ rotation
    points *= ranges[keep, None]
    points += scan.position[:2]
    return points


def joined(clouds: list) -> np.ndarray:
    """Point clouds (each (n, 2)) as one array."""
    return np.concatenate(clouds) if clouds else np.zeros((0, 2))


def path_in_frame(points: list, x: float, y: float, yaw: float) -> np.ndarray:
    """A few world (x, y) points in the frame of a robot at (x, y, yaw), as an (m, 2) array."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([(c * (px - x) + s * (py - y), -s * (px - x) + c * (py - y)) for px, py in points])
