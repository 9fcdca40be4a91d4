"""The local controller's free-space distances: how far the goal is through free space, on a
square grid around the robot, when the path ahead runs into something the map did not have
(timeline/local.py; nav2 propagates such distances through its costmap).

The lidar points are grown by the robot's radius, and the distance from the goal's cell to every
free cell is the shortest way over free cells (eight neighbours, diagonal steps sqrt(2) cells
long), by one Dijkstra search (scipy.sparse.csgraph, in C: a few hundred microseconds for the
2,500 cells). Each step is added one hop at a time in float64, so any correct shortest-path
search gives the same numbers bit for bit (tests/timeline/test_wavefront.py checks one).
"""

from __future__ import annotations

import functools
import math

import numpy as np

WAVE_CELL = 0.1  # m: the grid's cell
WAVE_REACH = 2.5  # m: its half width around the robot

_N = int(round(2 * WAVE_REACH / WAVE_CELL))
_DIAG = math.sqrt(2.0) * WAVE_CELL
MOVES = ((0, 1, WAVE_CELL), (0, -1, WAVE_CELL), (1, 0, WAVE_CELL), (-1, 0, WAVE_CELL),
         (1, 1, _DIAG), (1, -1, _DIAG), (-1, 1, _DIAG), (-1, -1, _DIAG))  # (dy, dx, step)


class Wavefront:
    """Distances (m) to the goal through free space on a square grid around the robot."""

    def __init__(self, goal, points: np.ndarray, radius: float):
        n = self.n = _N
        self.origin = -WAVE_REACH
        blocked = np.zeros((n, n), dtype=bool)
        if len(points):
            ij = np.floor((points - self.origin) / WAVE_CELL).astype(int)
            inside = ((ij >= 0) & (ij < n)).all(axis=1)
            blocked[ij[inside, 1], ij[inside, 0]] = True
            blocked = _dilate(blocked, radius / WAVE_CELL)
        gx, gy = (np.clip(np.floor((np.asarray(goal) - self.origin) / WAVE_CELL).astype(int), 0, n - 1))
        seed_d = math.hypot(goal[0] - (self.origin + (gx + 0.5) * WAVE_CELL),
                            goal[1] - (self.origin + (gy + 0.5) * WAVE_CELL))
        free = ~blocked
        free[gy, gx] = True  # the goal's cell is free, even inside an obstacle
        dist = seed_d + shortest(free, (int(gy), int(gx)))
        # Cells nothing reaches (inside obstacles, walled off) cost as far as the grid is wide
        # beyond the farthest cell reached: never less than a way there (a maze's can be longer).
        unreached = ~np.isfinite(dist)
        dist[unreached] = np.max(dist, where=~unreached, initial=0.0) + unreachable_beyond()
        self.dist = dist

    def at(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The distance at each point (the grid's edge value beyond it)."""
        ix = np.clip(np.floor((x - self.origin) / WAVE_CELL).astype(int), 0, self.n - 1)
        iy = np.clip(np.floor((y - self.origin) / WAVE_CELL).astype(int), 0, self.n - 1)
        return self.dist[iy, ix]


def unreachable_beyond() -> float:
    """How much more than the farthest cell reached a cell nothing reaches costs (m)."""
    return 2 * _N * WAVE_CELL


def shortest(free: np.ndarray, seed: tuple[int, int]) -> np.ndarray:
    """The length (m) of the shortest way from ``seed`` to each cell over ``free`` cells (MOVES);
    +inf where none leads."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import dijkstra

    ny, nx = free.shape
    ends, steps, starts = _grid_graph(ny, nx)
    weights = np.where(free.ravel()[ends], steps, np.inf)  # no step onto a cell that is not free
    graph = csr_matrix((weights, ends, starts), shape=(ny * nx, ny * nx))
    out = dijkstra(graph, indices=seed[0] * nx + seed[1]).reshape(ny, nx)
    out[~free] = np.inf
    return out


@functools.lru_cache(maxsize=4)
def _grid_graph(ny: int, nx: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every cell's steps to its neighbours within the grid, as CSR arrays: (the cell each step
    ends on, its length, where each cell's steps start)."""
    cell = np.arange(ny * nx).reshape(ny, nx)
    ends = np.full((ny, nx, len(MOVES)), -1)
    steps = np.zeros(len(MOVES))
    for k, (dy, dx, step) in enumerate(MOVES):
        ys, xs = slice(max(0, -dy), ny - max(0, dy)), slice(max(0, -dx), nx - max(0, dx))
        ends[ys, xs, k] = cell[max(0, dy):ny - max(0, -dy), max(0, dx):nx - max(0, -dx)]
        steps[k] = step
    ends = ends.reshape(ny * nx, len(MOVES))
    inside = ends >= 0
    counts = inside.sum(axis=1)
    starts = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)
    lengths = np.broadcast_to(steps, ends.shape)[inside]
    return ends[inside].astype(np.int32), lengths, starts


def _dilate(mask: np.ndarray, cells: float) -> np.ndarray:
    """``mask`` grown by a disc: the cells within ``cells`` + 0.5 cells of a marked one."""
    ny, nx = mask.shape
    reach, offsets = _disc(cells, nx)
    grown = np.zeros((ny + 2 * reach, nx + 2 * reach), dtype=bool)  # a border for the discs to spill on
    inner = grown[reach:reach + ny, reach:reach + nx]
    inner[...] = mask
    flat = grown.ravel()
    flat[np.flatnonzero(flat)[:, None] + offsets] = True
    return inner.copy()


@functools.lru_cache(maxsize=16)
def _disc(cells: float, nx: int) -> tuple[int, np.ndarray]:
    """The disc's reach, and its cells as flat offsets in a grid nx + 2 reach wide."""
    reach = max(0, int(math.ceil(cells)))
    dy, dx = np.mgrid[-reach:reach + 1, -reach:reach + 1]
    disc = dy * dy + dx * dx <= (cells + 0.5) ** 2
    return reach, (dy * (nx + 2 * reach) + dx)[disc]
