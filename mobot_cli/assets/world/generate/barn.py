"""BARN-style worlds: a cellular automaton's grid of cylinders with a guaranteed free path.

The recipe of the BARN dataset's generator (Perille et al., 2020; github.com/dperille/
jackal-map-creation, gen_world_ca.py), written anew on NumPy: a grid of 30 x 30 cells of
0.15 m, its two side rows (along y) filled, every other cell filled with probability ``fill``;
then ``smooth`` rounds of smoothing (a cell with more than 4 filled neighbours of 8 fills, one
with fewer than 2 empties; beyond the side rows counts as filled). A robot needs ``corridor``
x ``corridor`` free cells (BARN: 3, a 0.45 m gap between cylinders, for a Jackal): when no
such corridor joins the start side (y low) to the goal side, the largest open regions
touching each side are joined by an L-shaped cut. Each filled cell with
an empty neighbour becomes a cylinder of radius 0.075 m and 1 m high, placed where BARN's
worlds have them (x -4.5..0, y 5..9.5), with BARN's containment wall around the start.
"""

from __future__ import annotations

from collections import deque

import numpy as np

from mobot_cli.assets.world.generate.barn_grid import CELL, CYLINDER_RADIUS, GOAL, START
from mobot_cli.assets.world.generate.shapes import Obstacle, rounded

HEIGHT = 1.0  # m
X0, Y0 = START[0] - 14.5 * CELL, 5.0 + CYLINDER_RADIUS  # centre of cell (0, 0): the grid is centred on the start's x
CONTAIN = 5.0  # m: the containment wall's sides reach this far back from the grid


def generate(rng: np.random.Generator, fill: float = 0.2, smooth: int = 4, rows: int = 30,
             cols: int = 30, enclosure: bool = True, corridor: int = 3) -> tuple[list[Obstacle], dict]:
    """The cylinders of one BARN-style world; info holds the grid and the free path's cells."""
    grid = rng.random((rows, cols)) < fill
    grid[0, :] = grid[-1, :] = True
    for _ in range(smooth):
        grid = _smoothed(grid)
    path = _connect(grid, corridor)
    edge = _has_empty_neighbour(grid)
    obstacles = [_cylinder(f"cylinder_{r}_{c}", X0 + r * CELL, Y0 + c * CELL)
                 for r, c in zip(*np.nonzero(grid & edge))]
    if enclosure:
        obstacles += _enclosure(rows)
    return obstacles, {"grid": grid, "path": path, "start": START, "goal": GOAL}


def _cylinder(name: str, x: float, y: float) -> Obstacle:
    return Obstacle(name, "cylinder", (CYLINDER_RADIUS, HEIGHT), rounded(x), rounded(y))


def _smoothed(grid: np.ndarray) -> np.ndarray:
    padded = np.pad(grid.astype(np.int8), 1)
    padded[0, :] = padded[-1, :] = 1  # beyond the side rows: filled
    rows, cols = grid.shape
    around = sum(padded[1 + dr:1 + dr + rows, 1 + dc:1 + dc + cols]
                 for dr in (-1, 0, 1) for dc in (-1, 0, 1) if dr or dc)
    out = grid.copy()
    out[around > 4] = True
    out[around < 2] = False
    return out


def _has_empty_neighbour(grid: np.ndarray) -> np.ndarray:
    """Cells with an empty (or off-grid) cell among their 8 neighbours: the cylinders a robot can see."""
    padded = np.pad(grid, 1, constant_values=False)
    rows, cols = grid.shape
    full = np.ones_like(grid)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            full &= padded[1 + dr:1 + dr + rows, 1 + dc:1 + dc + cols]
    return ~full


def _open(grid: np.ndarray, kernel: int) -> np.ndarray:
    """Robot space: cell (r, c) is open when the kernel x kernel cells from it are all empty."""
    rows, cols = grid.shape[0] - kernel + 1, grid.shape[1] - kernel + 1
    blocked = np.zeros((rows, cols), dtype=bool)
    for dr in range(kernel):
        for dc in range(kernel):
            blocked |= grid[dr:dr + rows, dc:dc + cols]
    return ~blocked


def _region(free: np.ndarray, seeds: list[tuple[int, int]]) -> np.ndarray:
    """The cells 4-connected through ``free`` to any of ``seeds``."""
    seen = np.zeros_like(free)
    queue = deque(s for s in seeds if free[s])
    for s in queue:
        seen[s] = True
    rows, cols = free.shape
    while queue:
        r, c = queue.popleft()
        for n in ((r + 1, c), (r - 1, c), (r, c + 1), (r, c - 1)):
            if 0 <= n[0] < rows and 0 <= n[1] < cols and free[n] and not seen[n]:
                seen[n] = True
                queue.append(n)
    return seen


def _largest_touching(free: np.ndarray, col: int) -> np.ndarray:
    best, seen = np.zeros_like(free), np.zeros_like(free)
    for r in range(free.shape[0]):
        if free[r, col] and not seen[r, col]:  # each region is searched once
            region = _region(free, [(r, col)])
            seen |= region
            if region.sum() > best.sum():
                best = region
    return best


def _connect(grid: np.ndarray, kernel: int) -> list[tuple[int, int]]:
    """Make sure a corridor ``kernel`` cells wide joins the first column to the last (clearing
    cells of ``grid`` in place); returns its robot-space cells, from the start side."""
    free = _open(grid, kernel)
    last = free.shape[1] - 1
    start = _largest_touching(free, 0)
    goal = _largest_touching(free, last)
    if not (start & goal).any():
        mid = free.shape[0] // 2
        a = _extreme(start, rightmost=True) or (mid, 0)
        b = _extreme(goal, rightmost=False) or (mid, last)
        cut = [(a[0], c) for c in range(min(a[1], b[1]), max(a[1], b[1]) + 1)]
        cut += [(r, b[1]) for r in range(min(a[0], b[0]), max(a[0], b[0]) + 1)]
        for r, c in cut:
            grid[r:r + kernel, c:c + kernel] = False
        grid[0, :] = grid[-1, :] = True  # the side rows stay: the cut runs between them
        free = _open(grid, kernel)
    return _path(free)


def _extreme(region: np.ndarray, rightmost: bool) -> tuple[int, int] | None:
    cells = list(zip(*np.nonzero(region)))
    if not cells:
        return None
    return max(cells, key=lambda rc: (rc[1], -rc[0])) if rightmost else min(cells, key=lambda rc: (rc[1], rc[0]))


def _path(free: np.ndarray) -> list[tuple[int, int]]:
    """A 4-connected path through ``free`` from the first column to the last (breadth first)."""
    rows, cols = free.shape
    parent: dict[tuple[int, int], tuple[int, int] | None] = {}
    queue: deque = deque()
    for r in range(rows):
        if free[r, 0]:
            parent[(r, 0)] = None
            queue.append((r, 0))
    while queue:
        here = queue.popleft()
        if here[1] == cols - 1:
            out = []
            cell: tuple[int, int] | None = here
            while cell is not None:
                out.append((int(cell[0]), int(cell[1])))
                cell = parent[cell]
            return out[::-1]
        r, c = here
        for n in ((r, c + 1), (r + 1, c), (r - 1, c), (r, c - 1)):
            if 0 <= n[0] < rows and 0 <= n[1] < cols and free[n] and n not in parent:
                parent[n] = here
                queue.append(n)
    return []


def _enclosure(rows: int) -> list[Obstacle]:
    """BARN's containment wall: the side rows continued CONTAIN m back, closed across."""
    sides = (X0, X0 + (rows - 1) * CELL)
    out = []
    steps = int(round(CONTAIN / CELL))
    for k in range(1, steps + 1):
        y = Y0 - k * CELL
        out += [_cylinder(f"wall_{side}_{k}", x, y) for side, x in zip(("left", "right"), sides)]
    back = Y0 - steps * CELL
    for k in range(1, rows - 1):
        out.append(_cylinder(f"wall_back_{k}", X0 + k * CELL, back))
    return out
