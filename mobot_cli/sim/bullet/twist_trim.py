"""Closing the loop on body twist for skid-steer drives.

A skid-steer base (several driven wheels per side) turns by scrubbing its wheels sideways, and
how far its body twist falls from the wheel kinematics depends on everything at once: wheelbase
over track, mass and where it sits, torque, speed, turn radius. No fixed separation multiplier
fits them all: measured on four-wheel robots of our own (tests/sim/robots/skid4.urdf.xacro) the
default multiplier over-turned in place by 2..18 deg of 90 and drove 1 m-radius arcs up to 16 %
too tight, a centre of mass 10 cm ahead of the axle centre alone giving 9..15 %. Real skid-steer
bases close the loop on a gyro and wheel odometry for the same reason; so does mobot: the
multiplier stays the feed-forward (and what encoder odometry uses), and two gains trim the
commanded linear and angular speeds until the measured body twist matches the command.

The gains adapt only where the model is roughly right: while the command holds (not in the
control period that saw it change, nor while wheel targets ramp) and while the measured twist is
within ``BAND`` of the command, so a robot pushing against a wall, or accelerating from rest,
does not wind them up. They persist across commands (they describe the robot on this floor)
and stay within ``LIMITS``.
"""

from __future__ import annotations

from dataclasses import dataclass

# Integral gain on the relative twist error, per second: errors decay with a 0.25 s time
# constant, behind the wheels' own response (< 0.1 s), so the loop does not ring. At 2/s the
# first quarter-second of a 90 deg turn in place went by untrimmed: 93..96 deg instead of 90.
GAIN = 4.0  # 1/s
# Adapt only while the measured twist is within this fraction of the command.
BAND = 0.3
LIMITS = (0.5, 2.0)
# Commands smaller than these are "zero" for the trim (nothing to compare against).
MIN_LINEAR = 1e-3  # m/s
MIN_ANGULAR = 1e-3  # rad/s


@dataclass
class TwistTrim:
    """Gains applied to a commanded (linear, angular) twist before it becomes wheel speeds."""

    linear: float = 1.0
    angular: float = 1.0

    def update(self, command: tuple[float, float], measured: tuple[float, float],
               dt: float) -> bool:
        """Fold one control period's measured body twist in; True when a gain changed."""
        changed = False
        for index, (wanted, got, floor) in enumerate(
                zip(command, measured, (MIN_LINEAR, MIN_ANGULAR))):
            if abs(wanted) < floor:
                continue
            error = 1.0 - got / wanted  # > 0: the body falls short of the command
            if abs(error) > BAND:
                continue
            name = ("linear", "angular")[index]
            value = getattr(self, name) + GAIN * dt * error
            setattr(self, name, min(LIMITS[1], max(LIMITS[0], value)))
            changed = True
        return changed

    def apply(self, linear: float, angular: float) -> tuple[float, float]:
        """The twist to turn into wheel speeds for a commanded one."""
        return linear * self.linear, angular * self.angular
