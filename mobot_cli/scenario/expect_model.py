"""The typed ``expect:`` list: checks that make a run a test (``mobot run`` exits 1 on a failure).

Each item names a robot (or ``all``) and exactly one check. ``at`` is when: for ``within``
the moment the robot must be inside the area, for the other checks the end of the span
they cover (default: the end of the run). The checks over time (``reaches``, ``visits``,
``coverage``) take a deadline instead, ``within: SECONDS`` (default: the end of the run);
``goal`` checks how a goal command ended.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal, Optional, Union

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from mobot_cli.scenario.goal_model import Area, Waypoints, check_area
from mobot_cli.scenario.limits import Coordinate, Float, Int, NonNegativeFloat, PositiveFloat, Seconds

KINDS = ("within", "collisions", "distance", "upright", "odom_error", "reaches", "visits", "coverage", "goal",
         "clearance", "metric")
# The metrics a ``metric`` check may bound (timeline/metrics.py NUMERIC; success is 0 or 1)
METRICS = ("success", "collisions", "time", "path_length", "spl", "clearance_min", "clearance_mean",
           "danger_time", "jerk_linear", "jerk_angular", "people_distance_min", "people_intimate_time",
           "people_personal_time", "people_collisions")
OVER_TIME = ("reaches", "visits", "coverage")  # deadline: within: SECONDS
GOAL_STATUSES = ("reached", "reached_by_odometry_only", "timed_out", "blocked", "stuck", "cancelled",
                 "unreachable", "unfinished", "failed")
DEFAULT_VISIT_RADIUS = 0.3  # m
# Tilt (angle between the robot's z axis and the world's) beyond which a robot has tipped over.
DEFAULT_MAX_TILT = math.radians(45.0)


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True, defer_build=True)


class WithinSpec(_Strict):
    """A circle {x, y, radius} or a box {xmin, xmax, ymin, ymax}, in the world frame (metres)."""

    x: Optional[Float] = None
    y: Optional[Float] = None
    radius: Optional[PositiveFloat] = None
    xmin: Optional[Float] = None
    xmax: Optional[Float] = None
    ymin: Optional[Float] = None
    ymax: Optional[Float] = None

    @model_validator(mode="after")
    def _one_shape(self) -> "WithinSpec":
        circle = [k for k in ("x", "y", "radius") if getattr(self, k) is not None]
        box = [k for k in ("xmin", "xmax", "ymin", "ymax") if getattr(self, k) is not None]
        if circle and box:
            raise ValueError("mixes a circle (x, y, radius) with a box (xmin, xmax, ymin, ymax): use one")
        if box and len(box) < 4:
            raise ValueError("a box needs xmin, xmax, ymin and ymax")
        if box and (self.xmin >= self.xmax or self.ymin >= self.ymax):
            raise ValueError("a box needs xmin < xmax and ymin < ymax")
        if not box and len(circle) < 3:
            raise ValueError("give a circle {x, y, radius} or a box {xmin, xmax, ymin, ymax}")
        return self


class RangeSpec(_Strict):
    """Travelled distance bounds in metres; at least one of min and max."""

    min: Optional[NonNegativeFloat] = None
    max: Optional[NonNegativeFloat] = None

    @model_validator(mode="after")
    def _bounds(self) -> "RangeSpec":
        if self.min is None and self.max is None:
            raise ValueError("give 'min', 'max' or both (metres travelled)")
        if self.min is not None and self.max is not None and self.min > self.max:
            raise ValueError(f"min {self.min:g} is above max {self.max:g}")
        return self


class UprightSpec(_Strict):
    """The largest tilt (radians from vertical) that still counts as upright."""

    max_tilt: Annotated[Float, Field(gt=0, le=math.pi)] = DEFAULT_MAX_TILT


class OdomErrorSpec(_Strict):
    """Largest allowed drift of the robot's odometry from the truth."""

    position: Optional[NonNegativeFloat] = None  # metres
    yaw: Optional[NonNegativeFloat] = None  # radians

    @model_validator(mode="after")
    def _some(self) -> "OdomErrorSpec":
        if self.position is None and self.yaw is None:
            raise ValueError("give 'position' (m), 'yaw' (rad) or both")
        return self


class ClearanceSpec(_Strict):
    """The closest the robot's geometry may come to world geometry or other robots (metres)."""

    min: PositiveFloat


class ReachesSpec(_Strict):
    """A circle the robot must enter, in the world frame (metres)."""

    x: Coordinate
    y: Coordinate
    radius: PositiveFloat


class CoverageCheck(_Strict):
    """The fraction (0..1) of an area's free space the robot's footprint must sweep."""

    area: Area  # [xmin, xmax, ymin, ymax] or [[x, y], ...]
    min: Annotated[Float, Field(gt=0, le=1)]

    @model_validator(mode="after")
    def _not_empty(self) -> "CoverageCheck":
        check_area(self.area)
        return self


class GoalCheck(_Strict):
    """How goal command ``command`` (its index in the robot's commands list) must end."""

    command: Annotated[Int, Field(ge=0)]
    status: Literal[GOAL_STATUSES] = "reached"


class MetricCheck(_Strict):
    """Bounds on one navigation metric (docs/metrics.md) of goal command ``command`` or, without
    it, of the robot's whole life."""

    name: Literal[METRICS]
    min: Optional[Float] = None
    max: Optional[Float] = None
    command: Optional[Annotated[Int, Field(ge=0)]] = None

    @model_validator(mode="after")
    def _bounds(self) -> "MetricCheck":
        if self.min is None and self.max is None:
            raise ValueError(f"give 'min', 'max' or both for metric '{self.name}'")
        if self.min is not None and self.max is not None and self.min > self.max:
            raise ValueError(f"min {self.min:g} is above max {self.max:g}")
        return self


class ExpectSpec(_Strict):
    """One expectation: a robot (or ``all``), one check and when it applies."""

    robot: str
    at: Union[Seconds, Literal["end"]] = "end"  # Seconds first: its error is the one shown
    within: Optional[Union[WithinSpec, Seconds]] = None  # an area, or the deadline of a check over time
    collisions: Optional[Annotated[Int, Field(ge=0)]] = None
    distance: Optional[RangeSpec] = None
    upright: Optional[Union[Literal[True], UprightSpec]] = None
    odom_error: Optional[Union[NonNegativeFloat, OdomErrorSpec]] = None
    clearance: Optional[ClearanceSpec] = None
    reaches: Optional[ReachesSpec] = None
    visits: Optional[Waypoints] = None
    radius: Optional[PositiveFloat] = None  # visits: how close counts as a visit
    coverage: Optional[CoverageCheck] = None
    goal: Optional[GoalCheck] = None
    metric: Optional[MetricCheck] = None  # checked at the end of the run, from summary.json's metrics

    @field_validator("at", mode="before")
    @classmethod
    def _at(cls, v: object) -> object:
        if isinstance(v, str) and v != "end" or isinstance(v, bool):
            raise ValueError(f"'at' is 'end' or a time in seconds, e.g. 5.0; got {v!r}")
        return v

    @field_validator("upright", mode="before")
    @classmethod
    def _upright(cls, v: object) -> object:
        if v is False:
            raise ValueError("'upright: false' checks nothing: write 'upright: true' or {max_tilt: RADIANS}")
        return v

    @model_validator(mode="after")
    def _one_check(self) -> "ExpectSpec":
        given = self._given()
        if not given and self.within is not None:
            raise ValueError(f"'within: {self.within:g}' is a deadline, for " + ", ".join(OVER_TIME)
                             + "; an area is within: {x, y, radius} or {xmin, xmax, ymin, ymax}")
        if len(given) != 1:
            raise ValueError(("gives " + " and ".join(f"'{k}'" for k in given) + ": one check per item")
                             if given else "needs one check: " + ", ".join(KINDS))
        kind = given[0]
        if isinstance(self.within, (int, float)) and kind not in OVER_TIME:
            raise ValueError(f"'within: {self.within:g}' is a deadline, for " + ", ".join(OVER_TIME)
                             + "; an area is within: {x, y, radius} or {xmin, xmax, ymin, ymax}")
        if (kind in OVER_TIME or kind in ("goal", "metric")) and "at" in self.model_fields_set:
            raise ValueError(f"'{kind}' takes no 'at': " + ("it checks how the command ended" if kind == "goal"
                             else "it is measured over the run" if kind == "metric"
                             else "give its deadline as within: SECONDS"))
        if self.radius is not None and kind != "visits":
            raise ValueError("'radius' goes with 'visits' (reaches takes {x, y, radius})")
        if kind == "metric" and self.metric.command is not None and self.robot == "all":
            raise ValueError("a metric of a goal command names one robot: goal commands are a robot's own")
        if kind == "goal" and self.robot == "all":
            raise ValueError("a goal check names one robot: goal commands are a robot's own")
        return self

    def _given(self) -> list[str]:
        return [k for k in KINDS if getattr(self, k) is not None and not
                (k == "within" and isinstance(self.within, (int, float)))]

    @property
    def kind(self) -> str:
        """The name of the one check this item makes."""
        return self._given()[0]

    @property
    def deadline(self) -> Optional[float]:
        """Seconds by which a check over time must pass (None: the end of the run)."""
        return float(self.within) if isinstance(self.within, (int, float)) else None
