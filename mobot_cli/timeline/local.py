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
        ramp = np.arange(1, STEPS + 1) * (SIM_TIME / STEPS)
        self._ramp = ramp  # s: the time of each pose
        # The window and its rollouts depend on the current twist alone: kept for the twists seen
        # (a robot cruising or turning at its limits meets the same one tick after tick).
        self._fans: dict[tuple[float, float], _Fan] = {}

    def command(self, obstacles: np.ndarray, path: np.ndarray, pose=(0.0, 0.0, 0.0)) -> Choice:
        """The twist for this tick. ``obstacles``: (n, 2) lidar points in the robot frame;
        ``path``: (m, 2) the path ahead in the robot frame, its last point the local goal;
        ``pose``: the robot's world x, y, yaw (for the oscillation critic's reset only)."""
        fan = self._fan()
        vs, ws, xs, ys = fan.vs, fan.ws, fan.xs, fan.ys
        reach = SIM_TIME * max(self.control.max_linear, abs(self.v)) + self.radius + INFLATION
        d2 = np.einsum("ij,ij->i", obstacles, obstacles)
        near = obstacles[d2 <= reach * reach]
        cost, ok = self._obstacle_cost(fan, near)
        if self.spun:
            ok &= self._not_oscillating(vs, ws, pose)
        path, beyond = _cut(path, LOCAL_PLAN)
        blocked = self._path_blocked(path, near)
        score = WEIGHTS["BaseObstacle"] * cost if len(near) else np.zeros(len(vs))
        fx, fy = fan.fx, fan.fy
        # The align critics aim the robot's nose (the point ahead of it) at the goal moved
        # FORWARD_POINT on along the line from the robot, as nav2's GoalAlign does: a robot that
        # stops on the goal facing it scores zero.
        seen = obstacles[d2 <= WAVE_REACH * WAVE_REACH] if blocked else near
        goal = self._past(beyond, seen) if blocked else path[-1]
        along = math.hypot(goal[0], goal[1])
        nose = goal + FORWARD_POINT * (goal / along if along > 1e-9 else np.array([1.0, 0.0]))
        if blocked:  # a path through an obstacle is no guide: the wavefront leads round it
            field = Wavefront(goal, seen, self.radius)
            score += WEIGHTS["GoalDist"] * field.at(xs[:, -1], ys[:, -1]) / CELL
            score += WEIGHTS["GoalAlign"] * field.at(fx - nose[0] + goal[0], fy - nose[1] + goal[1]) / CELL
        else:
            route = path.tolist()
            # PathDist of the last poses and PathAlign of the points ahead of them in one call; the
            # align critic's path goes on to the nose target: one more segment.
            both = _to_polyline(fan.efx, fan.efy, route)
            count = len(vs)
            align = np.minimum(both[count:], _to_polyline(fx, fy, [route[-1], nose.tolist()]))
            score += (WEIGHTS["PathDist"] / CELL) * both[:count]
            score += (WEIGHTS["PathAlign"] / CELL) * align
            score += WEIGHTS["GoalDist"] * np.hypot(fan.ex - goal[0], fan.ey - goal[1]) / CELL
            score += WEIGHTS["GoalAlign"] * np.hypot(fx - nose[0], fy - nose[1]) / CELL
        if not ok.any():
            self._step(0.0, 0.0)
            return Choice(self.v, self.w, False, blocked)
        score = np.where(ok, score, np.inf)
        best = int(np.argmin(score))
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
            vs, ws = self._window()
            fan = self._fans[key] = _Fan(vs, ws, *self._rollouts(vs, ws))
        return fan

    def _window(self) -> tuple[np.ndarray, np.ndarray]:
        """The target (v, w) pairs: a grid over the reachable window, flattened."""
        c = self.control
        v_lo = max(0.0, self.v - c.linear_acceleration * SIM_TIME)
        v_hi = min(c.max_linear, self.v + c.linear_acceleration * SIM_TIME)
        w_lo = max(-c.max_angular, self.w - c.angular_acceleration * SIM_TIME)
        w_hi = min(c.max_angular, self.w + c.angular_acceleration * SIM_TIME)
        v = _spaced(v_lo, v_hi, _V_INDEX)
        w = _spaced(w_lo, w_hi, _W_INDEX)
        if w_lo < 0.0 < w_hi:  # straight on is always a sample
            w[np.argmin(np.abs(w))] = 0.0
        return np.repeat(v, W_SAMPLES), np.tile(w, V_SAMPLES)

    def _rollouts(self, vs: np.ndarray, ws: np.ndarray):
        """Poses (T, STEPS) of each target driven from the current twist, speeds ramping at the
        acceleration limits (Euler steps, as nav2's generator integrates)."""
        c, t, h = self.control, self._ramp, SIM_TIME / STEPS
        v = _toward(self.v, vs[:, None], c.linear_acceleration * t[None, :])
        w = _toward(self.w, ws[:, None], c.angular_acceleration * t[None, :])
        yaw = np.cumsum(w * h, axis=1)
        heading = yaw - w * h  # the heading at the start of each step
        xs = np.cumsum(v * np.cos(heading) * h, axis=1)
        ys = np.cumsum(v * np.sin(heading) * h, axis=1)
        return xs, ys, yaw

    def _obstacle_cost(self, fan: "_Fan", points: np.ndarray):
        """BaseObstacle: (cost of the last pose, admissible) per rollout."""
        count = len(fan.vs)
        if not len(points):
            return np.zeros(count), np.ones(count, dtype=bool)
        squares = np.einsum("ij,ij->i", points, points)
        start = float(squares.min())
        # Only a point within the farthest pose's reach plus the radius can touch a pose: every
        # pose is checked against those; only the last poses cost, against the points they reach.
        touch = squares <= (fan.reach + self.radius) ** 2
        cost_near = squares <= (fan.reach + self.radius + INFLATION) ** 2
        if not cost_near.any():
            return np.zeros(count), np.ones(count, dtype=bool)
        last = np.sqrt(np.maximum(_min_d2(fan.last32, fan.last_sq, points[cost_near], squares[cost_near]), 0.0))
        if start < self.radius * self.radius:  # already within reach of a point: moving away is allowed
            ok = last >= math.sqrt(start)
        elif touch.any():
            nearest = _min_d2(fan.poses32, fan.poses_sq, points[touch], squares[touch]).reshape(fan.xs.shape)
            ok = (nearest >= self.radius * self.radius).all(axis=1)
        else:
            ok = np.ones(count, dtype=bool)
        cost = np.where(last < self.radius + INFLATION, 252.0 * np.exp(-COST_SCALING * (last - self.radius)), 0.0)
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

    def _path_blocked(self, path: np.ndarray, points: np.ndarray) -> bool:
        """Whether the path ahead runs into a point: passes nearer than the footprint's radius
        less ``PATH_SLACK``. A planned path keeps that radius from the map's obstacles on the
        planner's grid, so a doorway or a gap it threads is not blocked; something new on it is."""
        if not len(points) or len(path) < 2:
            return False
        reach = self.radius - MARGIN - PATH_SLACK
        return bool((_to_polyline(points[:, 0], points[:, 1], path.tolist()) < reach).any())

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

    def __init__(self, vs: np.ndarray, ws: np.ndarray, xs: np.ndarray, ys: np.ndarray, yaws: np.ndarray):
        self.vs, self.ws, self.xs, self.ys = vs, ws, xs, ys
        self.poses32 = np.stack([xs.ravel(), ys.ravel()], axis=1).astype(np.float32)
        self.poses_sq = (self.poses32 * self.poses32).sum(axis=1)
        self.reach = float(np.sqrt(self.poses_sq.max()))  # m: the farthest pose from the robot
        self.fx = xs[:, -1] + FORWARD_POINT * np.cos(yaws[:, -1])
        self.fy = ys[:, -1] + FORWARD_POINT * np.sin(yaws[:, -1])
        self.ex, self.ey = xs[:, -1].copy(), ys[:, -1].copy()
        self.efx, self.efy = np.concatenate([self.ex, self.fx]), np.concatenate([self.ey, self.fy])
        self.last32 = np.stack([self.ex, self.ey], axis=1).astype(np.float32)
        self.last_sq = (self.last32 * self.last32).sum(axis=1)


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


_V_INDEX = np.arange(V_SAMPLES, dtype=float)
_W_INDEX = np.arange(W_SAMPLES, dtype=float)


def _spaced(lo: float, hi: float, index: np.ndarray) -> np.ndarray:
    """np.linspace(lo, hi, len(index)), the same numbers, without its per-call overhead."""
    values = index * ((hi - lo) / (len(index) - 1)) + lo
    values[-1] = hi
    return values


def _min_d2(poses32: np.ndarray, poses_sq: np.ndarray, points: np.ndarray, squares: np.ndarray) -> np.ndarray:
    """Each pose's squared distance (float32) to its nearest point."""
    d2 = poses_sq[:, None] + squares.astype(np.float32)[None, :] - 2.0 * (poses32 @ points.astype(np.float32).T)
    return d2.min(axis=1)


def _toward(current, target, step):
    return np.minimum(np.maximum(target, current - step), current + step)


def _to_polyline(px: np.ndarray, py: np.ndarray, path: list) -> np.ndarray:
    """Distance of each point (px, py) from the polyline ``path`` ([[x, y], ...]; one point:
    from it), vectorised over the points and the segments at once."""
    if len(path) < 2:
        return np.hypot(px - path[0][0], py - path[0][1])
    if len(path) == 2:  # one segment (most ticks): fewer numpy calls than the general form
        (ax, ay), (bx, by) = path
        dx, dy = bx - ax, by - ay
        rx, ry = px - ax, py - ay
        length2 = dx * dx + dy * dy
        if length2 > 1e-12:
            t = np.minimum(np.maximum((rx * dx + ry * dy) / length2, 0.0), 1.0)
            rx, ry = rx - t * dx, ry - t * dy
        return np.sqrt(rx * rx + ry * ry)
    ends = np.asarray(path, dtype=float)
    ax, ay = ends[:-1, 0:1], ends[:-1, 1:2]
    dx, dy = ends[1:, 0:1] - ax, ends[1:, 1:2] - ay
    length2 = dx * dx + dy * dy
    rx, ry = px[None, :] - ax, py[None, :] - ay
    # A segment of no length: t = 0 (its end point), from a zero numerator over 1.
    t = np.minimum(np.maximum((rx * dx + ry * dy) / np.where(length2 > 1e-12, length2, 1.0), 0.0), 1.0)
    rx, ry = rx - t * dx, ry - t * dy
    return np.sqrt((rx * rx + ry * ry).min(axis=0))


def level_points(scan) -> np.ndarray:
    """A lidar scan's returns as world (x, y) points (n, 2): a 3D lidar gives its beam row
    nearest the horizontal (its floor and ceiling returns are not obstacles)."""
    beams = scan.beams
    row = int(np.argmin(np.abs(beams.vertical)))
    ranges = scan.ranges[row].astype(float)
    keep = np.isfinite(ranges)
    count = len(beams.horizontal)
    local = beams.directions[row * count:(row + 1) * count][keep] * ranges[keep, None]
    x, y, z, w = scan.quat
    rotation = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                         [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)]])
    return local @ rotation.T + np.array(scan.position[:2])


def joined(clouds: list) -> np.ndarray:
    """Point clouds (each (n, 2)) as one array."""
    return np.concatenate(clouds) if clouds else np.zeros((0, 2))


def in_frame(points: np.ndarray, x: float, y: float, yaw: float) -> np.ndarray:
    """World (x, y) points (n, 2) in the frame of a robot at (x, y, yaw)."""
    c, s = math.cos(yaw), math.sin(yaw)
    return (points - (x, y)) @ np.array([[c, -s], [s, c]])


def path_in_frame(points: list, x: float, y: float, yaw: float) -> np.ndarray:
    """A few world (x, y) points in the frame of a robot at (x, y, yaw), as an (m, 2) array."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([(c * (px - x) + s * (py - y), -s * (px - x) + c * (py - y)) for px, py in points])
