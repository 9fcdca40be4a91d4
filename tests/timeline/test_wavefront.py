"""The local controller's free-space distances (timeline/wavefront.py) on grids with known answers."""

from __future__ import annotations

import heapq
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.timeline.wavefront import MOVES, WAVE_CELL, WAVE_REACH, Wavefront, _dilate


def test_open_ground_is_the_distance_along_eight_neighbour_steps():
    field = Wavefront((1.0, 0.0), np.zeros((0, 2)), radius=0.3)
    # straight along a row: exact to the cell; on a diagonal: sqrt(2) steps, as exact
    assert field.at(np.array([-1.0]), np.array([0.0]))[0] == pytest.approx(2.0, abs=WAVE_CELL)
    assert field.at(np.array([0.0]), np.array([1.0]))[0] == pytest.approx(math.hypot(1.0, 1.0), abs=WAVE_CELL)


def test_a_wall_between_makes_the_way_round_it_longer():
    wall = np.array([[0.5, y] for y in np.arange(-1.0, 1.01, 0.05)])  # 2 m wall across x = 0.5
    field = Wavefront((1.0, 0.0), wall, radius=0.3)
    straight = field.at(np.array([0.0]), np.array([0.0]))[0]
    # round either end of the wall (grown by the radius): well over the 1 m straight line
    assert straight > 2.0
    beyond = field.at(np.array([0.0]), np.array([1.6]))[0]
    assert beyond < straight  # a cell past the wall's end is nearer by the way round
    inside = field.at(np.array([0.5]), np.array([0.0]))[0]
    assert inside == field.dist.max() > straight + 2 * round(2 * WAVE_REACH / WAVE_CELL) * WAVE_CELL  # unreachable


# --- The shortest way over free cells, as a plain Dijkstra (heapq) computes it -------------------


def _oracle(goal, points, radius):
    """The distances by a textbook Dijkstra over the free cells (the same grown obstacles, the same
    seed offset added last), cells nothing reaches at the grid's width."""
    n = int(round(2 * WAVE_REACH / WAVE_CELL))
    origin = -WAVE_REACH
    blocked = np.zeros((n, n), dtype=bool)
    if len(points):
        ij = np.floor((points - origin) / WAVE_CELL).astype(int)
        inside = ((ij >= 0) & (ij < n)).all(axis=1)
        blocked[ij[inside, 1], ij[inside, 0]] = True
        blocked = _oracle_dilate(blocked, radius / WAVE_CELL)
    gx, gy = (np.clip(np.floor((np.asarray(goal) - origin) / WAVE_CELL).astype(int), 0, n - 1))
    seed_d = math.hypot(goal[0] - (origin + (gx + 0.5) * WAVE_CELL), goal[1] - (origin + (gy + 0.5) * WAVE_CELL))
    free = ~blocked
    free[gy, gx] = True
    best = {(int(gy), int(gx)): 0.0}
    queue = [(0.0, int(gy), int(gx))]
    while queue:
        d, y, x = heapq.heappop(queue)
        if d > best[(y, x)]:
            continue
        for dy, dx, step in MOVES:
            v = (y + dy, x + dx)
            if 0 <= v[0] < n and 0 <= v[1] < n and free[v] and d + step < best.get(v, math.inf):
                best[v] = d + step
                heapq.heappush(queue, (d + step, *v))
    dist = np.full((n, n), np.inf)
    for (y, x), d in best.items():
        dist[y, x] = seed_d + d
    dist[dist == np.inf] = max(seed_d + d for d in best.values()) + 2 * n * WAVE_CELL
    return dist


def _oracle_dilate(mask, cells):
    reach = int(math.ceil(cells))
    out = mask.copy()
    ny, nx = mask.shape
    for dy in range(-reach, reach + 1):
        for dx in range(-reach, reach + 1):
            if (dx or dy) and dx * dx + dy * dy <= (cells + 0.5) ** 2:
                src = mask[max(0, -dy):ny - max(0, dy), max(0, -dx):nx - max(0, dx)]
                out[max(0, dy):ny - max(0, -dy), max(0, dx):nx - max(0, -dx)] |= src
    return out


def _same(goal, points, radius):
    """Wavefront's distances are the oracle's, bit for bit; the oracle's result for more checks."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    got = Wavefront(goal, points, radius).dist
    want = _oracle(goal, points, radius)
    assert got.dtype == want.dtype and got.shape == want.shape
    assert got.tobytes() == want.tobytes()
    return want


@st.composite
def _scenes(draw):
    """Lidar-like point sets: walls (points along segments), clusters and scattered points,
    inside the grid and beyond it (it spans +-2.5 m), 0 to 400 points; a goal anywhere."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    parts = [np.zeros((0, 2))]
    for _ in range(draw(st.integers(0, 5))):  # walls, 1 to 5 cm apart, some across the edge
        a = np.array([draw(st.floats(-3.2, 3.2)), draw(st.floats(-3.2, 3.2))])
        b = np.array([draw(st.floats(-3.2, 3.2)), draw(st.floats(-3.2, 3.2))])
        count = max(2, min(80, int(np.hypot(*(b - a)) / draw(st.floats(0.01, 0.05)))))
        parts.append(a + np.linspace(0.0, 1.0, count)[:, None] * (b - a))
    for _ in range(draw(st.integers(0, 3))):  # clusters
        centre = rng.uniform(-3.0, 3.0, 2)
        parts.append(centre + rng.normal(0.0, draw(st.floats(0.02, 0.4)), (draw(st.integers(1, 60)), 2)))
    parts.append(rng.uniform(-3.2, 3.2, (draw(st.integers(0, 120)), 2)))  # scattered
    points = np.concatenate(parts)[:400]
    where = draw(st.sampled_from(["anywhere", "edge", "on a point", "beyond"]))
    if where == "edge":
        edge = draw(st.sampled_from([-WAVE_REACH, WAVE_REACH - 1e-9, WAVE_REACH]))
        along = draw(st.floats(-WAVE_REACH, WAVE_REACH))
        goal = (edge, along) if draw(st.booleans()) else (along, edge)
    elif where == "on a point" and len(points):
        goal = tuple(points[draw(st.integers(0, len(points) - 1))])
    elif where == "beyond":
        goal = (draw(st.floats(-8.0, 8.0)), draw(st.sampled_from([-1.0, 1.0])) * draw(st.floats(2.5, 8.0)))
    else:
        goal = (draw(st.floats(-2.6, 2.6)), draw(st.floats(-2.6, 2.6)))
    return goal, points, draw(st.floats(0.0, 0.5))


@settings(max_examples=150, deadline=None)
@given(_scenes())
def test_the_distances_are_a_plain_dijkstras_bit_for_bit(scene):
    _same(*scene)


@settings(max_examples=100, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(0.0, 0.3), st.floats(-1.0, 6.0))
def test_the_grown_obstacles_are_every_offset_within_the_disc(seed, density, cells):
    mask = np.random.default_rng(seed).random((50, 50)) < density
    assert np.array_equal(_dilate(mask, cells), _oracle_dilate(mask, cells))


def test_no_points_leave_every_cell_reached_and_the_goals_cell_its_offset():
    dist = _same((0.33, -1.27), np.zeros((0, 2)), 0.3)
    assert dist.max() < 2 * 50 * WAVE_CELL
    assert dist[12, 28] == pytest.approx(math.hypot(0.02, 0.02), abs=1e-12)  # the goal's cell: its centre's offset


def test_a_walled_off_goal_leaves_the_world_outside_unreached():
    angle = np.linspace(0.0, 2 * math.pi, 200, endpoint=False)
    ring = np.c_[1.0 + 0.6 * np.cos(angle), 0.6 * np.sin(angle)]  # 0.6 m round the goal, grown 0.2 m
    dist = _same((1.0, 0.0), ring, 0.2)
    assert dist[25, 35] < 0.1  # the goal's cell
    assert dist[25, 5] == dist.max() > dist[25, 35] + 2 * 50 * WAVE_CELL  # outside the ring: unreached


def test_a_goal_inside_an_obstacle_is_reached_from_its_own_cell_only():
    blob = np.array([[x, y] for x in np.arange(-0.5, 0.51, 0.05) for y in np.arange(-0.5, 0.51, 0.05)])
    dist = _same((0.02, 0.03), blob, 0.3)
    assert dist[25, 25] < 0.1
    assert dist[25, 26] == dist.max() >= 2 * 50 * WAVE_CELL  # next to it, inside the blob: never free


def test_a_one_cell_wall_across_the_grid_is_not_crossed():
    # Radius 0: a wall one cell thick across the whole grid. The first wavefront (rounds of eight
    # shifted minima, the wall cleared after each round) stepped into it and out again diagonally
    # within a round, so the far side looked reachable through the wall; it is not.
    wall = np.array([[0.05, y] for y in np.arange(-2.45, 2.5, 0.1)])
    dist = _same((1.0, 0.0), wall, 0.0)
    assert dist[25, 10] == dist.max() > dist[25, 30] + 2 * 50 * WAVE_CELL  # the far side: unreached


def test_a_maze_longer_than_the_grid_is_wide_is_followed_to_its_end():
    # Walls three cells thick, corridors one cell wide, joined at alternate ends: a way of some
    # 600 cells (the first wavefront stopped after 200 rounds and left the far corridors unreached).
    walls = []
    for k, row in enumerate(range(1, 50, 4)):
        y = -WAVE_REACH + (row + 0.5) * WAVE_CELL
        xs = np.arange(2, 50) if k % 2 == 0 else np.arange(0, 48)  # grown by a cell: gaps at alternate ends
        walls += [[-WAVE_REACH + (x + 0.5) * WAVE_CELL, y] for x in xs]
    dist = _same((-2.45, -2.15), np.array(walls), 0.1)  # in the first corridor
    assert dist[3, 10] < 1.0  # along the first corridor
    assert 40.0 < dist[47, 10] < dist.max()  # the last corridor: reached, the long way round
