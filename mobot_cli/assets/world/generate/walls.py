"""Walls as boxes: straight pieces along x or y between two points, for the maze and rooms."""

from __future__ import annotations

from mobot_cli.assets.world.generate.shapes import Obstacle, rounded


def wall(name: str, a: tuple[float, float], b: tuple[float, float], thickness: float,
         height: float) -> Obstacle:
    """A box wall from ``a`` to ``b`` (one axis-aligned segment), ``thickness`` wide, its ends
    grown by half the thickness so that walls meeting at a corner close it."""
    (x0, y0), (x1, y1) = a, b
    horizontal = abs(y1 - y0) < 1e-12
    length = abs(x1 - x0) if horizontal else abs(y1 - y0)
    size = (length + thickness, thickness, height) if horizontal else (thickness, length + thickness, height)
    return Obstacle(name, "box", tuple(rounded(v) for v in size), rounded((x0 + x1) / 2), rounded((y0 + y1) / 2))


def runs(present: list[bool]) -> list[tuple[int, int]]:
    """(first, end) index ranges of consecutive True values."""
    out, start = [], None
    for i, on in enumerate([*present, False]):
        if on and start is None:
            start = i
        elif not on and start is not None:
            out.append((start, i))
            start = None
    return out


def room_walls(prefix: str, width: float, depth: float, thickness: float, height: float) -> list[Obstacle]:
    """The four walls of a ``width`` x ``depth`` room centred on the origin."""
    x, y = width / 2, depth / 2
    return [wall(f"{prefix}_south", (-x, -y), (x, -y), thickness, height),
            wall(f"{prefix}_north", (-x, y), (x, y), thickness, height),
            wall(f"{prefix}_west", (-x, -y), (-x, y), thickness, height),
            wall(f"{prefix}_east", (x, -y), (x, y), thickness, height)]
