"""The global planner of goal commands (``planner: astar``): A* on an occupancy grid.

Pure: a boolean grid of blocked cells (obstacles already inflated by the robot's radius, row
0 at the lowest y) in, a few waypoints out. The search is 8-connected with octile costs (a
diagonal step costs sqrt 2 and may not cut between two blocked cells), the octile distance as
its heuristic, ties broken toward the goal; the path it finds is shortest on the grid. It is
then pruned to the cells where it must turn: a waypoint is dropped when the straight line that
skips it crosses only free cells (sampled at a quarter cell), so the pursuit controller gets
few, long segments.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np

SQRT2 = math.sqrt(2.0)


@dataclass(frozen=True)
class Planned:
    """A path from the start cell to the goal cell (grid indices (ix, iy)), or why there is none:
    ``reason`` names it ("start in an obstacle", "goal in an obstacle", "no path")."""

    cells: tuple[tuple[int, int], ...] = ()
    reason: str = ""
    length: float = 0.0  # in cells: the A* path's own length


def astar(blocked: np.ndarray, start: tuple[int, int], goal: tuple[int, int]) -> Planned:
    """The shortest 8-connected path over the free cells of ``blocked`` ([iy, ix]) from
    ``start`` to ``goal`` (each (ix, iy))."""
    ny, nx = blocked.shape
    for what, (ix, iy) in (("start", start), ("goal", goal)):
        if not (0 <= ix < nx and 0 <= iy < ny) or blocked[iy, ix]:
            return Planned(reason=f"{what} in an obstacle")
    if start == goal:
        return Planned(cells=(start,))
    # Flat indices over a grid padded with a blocked border: no bounds checks in the loop.
    width = nx + 2
    free = np.pad(~blocked, 1, constant_values=False).ravel().tolist()
    s, g = (start[1] + 1) * width + start[0] + 1, (goal[1] + 1) * width + goal[0] + 1
    gx, gy = goal[0] + 1, goal[1] + 1
    moves = [(1, 1.0, 0, 0), (-1, 1.0, 0, 0), (width, 1.0, 0, 0), (-width, 1.0, 0, 0),
             (width + 1, SQRT2, 1, width), (width - 1, SQRT2, -1, width),
             (-width + 1, SQRT2, 1, -width), (-width - 1, SQRT2, -1, -width)]
    cost = {s: 0.0}
    parent = {s: -1}
    heap = [(0.0, 0.0, s)]
    push, pop, bend = heapq.heappush, heapq.heappop, SQRT2 - 2.0
    while heap:
        f, h_here, here = pop(heap)
        if here == g:
            break
        base = cost[here]
        if f > base + h_here + 1e-9:  # a stale entry: this cell was reached more cheaply since
            continue
        for step, extra, sx, sy in moves:
            there = here + step
            if not free[there] or (sx and not (free[here + sx] and free[here + sy])):
                continue  # blocked, or a diagonal squeezing between two blocked cells
            new = base + extra
            if new < cost.get(there, math.inf):
                cost[there], parent[there] = new, here
                iy, ix = divmod(there, width)
                dx, dy = abs(ix - gx), abs(iy - gy)
                h = dx + dy + bend * (dx if dx < dy else dy)  # octile distance
                push(heap, (new + h, h, there))
    else:
        return Planned(reason="no path")
    cells = []
    at = g
    while at != -1:
        iy, ix = divmod(at, width)
        cells.append((ix - 1, iy - 1))
        at = parent[at]
    return Planned(cells=tuple(reversed(cells)), length=cost[g])


def prune(blocked: np.ndarray, cells: tuple[tuple[int, int], ...]) -> list[tuple[int, int]]:
    """The cells of a path where it must turn: the first, the last, and each cell beyond which
    the straight line from the last kept cell would cross a blocked cell."""
    if len(cells) <= 2:
        return list(cells)
    kept = [cells[0]]
    i = 0
    while i < len(cells) - 1:
        j = i + 1
        while j + 1 < len(cells) and visible(blocked, cells[i], cells[j + 1]):
            j += 1
        kept.append(cells[j])
        i = j
    return kept


def visible(blocked: np.ndarray, a: tuple[int, int], b: tuple[int, int]) -> bool:
    """Whether the straight line between the centres of cells ``a`` and ``b`` crosses only free cells."""
    n = max(2, int(math.ceil(math.hypot(b[0] - a[0], b[1] - a[1]) * 4)) + 1)
    t = np.linspace(0.0, 1.0, n)
    ix = np.floor(a[0] + 0.5 + t * (b[0] - a[0])).astype(int)
    iy = np.floor(a[1] + 0.5 + t * (b[1] - a[1])).astype(int)
    return not blocked[iy, ix].any()
