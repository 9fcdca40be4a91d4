"""Actor trajectories on Gazebo's splines (sim/movers/spline.py), checked against gz-math's own
formulation written out here independently: the Hermite basis matrix times the control matrix
(SplinePrivate.cc) and full four-component quaternions (Quaternion.hh: Log, Exp, Slerp, Squad)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.assets.world.actors import read_actor
from mobot_cli.plan import MoverPlan
from mobot_cli.sim.movers.script import Script
from mobot_cli.sim.movers.spline import Curve

HERMITE = np.array([[2.0, -2.0, 1.0, 1.0], [-3.0, 3.0, -2.0, -1.0], [0.0, 0.0, 1.0, 0.0], [1.0, 0.0, 0.0, 0.0]])


def q_mul(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def q_log(q):
    out = np.zeros(4)
    if abs(q[0]) < 1.0:
        angle = math.acos(q[0])
        if abs(math.sin(angle)) >= 1e-3:
            out[1:] = angle / math.sin(angle) * q[1:]
            return out
    out[1:] = q[1:]
    return out


def q_exp(q):
    angle = float(np.linalg.norm(q[1:]))
    coeff = math.sin(angle) / angle if abs(math.sin(angle)) >= 1e-3 else 1.0
    return np.array([math.cos(angle), *(coeff * q[1:])])


def q_slerp(t, p, q, shortest=False):
    cos = float(p @ q)
    if cos < 0.0 and shortest:
        cos, q = -cos, -q
    if abs(cos) < 1 - 1e-3:
        sin = math.sqrt(1 - cos * cos)
        angle = math.atan2(sin, cos)
        return p * (math.sin((1 - t) * angle) / sin) + q * (math.sin(t * angle) / sin)
    out = p * (1 - t) + q * t
    return out / np.linalg.norm(out)


def q_yaw(yaw):  # Quaternion(0, 0, yaw): SetFromEuler
    return np.array([math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)])


def gazebo_pose(frames, tension, index, s):
    """gz-common PoseAnimation::InterpolatedKeyFrame between keyframes index and index + 1."""
    points = np.array([[f[1], f[2], 0.0] for f in frames])
    n, k = len(points), 1.0 - tension
    closed = np.allclose(points[0], points[-1], atol=1e-6, rtol=0)
    tangents = []
    for i in range(n):
        if i == 0:
            tangents.append((points[1] - (points[n - 2] if closed else points[0])) * 0.5 * k)
        elif i == n - 1:
            tangents.append(tangents[0] if closed else (points[i] - points[i - 1]) * 0.5 * k)
        else:
            tangents.append((points[i + 1] - points[i - 1]) * 0.5 * k)
    control = np.array([[*points[index], 1.0], [*points[index + 1], 1.0],
                        [*tangents[index], 1.0], [*tangents[index + 1], 1.0]])
    position = np.array([s ** 3, s ** 2, s, 1.0]) @ (HERMITE @ control)
    quats = [q_yaw(f[3]) for f in frames]
    closed_q = np.allclose(quats[0], quats[-1], atol=1e-3, rtol=0)
    rot_tangents = []
    for i, q in enumerate(quats):
        inverse = np.array([q[0], -q[1], -q[2], -q[3]])
        after = quats[i + 1] if i < n - 1 else (quats[1] if closed_q else q)
        before = quats[i - 1] if i > 0 else (quats[n - 2] if closed_q else q)
        rot_tangents.append(q_mul(q, q_exp((q_log(q_mul(inverse, after)) + q_log(q_mul(inverse, before))) * -0.25)))
    p, q = quats[index], quats[index + 1]
    squad = q_slerp(2 * s * (1 - s), q_slerp(s, p, q, True),
                    q_slerp(s, rot_tangents[index], rot_tangents[index + 1]))
    yaw = math.atan2(2 * (squad[0] * squad[3] + squad[1] * squad[2]), 1 - 2 * (squad[2] ** 2 + squad[3] ** 2))
    return position[0], position[1], yaw


def same_heading(a, b, tol):
    return abs(math.remainder(a - b, 2 * math.pi)) < tol


@settings(max_examples=150, deadline=None)
@given(st.lists(st.tuples(st.floats(-10, 10), st.floats(-10, 10), st.floats(-math.pi, math.pi)),
                min_size=2, max_size=7),
       st.floats(0.0, 1.0), st.data())
def test_curves_match_gz_maths_own_formulation(points, tension, data):
    frames = [(1.5 * i, x, y, yaw) for i, (x, y, yaw) in enumerate(points)]
    if data.draw(st.booleans()):
        frames.append((1.5 * len(frames), *frames[0][1:]))  # a closed trajectory
    index = data.draw(st.integers(0, len(frames) - 2))
    s = data.draw(st.floats(0.001, 0.999))
    x, y, yaw = Curve(frames, tension).at(index, s)
    gx, gy, gyaw = gazebo_pose(frames, tension, index, s)
    assert abs(x - gx) < 1e-9 and abs(y - gy) < 1e-9
    assert same_heading(yaw, gyaw, 1e-7)


def test_catmull_rom_numbers_and_tension():
    frames = [(0.0, 0.0, 0.0, 0.0), (1.0, 1.0, 0.0, 0.0), (2.0, 2.0, 0.0, 0.0)]
    # tangents 0.5 at the start and 1 at (1, 0): a Hermite curve slower than a straight line
    assert Curve(frames, 0.0).at(0, 0.5)[0] == 0.4375
    assert Curve(frames, 1.0).at(0, 0.5)[0] == 0.5  # no tangents: a smoothstep
    assert Curve(frames, 0.0).at(1, 0.0) == (1.0, 0.0, 0.0)  # keyframes are met exactly


def test_a_turn_on_the_spot_swings_out_as_in_gazebo():
    # Gazebo's actor.sdf: walk to (5, 4), turn there for 0.5 s, walk on north
    frames = [(0.0, 3.0, 4.0, 0.0), (2.0, 5.0, 4.0, 0.0), (2.5, 5.0, 4.0, 1.57), (4.0, 5.0, 6.0, 1.57)]
    x, y, yaw = Curve(frames, 0.6).at(1, 0.5)
    assert x > 5.0 and y < 4.0  # past the corner and back: Catmull-Rom overshoots
    assert 0.6 < yaw < 1.0


def actor(tmp_path: Path, trajectories: str) -> MoverPlan:
    from lxml import etree

    text = f"<actor name='a'><script><loop>false</loop>{trajectories}</script></actor>"
    element = etree.fromstring(text)

    def pose_of(pose):
        x, y, _, _, _, yaw = (float(v) for v in pose.text.split())
        return [[math.cos(yaw), -math.sin(yaw), 0, x], [math.sin(yaw), math.cos(yaw), 0, y], [0, 0, 1, 0]]

    plan, _ = read_actor(element, tmp_path / "w.sdf", pose_of)
    return plan


def test_trajectories_play_from_their_first_waypoint_one_after_the_other(tmp_path):
    plan = actor(tmp_path, """
        <trajectory id='0' type='walk' tension='2'>
          <waypoint><time>1</time><pose>0 0 1 0 0 0</pose></waypoint>
          <waypoint><time>3</time><pose>2 0 1 0 0 0</pose></waypoint>
        </trajectory>
        <trajectory id='1' type='walk'>
          <waypoint><time>5</time><pose>2 0 1 0 0 1.5708</pose></waypoint>
          <waypoint><time>6</time><pose>2 1 1 0 0 1.5708</pose></waypoint>
        </trajectory>""")
    assert [f[0] for f in plan.keyframes] == [0.0, 2.0, 2.0, 3.0]  # no wait for the first times
    assert plan.curves == ((0, 1, 1.0), (2, 3, 0.0))  # tension clamped to 1, as Gazebo does
    script = Script(plan)
    assert script.pose(0.0) == (0.0, 0.0, 0.0)
    assert script.pose(1.0)[:2] == (1.0, 0.0)  # tension 1: a smoothstep, halfway at half time
    x, y, _ = script.pose(2.5)
    assert x == 2.0 and abs(y - 0.5) < 1e-12  # the second trajectory's two points: halfway
    assert script.pose(10.0)[:2] == (2.0, 1.0)  # no loop: it stays at the end


def test_a_file_yaw_past_pi_is_followed_as_gazebo_follows_its_quaternion(tmp_path):
    plan = actor(tmp_path, """
        <trajectory id='0' type='walk'>
          <waypoint><time>0</time><pose>0 0 1 0 0 3.0</pose></waypoint>
          <waypoint><time>1</time><pose>0 0 1 0 0 3.142</pose></waypoint>
          <waypoint><time>2</time><pose>0 0 1 0 0 3.3</pose></waypoint>
        </trajectory>""")
    assert plan.keyframes[1][3] == 3.142
    yaws = [Script(plan).pose(t / 10)[2] for t in range(21)]
    for a, b in zip(yaws, yaws[1:]):
        assert abs(math.remainder(b - a, 2 * math.pi)) < 0.05  # turns steadily through pi
    assert all(-math.pi <= yaw <= math.pi for yaw in yaws)
