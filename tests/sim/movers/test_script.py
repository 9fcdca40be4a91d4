"""Keyframes played as Gazebo plays an actor's script, rays against movers' shapes, the social force."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.plan import MoverPlan
from mobot_cli.sim.movers import social
from mobot_cli.sim.movers.script import Script, path_keyframes
from mobot_cli.sim.movers.shapes import BOX, CYLINDER, PERSON, Snapshot, cast

FRAMES = ((0.0, 2.0, -2.0, 1.0), (4.0, 2.0, 2.0, 1.0), (8.0, 2.0, -2.0, 1.0))


def script(**kw) -> Script:
    return Script(MoverPlan(name="a", shape="person", size=(0.3, 1.7), keyframes=FRAMES, **kw))


def test_delay_then_linear_by_time():
    s = script(delay=0.5)
    assert s.pose(0.3) == (2.0, -2.0, 1.0)  # waiting at the first keyframe
    x, y, _ = s.pose(0.5 + 1.0)
    assert (x, y) == (2.0, -1.0)
    assert s.pose(0.5 + 6.0)[1] == 0.0


def test_loop_waits_the_delay_again_as_gazebo_classic():
    s = script(delay=0.5)
    # 8 s of script after 0.5 s: at 8.5 s it wraps and waits 0.5 s at the start again
    assert s.pose(8.7)[:2] == (2.0, -2.0)
    assert s.pose(9.0 + 2.0)[:2] == (2.0, 0.0)


def test_once_stays_at_the_end_and_auto_start_false_stays_at_the_start():
    assert script(loop=False).pose(100.0)[:2] == (2.0, -2.0)
    assert script(loop=False).pose(6.0)[:2] == (2.0, 0.0)
    assert script(auto_start=False).pose(3.0)[:2] == (2.0, -2.0)


def test_heading_turns_the_short_way():
    s = Script(MoverPlan(name="a", shape="box", size=(1, 1, 1),
                         keyframes=((0.0, 0.0, 0.0, 3.0), (1.0, 0.0, 0.0, -3.0))))
    yaw = s.pose(0.5)[2]
    assert abs(abs(yaw) - math.pi) < 1e-9  # through pi, not through 0


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(-20, 20), st.floats(-20, 20)), min_size=2, max_size=6, unique=True),
       st.floats(0.1, 3.0), st.sampled_from(["loop", "pingpong", "once"]), st.floats(0.0, 60.0))
def test_path_movers_keep_their_speed_and_stay_on_the_path(points, speed, mode, t):
    frames = path_keyframes(points, speed, mode)
    s = Script(MoverPlan(name="a", shape="person", size=(0.3, 1.7), keyframes=frames, loop=mode != "once"))
    x, y, _ = s.pose(t)
    dt = 0.01
    x2, y2, _ = s.pose(t + dt)
    assert math.hypot(x2 - x, y2 - y) <= speed * dt + 1e-6
    # on one of the segments
    route = points + ([points[0]] if mode == "loop" else [])
    gaps = [_segment_distance((x, y), a, b) for a, b in zip(route, route[1:])]
    assert min(gaps) < 1e-6


def _segment_distance(p, a, b) -> float:
    ax, ay = a
    dx, dy = b[0] - ax, b[1] - ay
    n = dx * dx + dy * dy
    f = 0.0 if n == 0 else max(0.0, min(1.0, ((p[0] - ax) * dx + (p[1] - ay) * dy) / n))
    return math.hypot(p[0] - ax - f * dx, p[1] - ay - f * dy)


def snap(kind, x, y, yaw=0.0, r=0.3, hx=0.0, hy=0.0, z0=0.0, z1=1.7) -> Snapshot:
    a = lambda v: np.array([v], dtype=float)  # noqa: E731
    return Snapshot(np.array([kind]), a(x), a(y), a(yaw), a(r if kind != BOX else math.hypot(hx, hy)), a(hx), a(hy),
                    a(z0), a(z1))


def test_rays_meet_shapes_where_geometry_says():
    origins = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 0.1], [0.0, 0.0, 2.0], [0.0, 0.0, 1.0]])
    dirs = np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    lengths = np.full(4, 10.0)
    person = cast(snap(PERSON, 3.0, 0.0), origins, dirs, lengths)
    assert person[0] == 2.7  # the straight part
    assert abs(person[1] - (3.0 - math.sqrt(0.09 - 0.04))) < 1e-12  # the bottom sphere, at 0.1 m
    assert np.isinf(person[2]) and np.isinf(person[3])  # above it; beside it
    assert cast(snap(CYLINDER, 3.0, 0.0), origins, dirs, lengths)[1] == 2.7
    box = cast(snap(BOX, 3.0, 0.0, yaw=math.pi / 4, hx=0.5, hy=0.5, z1=1.0), origins, dirs, lengths)
    assert abs(box[0] - (3.0 - 0.5 * math.sqrt(2.0))) < 1e-12 and np.isinf(box[2])
    assert cast(snap(PERSON, 30.0, 0.0), origins, dirs, lengths) is None  # out of reach: nothing cast


def test_social_force_pushes_apart_and_pulls_to_the_goal():
    pos = np.array([[0.0, 0.0], [0.5, 0.0]])
    vel = np.zeros((2, 2))
    goal = np.array([[0.0, 5.0], [0.5, 5.0]])
    a = social.forces(pos, vel, goal, np.ones(2), np.full(2, 0.3), np.zeros((0, 2)), np.zeros(0),
                      np.full((2, 4), np.inf), np.array([[1, 0], [0, 1], [-1, 0], [0, -1.0]]))
    assert a[0, 0] < 0.0 < a[1, 0]  # apart along x
    assert a[0, 1] > 0.0 and a[1, 1] > 0.0  # toward their goals
    wall = social.forces(pos[:1], vel[:1], goal[:1], np.ones(1), np.full(1, 0.3), np.zeros((0, 2)), np.zeros(0),
                         np.array([[0.35, np.inf, np.inf, np.inf]]), np.array([[1, 0], [0, 1], [-1, 0], [0, -1.0]]))
    assert wall[0, 0] < -5.0  # a wall 0.35 m to the east pushes west
