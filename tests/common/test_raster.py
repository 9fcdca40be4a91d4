"""Shapes on a grid (common/raster.py) and lawn-mower routes (common/boustrophedon.py), checked
against areas and routes worked out by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.common.boustrophedon import lawnmower
from mobot_cli.common.polygon import area, box_polygon, contains
from mobot_cli.common.raster import Grid, dilate, fill_polygon, fill_segment

CELL = 0.01


def covered(polygon, cell: float = CELL) -> float:
    """m^2 of the cells a polygon covers."""
    xs, ys = [p[0] for p in polygon], [p[1] for p in polygon]
    grid = Grid.covering(min(xs) - 1, max(xs) + 1, min(ys) - 1, max(ys) + 1, cell)
    mask = grid.empty()
    fill_polygon(mask, grid, polygon)
    return float(mask.sum()) * cell * cell


def test_hand_shapes():
    assert covered(box_polygon(0.0, 3.0, 0.0, 2.0)) == pytest.approx(6.0, rel=1e-9)  # edges on cell edges
    assert covered([(0, 0), (2, 0), (0, 2)]) == pytest.approx(2.0, rel=0.01)  # right triangle
    disc = [(math.cos(a), math.sin(a)) for a in np.linspace(0, 2 * math.pi, 721)[:-1]]
    assert covered(disc) == pytest.approx(math.pi, rel=0.005)
    # An L-shaped room: 3 x 3 less its 1.5 x 1.5 corner, given clockwise.
    room = [(0, 0), (0, 3), (1.5, 3), (1.5, 1.5), (3, 1.5), (3, 0)]
    assert area(room) == pytest.approx(6.75)
    assert covered(room) == pytest.approx(6.75, rel=0.005)
    assert contains(room, 1.0, 1.0) and not contains(room, 2.0, 2.0)


@settings(max_examples=60, deadline=None)
@given(x=st.floats(-5, 5), y=st.floats(-5, 5), w=st.floats(0.2, 4), h=st.floats(0.2, 4),
       turn=st.floats(0, math.pi))
def test_a_turned_rectangle_covers_its_area(x, y, w, h, turn):
    c, s = math.cos(turn), math.sin(turn)
    corners = [(x + c * px - s * py, y + s * px + c * py) for px, py in box_polygon(-w / 2, w / 2, -h / 2, h / 2)]
    # Centre sampling misses or adds at most a strip half a cell wide along the outline, and its
    # four corners' quarter cells: a square of 0.27 m at the origin, grid-aligned, covers 0.28^2.
    assert covered(corners) == pytest.approx(w * h, abs=(w + h) * CELL + CELL ** 2)


def test_a_segment_marks_every_cell_it_crosses_and_dilate_grows_a_disc():
    grid = Grid.covering(0, 1, 0, 1, 0.1)
    mask = grid.empty()
    fill_segment(mask, grid, (0.05, 0.05), (0.95, 0.95))
    assert [tuple(c) for c in np.argwhere(mask)] == [(i, i) for i in range(10)]  # the diagonal
    dot = Grid.covering(-1, 1, -1, 1, 0.1).empty()
    dot[10, 10] = True
    assert dilate(dot, 3.0).sum() == 29  # cells whose centres lie within 3 cells of the centre


def test_lanes_over_an_open_room_zigzag_at_the_spacing():
    grid = Grid.covering(0, 3, 0, 2, 0.05)
    lanes = grid.empty()
    lanes[4:36, 4:56] = True  # free where the robot's centre may go: x 0.2..2.8, y 0.2..1.8
    route, skipped = lawnmower(lanes, lanes | True, grid, 0.3)
    assert skipped == 0
    ys = sorted({round(y, 3) for _, y in route})
    assert ys[0] == pytest.approx(0.225) and ys[-1] == pytest.approx(1.775)
    assert len(ys) == 7 and max(np.diff(ys)) <= 0.3  # ceil(1.55 / 0.3) + 1 lanes, evenly spread
    expected = [(0.225, 0.225), (2.775, 0.225), (2.775, ys[1]), (0.225, ys[1])]
    assert np.allclose(route[:4], expected)


def test_lanes_split_around_an_obstacle_and_join_through_free_space():
    grid = Grid.covering(0, 4, 0, 2, 0.05)
    free = np.ones((grid.ny, grid.nx), dtype=bool)
    free[:, 36:44] = False  # a wall across the room, x 1.8..2.2, with a gap at the top
    free[36:, 36:44] = True
    route, skipped = lawnmower(free, free, grid, 0.4)
    assert skipped == 0
    for a, b in zip(route, route[1:]):  # no leg crosses the wall
        xs = np.linspace(a[0], b[0], 200)
        ys = np.linspace(a[1], b[1], 200)
        assert all(free[int(y / 0.05), int(x / 0.05)] for x, y in zip(xs, ys)), (a, b)
    assert any(x > 2.2 for x, _ in route) and any(x < 1.8 for x, _ in route)
