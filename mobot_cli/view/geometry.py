"""Small pose maths for the view: transforms of ROS poses, rotations as viser's (w, x, y, z) quaternions."""

from __future__ import annotations

import math

import numpy as np

Quat = tuple[float, float, float, float]


def matrix(xyz: tuple[float, ...], quat: Quat) -> np.ndarray:
    """The 4x4 transform of a position and a ROS (x, y, z, w) quaternion."""
    x, y, z, w = quat
    n = math.sqrt(x * x + y * y + z * z + w * w) or 1.0
    x, y, z, w = x / n, y / n, z / n, w / n
    m = np.eye(4)
    m[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                 [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                 [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    m[:3, 3] = xyz[:3]
    return m


def matrix_wxyz(m: np.ndarray) -> tuple[float, float, float, float]:
    """The (w, x, y, z) quaternion of a rotation matrix (its upper-left 3x3)."""
    r = m[:3, :3]
    t = r[0, 0] + r[1, 1] + r[2, 2]
    if t > 0:
        s = math.sqrt(t + 1.0) * 2
        return (0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s)
    i = int(np.argmax([r[0, 0], r[1, 1], r[2, 2]]))
    j, k = (i + 1) % 3, (i + 2) % 3
    s = math.sqrt(1.0 + r[i, i] - r[j, j] - r[k, k]) * 2
    q = [0.0, 0.0, 0.0, 0.0]
    q[0] = (r[k, j] - r[j, k]) / s
    q[1 + i] = 0.25 * s
    q[1 + j] = (r[j, i] + r[i, j]) / s
    q[1 + k] = (r[k, i] + r[i, k]) / s
    return (q[0], q[1], q[2], q[3])


def rpy_matrices(rpy: np.ndarray) -> np.ndarray:
    """(n, 3) roll, pitch, yaw (URDF's fixed axes) as (n, 3, 3) rotation matrices."""
    cr, sr = np.cos(rpy[:, 0]), np.sin(rpy[:, 0])
    cp, sp = np.cos(rpy[:, 1]), np.sin(rpy[:, 1])
    cy, sy = np.cos(rpy[:, 2]), np.sin(rpy[:, 2])
    return np.stack([np.stack([cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr], -1),
                     np.stack([sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr], -1),
                     np.stack([-sp, cp * sr, cp * cr], -1)], axis=1)


def axis_rotations(axis: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotations by ``angles`` about one unit ``axis`` (Rodrigues)."""
    x, y, z = axis
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    s, c = np.sin(angles)[:, None, None], np.cos(angles)[:, None, None]
    return np.eye(3) + s * k + (1 - c) * (k @ k)


def matrices_wxyz(r: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotation matrices as (n, 4) unit (w, x, y, z) quaternions."""
    m00, m11, m22 = r[:, 0, 0], r[:, 1, 1], r[:, 2, 2]
    q = np.stack([1 + m00 + m11 + m22, 1 + m00 - m11 - m22, 1 - m00 + m11 - m22, 1 - m00 - m11 + m22], -1)
    q = np.sqrt(np.maximum(q, 0.0)) / 2  # magnitudes; signs from the off-diagonal terms
    q[:, 1] = np.copysign(q[:, 1], r[:, 2, 1] - r[:, 1, 2])
    q[:, 2] = np.copysign(q[:, 2], r[:, 0, 2] - r[:, 2, 0])
    q[:, 3] = np.copysign(q[:, 3], r[:, 1, 0] - r[:, 0, 1])
    return q / np.linalg.norm(q, axis=1, keepdims=True)
