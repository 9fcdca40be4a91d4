"""A simple floor plan: a ``size`` m building of rooms in a grid (``rooms`` across and deep),
the inner walls moved from the even split by up to ``jitter`` of a room, and one door of
``door`` m in every wall two rooms share, at a place drawn from the seed."""

from __future__ import annotations

import numpy as np

from mobot_cli.assets.world.generate.shapes import Obstacle
from mobot_cli.assets.world.generate.walls import room_walls
from mobot_cli.assets.world.generate.walls import wall as wall_box

END = 0.15  # m of wall kept at least between a door and a wall's end


def generate(rng: np.random.Generator, size: tuple[float, float] = (12.0, 8.0), rooms: tuple[int, int] = (3, 2),
             door: float = 0.9, jitter: float = 0.2, wall: float = 0.1,
             height: float = 1.0) -> tuple[list[Obstacle], dict]:
    """The outer walls and the inner walls with their doors; info: the rooms' centres."""
    width, depth = size
    xs = _lines(rng, -width / 2, width, rooms[0], jitter)
    ys = _lines(rng, -depth / 2, depth, rooms[1], jitter)
    out = room_walls("outer", width, depth, wall, height)
    for i, x in enumerate(xs[1:-1], start=1):  # inner walls along y, a door per room they divide
        for j in range(rooms[1]):
            out += _with_door(rng, f"wall_x{i}_{j}", (x, ys[j]), (x, ys[j + 1]), door, wall, height)
    for j, y in enumerate(ys[1:-1], start=1):
        for i in range(rooms[0]):
            out += _with_door(rng, f"wall_y{j}_{i}", (xs[i], y), (xs[i + 1], y), door, wall, height)
    centres = [((xs[i] + xs[i + 1]) / 2, (ys[j] + ys[j + 1]) / 2) for j in range(rooms[1]) for i in range(rooms[0])]
    return out, {"centres": centres, "xs": xs, "ys": ys}


def _lines(rng: np.random.Generator, start: float, length: float, n: int, jitter: float) -> list[float]:
    step = length / n
    inner = [start + k * step + (rng.random() * 2 - 1) * jitter * step for k in range(1, n)]
    return [start, *inner, start + length]


def _with_door(rng: np.random.Generator, name: str, a: tuple[float, float], b: tuple[float, float],
               door: float, wall: float, height: float) -> list[Obstacle]:
    """The wall from ``a`` to ``b`` in two pieces around a door (or whole when the door does not fit)."""
    axis = 0 if abs(b[1] - a[1]) < 1e-12 else 1
    lo, hi = a[axis], b[axis]
    room = hi - lo - 2 * END - door - wall
    if room < 0:
        return [wall_box(name, a, b, wall, height)]
    start = lo + END + wall / 2 + rng.random() * room  # where the door begins

    def point(t: float) -> tuple[float, float]:
        return (t, a[1]) if axis == 0 else (a[0], t)

    # a wall's box reaches half its thickness past its ends: the opening is ``door`` wide
    return [wall_box(f"{name}_a", point(lo), point(start - wall / 2), wall, height),
            wall_box(f"{name}_b", point(start + door + wall / 2), point(hi), wall, height)]
