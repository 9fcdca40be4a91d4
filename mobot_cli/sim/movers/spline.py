"""An actor trajectory's curve, as Gazebo plays it (gz-common's PoseAnimation on gz-math's splines).

Gazebo does not draw straight lines between an actor's waypoints. Each ``<trajectory>`` becomes a
PoseAnimation whose position follows a cubic Hermite spline through the waypoints, and whose
rotation follows a quaternion spline (squad):

* position tangents by Catmull-Rom on the waypoint index, scaled by ``1 - tension`` (the
  trajectory's ``tension`` attribute, clamped to [0, 1]); an end tangent points to its
  neighbour, and a trajectory that ends where it starts is closed (its end tangents wrap round);
* rotation tangents by Shoemake's rule, q_i exp(-(log(q_i^-1 q_i+1) + log(q_i^-1 q_i-1)) / 4), and
  squad between keyframes, the shorter way only between the keyframes themselves;
* the fraction between two keyframes is the fraction of their time (not of arc length).

Actors turn about z only, so every quaternion here is (w, z) = (cos(yaw / 2), sin(yaw / 2)); the
arithmetic is gz-math's (Quaternion::Log, Exp, Slerp, Squad) restricted to that plane, with its
thresholds. Yaws are taken as the world file writes them (3.142 and -3.141 are the same heading
but not the same quaternion, and the spline follows the quaternion).
"""

from __future__ import annotations

import math

LOG_EPS = 1e-3  # gz-math Quaternion::Log / Exp: below this sine the vector part is taken as is
SLERP_EPS = 1e-3  # gz-math Quaternion::Slerp: nearer than this to parallel, lerp and normalise
TIME_EPS = 1e-6  # gz-math equal(): a fraction this near 0 or 1 is the keyframe itself


class Curve:
    """One trajectory's keyframes ``(t, x, y, yaw)`` (t from the trajectory's start, ascending)."""

    __slots__ = ("frames", "tangents", "turns")

    def __init__(self, frames: list[tuple[float, float, float, float]], tension: float):
        self.frames = frames
        self.tangents = _position_tangents([(f[1], f[2]) for f in frames], min(max(tension, 0.0), 1.0))
        self.turns = _rotation_tangents([_quat(f[3]) for f in frames])

    def at(self, index: int, s: float) -> tuple[float, float, float]:
        """(x, y, yaw) a fraction ``s`` of the time from keyframe ``index`` to the next."""
        f0 = self.frames[index]
        if index + 1 >= len(self.frames) or s <= TIME_EPS:
            return f0[1], f0[2], _yaw(_quat(f0[3]))
        f1 = self.frames[index + 1]
        if s >= 1.0 - TIME_EPS:
            return f1[1], f1[2], _yaw(_quat(f1[3]))
        (m0x, m0y), (m1x, m1y) = self.tangents[index], self.tangents[index + 1]
        s2, s3 = s * s, s * s * s
        h00, h10, h01, h11 = 2 * s3 - 3 * s2 + 1, s3 - 2 * s2 + s, -2 * s3 + 3 * s2, s3 - s2
        x = h00 * f0[1] + h10 * m0x + h01 * f1[1] + h11 * m1x
        y = h00 * f0[2] + h10 * m0y + h01 * f1[2] + h11 * m1y
        q = _squad(s, _quat(f0[3]), self.turns[index], self.turns[index + 1], _quat(f1[3]))
        return x, y, _yaw(q)


def _position_tangents(points: list[tuple[float, float]], tension: float) -> list[tuple[float, float]]:
    """gz-math Spline::RecalcTangents (Catmull-Rom, scaled by 1 - tension)."""
    n = len(points)
    if n < 2:
        return [(0.0, 0.0)] * n
    k = 0.5 * (1.0 - tension)
    closed = math.dist(points[0], points[-1]) <= 1e-6  # gz-math Vector3 == (within 1e-6)

    def half(a, b):
        return ((b[0] - a[0]) * k, (b[1] - a[1]) * k)

    tangents = []
    for i in range(n):
        if i == 0:
            tangents.append(half(points[n - 2], points[1]) if closed else half(points[0], points[1]))
        elif i == n - 1:
            tangents.append(tangents[0] if closed else half(points[i - 1], points[i]))
        else:
            tangents.append(half(points[i - 1], points[i + 1]))
    return tangents


def _rotation_tangents(quats: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """gz-math RotationSpline::RecalcTangents (Shoemake)."""
    n = len(quats)
    if n < 2:
        return list(quats)
    closed = all(abs(a - b) <= 1e-3 for a, b in zip(quats[0], quats[-1]))  # gz-math Quaternion ==
    tangents = []
    for i, q in enumerate(quats):
        inverse = (q[0], -q[1])
        if i == 0:
            after, before = quats[1], (quats[n - 2] if closed else q)
        elif i == n - 1:
            after, before = (quats[1] if closed else q), quats[i - 1]
        else:
            after, before = quats[i + 1], quats[i - 1]
        angle = -0.25 * (_log(_mul(inverse, after)) + _log(_mul(inverse, before)))
        tangents.append(_mul(q, _exp(angle)))
    return tangents


def _quat(yaw: float) -> tuple[float, float]:
    return math.cos(0.5 * yaw), math.sin(0.5 * yaw)


def _yaw(q: tuple[float, float]) -> float:
    return math.remainder(2.0 * math.atan2(q[1], q[0]), 2.0 * math.pi)


def _mul(a: tuple[float, float], b: tuple[float, float]) -> tuple[float, float]:
    return a[0] * b[0] - a[1] * b[1], a[0] * b[1] + a[1] * b[0]


def _log(q: tuple[float, float]) -> float:
    """The z of Quaternion::Log (its w is 0)."""
    if abs(q[0]) < 1.0:
        angle = math.acos(q[0])
        sine = math.sin(angle)
        if abs(sine) >= LOG_EPS:
            return angle / sine * q[1]
    return q[1]


def _exp(z: float) -> tuple[float, float]:
    """Quaternion::Exp of (0, 0, 0, z)."""
    angle = abs(z)
    sine = math.sin(angle)
    if abs(sine) >= LOG_EPS:
        return math.cos(angle), sine / angle * z
    return math.cos(angle), z


def _slerp(t: float, p: tuple[float, float], q: tuple[float, float], shortest: bool) -> tuple[float, float]:
    """gz-math Quaternion::Slerp."""
    cos = p[0] * q[0] + p[1] * q[1]
    if cos < 0.0 and shortest:
        cos, q = -cos, (-q[0], -q[1])
    if abs(cos) < 1.0 - SLERP_EPS:
        sin = math.sqrt(1.0 - cos * cos)
        angle = math.atan2(sin, cos)
        c0, c1 = math.sin((1.0 - t) * angle) / sin, math.sin(t * angle) / sin
        return c0 * p[0] + c1 * q[0], c0 * p[1] + c1 * q[1]
    w, z = (1.0 - t) * p[0] + t * q[0], (1.0 - t) * p[1] + t * q[1]
    norm = math.hypot(w, z)
    return (w / norm, z / norm) if norm > 0.0 else (1.0, 0.0)


def _squad(t: float, p, a, b, q) -> tuple[float, float]:
    """gz-math Quaternion::Squad (the shorter way between the keyframes p and q)."""
    return _slerp(2.0 * t * (1.0 - t), _slerp(t, p, q, True), _slerp(t, a, b, False), False)
