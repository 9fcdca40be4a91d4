"""Poses as SDF writes them (x y z roll pitch yaw, or a quaternion) and 4x4 transforms."""

from __future__ import annotations

import math

import numpy as np

Matrix = np.ndarray  # 4x4 homogeneous transform

IDENTITY = np.eye(4)


def rpy_rotation(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """SDF's (and URDF's) fixed-axis roll, pitch, yaw: R = Rz(yaw) * Ry(pitch) * Rx(roll)."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def quat_rotation(x: float, y: float, z: float, w: float) -> np.ndarray:
    """Rotation matrix of a quaternion (x, y, z, w), normalised first."""
    n = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


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
        return transform((x, y, z), quat_rotation(qx, qy, qz, qw))
    x, y, z, roll, pitch, yaw = values
    if degrees:
        roll, pitch, yaw = (math.radians(a) for a in (roll, pitch, yaw))
    return transform((x, y, z), rpy_rotation(roll, pitch, yaw))


def inverse(m: Matrix) -> Matrix:
    """The inverse of a rigid transform."""
    out = np.eye(4)
    out[:3, :3] = m[:3, :3].T
    out[:3, 3] = -m[:3, :3].T @ m[:3, 3]
    return out


def xyz_quat(m: Matrix) -> tuple[tuple[float, float, float], tuple[float, float, float, float]]:
    """Translation and quaternion (x, y, z, w) of a transform, as plain floats."""
    r = m[:3, :3]
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    if trace > 0:
        s = 2.0 * math.sqrt(trace + 1.0)
        q = ((r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, s / 4)
    elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q = (s / 4, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s, (r[2, 1] - r[1, 2]) / s)
    elif r[1, 1] > r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
        q = ((r[0, 1] + r[1, 0]) / s, s / 4, (r[1, 2] + r[2, 1]) / s, (r[0, 2] - r[2, 0]) / s)
    else:
        s = 2.0 * math.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
        q = ((r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, s / 4, (r[1, 0] - r[0, 1]) / s)
    if q[3] < 0:  # one canonical sign, so equal rotations print the same
        q = tuple(-c for c in q)
    n = math.sqrt(sum(c * c for c in q))
    xyz = tuple(_clean(v) for v in m[:3, 3])
    return xyz, tuple(_clean(c / n) for c in q)  # type: ignore[return-value]


def rpy(m: Matrix) -> tuple[float, float, float]:
    """Fixed-axis roll, pitch, yaw of a transform's rotation (URDF's <origin rpy>)."""
    r = m[:3, :3]
    pitch = math.asin(max(-1.0, min(1.0, -r[2, 0])))
    if abs(r[2, 0]) < 1.0 - 1e-9:
        roll = math.atan2(r[2, 1], r[2, 2])
        yaw = math.atan2(r[1, 0], r[0, 0])
    else:  # gimbal lock: put the whole turn into yaw
        roll = 0.0
        yaw = math.atan2(-r[0, 1], r[1, 1])
    return _clean(roll), _clean(pitch), _clean(yaw)


def _clean(v: float) -> float:
    # Round to 1e-12 so composing poses does not leave 1e-17 noise in texts and caches.
    return round(float(v), 12) + 0.0
