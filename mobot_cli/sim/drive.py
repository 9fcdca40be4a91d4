"""Differential-drive math: body twist to wheel speeds and wheel encoders to odometry.

Pure functions and one small integrator, written to match ros2_control's
``diff_drive_controller`` (same multipliers, same exact arc integration), so a run here
reports what that controller would report on the same wheel motion.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

# Skid-steer fit: multiplier = 1 + SKID_STEER_GAIN * min(wheelbase / track, 1)^2.
SKID_STEER_GAIN = 0.3


def default_separation_multiplier(track: float, wheelbase: float) -> float:
    """Wheel-separation multiplier for skid steer: 1 + 0.3 * min(wheelbase / track, 1)^2 (measured).

    Skid-steer bases (several wheels per side) turn slower than their wheel speeds say, as the
    wheels scrub sideways. The (wheelbase/track)^2 shape is the classic effective-track result;
    the gain is fitted in PyBullet with mobot's defaults (pyramid friction, axial wheel friction
    0.5, torque 20 N*m), commanding a 90 deg turn in place:
      multiplier 1.0:   husky 66.5 deg (0.5 rad/s), jackal 76.1, linorobot2 4wd 73.0 (1 rad/s)
      multiplier 1.5:   husky 113, jackal 120, linorobot2 4wd 114 (0.3..1 rad/s)
      this model:       husky 1.241 -> 90.2, jackal 1.146 -> 89.0, linorobot2 4wd 1.235 -> 93.1;
                        over 0.3..1.5 rad/s: husky 80..92, jackal 89..91, linorobot2 4wd 92..93.
    1 + (wheelbase/track)^2 (1.49..1.80) would over-turn by 25-35 %.
    Bases longer than wide scrub with less sideways friction (sim/bullet/friction.py,
    skid_axial_fraction), which makes them turn as a square base does: open loop at
    multiplier 1.0, 0.5 and 1 rad/s, a 4-wheel base of our own turned 0.72..0.75 of its wheel
    kinematics at wheelbase/track 1.0, 1.4, 1.6 and 2.0 alike; so the ratio stops at 1.
    """
    if track <= 0.0:
        raise ValueError(f"track must be positive, got {track}")
    return 1.0 + SKID_STEER_GAIN * min(wheelbase / track, 1.0) ** 2


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
        self.x, self.y, self.yaw = arc(self.x, self.y, self.yaw, distance, turn)


def arc(x: float, y: float, yaw: float, distance: float, turn: float) -> tuple[float, float, float]:
    """The planar pose after driving ``distance`` along an arc that turns by ``turn`` (exact)."""
    if abs(turn) < 1e-6:
        # Second-order Runge-Kutta, as the controller does, avoids dividing by ~0.
        mid = yaw + turn / 2.0
        return x + distance * math.cos(mid), y + distance * math.sin(mid), yaw + turn
    radius = distance / turn
    end = yaw + turn
    return (x + radius * (math.sin(end) - math.sin(yaw)),
            y - radius * (math.cos(end) - math.cos(yaw)), end)


def wrap_angle(angle: float) -> float:
    """Wrap an angle to [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi
