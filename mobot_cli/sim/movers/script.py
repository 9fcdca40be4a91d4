"""Keyframes played by time, as Gazebo plays an actor's ``<script>`` (gazebo classic's Actor.cc,
gz-common's PoseAnimation): ``delay`` s at the first keyframe before it starts, and again before
every round when it loops; without ``loop`` it stays at the last keyframe.

Between two keyframes of a Gazebo actor's trajectory (``MoverPlan.curves``) the pose follows
Gazebo's splines (spline.py); a scenario's path mover goes in straight lines at its speed,
heading by the shorter turn."""

from __future__ import annotations

import bisect
import math

from mobot_cli.plan import MoverPlan
from mobot_cli.sim.movers.spline import Curve


class Script:
    """One mover's keyframes, ready to be asked for its pose at a time."""

    __slots__ = ("times", "frames", "length", "loop", "delay", "auto_start", "curves")

    def __init__(self, plan: MoverPlan):
        self.frames = plan.keyframes
        self.times = [frame[0] for frame in plan.keyframes]
        self.length = self.times[-1]
        self.loop, self.delay, self.auto_start = plan.loop, plan.delay, plan.auto_start
        # keyframe index -> (its trajectory's curve, its index there), for all but a curve's last
        self.curves: dict[int, tuple[Curve, int]] = {}
        for first, last, tension in plan.curves:
            start = self.frames[first][0]
            curve = Curve([(t - start, x, y, yaw) for t, x, y, yaw in self.frames[first:last + 1]], tension)
            self.curves.update((first + k, (curve, k)) for k in range(last - first))

    def pose(self, t: float) -> tuple[float, float, float]:
        """(x, y, yaw) ``t`` s after the mover entered the world."""
        first = self.frames[0]
        if not self.auto_start or self.length <= 0.0:
            return _at(first)
        u = t - self.delay
        if u < 0.0:
            return _at(first)
        if self.loop:
            u = math.fmod(u, self.length + self.delay)
            if u >= self.length:  # the delay again, at the first keyframe
                return _at(first)
        elif u >= self.length:
            return _at(self.frames[-1])
        i = bisect.bisect_right(self.times, u)  # frames[i - 1] <= u < frames[i]
        (t0, x0, y0, a0), (t1, x1, y1, a1) = self.frames[i - 1], self.frames[i]
        f = (u - t0) / (t1 - t0) if t1 > t0 else 1.0
        if i - 1 in self.curves:
            curve, k = self.curves[i - 1]
            return curve.at(k, f)
        turn = math.remainder(a1 - a0, 2.0 * math.pi)
        return x0 + (x1 - x0) * f, y0 + (y1 - y0) * f, math.remainder(a0 + turn * f, 2.0 * math.pi)


def _at(frame) -> tuple[float, float, float]:
    """A keyframe's pose, its heading in [-pi, pi] (an actor's keyframe keeps the file's yaw)."""
    return frame[1], frame[2], math.remainder(frame[3], 2.0 * math.pi)


def path_keyframes(points: list[tuple[float, float]], speed: float, mode: str) -> tuple[tuple, ...]:
    """Keyframes that go along ``points`` at ``speed`` m/s facing the way they go: ``loop`` back to
    the first point, ``pingpong`` back along the path, ``once`` to the last point."""
    route = list(points)
    if mode == "loop":
        route = route + [route[0]]
    elif mode == "pingpong":
        route = route + route[-2::-1]
    frames, t = [], 0.0
    for i, (x, y) in enumerate(route):
        nxt = route[i + 1] if i + 1 < len(route) else None
        prev = route[i - 1] if i else None
        if nxt is not None and (nxt[0], nxt[1]) != (x, y):
            yaw = math.atan2(nxt[1] - y, nxt[0] - x)
        elif prev is not None:
            yaw = math.atan2(y - prev[1], x - prev[0])
        else:
            yaw = 0.0
        if prev is not None:
            t += math.dist(prev, (x, y)) / speed
            if frames and nxt is not None:  # turn on the spot: arrive facing the old way, leave facing the new
                frames.append((t, x, y, frames[-1][3]))
                t += 1e-3
        frames.append((t, x, y, yaw))
    return tuple(frames)
