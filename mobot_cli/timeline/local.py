"""Local obstacle avoidance for goal commands: a dynamic-window controller after nav2's DWB.

Pure maths on numpy, in the robot's frame (x ahead, y to the left): obstacle points from the
robot's own lidar and the stretch of the goal's path ahead go in, a twist comes out.

Each control tick (``Dwb.command``):

1. The dynamic window: target speeds v in [0, max_linear] and w in [-max_angular, max_angular]
   reachable from the current twist within ``SIM_TIME`` at the acceleration limits
   (``V_SAMPLES`` x ``W_SAMPLES`` of them, straight on always among them), as nav2's
   StandardTrajectoryGenerator samples them.
2. Rollouts: each target is driven for ``SIM_TIME`` in ``STEPS`` steps, its speeds ramping
   from the current twist at the acceleration limits (so the first step is what the robot can
   do next).
3. Critics, named as DWB names them, scored on each rollout (distances in ``CELL`` units, as
   nav2's grid critics count cells), weights (``WEIGHTS``) as nav2's default DWB setup:

   * BaseObstacle / ObstacleFootprint: a rollout whose footprint circle (``radius``, the
     robot's circumscribed radius, plus ``MARGIN``) meets a lidar point at any pose is
     rejected; the last pose costs 252 exp(-3 (d - radius)) within ``INFLATION`` of a point
     (nav2's inflation layer, cost_scaling_factor 3).
   * PathDist: distance of the last pose from the path. PathAlign: the same for the point
     ``FORWARD_POINT`` ahead of it (nav2's forward_point_distance).
   * GoalDist: distance of the last pose from the local goal (the path's end within
     ``LOCAL_PLAN``); GoalAlign: the same for the point ahead of it. When the path ahead runs
     into an obstacle, these distances are measured through free space (a wavefront on a
     ``WAVE_CELL`` grid around the robot, timeline/wavefront.py, as nav2 propagates them
     through its costmap), so a rollout that goes round the obstacle scores better than one
     that waits before it.
   * Oscillation: once the robot turned on the spot one way, turning on the spot the other
     way is rejected until it has moved ``OSCILLATION_RESET`` m or turned
     ``OSCILLATION_RESET_ANGLE`` rad (nav2's oscillation_reset_dist / _angle).
   * RotateToGoal is the pursuit's own final turn (timeline/pursuit.py) and is not scored here.

4. The best rollout (lowest weighted sum; the first of equals, so the same inputs give the
   same twist) gives the target; the command moves toward it within the acceleration limits.
   No admissible rollout: the robot stops (``Choice.admissible`` is False).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mobot_cli.plan import GoalControl
from mobot_cli.timeline.scan_points import Cloud
from mobot_cli.timeline.wavefront import WAVE_CELL, WAVE_REACH, Wavefront

SIM_TIME = 1.7  # s: how far ahead each rollout looks (nav2 DWB sim_time)
STEPS = 8  # poses per rollout (0.11 m apart at 0.5 m/s)
V_SAMPLES = 6  # target speeds sampled in the window (nav2: vx_samples 20)
W_SAMPLES = 11  # target turn rates (nav2: vtheta_samples 20)
CELL = 0.05  # m: distances of the path and goal critics are counted in these (nav2's 0.05 m grid)
MARGIN = 0.03  # m added to the robot's radius before a lidar point counts as a hit
INFLATION = 0.55  # m: points nearer the last pose than this (beyond the radius) cost (nav2 inflation_radius)
COST_SCALING = 3.0  # 1/m: nav2 inflation layer cost_scaling_factor
FORWARD_POINT = 0.1  # m: nav2 PathAlign / GoalAlign forward_point_distance
LOCAL_PLAN = 1.5  # m of the path ahead the critics see (nav2 prunes the plan to its 3 m local costmap)
OSCILLATION_RESET = 0.05  # m
OSCILLATION_RESET_ANGLE = 0.2  # rad
SPIN = 0.05  # m/s: below this a rollout turns on the spot (nav2 Oscillation x_only_threshold)
PATH_SLACK = 0.05  # m: how much nearer than the footprint's radius a path may pass a point (the planner's cell)
FANS_KEPT = 256  # windows kept (cleared when full)
WEIGHTS = {  # nav2's default DWB critic scales (nav2_params.yaml)
    "BaseObstacle": 0.02,
    "PathAlign": 32.0,
    "PathDist": 32.0,
    "GoalAlign": 24.0,
    "GoalDist": 24.0,
}


@dataclass(frozen=True)
class Choice:
    """What one control tick chose: the command, its target, and why."""

    linear: float
    angular: float
    admissible: bool  # False: every rollout met an obstacle (the robot stops)
    blocked_path: bool  # the path ahead runs into an obstacle (free-space distances in use)


class Dwb:
    """A dynamic-window controller for one goal: ``radius`` is the robot's footprint radius (m)."""

    def __init__(self, control: GoalControl, dt: float, radius: float):
        self.control, self.dt = control, dt
        self.radius = radius + MARGIN
        self.v = self.w = 0.0  # the twist last commanded
        self.spun = 0.0  # the sign of the last turn on the spot (0: none since the reset)
        self.spun_at = (0.0, 0.0, 0.0)  # world x, y, yaw where it was (for the reset)
        # How far each speed can move by each pose (its time t = 1..STEPS steps), times the step
        # (rollouts integrate v h and w h).
        h = SIM_TIME / STEPS
        ramp = np.arange(1, STEPS + 1) * h
        self._v_ramp, self._w_ramp = control.linear_acceleration * ramp * h, control.angular_acceleration * ramp * h
        # The window and its rollouts depend on the current twist alone: kept for the twists seen
        # (a robot cruising or turning at its limits meets the same one tick after tick).
        self._fans: dict[tuple[float, float], _Fan] = {}

    def command(self, obstacles, path: np.ndarray, pose=(0.0, 0.0, 0.0)) -> Choice:
        """The twist for this tick. ``obstacles``: lidar points, a ``Cloud`` or (n, 2) world x, y;
        ``path``: (m, 2) the path ahead in the robot frame, its last point the local goal;
        ``pose``: the robot's world x, y, yaw (the points are put in its frame; the oscillation
        critic's reset). With the default pose the points are in the robot's frame."""
        fan = self._fan()
        vs, ws = fan.vs, fan.ws
        cloud = obstacles if isinstance(obstacles, Cloud) else Cloud(obstacles)
        # The points in the robot's frame and their squared distances from it (3, n), one product.
        mine = cloud.seen_from(pose)
        reach = SIM_TIME * max(self.control.max_linear, abs(self.v)) + self.radius + INFLATION
        near = mine[:, mine[2] <= reach * reach]
        cost, ok = self._obstacle_cost(fan, near)
        if self.spun:
            ok &= self._not_oscillating(vs, ws, pose)
        path, beyond = _cut(path, LOCAL_PLAN)
        route = path.tolist()
        goal = route[-1]
        nose = _nose(goal)
        # One pass gives every distance the path critics and the path's check read: of the last
        # poses, the points ahead of them and the near lidar points, from each segment of the path,
        # from the stretch on from the goal to the nose target, and from the goal and the nose.
        count, segments = len(vs), max(1, len(route) - 1)
        ends = _segment_rows(route, nose)
        far = _segment_d2(np.concatenate((fan.ends, near[:2]), axis=1), ends)
        from_path = far[0] if segments == 1 else far[:segments].min(axis=0)
        slack = self.radius - MARGIN - PATH_SLACK
        # The path ahead runs into a point when it passes nearer than the footprint's radius less
        # PATH_SLACK. A planned path keeps that radius from the map's obstacles on the planner's
        # grid, so a doorway or a gap it threads is not blocked; something new on it is.
        blocked = near.shape[1] > 0 and len(route) >= 2 and slack > 0.0 and bool(
            (from_path[2 * count:] < slack * slack).any())
        score = cost
        if blocked:  # a path through an obstacle is no guide: the wavefront leads round it
            # The align critics aim the robot's nose (the point ahead of it) at the goal moved
            # FORWARD_POINT on along the line from the robot, as nav2's GoalAlign does.
            seen = mine[:2, mine[2] <= WAVE_REACH * WAVE_REACH].T
            goal = self._past(beyond, seen)
            nose = _nose(goal)
            field = Wavefront(goal, seen, self.radius)
            score += WEIGHTS["GoalDist"] * field.at(fan.ex, fan.ey) / CELL
            score += WEIGHTS["GoalAlign"] * field.at(fan.fx - nose[0] + goal[0], fan.fy - nose[1] + goal[1]) / CELL
        else:
            # PathDist of the last poses; PathAlign of the points ahead of them, its path going on
            # to the nose target (one more segment); GoalDist and GoalAlign from the goal and the nose.
            parts = np.empty((4, count))
            parts[0] = from_path[:count]
            np.minimum(from_path[count:2 * count], far[segments, count:2 * count], out=parts[1])
            parts[2] = far[segments + 1, :count]
            parts[3] = far[segments + 2, count:2 * count]
            score += _CRITICS @ np.sqrt(parts, out=parts)
        if not ok.any():
            self._step(0.0, 0.0)
            return Choice(self.v, self.w, False, blocked)
        score[~ok] = np.inf
        best = int(score.argmin())
        self._step(float(vs[best]), float(ws[best]))
        if abs(self.v) < SPIN and abs(self.w) > 1e-3 and np.sign(self.w) != self.spun:
            self.spun, self.spun_at = float(np.sign(self.w)), tuple(pose)
        return Choice(self.v, self.w, True, blocked)

    def _fan(self) -> "_Fan":
        key = (self.v, self.w)
        fan = self._fans.get(key)
        if fan is None:
            if len(self._fans) >= FANS_KEPT:
                self._fans.clear()
            fan = self._fans[key] = self._rollouts(*self._window())
        return fan

    def _window(self) -> tuple[list, list]:
        """The target speeds v and turn rates w sampled over the reachable window."""
        c = self.control
        v_lo = max(0.0, self.v - c.linear_acceleration * SIM_TIME)
        v_hi = min(c.max_linear, self.v + c.linear_acceleration * SIM_TIME)
        w_lo = max(-c.max_angular, self.w - c.angular_acceleration * SIM_TIME)
        w_hi = min(c.max_angular, self.w + c.angular_acceleration * SIM_TIME)
        v, w = _spaced(v_lo, v_hi, V_SAMPLES), _spaced(w_lo, w_hi, W_SAMPLES)
        if w_lo < 0.0 < w_hi:  # straight on is always a sample
            w[min(range(W_SAMPLES), key=lambda k: abs(w[k]))] = 0.0
        return v, w

    def _rollouts(self, v: list, w: list) -> "_Fan":
        """Each (v, w) target driven for SIM_TIME from the current twist, speeds ramping at the
        acceleration limits (Euler steps, as nav2's generator integrates)."""
        h = SIM_TIME / STEPS
        vs, ws = np.array([a for a in v for _ in w]), np.array(w * V_SAMPLES)
        vh = np.minimum(np.maximum(vs[:, None] * h, self.v * h - self._v_ramp), self.v * h + self._v_ramp)
        wh = np.minimum(np.maximum(ws[:, None] * h, self.w * h - self._w_ramp), self.w * h + self._w_ramp)
        yaw = np.cumsum(wh, axis=1)
        heading = yaw - wh  # the heading at the start of each step
        xy = np.empty((2,) + heading.shape)
        np.cos(heading, out=xy[0])
        np.sin(heading, out=xy[1])
        xy *= vh
        return _Fan(vs, ws, np.cumsum(xy, axis=2, out=xy), yaw[:, -1])

    def _obstacle_cost(self, fan: "_Fan", near: np.ndarray):
        """BaseObstacle: (weighted cost of the last pose, admissible) per rollout, from the points
        ``near`` the robot: (3, n) x, y and squared distance from it."""
        count = len(fan.vs)
        if not near.shape[1]:
            return np.zeros(count), np.ones(count, dtype=bool)
        # Each pose's squared distance to its nearest point, |p|^2 + min over q of (|q|^2 - 2 p.q):
        # one product of the points (x, y, |q|^2) with the poses (-2x, -2y, 1), in float32, laid
        # out so that the minimum runs down columns (numpy's fast way).
        nearest = (near.T.astype(np.float32) @ fan.poses).min(axis=0)
        nearest += fan.poses_sq
        nearest = nearest.reshape(fan.shape)
        last = np.sqrt(np.maximum(nearest[:, -1], 0.0))
        start = float(near[2].min())
        if start < self.radius * self.radius:  # already within reach of a point: moving away is allowed
            ok = last >= math.sqrt(start)
        else:
            ok = (nearest >= self.radius * self.radius).all(axis=1)
        # nav2's inflation: 252 exp(-COST_SCALING (d - radius)) within INFLATION, weighted.
        cost = np.exp(last * -COST_SCALING + COST_SCALING * self.radius)
        cost *= 252.0 * WEIGHTS["BaseObstacle"]
        cost[last >= self.radius + INFLATION] = 0.0
        return cost, ok

    def _not_oscillating(self, vs: np.ndarray, ws: np.ndarray, pose) -> np.ndarray:
        """Oscillation: turning on the spot against the last such turn is rejected until reset."""
        if self.spun:
            moved = math.hypot(pose[0] - self.spun_at[0], pose[1] - self.spun_at[1])
            turned = abs(math.remainder(pose[2] - self.spun_at[2], math.tau))
            if moved >= OSCILLATION_RESET or turned >= OSCILLATION_RESET_ANGLE:
                self.spun = 0.0
        if not self.spun:
            return np.ones(len(vs), dtype=bool)
        return ~((vs < SPIN) & (np.sign(ws) == -self.spun))

    def _past(self, path: np.ndarray, points: np.ndarray) -> np.ndarray:
        """The local goal when the path ahead is blocked: its first point clear of every lidar
        point by the robot's radius after the last one that is not (its end if none is)."""
        samples = _resample(path, WAVE_CELL)
        if not len(points):
            return samples[-1]
        clear = _nearest(samples, points) >= self.radius + WAVE_CELL
        hit = np.flatnonzero(~clear)
        after = np.flatnonzero(clear[hit[-1] + 1:]) if len(hit) else np.arange(len(samples))
        return samples[hit[-1] + 1 + after[0]] if len(hit) and len(after) else samples[-1]

    def _step(self, v: float, w: float) -> None:
        c = self.control
        dv, dw = c.linear_acceleration * self.dt, c.angular_acceleration * self.dt
        self.v = min(max(v, self.v - dv), self.v + dv)
        self.w = min(max(w, self.w - dw), self.w + dw)


class _Fan:
    """The rollouts of one window: targets, poses, and what the critics read of them."""

    def __init__(self, vs: np.ndarray, ws: np.ndarray, xy: np.ndarray, yaw: np.ndarray):
        """``xy``: (2, T, STEPS) the poses' x and y; ``yaw``: (T,) the last poses' yaw."""
        self.vs, self.ws, self.shape = vs, ws, xy.shape[1:]
        count = len(vs)
        # Each pose as (-2x, -2y, 1) (3, T * STEPS, float32) and its |p|^2: its distances to
        # points in one matrix product.
        self.poses = np.empty((3, count * STEPS), dtype=np.float32)
        np.multiply(xy.reshape(2, -1), -2.0, out=self.poses[:2], casting="same_kind")
        self.poses[2] = 1.0
        self.poses_sq = np.einsum("ij,ij->j", xy.reshape(2, -1), xy.reshape(2, -1)).astype(np.float32)
        # The last poses (ex, ey) and the points FORWARD_POINT ahead of them (fx, fy): (2, 2T).
        self.ends = np.empty((2, 2 * count))
        self.ends[:, :count] = xy[:, :, -1]
        ahead = self.ends[:, count:]
        np.cos(yaw, out=ahead[0])
        np.sin(yaw, out=ahead[1])
        ahead *= FORWARD_POINT
        ahead += self.ends[:, :count]
        self.ex, self.ey = self.ends[0, :count], self.ends[1, :count]
        self.fx, self.fy = self.ends[0, count:], self.ends[1, count:]


def _cut(path: np.ndarray, length: float) -> tuple[np.ndarray, np.ndarray]:
    """The first ``length`` m of ``path``, and the path within the wavefront grid."""
    return _clip(path, length), _clip(path, WAVE_REACH - WAVE_CELL)


def _clip(path: np.ndarray, length: float) -> np.ndarray:
    """The first ``length`` m of ``path`` (a few points: a plain loop)."""
    points = path.tolist()
    left = length
    for k in range(1, len(points)):
        step = math.dist(points[k - 1], points[k])
        if step >= left:
            f = left / step if step > 0.0 else 0.0
            a, b = points[k - 1], points[k]
            return np.array(points[:k] + [[a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])]])
        left -= step
    return path


def _resample(path: np.ndarray, spacing: float) -> np.ndarray:
    """Points along ``path`` at most ``spacing`` apart, its vertices included."""
    out = [path[:1]]
    for a, b in zip(path[:-1], path[1:]):
        n = max(1, int(math.ceil(math.dist(a, b) / spacing)))
        out.append(a + np.outer(np.arange(1, n + 1) / n, b - a))
    return np.vstack(out)


def _nearest(samples: np.ndarray, points: np.ndarray) -> np.ndarray:
    d2 = (samples * samples).sum(axis=1)[:, None] + (points * points).sum(axis=1)[None, :] - 2.0 * samples @ points.T
    return np.sqrt(np.maximum(d2.min(axis=1), 0.0))


def _spaced(lo: float, hi: float, count: int) -> list:
    """np.linspace(lo, hi, count).tolist(), the same numbers, without numpy."""
    step = (hi - lo) / (count - 1)
    return [k * step + lo for k in range(count - 1)] + [hi]


def _nose(goal: list) -> list:
    """The align critics' target: the goal moved FORWARD_POINT on along the line from the robot
    (a robot that stops on the goal facing it scores zero, as nav2's GoalAlign)."""
    along = math.hypot(goal[0], goal[1])
    if along <= 1e-9:
        return [goal[0] + FORWARD_POINT, goal[1]]
    return [goal[0] * (1.0 + FORWARD_POINT / along), goal[1] * (1.0 + FORWARD_POINT / along)]


def _segment_rows(route: list, nose: list) -> np.ndarray:
    """(5, k, 1) start x, start y, dx, dy and 1/length^2 (0: no length) of the route's segments
    (one point: that point), the segment from its end to ``nose``, and the end and ``nose`` as
    points."""
    pairs = list(zip(route[:-1], route[1:])) or [(route[0], route[0])]
    pairs += [(route[-1], nose), (route[-1], route[-1]), (nose, nose)]
    rows = []
    for (ax, ay), (bx, by) in pairs:
        dx, dy = bx - ax, by - ay
        length2 = dx * dx + dy * dy
        rows.append((ax, ay, dx, dy, 1.0 / length2 if length2 > 1e-12 else 0.0))
    return np.array(rows).T[:, :, None]


def _segment_d2(points: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """(k, n) squared distance of each point (2, n) from each segment of ``_segment_rows``."""
    ax, ay, dx, dy, inverse = rows
    rx, ry = points[0] - ax, points[1] - ay
    t = rx * dx
    t += ry * dy
    t *= inverse
    np.maximum(t, 0.0, out=t)
    np.minimum(t, 1.0, out=t)
    rx -= t * dx
    ry -= t * dy
    rx *= rx
    ry *= ry
    rx += ry
    return rx


_CRITICS = np.array([WEIGHTS["PathDist"], WEIGHTS["PathAlign"], WEIGHTS["GoalDist"], WEIGHTS["GoalAlign"]]) / CELL
