"""Ackermann (car-like) steering: the bicycle model, its limits, wheel angles, speeds, odometry.

Positions are in the root frame, measured from the middle of the driven (rear) axle: x forward,
y left. A body twist (v, w) drives that point along a circle of radius v / w; each steered wheel
at (x, y) points at atan(w x / (v - w y)) (inner and outer angles from wheelbase and track, as
gz-sim's AckermannSteering sets them) and each wheel rolls at its own speed (the differential).
"""

from __future__ import annotations

import math

from mobot_cli.sim.drive import arc

# Below these a command counts as zero (gz-sim's AckermannSteering uses 0.001 rad/s too).
MIN_LINEAR = 1e-6  # m/s
MIN_ANGULAR = 1e-3  # rad/s


def min_turning_radius(wheelbase: float, max_steering_angle: float) -> float:
    """The tightest radius of the rear axle's middle: wheelbase / tan(max steering angle)."""
    return wheelbase / math.tan(max_steering_angle)


def clamp(linear: float, angular: float, min_radius: float) -> tuple[float, float, str | None]:
    """The twist a car can follow, and why it differs: "radius" (tighter than ``min_radius``),
    "in place" (a turn without forward speed), or None when it is unchanged."""
    if abs(angular) < MIN_ANGULAR:
        return linear, 0.0, None
    if abs(linear) < MIN_LINEAR:
        return 0.0, 0.0, "in place"
    limit = abs(linear) / min_radius
    if abs(angular) > limit * (1.0 + 1e-9):
        return linear, math.copysign(limit, angular), "radius"
    return linear, angular, None


def steering_angle(linear: float, angular: float, x: float, y: float) -> float:
    """The angle (rad, about +z) of a steered wheel at (x, y) for the twist (v, w)."""
    along = linear - angular * y
    if abs(along) < MIN_LINEAR:
        return 0.0
    return math.atan(angular * x / along)


def rim_speed(linear: float, angular: float, x: float, y: float, steer: float = 0.0) -> float:
    """The rolling speed (m/s) of a wheel at (x, y) pointing ``steer`` rad off the body's x axis."""
    return (linear - angular * y) * math.cos(steer) + angular * x * math.sin(steer)


def curvature(steer: float, x: float, y: float) -> float:
    """The path curvature (1/m, + turning left) that a steered wheel at (x, y) set to ``steer``
    stands for: the inverse of ``steering_angle``."""
    tangent = math.tan(steer)
    denominator = x + y * tangent
    return tangent / denominator if abs(denominator) > 1e-9 else 0.0


def angular_from_steering(linear: float, steer: float, wheelbase: float) -> float:
    """The yaw rate of the bicycle model at this speed and steering angle: v tan(steer) / L."""
    return linear * math.tan(steer) / wheelbase


def lever_arc(point: tuple[float, float], x: float, y: float, yaw: float, distance: float,
              turn: float) -> tuple[float, float, float]:
    """The root's pose after the body ``point`` (root frame: the rear axle's middle) drives
    ``distance`` along an arc that turns by ``turn``: a car's root off its rear axle swings out."""
    c, s = math.cos(yaw), math.sin(yaw)
    px, py = x + c * point[0] - s * point[1], y + s * point[0] + c * point[1]
    px, py, yaw = arc(px, py, yaw, distance, turn)
    c, s = math.cos(yaw), math.sin(yaw)
    return px - c * point[0] + s * point[1], py - s * point[0] - c * point[1], yaw
