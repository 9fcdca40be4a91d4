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

The gains adapt only while the command holds (not in the control period that saw it change,
nor while wheel targets ramp) and while the measured twist is not more than ``BAND`` short of
the command, so a robot pushing against a wall, or accelerating from rest, does not wind them
up. A body going more than ``BAND`` beyond the command (no wall does that) adapts as if it were
``BAND`` over: skipping those periods too froze the loop whenever a command began with the body
moving faster than asked, as after a turn in place (a 1 m arc then ran 35.9 % tight on a base
whose separation multiplier over-turned by half; 0.03 % fresh). They stay within ``LIMITS``.

How far a skid base falls short depends on the shape of the command (straight, arc, turn in
place), so the gains are learnt per shape: the share of the wheel speed that turns the body,
|w| * track/2 / (|v| + |w| * track/2), in ``SHAPES`` steps, forward and reverse apart. A shape
keeps its gains across commands (they describe the robot on this floor doing that), and a
command never inherits another shape's: with one pair of gains for everything, an arc right
after a turn in place started from the turn's gains and ran 2.5 % tighter than a fresh one
(a square 4-wheel base of our own; 5.7 % on a long one before its friction was fixed).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

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
# Command shapes told apart: the turning share of the wheel speed in this many steps (0 straight,
# SHAPES in place); a 1 m-radius arc of a 0.5 m-track base is shape 1, a 0.3 m one shape 3.
SHAPES = 6


@dataclass
class TwistTrim:
    """Gains applied to a commanded (linear, angular) twist before it becomes wheel speeds."""

    half_track: float = 0.25  # m, half the wheel separation the drive uses
    gains: dict[tuple[int, int], list[float]] = field(default_factory=dict)  # shape -> [linear, angular]

    def shape(self, linear: float, angular: float) -> tuple[int, int]:
        """The command's shape: (direction of travel, turning share in SHAPES steps)."""
        turning = abs(angular) * self.half_track
        share = turning / (abs(linear) + turning) if turning > 0.0 else 0.0
        return (0 if abs(linear) < MIN_LINEAR else int(math.copysign(1, linear)), round(share * SHAPES))

    def gains_for(self, linear: float, angular: float) -> tuple[float, float]:
        """The (linear, angular) gains learnt for this command's shape (1, 1 when new)."""
        gains = self.gains.get(self.shape(linear, angular))
        return (1.0, 1.0) if gains is None else (gains[0], gains[1])

    def update(self, command: tuple[float, float], measured: tuple[float, float],
               dt: float) -> bool:
        """Fold one control period's measured body twist in; True when a gain changed."""
        gains = list(self.gains_for(*command))
        changed = False
        for index, (wanted, got, floor) in enumerate(
                zip(command, measured, (MIN_LINEAR, MIN_ANGULAR))):
            if abs(wanted) < floor:
                continue
            error = 1.0 - got / wanted  # > 0: the body falls short of the command
            if error > BAND:  # far short: blocked, or starting
                continue
            error = max(error, -BAND)  # far over (no wall does that): adapt, at the band's pace
            value = gains[index] + GAIN * dt * error
            gains[index] = min(LIMITS[1], max(LIMITS[0], value))
            changed = True
        if changed:
            self.gains[self.shape(*command)] = gains
        return changed

    def apply(self, linear: float, angular: float) -> tuple[float, float]:
        """The twist to turn into wheel speeds for a commanded one."""
        gain_linear, gain_angular = self.gains_for(linear, angular)
        return linear * gain_linear, angular * gain_angular
