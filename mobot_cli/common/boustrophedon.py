"""A lawn-mower (boustrophedon) route over the free cells of a grid.

Lanes run along the longer side of the free region's bounding box, ``spacing`` apart at most
(evenly spread so that the first and last lanes lie on the region's edges). Each lane is cut
into pieces by obstacles; pieces are taken greedily, the nearest end next, each driven from
that end, which gives the back-and-forth of a mower in open rooms. Two pieces are joined by a
straight line when the robot can drive it, else by the shortest 8-connected path through
``passable`` cells, shortened to the corners it needs. Everything is deterministic.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from mobot_cli.common.raster import Grid

Point = tuple[float, float]
Cell = tuple[int, int]  # (row, column) of an array


def lawnmower(lanes: np.ndarray, passable: np.ndarray, grid: Grid,
              spacing: float) -> tuple[list[Point], int]:
    """Waypoints of a route over the ``lanes`` cells (where lanes may run) and how many lane
    pieces could not be reached through ``passable`` cells from the first one (left out)."""
    transpose = _extent(lanes, 0) > _extent(lanes, 1)
    if transpose:  # lanes along y: plan on the transposed grid, swap the coordinates back
        lanes, passable = lanes.T, passable.T
        grid = Grid(grid.y0, grid.x0, grid.cell, grid.ny, grid.nx)
    pieces = _pieces(lanes, grid.cell, spacing)
    route, skipped = _order(pieces, passable)
    points = [grid.centre(c, r) for r, c in route]
    return ([(y, x) for x, y in points] if transpose else points), skipped


def _extent(mask: np.ndarray, axis: int) -> int:
    """How many rows (axis 0) or columns (axis 1) the set cells span."""
    used = np.flatnonzero(mask.any(axis=1 - axis))
    return int(used[-1] - used[0] + 1) if len(used) else 0


def _pieces(lanes: np.ndarray, cell: float, spacing: float) -> list[tuple[Cell, Cell]]:
    """Each lane's runs of set cells, as (first, last) cells, lanes from the bottom up."""
    rows = np.flatnonzero(lanes.any(axis=1))
    if not len(rows):
        return []
    first, last = int(rows[0]), int(rows[-1])
    count = max(1, math.ceil((last - first) * cell / spacing - 1e-9)) + 1 if last > first else 1
    picked = sorted({round(first + (last - first) * k / (count - 1)) if count > 1 else first
                     for k in range(count)})
    out = []
    for row in picked:
        line = lanes[row].astype(np.int8)
        edges = np.flatnonzero(np.diff(np.concatenate(([0], line, [0]))))
        out.extend(((row, int(a)), (row, int(b) - 1)) for a, b in zip(edges[::2], edges[1::2]))
    return out


def _order(pieces: list[tuple[Cell, Cell]], passable: np.ndarray) -> tuple[list[Cell], int]:
    """The route through every reachable piece, nearest end next, and the pieces left out."""
    if not pieces:
        return [], 0
    reach = _distances(passable, pieces[0][0])
    left = [p for p in pieces if reach[p[0]] >= 0]
    skipped = len(pieces) - len(left)
    route: list[Cell] = [left[0][0], left[0][1]]
    left.pop(0)
    while left:
        here = route[-1]
        best = min(range(len(left)), key=lambda i: (min(_d2(here, left[i][0]), _d2(here, left[i][1])), i))
        a, b = left.pop(best)
        if _d2(here, b) < _d2(here, a):
            a, b = b, a
        route.extend(_join(here, a, passable)[1:])
        if b != a:
            route.append(b)
    return _dedupe(route), skipped


def _d2(a: Cell, b: Cell) -> int:
    return (a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2


def _join(a: Cell, b: Cell, passable: np.ndarray) -> list[Cell]:
    """From ``a`` to ``b``: straight when clear, else the shortest grid path cut to its corners."""
    if _clear(a, b, passable):
        return [a, b]
    path = _path(a, b, passable)
    out = [path[0]]
    i = 0
    while i < len(path) - 1:  # string pulling: the farthest cell still in a straight line of sight
        j = len(path) - 1
        while j > i + 1 and not _clear(path[i], path[j], passable):
            j -= 1
        out.append(path[j])
        i = j
    return out


def _clear(a: Cell, b: Cell, passable: np.ndarray) -> bool:
    """Whether every cell the straight line from ``a``'s centre to ``b``'s meets (sampled every
    quarter cell) is passable."""
    n = 4 * max(abs(b[0] - a[0]), abs(b[1] - a[1])) + 1
    rows = np.floor(np.linspace(a[0], b[0], n) + 0.5).astype(int)
    cols = np.floor(np.linspace(a[1], b[1], n) + 0.5).astype(int)
    return bool(passable[rows, cols].all())


STEPS = ((0, 1), (1, 0), (0, -1), (-1, 0), (1, 1), (1, -1), (-1, 1), (-1, -1))


def _distances(passable: np.ndarray, start: Cell) -> np.ndarray:
    """Breadth-first step counts from ``start`` over passable cells (-1: unreachable)."""
    dist = np.full(passable.shape, -1, dtype=np.int32)
    dist[start] = 0
    queue = deque([start])
    ny, nx = passable.shape
    while queue:
        r, c = queue.popleft()
        d = dist[r, c] + 1
        for dr, dc in STEPS:
            rr, cc = r + dr, c + dc
            if 0 <= rr < ny and 0 <= cc < nx and dist[rr, cc] < 0 and passable[rr, cc]:
                dist[rr, cc] = d
                queue.append((rr, cc))
    return dist


def _path(a: Cell, b: Cell, passable: np.ndarray) -> list[Cell]:
    """A shortest 8-connected path from ``a`` to ``b`` (both reachable from each other)."""
    dist = _distances(passable, b)
    path = [a]
    ny, nx = passable.shape
    while path[-1] != b:
        r, c = path[-1]
        here = dist[r, c]
        path.append(next((r + dr, c + dc) for dr, dc in STEPS
                         if 0 <= r + dr < ny and 0 <= c + dc < nx and dist[r + dr, c + dc] == here - 1))
    return path


def _dedupe(route: list[Cell]) -> list[Cell]:
    out: list[Cell] = []
    for cell in route:
        if not out or out[-1] != cell:
            out.append(cell)
    return out
