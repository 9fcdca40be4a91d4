"""A scenario's ``movers:`` items (docs/movers.md): shapes that follow waypoints or walk."""

from __future__ import annotations

from typing import Annotated, Literal, Optional

from pydantic import BaseModel, ConfigDict, Field, model_validator

from mobot_cli.scenario.limits import FLEET_NAME_RE, Coordinate, Float, Int, Seconds, check_name

MAX_MOVERS = 1000  # count, and movers in one scenario
MAX_SIZE = 100.0  # m, any size of a mover's shape
MAX_MOVER_SPEED = 10.0  # m/s
MIN_MOVER_SPEED = 0.001  # m/s: slower paths would take longer than any run
Point2 = tuple[Coordinate, Coordinate]
Size = Annotated[Float, Field(gt=0, le=MAX_SIZE)]
DEFAULT_SIZES = {"person": (0.3, 1.7), "cylinder": (0.3, 1.0), "box": (0.5, 0.5, 1.0)}


class MoverSpec(BaseModel):
    """One mover: ``path`` (waypoints it follows at ``speed``) or ``region`` (a social-force walker
    going between random goals in it); ``count`` makes a fleet named with ``{i}``."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True, defer_build=True)

    name: str
    shape: Literal["person", "box", "cylinder"] = "person"
    size: Optional[tuple[Size, ...]] = None  # person, cylinder: radius, height; box: x, y, z
    path: Optional[Annotated[list[Point2], Field(min_length=2)]] = None
    mode: Literal["loop", "pingpong", "once"] = "loop"
    region: Optional[tuple[Coordinate, Coordinate, Coordinate, Coordinate]] = None  # xmin, xmax, ymin, ymax
    start: Optional[Point2] = None
    speed: Annotated[Float, Field(ge=MIN_MOVER_SPEED, le=MAX_MOVER_SPEED)] = 1.0
    at: Seconds = 0.0
    count: Optional[Annotated[Int, Field(ge=1, le=MAX_MOVERS)]] = None

    @model_validator(mode="after")
    def _check(self) -> "MoverSpec":
        check_name(self.name, "mover", FLEET_NAME_RE, "use letters, digits and '_' ({i} in a fleet)")
        if (self.path is None) == (self.region is None):
            raise ValueError("a mover needs exactly one of 'path' (waypoints) or 'region' (a walker)")
        if self.size is not None and len(self.size) != len(DEFAULT_SIZES[self.shape]):
            raise ValueError(f"a {self.shape}'s size is {len(DEFAULT_SIZES[self.shape])} numbers: "
                             + ("x, y, z" if self.shape == "box" else "radius, height"))
        if self.shape == "person" and self.size is not None and self.size[1] < 2.0 * self.size[0]:
            raise ValueError("a person's height must be at least twice its radius (it is a capsule)")
        if self.region is not None and not (self.region[0] < self.region[1] and self.region[2] < self.region[3]):
            raise ValueError("region is [xmin, xmax, ymin, ymax] with xmin < xmax and ymin < ymax")
        if self.count is not None and "{i}" not in self.name:
            raise ValueError("a fleet of movers (count) needs '{i}' in its name")
        if self.count is not None and self.path is not None:
            raise ValueError("count makes walkers of a region; give each path mover its own item")
        if self.start is not None and self.count is not None:
            raise ValueError("a fleet of walkers starts at random points of its region: leave out 'start'")
        return self
