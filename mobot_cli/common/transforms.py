"""Rotations and rigid poses in plain Python: the one implementation every layer uses.

Conventions are ROS's: quaternions are (x, y, z, w); roll, pitch, yaw are fixed-axis angles,
R = Rz(yaw) * Ry(pitch) * Rx(roll), as URDF's <origin rpy> and SDF's <pose> write them.
Plain tuples, not numpy: drive detection, TF frames and floor plans need a handful of 3x3
products, and this keeps numpy's import time out of them. Code holding numpy arrays (SDF
poses) passes them in as they are: indexing is the same.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

Vec = tuple[float, float, float]
Mat = tuple[Vec, Vec, Vec]
Quat = tuple[float, float, float, float]

IDENTITY: Mat = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


def rpy_matrix(roll: float, pitch: float, yaw: float) -> Mat:
    """Fixed-axis roll, pitch, yaw as a rotation matrix: R = Rz(yaw) * Ry(pitch) * Rx(roll)."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return ((cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr),
            (sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr),
            (-sp, cp * sr, cp * cr))


def matrix_rpy(m) -> Vec:
    """Fixed-axis roll, pitch, yaw of a rotation matrix (the whole turn in yaw at gimbal lock)."""
    pitch = math.asin(max(-1.0, min(1.0, -m[2][0])))
    if abs(m[2][0]) < 1.0 - 1e-9:
        roll = math.atan2(m[2][1], m[2][2])
        yaw = math.atan2(m[1][0], m[0][0])
    else:
        roll = 0.0
        yaw = math.atan2(-m[0][1], m[1][1])
    return roll, pitch, yaw


def quat_from_rpy(roll: float, pitch: float, yaw: float) -> Quat:
    """Fixed-axis roll, pitch, yaw as a quaternion (x, y, z, w)."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy, cr * cp * cy + sr * sp * sy)


def yaw_quat(yaw: float) -> Quat:
    """The rotation about +z by ``yaw``."""
    return (0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0))


def quat_matrix(q) -> Mat:
    """The rotation matrix of a quaternion (x, y, z, w), normalised first."""
    x, y, z, w = q
    n = math.sqrt(x * x + y * y + z * z + w * w) or 1.0
    x, y, z, w = x / n, y / n, z / n, w / n
    return ((1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)),
            (2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)),
            (2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)))


def quat_from_matrix(m) -> Quat:
    """A unit quaternion (x, y, z, w) from a 3x3 rotation matrix, w >= 0 and never -0.0."""
    trace = m[0][0] + m[1][1] + m[2][2]
    if trace > 0.0:
        s = 2.0 * math.sqrt(trace + 1.0)
        q = ((m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s, s / 4.0)
    elif m[0][0] > m[1][1] and m[0][0] > m[2][2]:
        s = 2.0 * math.sqrt(1.0 + m[0][0] - m[1][1] - m[2][2])
        q = (s / 4.0, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s, (m[2][1] - m[1][2]) / s)
    elif m[1][1] > m[2][2]:
        s = 2.0 * math.sqrt(1.0 + m[1][1] - m[0][0] - m[2][2])
        q = ((m[0][1] + m[1][0]) / s, s / 4.0, (m[1][2] + m[2][1]) / s, (m[0][2] - m[2][0]) / s)
    else:
        s = 2.0 * math.sqrt(1.0 + m[2][2] - m[0][0] - m[1][1])
        q = ((m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, s / 4.0, (m[1][0] - m[0][1]) / s)
    norm = math.sqrt(sum(v * v for v in q))
    sign = -1.0 if q[3] < 0.0 else 1.0  # one canonical sign, so equal rotations print the same
    return tuple(sign * v / norm + 0.0 for v in q)  # type: ignore[return-value]


def quat_mul(a: Quat, b: Quat) -> Quat:
    """The Hamilton product a * b (rotate by b first, then a)."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz)


def mat_mul(a: Mat, b: Mat) -> Mat:
    """The product a * b of two 3x3 matrices."""
    return tuple(tuple(sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3))
                 for i in range(3))  # type: ignore[return-value]


def mat_vec(a: Mat, v: Vec) -> Vec:
    """The product a * v."""
    return tuple(sum(a[i][k] * v[k] for k in range(3)) for i in range(3))  # type: ignore


@dataclass(frozen=True)
class Frame:
    """A rigid transform as a rotation matrix and a translation: x_parent = rot * x_child + pos."""

    rot: Mat = IDENTITY
    pos: Vec = (0.0, 0.0, 0.0)

    def compose(self, other: "Frame") -> "Frame":
        """self * other: first other, then self."""
        moved = mat_vec(self.rot, other.pos)
        return Frame(mat_mul(self.rot, other.rot),
                     (moved[0] + self.pos[0], moved[1] + self.pos[1], moved[2] + self.pos[2]))

    def point(self, v: Vec) -> Vec:
        """A point given in the child frame, expressed in the parent frame."""
        moved = mat_vec(self.rot, v)
        return (moved[0] + self.pos[0], moved[1] + self.pos[1], moved[2] + self.pos[2])


def pose_point(xyz: Vec, quat: Quat, p: Vec) -> Vec:
    """A point given in the frame of the pose (xyz, quat), expressed in the parent frame."""
    m = quat_matrix(quat)
    return tuple(m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2] + xyz[i] for i in range(3))  # type: ignore


def compose_poses(a: tuple[Vec, Quat], b: tuple[Vec, Quat]) -> tuple[Vec, Quat]:
    """Pose a * pose b, each an (xyz, quat) pair: b is given in a's frame."""
    return pose_point(a[0], a[1], b[0]), quat_mul(a[1], b[1])


class Planar:
    """A 2D frame (x, y, yaw) in its parent: maps its points into the parent, as odometry needs."""

    def __init__(self, x: float, y: float, yaw: float):
        self.x, self.y, self.yaw = x, y, yaw
        self.c, self.s = math.cos(yaw), math.sin(yaw)

    def __call__(self, x: float, y: float) -> tuple[float, float]:
        """The point (x, y) of this frame in the parent frame."""
        return self.x + self.c * x - self.s * y, self.y + self.s * x + self.c * y


def odom_origin(true_x: float, true_y: float, true_yaw: float,
                odom_x: float, odom_y: float, odom_yaw: float) -> Planar:
    """Where odometry's (0, 0, 0) lies in the world: the true pose now, less the odometry so far."""
    yaw = true_yaw - odom_yaw
    c, s = math.cos(yaw), math.sin(yaw)
    return Planar(true_x - (c * odom_x - s * odom_y), true_y - (s * odom_x + c * odom_y), yaw)
