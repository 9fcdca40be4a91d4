"""The goal controller (timeline/pursuit.py) on an ideal unicycle: it gets there, within its limits."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.plan import GoalControl
from mobot_cli.timeline.pursuit import MIN_APPROACH_SPEED, PlanarPose, Pursuit

DT = 0.05
CONTROL = GoalControl()


def drive(route, pose: PlanarPose, yaw=None, ticks: int = 4000):
    """Run the controller on a unicycle that does exactly what it is told; (pursuit, poses, twists)."""
    pursuit = Pursuit([(pose.x, pose.y), *route], CONTROL, DT, yaw=yaw)
    poses, twists = [], []
    for _ in range(ticks):
        v, w = pursuit.update(pose)
        twists.append((v, w))
        if pursuit.done:
            break
        pose = PlanarPose(pose.x + v * math.cos(pose.yaw) * DT, pose.y + v * math.sin(pose.yaw) * DT, pose.yaw + w * DT)
        poses.append(pose)
    return pursuit, poses, twists


coordinate = st.floats(-5, 5)


@settings(max_examples=60, deadline=None)
@given(x=coordinate, y=coordinate, heading=st.floats(-math.pi, math.pi), gx=coordinate, gy=coordinate,
       yaw=st.one_of(st.none(), st.floats(-math.pi, math.pi)))
def test_every_goal_is_reached_within_the_limits(x, y, heading, gx, gy, yaw):
    pursuit, poses, twists = drive([(gx, gy)], PlanarPose(x, y, heading), yaw)
    assert pursuit.done
    end = poses[-1] if poses else PlanarPose(x, y, heading)
    assert math.hypot(end.x - gx, end.y - gy) <= CONTROL.tolerance
    if yaw is not None:
        assert abs(math.remainder(end.yaw - yaw, math.tau)) <= CONTROL.yaw_tolerance + 1e-9
    for (v0, w0), (v1, w1) in zip([(0.0, 0.0), *twists], twists):
        assert abs(v1) <= CONTROL.max_linear + 1e-9 and abs(w1) <= CONTROL.max_angular + 1e-9
        assert abs(v1 - v0) <= CONTROL.linear_acceleration * DT + 1e-9
        assert abs(w1 - w0) <= CONTROL.angular_acceleration * DT + 1e-9
    # It never reverses, but for a creep while it turns to the goal's yaw on the spot.
    assert min(v for v, _ in twists) >= -MIN_APPROACH_SPEED


def test_sharp_corners_are_driven_onto_and_gentle_ones_cut():
    zigzag = [(2.0, 0.0), (2.0, 1.0), (3.0, 1.2), (4.0, 1.2)]  # 90 deg at (2, 0); 11 deg at (3, 1.2)
    pursuit, poses, _ = drive(zigzag, PlanarPose(0.0, 0.0, 0.0))
    assert pursuit.done
    assert min(math.hypot(p.x - 2.0, p.y) for p in poses) <= CONTROL.tolerance
    passing = min(math.hypot(p.x - 3.0, p.y - 1.2) for p in poses)
    assert 0.0 < passing <= 0.05
