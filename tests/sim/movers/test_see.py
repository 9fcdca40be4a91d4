"""A scan's rays at movers: the pairs ``see`` leaves out (beyond the ray's apex angle, or beyond
what the ray already reached) change no range, to the bit."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.sim.movers.shapes import BOX, CYLINDER, PERSON, Snapshot, _box, _round_pairs, see


def crowd(rng: np.random.Generator, count: int, spread: float) -> Snapshot:
    kind = rng.choice([PERSON, CYLINDER, BOX, PERSON], size=count)
    box = kind == BOX
    hx, hy = np.where(box, rng.uniform(0.1, 0.6, count), 0.0), np.where(box, rng.uniform(0.1, 0.6, count), 0.0)
    r = np.where(box, np.hypot(hx, hy), rng.uniform(0.05, 0.5, count))
    z0 = rng.uniform(-0.2, 0.3, count)
    return Snapshot(kind, rng.uniform(-spread, spread, count), rng.uniform(-spread, spread, count),
                    rng.uniform(-math.pi, math.pi, count), r, hx, hy, z0, z0 + rng.uniform(0.2, 1.9, count))


def beams(horizontal: int, vertical: int, range_max: float, range_min: float) -> SimpleNamespace:
    az = np.linspace(-math.pi, math.pi, horizontal, endpoint=False)
    el = np.linspace(-0.26, 0.26, vertical) if vertical > 1 else np.zeros(1)
    e, a = np.meshgrid(el, az, indexing="ij")
    d = np.stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)], axis=-1).reshape(-1, 3)
    return SimpleNamespace(directions=d, lengths32=np.full(len(d), range_max - range_min, np.float32))


def every_pair(snap: Snapshot, origins: np.ndarray, dirs: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """Each ray's nearest mover within its length, trying every (ray, mover) pair and every part."""
    rays, movers = np.repeat(np.arange(len(origins)), len(snap)), np.tile(np.arange(len(snap)), len(origins))
    round_ = snap.kind[movers] != BOX
    best = np.full(len(origins), np.inf)
    np.minimum.at(best, rays[round_], _round_pairs(origins[rays[round_]], dirs[rays[round_]], snap, movers[round_]))
    for i in np.flatnonzero(snap.kind == BOX).tolist():
        np.minimum(best, _box(origins, dirs, snap, i), out=best)
    best[best > lengths] = np.inf
    return best


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), count=st.integers(1, 40), vertical=st.sampled_from([1, 1, 4]),
       tilt=st.sampled_from([0.0, 1e-6, 0.05]), range_min=st.sampled_from([0.0, 0.12, 0.4]))
def test_see_cuts_pairs_without_changing_a_range(seed, count, vertical, tilt, range_min):
    rng = np.random.default_rng(seed)
    snap = crowd(rng, count, spread=4.0)
    beam = beams(181, vertical, 8.0, range_min)
    position = (float(rng.uniform(-1, 1)), float(rng.uniform(-1, 1)), float(rng.uniform(0.1, 0.6)))
    yaw = float(rng.uniform(-3, 3))
    turn = np.array([[math.cos(yaw), -math.sin(yaw), 0.0], [math.sin(yaw), math.cos(yaw), 0.0], [0.0, 0.0, 1.0]])
    roll = np.array([[1.0, 0.0, 0.0], [0.0, math.cos(tilt), -math.sin(tilt)], [0.0, math.sin(tilt), math.cos(tilt)]])
    rotation = (turn @ roll).tolist()  # a robot turned and tilted a little, as on PyBullet's floor
    # what the static world left: walls at random distances, some beams open (+inf)
    static = rng.uniform(range_min + 0.05, 8.0, len(beam.directions)).astype(np.float32)
    static[rng.random(len(static)) < 0.3] = np.inf
    ranges = static.reshape(vertical, -1).copy()
    see(snap, range_min, beam, position, rotation, ranges)
    # every ray against every mover, every part of each shape: the definition
    dirs = beam.directions @ np.array(rotation).T
    origins = np.array(position) + dirs * range_min
    full = every_pair(snap, origins, dirs, beam.lengths32.astype(float))
    expected = np.minimum(static, (full + range_min).astype(np.float32))
    assert ranges.reshape(-1).tobytes() == expected.tobytes()


def test_a_walker_behind_a_wall_or_outside_its_angle_is_not_cast_at():
    """The pairs left out are the ones that cannot matter, and only those (a hit nearer than the
    wall is kept)."""
    snap = Snapshot(np.array([PERSON, PERSON]), np.array([3.0, 1.0]), np.array([0.0, 0.0]), np.zeros(2),
                    np.array([0.3, 0.3]), np.zeros(2), np.zeros(2), np.zeros(2), np.full(2, 1.7))
    beam = beams(360, 1, 12.0, 0.1)
    ranges = np.full((1, 360), 2.0, np.float32)  # a wall 2 m away all round
    see(snap, 0.1, beam, (0.0, 0.0, 1.0), np.eye(3), ranges)
    assert abs(float(ranges[0, 180]) - 0.7) < 1e-6  # beam 180 faces +x: the near walker, 0.7 m
    assert int((ranges < 2.0).sum()) == 35  # the beams it spans: 2 asin(0.3 / 1) = 34.9 degrees
