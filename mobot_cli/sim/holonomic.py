"""Holonomic-drive maths: a body twist (vx, vy, wz) to mecanum wheel speeds and back, and the
exact integration of a planar twist.

Written to match gz-sim's MecanumDrive system and gz-math's MecanumDriveOdometry: the same
wheel equations (with L = (wheel_separation + wheelbase) / 2), the same forward kinematics
from the four wheels' travel, the same exact integration (Runge-Kutta 2 below 1e-6 rad).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

# DriveSpec kinds that take a sideways linear_y: a scenario's drive type "holonomic".
KINDS = ("mecanum", "omni")


def mecanum_wheel_speeds(linear: float, lateral: float, angular: float, separation: float,
                         wheelbase: float, radius: float) -> tuple[float, float, float, float]:
    """Front-left, front-right, back-left, back-right wheel speeds (rad/s) for a body twist."""
    reach = 0.5 * (separation + wheelbase)
    turn = angular * reach
    return ((linear - lateral - turn) / radius, (linear + lateral + turn) / radius,
            (linear + lateral - turn) / radius, (linear - lateral + turn) / radius)


def mecanum_body_twist(front_left: float, front_right: float, back_left: float, back_right: float,
                       separation: float, wheelbase: float) -> tuple[float, float, float]:
    """Body (forward, lateral, turn) from the four wheels' rim travel (or rim speeds)."""
    reach = max(0.5 * (separation + wheelbase), 1e-9)
    return ((front_left + front_right + back_left + back_right) * 0.25,
            (-front_left + front_right + back_left - back_right) * 0.25,
            (-front_left + front_right - back_left + back_right) / (4.0 * reach))


def planar(x: float, y: float, yaw: float, forward: float, lateral: float,
           turn: float) -> tuple[float, float, float]:
    """The pose after moving ``forward`` and ``lateral`` (in the body frame) while turning by
    ``turn``, all at constant rates: gz-math's IntegrateExact (RK2 for tiny turns)."""
    if abs(turn) < 1e-6:
        mid = yaw + turn / 2.0
        c, s = math.cos(mid), math.sin(mid)
        return x + forward * c - lateral * s, y + forward * s + lateral * c, yaw + turn
    end = yaw + turn
    ratio, ratio2 = forward / turn, lateral / turn
    sin_d, cos_d = math.sin(end) - math.sin(yaw), math.cos(end) - math.cos(yaw)
    return x + ratio * sin_d + ratio2 * cos_d, y - ratio * cos_d + ratio2 * sin_d, end


@dataclass
class PlanarOdometry:
    """Planar pose integrated from body-frame (forward, lateral, turn) steps."""

    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0

    def integrate(self, forward: float, lateral: float, turn: float) -> None:
        """Fold in one interval's motion (metres, metres, radians)."""
        self.x, self.y, self.yaw = planar(self.x, self.y, self.yaw, forward, lateral, turn)


def _places(count: int) -> list[float]:
    """Where each of a side's wheels (front first) sits from front (0) to back (1)."""
    return [i / (count - 1) for i in range(count)] if count > 1 else [0.5]


def side_rates(n_left: int, n_right: int, linear: float, lateral: float, angular: float,
               separation: float, wheelbase: float, radius: float) -> list[float]:
    """Every wheel's forward rate (rad/s), left side then right, front first: the front and back
    wheels of a side as MecanumDrive turns them, wheels between them in proportion (one wheel a
    side, at wheelbase 0, turns as a diff drive's)."""
    fl, fr, bl, br = mecanum_wheel_speeds(linear, lateral, angular, separation, wheelbase, radius)
    return ([(1.0 - t) * fl + t * bl for t in _places(n_left)]
            + [(1.0 - t) * fr + t * br for t in _places(n_right)])


def corners(travel: list[float], n_left: int) -> tuple[float, float, float, float]:
    """Front-left, front-right, back-left, back-right travel from every wheel's (as side_rates
    orders them): the mean of each side's front half and back half (a middle wheel in both)."""
    out = []
    for side in (travel[:n_left], travel[n_left:]):
        places = _places(len(side))
        front = [v for v, t in zip(side, places) if t <= 0.5]
        back = [v for v, t in zip(side, places) if t >= 0.5]
        out.append((sum(front) / len(front), sum(back) / len(back)))
    (fl, bl), (fr, br) = out
    return fl, fr, bl, br
