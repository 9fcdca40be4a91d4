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
    the nearest wall (+inf: none). Points in the plane are complex numbers inside: every pair's
    vector, distance and direction is one numpy call each."""
    z = pos[:, 0] + 1j * pos[:, 1]
    v = vel[:, 0] + 1j * vel[:, 1]
    to_goal = (goal[:, 0] + 1j * goal[:, 1]) - z
    heading = to_goal / np.maximum(np.abs(to_goal), 1e-9)
    force = (heading * speed - v) / TAU
    everyone = np.concatenate([z, others[:, 0] + 1j * others[:, 1]]) if len(others) else z
    radii = np.concatenate([radius, others_radius]) if len(others) else radius
    diff = z[:, None] - everyone  # (n, n + k): from each other one to the walker
    d = np.abs(diff)
    d.flat[:: len(everyone) + 1] = np.inf  # not itself (the first n columns are the walkers)
    a = np.full(len(everyone), A_PEOPLE)
    b = np.full(len(everyone), B_PEOPLE)
    if robots:
        a[-robots:], b[-robots:] = A_ROBOT, B_ROBOT
    push = a * np.exp((radius[:, None] + radii - d) / b) / d  # over d: times diff is the unit vector
    speed_now = np.abs(v)
    facing = np.where(speed_now > 1e-6, v / np.maximum(speed_now, 1e-9), heading)
    # in view when the other one is ahead: the push (from it) points against the walker's heading
    behind = (diff * np.conj(facing)[:, None]).real > -VIEW_COS * d
    push *= np.where(behind, BEHIND, 1.0)  # the same numbers as a masked multiply, in a third of the time
    force += (push * diff).sum(axis=1)
    wall = A_WALL * np.exp((radius[:, None] - wall_gap) / B_WALL)  # exp(-inf) = 0 where no wall
    force -= wall @ (wall_dir[:, 0] + 1j * wall_dir[:, 1])
    return force.view(float).reshape(-1, 2)  # (real, imaginary) pairs: x, y


def integrate(pos: np.ndarray, vel: np.ndarray, accel: np.ndarray, speed: np.ndarray, dt: float) -> None:
    """One semi-implicit Euler step in place, speeds capped at MAX_SPEED_FACTOR x preferred."""
    vel += accel * dt
    v = np.hypot(vel[:, 0], vel[:, 1])
    cap = MAX_SPEED_FACTOR * speed
    over = v > cap
    if over.any():
        vel[over] *= (cap[over] / v[over])[:, None]
    pos += vel * dt
