"""The typed goal commands of a robot's ``commands:`` list: goto, path, patrol, coverage.

A command is a twist (``linear``, ``angular``, ``for``) or exactly one goal; the goal's own
settings (speed limits, timeout, localization) sit beside it on the command.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, Optional, Union

from pydantic import BaseModel, ConfigDict, Discriminator, Field, Tag, model_validator

from mobot_cli.common.polygon import area
from mobot_cli.scenario.limits import (
    MAX_ACCELERATION,
    MAX_ANGULAR_SPEED,
    MAX_COORDINATE,
    MAX_LANES,
    MAX_SPEED,
    MIN_SPACING,
    Coordinate,
    Float,
    Int,
    NonNegativeFloat,
    PositiveFloat,
    at_most,
)

GOALS = ("goto", "path", "patrol", "coverage")
# Settings that only a goal command takes.
GOAL_SETTINGS = ("timeout", "tolerance", "localization", "max_linear", "max_angular", "acceleration",
                 "angular_acceleration", "laps", "planner", "inflation", "local", "stuck_time", "danger_distance")
LOCAL_CONTROLLERS = ("dwb",)  # goal setting ``local:``: obstacle avoidance on the robot's own lidar
MAX_WAYPOINTS = 10_000
MIN_AREA = 1e-6  # m^2: a polygon enclosing less is empty
MAX_INFLATION = 10.0  # m: the largest radius a planner's map is inflated by
MAX_AREA_SIDE = 200.0  # m: the largest side of an area's bounding box (its grids stay small)

Point2 = tuple[Coordinate, Coordinate]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True, defer_build=True)


class GotoSpec(_Strict):
    """Drive to (x, y) in the world frame, then turn to ``yaw`` if given."""

    x: Coordinate
    y: Coordinate
    yaw: Optional[Float] = None  # rad
    tolerance: Optional[PositiveFloat] = None  # m; default 0.05


def _area_form(value: Any) -> str:
    """'box' for [xmin, xmax, ymin, ymax] (four numbers), 'polygon' for [[x, y], ...]."""
    if isinstance(value, (list, tuple)) and value and all(isinstance(v, (int, float)) for v in value):
        return "box"
    return "polygon"


Box = tuple[Coordinate, Coordinate, Coordinate, Coordinate]
Polygon = Annotated[list[Point2], Field(max_length=MAX_WAYPOINTS)]


Area = Annotated[Union[Annotated[Box, Tag("box")], Annotated[Polygon, Tag("polygon")]], Discriminator(_area_form)]


class CoverageSpec(_Strict):
    """Sweep an area lawn-mower style: lanes at most ``spacing`` apart over its free space."""

    area: Area
    spacing: Annotated[PositiveFloat, at_most(MAX_COORDINATE, "m", MIN_SPACING)]

    @model_validator(mode="after")
    def _not_empty(self) -> "CoverageSpec":
        side = check_area(self.area)
        if side / self.spacing > MAX_LANES:  # planning (and sweeping) grows with the lanes
            raise ValueError(f"spacing {self.spacing:g} m over an area {side:g} m across makes "
                             f"{side / self.spacing:.0f} lanes, more than the limit of {MAX_LANES}")
        return self


def check_area(value) -> float:
    """The area's longest side (m); ValueError for a box with its sides the wrong way round or a
    polygon with no inside."""
    if len(value) == 4 and all(isinstance(v, (int, float)) for v in value):
        xmin, xmax, ymin, ymax = value
        if not (xmin < xmax and ymin < ymax):
            raise ValueError(f"area [xmin, xmax, ymin, ymax] = {list(value)} needs xmin < xmax and ymin < ymax")
        side = max(xmax - xmin, ymax - ymin)
    else:
        if len(value) < 3:
            raise ValueError(f"area polygon has {len(value)} point{'s' if len(value) != 1 else ''}: "
                             "it needs at least 3 ([[x, y], ...])")
        if area(value) < MIN_AREA:
            raise ValueError("area polygon encloses no area (its points lie on one line)")
        side = max(max(p[i] for p in value) - min(p[i] for p in value) for i in (0, 1))
    if side > MAX_AREA_SIDE:
        raise ValueError(f"area is {side:g} m across, more than the limit of {MAX_AREA_SIDE:g} m")
    return side


Waypoints = Annotated[list[Point2], Field(min_length=1, max_length=MAX_WAYPOINTS)]


class GoalFields(_Strict):
    """The goal variants of a command and their settings (CommandSpec adds the twist)."""

    goto: Optional[GotoSpec] = None
    path: Optional[Waypoints] = None
    patrol: Optional[Annotated[list[Point2], Field(min_length=2, max_length=MAX_WAYPOINTS)]] = None
    coverage: Optional[CoverageSpec] = None
    laps: Optional[Annotated[Int, Field(ge=1, le=1_000_000)]] = None  # patrol; default: until the end
    timeout: Optional[Annotated[Float, Field(gt=0, le=1e6)]] = None  # s
    tolerance: Optional[PositiveFloat] = None  # m (goto takes its own inside goto:)
    localization: Optional[Literal["odometry", "ground_truth"]] = None
    max_linear: Optional[Annotated[PositiveFloat, at_most(MAX_SPEED, "m/s")]] = None
    max_angular: Optional[Annotated[PositiveFloat, at_most(MAX_ANGULAR_SPEED, "rad/s")]] = None
    acceleration: Optional[Annotated[PositiveFloat, at_most(MAX_ACCELERATION, "m/s^2")]] = None
    angular_acceleration: Optional[Annotated[PositiveFloat, at_most(MAX_ACCELERATION, "rad/s^2")]] = None
    planner: Optional[Literal["astar"]] = None  # goto, path, patrol: plan around the map's obstacles
    inflation: Optional[Annotated[Float, Field(ge=0, le=MAX_INFLATION)]] = None  # m; default: the footprint's radius
    local: Optional[Literal["dwb"]] = None  # default: none (the route is followed as it is)
    stuck_time: Optional[Annotated[Float, Field(gt=0, le=1e6)]] = None  # s without progress: blocked (stuck)
    danger_distance: Optional[Annotated[NonNegativeFloat, Field(le=100)]] = None  # m, for danger_time

    @property
    def goal(self) -> Optional[str]:
        """The goal this command gives, or None for a twist."""
        return next((k for k in GOALS if getattr(self, k) is not None), None)

    def check_goal(self, twist: list[str]) -> None:
        """ValueError unless the command is one twist or one goal with settings that fit it."""
        goals = [k for k in GOALS if getattr(self, k) is not None]
        if len(goals) > 1:
            raise ValueError(" and ".join(f"'{k}'" for k in goals) + ": one goal per command")
        settings = [k for k in GOAL_SETTINGS if getattr(self, k) is not None]
        if not goals:
            if settings:
                raise ValueError(f"'{settings[0]}' goes with a goal command ({', '.join(GOALS)})")
            return
        if twist:
            raise ValueError(f"mixes '{goals[0]}' with '{twist[0]}': a command is a twist or a goal")
        if self.laps is not None and goals[0] != "patrol":
            raise ValueError("'laps' goes with 'patrol'")
        if self.planner is not None and goals[0] == "coverage":
            raise ValueError("'planner' goes with goto, path or patrol (coverage plans its own lanes)")
        if self.inflation is not None and self.planner is None:
            raise ValueError("'inflation' goes with 'planner: astar'")
        if self.tolerance is not None and goals[0] == "goto":
            raise ValueError("a goto's tolerance goes inside it: goto: {x, y, tolerance}")
