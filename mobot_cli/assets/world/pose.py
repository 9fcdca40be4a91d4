"""Poses as SDF writes them (x y z roll pitch yaw, or a quaternion) as 4x4 numpy transforms.

The rotation maths is common.transforms'; SDF reading composes whole transforms, hence numpy.
"""

from __future__ import annotations

import math
import re

import numpy as np

from mobot_cli.common.transforms import matrix_rpy, quat_from_matrix, quat_matrix, rpy_matrix

Matrix = np.ndarray  # 4x4 homogeneous transform

IDENTITY = np.eye(4)


def transform(xyz, rotation: np.ndarray | None = None) -> Matrix:
    """A 4x4 transform from a translation and a 3x3 rotation."""
    m = np.eye(4)
    m[:3, 3] = xyz
    if rotation is not None:
        m[:3, :3] = rotation
    return m


def parse_pose(text: str | None, degrees: bool = False, quaternion: bool = False) -> Matrix:
    """A pose element's text as a transform; ValueError when it is not 6 (or 7) finite numbers."""
    values = [float(v) for v in (text or "").split()] if (text or "").strip() else [0.0] * 6
    expected = 7 if quaternion else 6
    if len(values) != expected:
        raise ValueError(f"needs {expected} numbers, got {len(values)}")
    if not all(math.isfinite(v) for v in values):
        raise ValueError("has a non-finite number")
    if quaternion:
        x, y, z, qx, qy, qz, qw = values
        if qx * qx + qy * qy + qz * qz + qw * qw < 1e-12:
            raise ValueError("has a zero quaternion")
        return transform((x, y, z), np.array(quat_matrix((qx, qy, qz, qw))))
    x, y, z, roll, pitch, yaw = values
    if degrees:
        roll, pitch, yaw = (math.radians(a) for a in (roll, pitch, yaw))
    return transform((x, y, z), np.array(rpy_matrix(roll, pitch, yaw)))


def inverse(m: Matrix) -> Matrix:
    """The inverse of a rigid transform."""
    out = np.eye(4)
    out[:3, :3] = m[:3, :3].T
    out[:3, 3] = -m[:3, :3].T @ m[:3, 3]
    return out


def xyz_quat(m: Matrix) -> tuple[tuple[float, float, float], tuple[float, float, float, float]]:
    """Translation and quaternion (x, y, z, w) of a transform, as plain floats."""
    xyz = tuple(_clean(v) for v in m[:3, 3])
    return xyz, tuple(_clean(c) for c in quat_from_matrix(m[:3, :3]))  # type: ignore[return-value]


def rpy(m: Matrix) -> tuple[float, float, float]:
    """Fixed-axis roll, pitch, yaw of a transform's rotation (URDF's <origin rpy>)."""
    return tuple(_clean(a) for a in matrix_rpy(m[:3, :3]))  # type: ignore[return-value]


def _clean(v: float) -> float:
    # Round to 1e-12 so composing poses does not leave 1e-17 noise in texts and caches.
    return round(float(v), 12) + 0.0


_NUMBER = re.compile(r"\s*([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)")


def stream_numbers(text: str) -> list[str] | None:
    """The numbers a C++ stream reads from ``text``, as Gazebo classic reads a pose: '41.6-0.19' is
    41.6 and -0.19. None when anything else is left."""
    out, pos, text = [], 0, text.strip()
    while pos < len(text):
        match = _NUMBER.match(text, pos)
        if match is None:
            return None
        out.append(match.group(1))
        pos = match.end()
    return out
