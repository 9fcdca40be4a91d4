"""A* on a grid (timeline/planner.py): shortest, never through or between blocked cells, pruned to its turns."""

from __future__ import annotations

import heapq
import math

import numpy as np
import pytest

from mobot_cli.timeline.planner import astar, prune, visible

SQRT2 = math.sqrt(2.0)


def dijkstra(blocked: np.ndarray, start, goal) -> float:
    """The reference: plain Dijkstra with the same moves (no corner cutting), written separately."""
    ny, nx = blocked.shape
    best = {start: 0.0}
    heap = [(0.0, start)]
    while heap:
        d, (x, y) = heapq.heappop(heap)
        if (x, y) == goal:
            return d
        if d > best[(x, y)]:
            continue
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                n = (x + dx, y + dy)
                if (dx or dy) and 0 <= n[0] < nx and 0 <= n[1] < ny and not blocked[n[1], n[0]]:
                    if dx and dy and (blocked[y, x + dx] or blocked[y + dy, x]):
                        continue
                    nd = d + (SQRT2 if dx and dy else 1.0)
                    if nd < best.get(n, math.inf):
                        best[n] = nd
                        heapq.heappush(heap, (nd, n))
    return math.inf


def test_open_grid_gives_the_octile_distance_and_a_straight_line():
    blocked = np.zeros((40, 60), dtype=bool)
    found = astar(blocked, (2, 3), (50, 30))
    assert found.length == pytest.approx(27 * SQRT2 + 21)
    assert prune(blocked, found.cells) == [(2, 3), (50, 30)]


def test_around_a_wall_through_its_gap():
    blocked = np.zeros((30, 30), dtype=bool)
    blocked[15, :] = True
    blocked[15, 25] = False  # a one-cell gap near the east side
    found = astar(blocked, (5, 5), (5, 25))
    assert (25, 15) in found.cells
    assert found.length == pytest.approx(dijkstra(blocked, (5, 5), (5, 25)))
    turns = prune(blocked, found.cells)
    assert 3 <= len(turns) <= 5 and turns[0] == (5, 5) and turns[-1] == (5, 25)
    assert all(visible(blocked, a, b) for a, b in zip(turns, turns[1:]))
    assert not visible(blocked, (5, 5), (5, 25))


def test_no_squeezing_between_two_diagonal_blocked_cells():
    blocked = np.zeros((3, 3), dtype=bool)
    blocked[0, 1] = blocked[1, 0] = True
    blocked[1, 2] = blocked[2, 1] = True  # (1, 1) is walled off diagonally on both sides
    assert astar(blocked, (0, 0), (1, 1)).reason == "no path"
    assert astar(blocked, (1, 1), (2, 2)).reason == "no path"


@pytest.mark.parametrize("seed", range(8))
def test_lengths_match_dijkstra_on_random_grids(seed):
    rng = np.random.default_rng(seed)
    blocked = rng.random((35, 45)) < 0.3
    blocked[2, 2] = blocked[32, 42] = False
    found = astar(blocked, (2, 2), (42, 32))
    reference = dijkstra(blocked, (2, 2), (42, 32))
    if math.isinf(reference):
        assert found.reason == "no path" and found.cells == ()
        return
    assert found.length == pytest.approx(reference)
    steps = list(zip(found.cells, found.cells[1:]))
    assert all(max(abs(a[0] - b[0]), abs(a[1] - b[1])) == 1 for a, b in steps)
    assert not any(blocked[y, x] for x, y in found.cells)
    assert sum(math.dist(a, b) for a, b in steps) == pytest.approx(reference)


def test_blocked_ends_and_the_trivial_path():
    blocked = np.zeros((5, 5), dtype=bool)
    blocked[4, 4] = True
    assert astar(blocked, (4, 4), (0, 0)).reason == "start in an obstacle"
    assert astar(blocked, (0, 0), (4, 4)).reason == "goal in an obstacle"
    assert astar(blocked, (0, 0), (9, 0)).reason == "goal in an obstacle"  # off the grid
    assert astar(blocked, (1, 1), (1, 1)).cells == ((1, 1),)


def test_enclosed_goal_has_no_path():
    blocked = np.zeros((20, 20), dtype=bool)
    blocked[8:13, 8] = blocked[8:13, 12] = blocked[8, 8:13] = blocked[12, 8:13] = True
    assert astar(blocked, (1, 1), (10, 10)) .reason == "no path"
