"""The social-force model (Helbing & Molnár 1995, Phys. Rev. E 51, 4282) for walkers, in numpy.

Each walker is pulled toward its goal at its preferred speed (relaxation time ``TAU``) and
pushed away from other walkers, robots and walls by forces that fall off exponentially with the
gap between them; someone behind a walker pushes it with a weight ``BEHIND`` (its field of view).
All walkers are one set of arrays: a step costs a few dozen numpy calls whatever their number.
"""

from __future__ import annotations

import numpy as np

TAU = 0.5  # s: how fast a walker takes up its preferred velocity
A_PEOPLE, B_PEOPLE = 2.1, 0.3  # m/s^2, m: Helbing & Molnar's V0 and sigma
A_ROBOT, B_ROBOT = 6.0, 0.4  # m/s^2, m: people keep further from robots than from each other
A_WALL, B_WALL = 10.0, 0.2  # m/s^2, m: walls push harder and closer
VIEW_COS = np.cos(np.radians(100.0))  # half the field of view (200 degrees, as the paper's)
BEHIND = 0.5  # the weight of what is out of view
MAX_SPEED_FACTOR = 1.3  # a walker never goes faster than this times its preferred speed


def forces(pos: np.ndarray, vel: np.ndarray, goal: np.ndarray, speed: np.ndarray, radius: np.ndarray,
           others: np.ndarray, others_radius: np.ndarray, wall_gap: np.ndarray, wall_dir: np.ndarray,
           robots: int = 0) -> np.ndarray:
    """Acceleration (n, 2) of n walkers at ``pos`` with velocities ``vel``: their goal's pull, the push
    of the other walkers and of ``others`` ((k, 2) with radii: other movers, then ``robots`` robots
    last), and of walls: ``wall_gap`` (n, m) distances along unit directions ``wall_dir`` (m, 2) to
    the nearest wall (+inf: none)."""
    to_goal = goal - pos
    dist = np.hypot(to_goal[:, 0], to_goal[:, 1])
    heading = to_goal / np.maximum(dist, 1e-9)[:, None]
    force = (heading * speed[:, None] - vel) / TAU
    everyone = np.concatenate([pos, others]) if len(others) else pos
    radii = np.concatenate([radius, others_radius]) if len(others) else radius
    diff = pos[:, None, :] - everyone[None, :, :]  # from each other one to the walker
    d = np.hypot(diff[..., 0], diff[..., 1])
    n = len(pos)
    d[np.arange(n), np.arange(n)] = np.inf  # not itself
    unit = diff / np.maximum(d, 1e-9)[..., None]
    a = np.full(len(everyone), A_PEOPLE)
    b = np.full(len(everyone), B_PEOPLE)
    if robots:
        a[-robots:], b[-robots:] = A_ROBOT, B_ROBOT
    push = a[None, :] * np.exp((radius[:, None] + radii[None, :] - d) / b[None, :])
    moving = np.hypot(vel[:, 0], vel[:, 1])
    facing = np.where(moving[:, None] > 1e-6, vel / np.maximum(moving, 1e-9)[:, None], heading)
    # in view when the other one is ahead: the push (from it) points against the walker's heading
    ahead = -np.einsum("nkj,nj->nk", unit, facing) >= VIEW_COS
    push *= np.where(ahead, 1.0, BEHIND)
    force += np.einsum("nk,nkj->nj", push, unit)
    wall = A_WALL * np.exp((radius[:, None] - wall_gap) / B_WALL)  # exp(-inf) = 0 where no wall
    force -= wall @ wall_dir
    return force


def integrate(pos: np.ndarray, vel: np.ndarray, accel: np.ndarray, speed: np.ndarray, dt: float) -> None:
    """One semi-implicit Euler step in place, speeds capped at MAX_SPEED_FACTOR x preferred."""
    vel += accel * dt
    v = np.hypot(vel[:, 0], vel[:, 1])
    cap = MAX_SPEED_FACTOR * speed
    over = v > cap
    if over.any():
        vel[over] *= (cap[over] / v[over])[:, None]
    pos += vel * dt
