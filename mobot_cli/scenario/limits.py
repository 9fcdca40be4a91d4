"""The scenario's documented limits, and number types that hold them at load.

Every number a scenario gives must be a real number (``true`` is not 1), finite, and where it
becomes steps, a file name or physics, bounded: past these limits a run would overflow, write
unnameable files or turn NaN. The README's "Limits" list names each one.
"""

from __future__ import annotations

import math
import re
import unicodedata
from typing import Annotated, Any

from pydantic import AfterValidator, BeforeValidator, Field

from mobot_cli.errors import did_you_mean, shown

MAX_SECONDS = 1e6  # any time or duration: about 11.6 days of simulated time
MAX_RATE_HZ = 10_000  # physics.rate_hz and log.rate_hz
MIN_LOG_RATE_HZ = 1e-3  # one log row every 1000 s
MAX_GRAVITY = 1000.0  # m/s^2, the length of physics.gravity (about 100 g)
MAX_COORDINATE = 1e6  # m, any spawn position component
MAX_NAME_LENGTH = 64  # robot and scenario names: file names (odom/<name>.csv) and ROS names
MAX_NAMESPACE_LENGTH = 256
MAX_REFERENCE_LENGTH = 1024  # a world or description: a bundled name or a path
# Physical bounds (docs/errors.md "Limits"): far beyond any ground robot, well inside what the
# physics and the odometry can carry without overflowing to inf.
MAX_SPEED = 100.0  # m/s, a command's linear speed and a goal's max_linear
MAX_ANGULAR_SPEED = 100.0  # rad/s, a command's angular speed and a goal's max_angular
MAX_ACCELERATION = 1000.0  # m/s^2 and rad/s^2, a goal's acceleration and angular_acceleration
MAX_WHEEL_RADIUS = 10.0  # m
MAX_WHEEL_SEPARATION = 100.0  # m
MAX_MULTIPLIER = 100.0  # wheel_radius_multiplier and wheel_separation_multiplier, both ways
MAX_WHEEL_TORQUE = 1e6  # N m
MAX_WHEEL_ACCELERATION = 1e5  # rad/s^2
MIN_SPACING = 0.005  # m, a coverage goal's lane spacing
MAX_LANES = 10_000  # a coverage area's longest side over its spacing

NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
FLEET_NAME_RE = re.compile(r"^[A-Za-z_]([A-Za-z0-9_]|\{i\})*$")
NAMESPACE_RE = re.compile(r"^(/[A-Za-z_][A-Za-z0-9_]*)+$")
SCENARIO_NAME_RE = re.compile(r"^[A-Za-z0-9_.-]+$")


def _number(value: Any) -> Any:
    # pydantic reads true as 1 and false as 0; `rate_hz: true` would run at 1 Hz.
    if isinstance(value, bool):
        raise ValueError(f"expected a number, got {str(value).lower()}")
    return value


def _seconds(value: float) -> float:
    if value > MAX_SECONDS:
        raise ValueError(f"{value:g} s is longer than the limit of {MAX_SECONDS:g} s (about 11.6 days)")
    return value


def _coordinate(value: float) -> float:
    if abs(value) > MAX_COORDINATE:
        raise ValueError(f"{value:g} m is farther than {MAX_COORDINATE:g} m from the origin")
    return value


def at_most(limit: float, unit: str, at_least: float = 0.0):
    """An AfterValidator: |value| within ``limit`` (and, when given, at least ``at_least``), the unit named."""
    unit = f" {unit}" if unit else ""

    def check(value: float) -> float:
        if abs(value) > limit:
            raise ValueError(f"{value:g}{unit} is beyond the limit of {limit:g}{unit}")
        if 0 < abs(value) < at_least:
            raise ValueError(f"{value:g}{unit} is below the limit of {at_least:g}{unit}")
        return value
    return AfterValidator(check)


def check_reference(value: str) -> str:
    """A world, description or scenario path: bounded, no control characters (ValueError if not)."""
    if len(value) > MAX_REFERENCE_LENGTH:
        raise ValueError(f"{shown(value, 40)} is {len(value)} characters long, the limit for a name or "
                         f"path is {MAX_REFERENCE_LENGTH}")
    if any(unicodedata.category(c) in ("Cc", "Zl", "Zp") for c in value):  # controls and line breaks
        raise ValueError(f"{shown(value, 40)} holds a control character (a newline, a tab): give a bundled "
                         "name or a path")
    return value


def gravity_length(vector: tuple[float, float, float]) -> tuple[float, float, float]:
    """Refuse a gravity vector longer than MAX_GRAVITY (math.hypot never overflows)."""
    if math.hypot(*vector) > MAX_GRAVITY:
        raise ValueError(f"gravity of length {math.hypot(*vector):g} m/s^2 is above the limit of "
                         f"{MAX_GRAVITY:g} m/s^2 (Earth's is 9.81)")
    return vector


ENGINES = ("bullet", "kinematic")  # physics.engine: see sim/plan.py Physics


def check_engine(name: str) -> str:
    """Refuse an engine mobot does not have, with the closest name."""
    if name not in ENGINES:
        close = did_you_mean(name, ENGINES)
        close = close + " " if close.startswith("Did") else ""
        raise ValueError(f"unknown engine {shown(name)}. {close}The engines are 'bullet' (the "
                         "default: wheels driven by torques) and 'kinematic' (robots follow the twist).")
    return name


Float = Annotated[float, BeforeValidator(_number)]
Int = Annotated[int, BeforeValidator(_number)]
PositiveFloat = Annotated[Float, Field(gt=0)]
NonNegativeFloat = Annotated[Float, Field(ge=0)]
Seconds = Annotated[Float, Field(ge=0), AfterValidator(_seconds)]  # a moment: at, settle
Duration = Annotated[Float, Field(gt=0), AfterValidator(_seconds)]  # a span: duration, for
Coordinate = Annotated[Float, AfterValidator(_coordinate)]
Vector3 = tuple[Float, Float, Float]
Speed = Annotated[Float, at_most(MAX_SPEED, "m/s")]
AngularSpeed = Annotated[Float, at_most(MAX_ANGULAR_SPEED, "rad/s")]
Reference = Annotated[str, AfterValidator(check_reference)]  # a world or description: bundled name or path


def check_name(value: str, what: str, pattern: re.Pattern, rule: str) -> str:
    """A name that is safe as a file name (and a ROS name): ``pattern`` and MAX_NAME_LENGTH."""
    if len(value) > MAX_NAME_LENGTH:
        raise ValueError(f"{shown(value, 40)} is not a valid {what} name: it is {len(value)} characters long, "
                         f"the limit is {MAX_NAME_LENGTH}")
    if not pattern.match(value):
        raise ValueError(f"{shown(value, 40)} is not a valid {what} name: {rule}")
    return value
