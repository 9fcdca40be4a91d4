"""Boxes scattered in a walled room: sizes, places and turns drawn from the seed, each box kept
``gap`` m from the others and from the walls (so the room stays passable for a robot narrower
than the gap) and out of the ``keep_clear`` discs; a box that finds no place in 200 tries is
left out, and the world says how many it holds."""

from __future__ import annotations

import math

import numpy as np

from mobot_cli.assets.world.generate.shapes import Obstacle, rounded
from mobot_cli.assets.world.generate.walls import room_walls

TRIES = 200  # places tried per box


def generate(rng: np.random.Generator, size: tuple[float, float] = (10.0, 10.0), count: int = 20,
             box_size: tuple[float, float] = (0.3, 1.0), height: float = 0.8, gap: float = 0.6,
             keep_clear: tuple = (), wall: float = 0.1) -> tuple[list[Obstacle], dict]:
    """The walls and boxes of one room centred on the origin."""
    width, depth = size
    placed: list[tuple[float, float, float]] = []  # x, y, bounding radius
    obstacles = room_walls("wall", width, depth, wall, 1.0)
    clear = [tuple(c) for c in keep_clear]
    for i in range(count):
        sx, sy = (box_size[0] + (box_size[1] - box_size[0]) * rng.random(2)).tolist()
        yaw = float(rng.random() * math.pi)
        radius = math.hypot(sx, sy) / 2
        for _ in range(TRIES):
            u, v = rng.random(2).tolist()
            margin = radius + gap + wall / 2
            x = -width / 2 + margin + u * (width - 2 * margin)
            y = -depth / 2 + margin + v * (depth - 2 * margin)
            if width <= 2 * margin or depth <= 2 * margin:
                break
            if all(math.hypot(x - px, y - py) >= radius + pr + gap for px, py, pr in placed) and \
                    all(math.hypot(x - cx, y - cy) >= radius + cr for cx, cy, cr in clear):
                placed.append((x, y, radius))
                obstacles.append(Obstacle(f"box_{i}", "box", (rounded(sx), rounded(sy), rounded(height)),
                                          rounded(x), rounded(y), rounded(yaw)))
                break
    notices = [] if len(placed) == count else [
        f"boxes: {len(placed)} of {count} boxes found a place {gap:g} m from the others and the walls"]
    return obstacles, {"placed": len(placed), "notices": notices}
