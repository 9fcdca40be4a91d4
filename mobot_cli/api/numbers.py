"""Numbers given to the Python API and the Gymnasium env, checked before the world sees them.

A NaN or 1e308 twist reaches PyBullet and the odometry and leaves the robot's state NaN for the
rest of the run; a NaN or infinite duration raised a bare ValueError or OverflowError. Each is
refused with mobot's own UsageError naming the argument, its unit and the limit (docs/errors.md).
"""

from __future__ import annotations

import math
import numbers

from mobot_cli.errors import UsageError


def bounded(what: str, value: object, unit: str, limit: float, low: float | None = None,
            strict: bool = False) -> float:
    """``value`` as a finite float with |value| <= limit (and >= ``low``, > when ``strict``)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise UsageError(f"{what}: expected a number in {unit}, got {type(value).__name__} {value!r:.40}")
    number = float(value)
    if not math.isfinite(number):
        raise UsageError(f"{what}: {number} {unit} is not a finite number")
    if abs(number) > limit:
        raise UsageError(f"{what}: {number:g} {unit} is beyond the limit of {limit:g} {unit}")
    if low is not None and (number < low or (strict and number == low)):
        raise UsageError(f"{what}: {number:g} {unit} must be {'above' if strict else 'at least'} {low:g} {unit}")
    return number
