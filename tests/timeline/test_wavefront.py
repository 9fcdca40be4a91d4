"""The local controller's free-space distances (timeline/wavefront.py) on grids with known answers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mobot_cli.timeline.wavefront import WAVE_CELL, WAVE_REACH, Wavefront


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
    assert inside == pytest.approx(2 * round(2 * WAVE_REACH / WAVE_CELL) * WAVE_CELL)  # unreachable: the grid's width
