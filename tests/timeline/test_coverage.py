"""The coverage metric (timeline/coverage.py) on shapes whose area is known by hand."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.common.polygon import box_polygon
from mobot_cli.plan import StaticBody, StaticShape, WorldPlan
from mobot_cli.timeline.coverage import Sweep

FOOTPRINT = (-0.2, 0.1, -0.17, 0.17)  # the bundled robot's: 0.3 x 0.34 m


def area(xmin, xmax, ymin, ymax):
    return tuple(box_polygon(xmin, xmax, ymin, ymax))


@settings(max_examples=40, deadline=None)
@given(length=st.floats(0.5, 3.0), y=st.floats(-1.0, 1.0), steps=st.integers(2, 300))
def test_a_straight_drive_sweeps_width_times_length_plus_the_footprint(length, y, steps):
    sweep = Sweep(area(-2, 4, -2, 2), None, FOOTPRINT)
    for k in range(steps + 1):
        sweep.add(length * k / steps, y, 0.0)
    swept = 0.34 * (length + 0.3)
    assert sweep.free_area == pytest.approx(24.0)
    assert sweep.fraction * sweep.free_area == pytest.approx(swept, abs=0.02 * (length + 0.64))


def test_a_turn_on_the_spot_sweeps_the_footprints_disc():
    sweep = Sweep(area(-1, 1, -1, 1), None, (-0.2, 0.2, -0.2, 0.2))
    for k in range(201):
        sweep.add(0.0, 0.0, 2 * math.pi * k / 200)
    assert sweep.fraction * 4.0 == pytest.approx(math.pi * 0.2 ** 2 * 2, rel=0.02)  # radius: half the diagonal


def test_obstacles_are_not_free_space_and_partly_covered_areas_count_their_inside():
    table = StaticBody(name="table", shapes=(StaticShape(kind="box", size=(1.0, 0.5, 0.8), xyz=(1.0, 1.0, 0.4)),))
    world = WorldPlan(bodies=(table,))
    sweep = Sweep(area(0, 2, 0, 2), world, FOOTPRINT)
    assert sweep.free_area == pytest.approx(4.0 - 0.5, abs=0.005)
    for x in range(0, 21):  # along y = 0.17: the footprint's band y 0..0.34, x -0.2..2.1 clipped to 0..2
        sweep.add(x / 10, 0.17, 0.0)
    assert sweep.fraction == pytest.approx(2.0 * 0.34 / 3.5, rel=0.03)
    triangle = Sweep(((0.0, 0.0), (2.0, 0.0), (0.0, 2.0)), None, FOOTPRINT)
    assert triangle.free_area == pytest.approx(2.0, rel=0.02)
