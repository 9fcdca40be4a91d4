"""A perfect maze (one path between any two cells): a depth-first search from a seeded cell,
choosing unvisited neighbours by the seed (the recursive backtracker, without recursion).
Cells are ``cell`` m squares, the maze centred on the origin; walls in a line are one box."""

from __future__ import annotations

import numpy as np

from mobot_cli.assets.world.generate.shapes import Obstacle
from mobot_cli.assets.world.generate.walls import runs
from mobot_cli.assets.world.generate.walls import wall as wall_box


def generate(rng: np.random.Generator, cells: tuple[int, int] = (6, 6), cell: float = 1.2,
             wall: float = 0.1, height: float = 1.0) -> tuple[list[Obstacle], dict]:
    """The walls of an nx x ny maze; info: every cell's centre (cell (0, 0) lowest x and y)."""
    nx, ny = cells
    # east[i][j]: a wall east of cell (i, j); north likewise
    east = np.ones((nx, ny), dtype=bool)
    north = np.ones((nx, ny), dtype=bool)
    seen = np.zeros((nx, ny), dtype=bool)
    first = (int(rng.integers(nx)), int(rng.integers(ny)))
    stack = [first]
    seen[first] = True
    while stack:
        i, j = stack[-1]
        options = [(di, dj) for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1))
                   if 0 <= i + di < nx and 0 <= j + dj < ny and not seen[i + di, j + dj]]
        if not options:
            stack.pop()
            continue
        di, dj = options[int(rng.integers(len(options)))]
        if di:
            east[min(i, i + di), j] = False
        else:
            north[i, min(j, j + dj)] = False
        seen[i + di, j + dj] = True
        stack.append((i + di, j + dj))
    x0, y0 = -nx * cell / 2, -ny * cell / 2
    out: list[Obstacle] = []
    for j in range(ny + 1):  # lines along x at y0 + j cell: south of row j
        present = [True] * nx if j in (0, ny) else [bool(north[i, j - 1]) for i in range(nx)]
        for a, b in runs(present):
            out.append(wall_box(f"wall_x{j}_{a}", (x0 + a * cell, y0 + j * cell), (x0 + b * cell, y0 + j * cell),
                            wall, height))
    for i in range(nx + 1):  # lines along y at x0 + i cell: west of column i
        present = [True] * ny if i in (0, nx) else [bool(east[i - 1, j]) for j in range(ny)]
        for a, b in runs(present):
            out.append(wall_box(f"wall_y{i}_{a}", (x0 + i * cell, y0 + a * cell), (x0 + i * cell, y0 + b * cell),
                            wall, height))
    centres = [[(x0 + (i + 0.5) * cell, y0 + (j + 0.5) * cell) for j in range(ny)] for i in range(nx)]
    passages = int((~east[:-1, :]).sum() + (~north[:, :-1]).sum())  # walls the search opened
    return out, {"centres": centres, "passages": passages}
