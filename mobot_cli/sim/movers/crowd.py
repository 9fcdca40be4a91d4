"""Every mover of a world in arrays: scripted ones posed by time, walkers by the social force.

Movers are updated every ``every`` physics steps (``MOVER_RATE_HZ``), at whole steps: their
poses between two updates are those of the last one, and every record, scan and collision
check sees those. Walkers draw their goals from one generator seeded by the run's seed and
their names: the same seed gives the same walks.
"""

from __future__ import annotations

import hashlib
import math
from typing import Callable

import numpy as np

from mobot_cli.plan import MoverPlan
from mobot_cli.sim.movers import social
from mobot_cli.sim.movers.script import Script
from mobot_cli.sim.movers.shapes import BOX, KINDS, Snapshot

# Updates a second, as gazebo classic animates actors (at most 20 Hz, Actor.cc): 12 steps at
# 240 Hz, so 10 Hz scans are taken where the movers were just put.
MOVER_RATE_HZ = 20
# Walkers move at every update but the social force is worked out at every FORCE_EVERY-th (10 Hz;
# PySocialForce steps at 2.5 Hz): it changes slowly, and it is most of what fifty walkers cost.
FORCE_EVERY = 2
GOAL_REACHED = 0.3  # m: a walker this close to its goal draws the next
PATIENCE = 5.0  # s more than the straight walk takes: a walker that cannot get there draws another goal
WALL_RAYS = 8  # directions a walker looks for walls in
WALL_REACH = 1.5  # m
WALL_HEIGHT = 0.3  # m above a walker's bottom: walls, and the furniture a person walks around


def walker_rng(seed: int, name: str) -> np.random.Generator:
    """A walker's own generator: the run's seed and its name, nothing else."""
    digest = hashlib.sha256(f"mover/{name}".encode()).digest()
    return np.random.default_rng([seed & 0xFFFFFFFFFFFFFFFF, int.from_bytes(digest[:8], "little")])


class Crowd:
    """The movers of one world; ``update`` moves them to a step."""

    def __init__(self, rate_hz: int, seed: int, walls: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]):
        self.rate_hz, self.seed, self.walls = rate_hz, seed, walls
        self.every = max(1, round(rate_hz / MOVER_RATE_HZ))
        self.plans: list[MoverPlan] = []
        self.born: list[int] = []  # the step each entered the world
        self.scripts: list[Script | None] = []
        self.rngs: list[np.random.Generator | None] = []
        self.goal = np.zeros((0, 2))
        self.deadline = np.zeros(0)  # s: when a walker gives up its goal
        self.pos = np.zeros((0, 2))
        self.vel = np.zeros((0, 2))
        self.yaw = np.zeros(0)
        self.updates = 0  # how many times they were moved: log rows record them when it changed
        angles = np.arange(WALL_RAYS) * (2.0 * math.pi / WALL_RAYS)
        self.wall_dir = np.column_stack([np.cos(angles), np.sin(angles)])
        self._shape_arrays()

    def __len__(self) -> int:
        return len(self.plans)

    def names(self) -> list[str]:
        return list(self._names)

    def add(self, plan: MoverPlan, step: int) -> None:
        """A mover enters the world at ``step``, where its script or region puts it."""
        self.plans.append(plan)
        self.born.append(step)
        script = Script(plan) if plan.keyframes else None
        self.scripts.append(script)
        rng = walker_rng(self.seed, plan.name) if plan.region is not None else None
        self.rngs.append(rng)
        if script is not None:
            x, y, yaw = script.pose(0.0)
        else:
            x, y = plan.start if plan.start is not None else self._random_point(plan, rng)
            yaw = 0.0
        self.pos = np.vstack([self.pos, [x, y]])
        self.vel = np.vstack([self.vel, [0.0, 0.0]])
        self.yaw = np.append(self.yaw, yaw)
        self.goal = np.vstack([self.goal, [x, y]])
        self.deadline = np.append(self.deadline, -1.0)  # a walker draws its first goal at its first update
        self.updates += 1
        self._people_xy = None
        self._shape_arrays()

    def remove(self, name: str) -> None:
        i = self.names().index(name)
        for items in (self.plans, self.born, self.scripts, self.rngs):
            del items[i]
        self.pos, self.vel = np.delete(self.pos, i, axis=0), np.delete(self.vel, i, axis=0)
        self.goal, self.yaw, self.deadline = np.delete(self.goal, i, axis=0), np.delete(self.yaw, i), \
            np.delete(self.deadline, i)
        self.updates += 1
        self._people_xy = None
        self._shape_arrays()

    def _shape_arrays(self) -> None:
        plans = self.plans
        self._names = [p.name for p in plans]
        self.kind = np.array([KINDS[p.shape] for p in plans], dtype=int)
        box = self.kind == BOX
        self.hx = np.array([p.size[0] / 2.0 if p.shape == "box" else 0.0 for p in plans])
        self.hy = np.array([p.size[1] / 2.0 if p.shape == "box" else 0.0 for p in plans])
        self.radius = np.array([p.size[0] for p in plans]) if plans else np.zeros(0)
        self.radius[box] = np.hypot(self.hx[box], self.hy[box])
        self.z0 = np.array([p.z for p in plans])
        self.z1 = np.array([p.z + (p.size[2] if p.shape == "box" else p.size[1]) for p in plans])
        self.middle = ((self.z0 + self.z1) / 2.0).tolist()  # each one's centre height
        self.walkers = np.array([p.region is not None for p in plans], dtype=bool)
        self.people = self.kind == KINDS["person"]
        self.accel = np.zeros((len(plans), 2))  # the walkers' social force, as last worked out
        self._forced = False  # accel holds the walkers' force (a new walker: not yet)
        # the walkers: a slice when every mover is one (numpy then hands out views, not copies)
        self._w = slice(None) if self.walkers.all() else np.flatnonzero(self.walkers)
        self._count = int(self.walkers.sum())
        self._rays = np.tile(np.column_stack([self.wall_dir, np.zeros(WALL_RAYS)]), (self._count, 1))
        self._reach = np.full(len(self._rays), WALL_REACH)
        self._origins = np.empty((self._count, WALL_RAYS, 3))  # where the wall rays start, filled each time
        self._scripted = [(i, script) for i, script in enumerate(self.scripts) if script is not None]
        self._index = np.arange(len(plans))[self._w]  # the walkers' places among the movers
        self._fixed = np.flatnonzero(~self.walkers)  # the other movers'
        self._people_xy = None  # the people's places as complex numbers, made when first asked after a move
        self.speed = np.array([p.speed for p in plans])

    def _random_point(self, plan: MoverPlan, rng: np.random.Generator) -> tuple[float, float]:
        x0, x1, y0, y1 = plan.region
        return float(rng.uniform(x0, x1)), float(rng.uniform(y0, y1))

    def update(self, step: int, robots: np.ndarray, robot_radius: np.ndarray) -> None:
        """Move every mover to ``step``; ``robots`` (k, 2) the robots' positions, their radii."""
        dt = 1.0 / self.rate_hz
        self.updates += 1
        self._people_xy = None
        for i, script in self._scripted:
            x, y, yaw = script.pose((step - self.born[i]) * dt)
            self.pos[i] = (x, y)
            self.yaw[i] = yaw
        if self._count:
            self._walk(step * dt, robots, robot_radius)

    def _walk(self, now: float, robots: np.ndarray, robot_radius: np.ndarray) -> None:
        # Runs 20 times a simulated second: each line is a numpy call or two on all walkers.
        w, index = self._w, self._index
        pos, vel = self.pos[w], self.vel[w]
        to_goal = pos - self.goal[w]
        due = (now >= self.deadline[w]) | (np.einsum("ij,ij->i", to_goal, to_goal) < GOAL_REACHED ** 2)
        for j in due.nonzero()[0].tolist():
            i = int(index[j])
            self.goal[i] = self._random_point(self.plans[i], self.rngs[i])
            self.deadline[i] = now + math.dist(pos[j], self.goal[i]) / self.speed[i] + PATIENCE
        if self.updates % FORCE_EVERY == 0 or not self._forced:
            self.accel[w] = self._force(w, pos, vel, robots, robot_radius)
            self._forced = True
        social.integrate(pos, vel, self.accel[w], self.speed[w], self.every / self.rate_hz)
        self.pos[w], self.vel[w] = pos, vel
        moving = np.einsum("ij,ij->i", vel, vel) > 0.05 ** 2
        self.yaw[index[moving]] = np.arctan2(vel[moving, 1], vel[moving, 0])

    def _force(self, w: np.ndarray, pos: np.ndarray, vel: np.ndarray, robots: np.ndarray,
               robot_radius: np.ndarray) -> np.ndarray:
        """The social force on walkers ``w`` now (sim/movers/social.py)."""
        radius = self.radius[w]
        # Walls: WALL_RAYS short rays from each walker, at its WALL_HEIGHT.
        origins = self._origins
        origins[:, :, :2] = pos[:, None, :]
        origins[:, :, 2] = (self.z0[w] + WALL_HEIGHT)[:, None]
        gaps = self.walls(origins.reshape(-1, 3), self._rays, self._reach).reshape(self._count, WALL_RAYS)
        # the other movers push as walkers do; robots as others
        fixed = self._fixed
        others = np.concatenate([self.pos[fixed], robots]) if len(robots) else self.pos[fixed]
        others_r = np.concatenate([self.radius[fixed], robot_radius]) if len(robots) else self.radius[fixed]
        return social.forces(pos, vel, self.goal[w], self.speed[w], radius, others, others_r, gaps, self.wall_dir,
                             robots=len(robots))

    def snapshot(self) -> Snapshot:
        """The movers' shapes where they are now (copies: later updates leave it as it is)."""
        return Snapshot(self.kind, self.pos[:, 0].copy(), self.pos[:, 1].copy(), self.yaw.copy(), self.radius,
                        self.hx, self.hy, self.z0, self.z1)

    def poses(self) -> dict[str, tuple[float, float, float]]:
        """Each mover's x, y, yaw now, by name."""
        return dict(zip(self._names, zip(self.pos[:, 0].tolist(), self.pos[:, 1].tolist(), self.yaw.tolist())))

    def people_distance(self, x: float, y: float) -> float:
        """The smallest distance in the plane from (x, y) to a person's axis (+inf: no person)."""
        if self._people_xy is None:
            people = self.pos[self.people]
            self._people_xy = people[:, 0] + 1j * people[:, 1]
        if not len(self._people_xy):
            return math.inf
        return float(np.abs(self._people_xy - complex(x, y)).min())
