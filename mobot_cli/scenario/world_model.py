"""``world: {generate: {kind: ..., seed: N, ...}}``: a world made from a seed, validated here.

One model for every kind: each parameter has one meaning and one range whichever kind takes
it (``size`` is a room's, ``wall`` a wall's thickness, ...), and a parameter the kind does not
take is an error naming the ones it does. assets/world/generate/ makes the worlds.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, Optional

from pydantic import BaseModel, ConfigDict, Field, model_validator

from mobot_cli.scenario.limits import Coordinate, Float, Int

KIND_PARAMETERS = {
    "barn": ("fill", "smooth", "rows", "cols", "enclosure", "corridor"),
    "boxes": ("size", "count", "box_size", "height", "gap", "keep_clear", "wall"),
    "maze": ("cells", "cell", "wall", "height"),
    "rooms": ("size", "rooms", "door", "jitter", "wall", "height"),
}
Metres = Annotated[Float, Field(gt=0, le=200)]
Span = Annotated[Float, Field(ge=1, le=200)]  # a room's side, m


class GenerateSpec(BaseModel):
    """The generator and its parameters; None: the generator's default."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True, defer_build=True)

    kind: Literal["barn", "boxes", "maze", "rooms"]
    seed: Annotated[Int, Field(ge=0, lt=2**32)] = 0
    # barn: the chance a cell starts filled, smoothing rounds, cells along x and y, the wall round the start
    fill: Optional[Annotated[Float, Field(ge=0, le=1)]] = None
    smooth: Optional[Annotated[Int, Field(ge=0, le=20)]] = None
    rows: Optional[Annotated[Int, Field(ge=6, le=200)]] = None
    cols: Optional[Annotated[Int, Field(ge=6, le=200)]] = None
    enclosure: Optional[bool] = None
    corridor: Optional[Annotated[Int, Field(ge=1, le=10)]] = None  # cells: the guaranteed way's width
    # boxes and rooms: the room's (building's) width and depth, m
    size: Optional[tuple[Span, Span]] = None
    # boxes
    count: Optional[Annotated[Int, Field(ge=0, le=2000)]] = None
    box_size: Optional[tuple[Annotated[Float, Field(ge=0.05, le=20)], Annotated[Float, Field(ge=0.05, le=20)]]] = None
    gap: Optional[Annotated[Float, Field(ge=0, le=20)]] = None
    keep_clear: Optional[list[tuple[Coordinate, Coordinate, Annotated[Float, Field(gt=0, le=200)]]]] = None
    # maze: cells along x and y, a cell's side (m)
    cells: Optional[tuple[Annotated[Int, Field(ge=1, le=100)], Annotated[Int, Field(ge=1, le=100)]]] = None
    cell: Optional[Annotated[Float, Field(ge=0.3, le=20)]] = None
    # rooms: rooms along x and y, a door's width, how far inner walls move from the even split
    rooms: Optional[tuple[Annotated[Int, Field(ge=1, le=20)], Annotated[Int, Field(ge=1, le=20)]]] = None
    door: Optional[Annotated[Float, Field(ge=0.3, le=10)]] = None
    jitter: Optional[Annotated[Float, Field(ge=0, le=0.45)]] = None
    # boxes, maze, rooms: a wall's thickness; obstacles' height (m)
    wall: Optional[Annotated[Float, Field(ge=0.01, le=2)]] = None
    height: Optional[Annotated[Float, Field(ge=0.05, le=10)]] = None

    @model_validator(mode="after")
    def _parameters_of_the_kind(self) -> "GenerateSpec":
        allowed = KIND_PARAMETERS[self.kind]
        for name in self.model_fields_set - {"kind", "seed"}:
            if name not in allowed:
                raise ValueError(f"'{name}' is not a parameter of kind {self.kind}: it takes seed, "
                                 f"{', '.join(allowed)}")
        if self.box_size is not None and self.box_size[0] > self.box_size[1]:
            raise ValueError(f"box_size [{self.box_size[0]:g}, {self.box_size[1]:g}] runs backwards: give [min, max]")
        given = self.parameters()
        if self.kind == "maze" and given["wall"] >= given["cell"] / 2:
            raise ValueError(f"wall {given['wall']:g} m leaves no room in cells of {given['cell']:g} m: "
                             "make it less than half a cell")
        if self.kind == "barn" and given["corridor"] > min(given["rows"], given["cols"]) - 2:
            raise ValueError(f"corridor {given['corridor']} does not fit between the side rows of "
                             f"{given['rows']} x {given['cols']} cells")
        return self

    def parameters(self) -> dict[str, Any]:
        """Every parameter of the kind, the ones not given at the generator's defaults."""
        from mobot_cli.assets.world.generate.make import parameters

        out = parameters(self.kind)
        for name in out:
            value = getattr(self, name)
            if value is not None:
                out[name] = [list(v) for v in value] if name == "keep_clear" else value
        return out


class GeneratedWorld(BaseModel):
    """``world: {generate: {...}}``."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True, defer_build=True)

    generate: GenerateSpec

    def document(self) -> dict[str, Any]:
        """As the resolved scenario writes it: every parameter, defaults filled in."""
        out = {"kind": self.generate.kind, "seed": self.generate.seed}
        for name, value in self.generate.parameters().items():
            out[name] = list(value) if isinstance(value, tuple) else value
        return {"generate": out}
