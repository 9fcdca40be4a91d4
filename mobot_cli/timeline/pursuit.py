"""The controller of goal commands: regulated pure pursuit along a polyline, after nav2's RPP.

A test driver, not a planner: it follows the straight segments it is given and never steers
around obstacles (a route through furniture drives into it; the goal then ends ``blocked``).
Each control tick it takes the pose the robot believes it has and returns a twist:

1. Progress: the robot's nearest point on the route, searched only forward from the last one
   and never past the next stop vertex, so loops and neighbouring lanes are never skipped to.
2. Stop vertices: the last point, and every vertex where the route turns by more than
   ``SHARP_TURN``. Like the cusps of nav2's RPP, the robot drives onto a stop vertex (within
   the tolerance, or within twice it once the vertex is behind), turns on the spot and goes on.
   Gentler vertices are cut smoothly. The last point is aimed at more closely: within half the
   tolerance, or within the tolerance once it is behind the robot (it drove past).
3. Lookahead: the point ``LOOKAHEAD_TIME`` x speed further along the route (clamped to
   ``LOOKAHEAD``), never beyond the next stop vertex.
4. Rotate to heading: a lookahead point more than ``ROTATE_ANGLE`` off the heading (nav2's
   rotate_to_heading_min_angle) is turned to on the spot until it is within ``ROTATED``, at
   most sqrt(a angle) rad/s (so the turn could brake at half the acceleration limit) and at
   least ``MIN_TURN_RATE``.
5. Otherwise: curvature k = 2 y / L^2 of the lookahead point (x, y) at distance L; speed
   ``max_linear`` times r / ``MIN_RADIUS`` on curves tighter than that radius (nav2's
   regulated_linear_scaling_min_radius) and at most sqrt(a d) at distance d (along the
   route) from the next stop vertex, so it arrives braking at half the acceleration limit
   (the role of nav2's approach velocity scaling), down to ``MIN_APPROACH_SPEED``;
   w = v k, clipped to ``max_angular`` with v scaled to keep the curvature.
6. Acceleration: v and w change by at most the acceleration limits times the control period.

At the last point the robot stops, turns to the goal's yaw if one was given, and is there.
While it turns it creeps forward or back (``HOLD_GAIN``, at most ``MIN_APPROACH_SPEED``) to
keep the point under it: skid-steer robots (husky) wander a few centimetres on a turn.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mobot_cli.plan import GoalControl

Point = tuple[float, float]

SHARP_TURN = math.radians(30.0)  # rad: a vertex turning more than this is driven onto and turned on
ROTATE_ANGLE = math.radians(45.0)  # rad: turn on the spot toward a lookahead point further off
ROTATED = math.radians(5.0)  # rad: ... until it is this close to straight ahead
LOOKAHEAD_TIME = 1.5  # s: lookahead distance = speed x this, within LOOKAHEAD
LOOKAHEAD = (0.25, 0.6)  # m
MIN_RADIUS = 0.9  # m: tighter curves slow the robot down
MIN_APPROACH_SPEED = 0.05  # m/s
MIN_TURN_RATE = 0.1  # rad/s: the slowest turn on the spot (so that a turn ends)
HOLD_GAIN = 1.0  # 1/s: forward speed per metre the goal lies ahead while turning to its yaw


@dataclass
class PlanarPose:
    """Where the robot thinks it is: world x, y (m) and yaw (rad)."""

    x: float
    y: float
    yaw: float


class Pursuit:
    """Follows ``route`` (its first point is where the robot starts) to its last point."""

    def __init__(self, route: list[Point], control: GoalControl, dt: float, yaw: float | None = None):
        self.route: list[Point] = []
        self.extend(route)
        self.control, self.dt, self.yaw = control, dt, yaw
        self.seg = 0  # the segment the robot is on: route[seg] -> route[seg + 1]
        self.passed = 0  # the last vertex driven past
        self.v = self.w = 0.0  # the twist last given
        self.rotating = False  # turning on the spot toward the lookahead point
        self.at_end = False  # the last point is reached; turning to yaw if one was given
        self.done = False

    def extend(self, points) -> None:
        """Add points to the route's end (a patrol's next lap); repeated points are dropped."""
        for point in points:
            point = (float(point[0]), float(point[1]))
            if not self.route or math.dist(point, self.route[-1]) > 1e-9:
                self.route.append(point)

    @property
    def stop(self) -> int:
        """The next vertex the robot must drive onto: a sharp turn, or the last point."""
        route = self.route
        for k in range(self.seg + 1, len(route) - 1):
            if _turn(route[k - 1], route[k], route[k + 1]) > SHARP_TURN:
                return k
        return len(route) - 1

    def follow(self, pose: PlanarPose) -> bool:
        """Carry the progress along the route forward; True while the robot is still on its way
        to the last point (False once there: ``update`` then turns it to its yaw and stops)."""
        if not self.at_end:
            self._advance(pose)
        return not self.at_end

    def ahead(self, pose: PlanarPose, length: float) -> list[Point]:
        """The route from the robot's nearest point on it, ``length`` along it (never past the
        next stop vertex): the path a local controller follows (timeline/local.py)."""
        route, stop = self.route, self.stop
        a, b = route[self.seg], route[self.seg + 1]
        t = _projection(pose, a, b)
        points = [(a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]))]
        left, k = length, self.seg
        while k < stop:
            end = route[k + 1]
            here = points[-1]
            step = math.dist(here, end)
            if step >= left:
                f = left / step if step > 0.0 else 0.0
                points.append((here[0] + f * (end[0] - here[0]), here[1] + f * (end[1] - here[1])))
                break
            points.append(end)
            left -= step
            k += 1
        return points

    def update(self, pose: PlanarPose) -> tuple[float, float]:
        """The twist for this control tick (both zero once ``done``)."""
        self.follow(pose)
        if self.at_end and not self.done:
            error = 0.0 if self.yaw is None else _wrap(self.yaw - pose.yaw)
            self.done = abs(error) <= self.control.yaw_tolerance
            if not self.done:  # turn on the spot, creeping to keep the point under the robot
                ahead = _in_frame(pose, self.route[-1])[0]
                hold = min(max(HOLD_GAIN * ahead, -MIN_APPROACH_SPEED), MIN_APPROACH_SPEED)
                return self._limit(hold, self._turn_rate(error))
        if self.done:
            return self._limit(0.0, 0.0)
        return self._pursue(pose)

    def _advance(self, pose: PlanarPose) -> None:
        """Carry the progress forward, across every stop vertex the robot has arrived on."""
        last, tol = len(self.route) - 1, self.control.tolerance
        while self.seg < last:
            stop = self.stop
            self._progress(pose, stop)
            near = math.dist((pose.x, pose.y), self.route[stop])
            behind = _in_frame(pose, self.route[stop])[0] < 0.0
            if stop == last:  # aim for half the tolerance; the whole of it once the point is behind
                arrived = near <= tol / 2 or near <= tol and behind
            else:
                arrived = near <= tol or near <= 2 * tol and behind
            if not arrived:
                return
            self.seg = self.passed = stop
        self.at_end = True

    def _progress(self, pose: PlanarPose, stop: int) -> None:
        """Move ``seg`` forward to the segment nearest the robot, up to the stop vertex."""
        best, best_d = self.seg, _segment_distance(pose, self.route[self.seg], self.route[self.seg + 1])
        for k in range(self.seg + 1, stop):
            d = _segment_distance(pose, self.route[k], self.route[k + 1])
            if d < best_d:
                best, best_d = k, d
        if best > self.seg:
            self.seg = best
            self.passed = max(self.passed, best)

    def _pursue(self, pose: PlanarPose) -> tuple[float, float]:
        c = self.control
        stop = self.stop
        lookahead = min(max(abs(self.v) * LOOKAHEAD_TIME, LOOKAHEAD[0]), LOOKAHEAD[1])
        point, remaining = self._lookahead(pose, lookahead, stop)
        lx, ly = _in_frame(pose, point)
        angle = math.atan2(ly, lx)
        self.rotating = abs(angle) > (ROTATED if self.rotating else ROTATE_ANGLE)
        if self.rotating:
            return self._limit(0.0, self._turn_rate(angle))
        dist2 = lx * lx + ly * ly
        curvature = 2.0 * ly / dist2 if dist2 > 1e-12 else 0.0
        v = c.max_linear
        if abs(curvature) > 1.0 / MIN_RADIUS:
            v *= 1.0 / (abs(curvature) * MIN_RADIUS)
        v = min(v, max(math.sqrt(c.linear_acceleration * remaining), MIN_APPROACH_SPEED))
        w = v * curvature
        if abs(w) > c.max_angular:
            v *= c.max_angular / abs(w)
            w = math.copysign(c.max_angular, w)
        return self._limit(v, w)

    def _lookahead(self, pose: PlanarPose, distance: float, stop: int) -> tuple[Point, float]:
        """The point ``distance`` along the route from the robot's projection (not past ``stop``),
        and how far the stop vertex is along the route."""
        route = self.route
        a, b = route[self.seg], route[self.seg + 1]
        t = _projection(pose, a, b)
        here = (a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]))
        to_stop = math.dist(here, b) + sum(math.dist(route[k], route[k + 1]) for k in range(self.seg + 1, stop))
        left, k, start = distance, self.seg, here
        while True:
            end = route[k + 1]
            length = math.dist(start, end)
            if left <= length or k + 1 >= stop:
                if left >= length:
                    return end, to_stop
                f = left / length
                return (start[0] + f * (end[0] - start[0]), start[1] + f * (end[1] - start[1])), to_stop
            left -= length
            k, start = k + 1, end

    def _turn_rate(self, angle: float) -> float:
        """A turn on the spot toward ``angle``, braking in time to stop on it."""
        c = self.control
        rate = min(c.max_angular, math.sqrt(c.angular_acceleration * abs(angle)))
        return math.copysign(max(rate, MIN_TURN_RATE), angle)

    def _limit(self, v: float, w: float) -> tuple[float, float]:
        """Move the last twist toward (v, w) within the acceleration limits."""
        c, dt = self.control, self.dt
        self.v = _toward(self.v, v, c.linear_acceleration * dt)
        self.w = _toward(self.w, w, c.angular_acceleration * dt)
        return self.v, self.w


def _toward(current: float, target: float, step: float) -> float:
    return min(max(target, current - step), current + step)


def _wrap(angle: float) -> float:
    return math.remainder(angle, math.tau)


def _turn(a: Point, b: Point, c: Point) -> float:
    """How much the route turns at ``b`` (rad, 0 when straight on)."""
    h1 = math.atan2(b[1] - a[1], b[0] - a[0])
    h2 = math.atan2(c[1] - b[1], c[0] - b[0])
    return abs(_wrap(h2 - h1))


def _in_frame(pose: PlanarPose, point: Point) -> Point:
    """``point`` in the robot's frame (x ahead, y to the left)."""
    dx, dy = point[0] - pose.x, point[1] - pose.y
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    return c * dx + s * dy, -s * dx + c * dy


def _projection(pose: PlanarPose, a: Point, b: Point) -> float:
    """Where the robot's nearest point on segment a-b lies, 0 (at a) to 1 (at b)."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    length2 = dx * dx + dy * dy
    if length2 <= 0.0:
        return 0.0
    return min(1.0, max(0.0, ((pose.x - a[0]) * dx + (pose.y - a[1]) * dy) / length2))


def _segment_distance(pose: PlanarPose, a: Point, b: Point) -> float:
    t = _projection(pose, a, b)
    return math.hypot(pose.x - (a[0] + t * (b[0] - a[0])), pose.y - (a[1] + t * (b[1] - a[1])))
