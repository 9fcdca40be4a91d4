"""Random spawn poses and goals in free space: a sweep file's ``random:`` entries written as
``{region: [xmin, xmax, ymin, ymax], clearance: C}`` instead of ``[LOW, HIGH]``.

Each run draws its own, after its other values (the world's seed, a generator's parameters)
are known: the run's world is prepared, its occupancy grid (assets/world/occupancy.py, the map
`mobot map` writes, at 0.05 m) inflated by the clearance, and a free cell of the region chosen
uniformly, then a point in it (a goal: its centre). A pose (a key ending in ``pose``) gets x, y and a yaw from
``yaw`` (default -pi..pi); a goal (a key ending in ``goto``) gets x, y, and must be reachable:
A* (timeline/planner.py) on the same inflated grid from the robot's start, drawn in this run or
the scenario's. Draws come from a NumPy PCG64 stream seeded by the sweep seed and the run's index.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from mobot_cli.errors import Location, UsageError
from mobot_cli.plan import WorldPlan

CELL = 0.05  # m: the grid the draws are checked on
TRIES = 100  # goals drawn before one is reachable, or the run's draw fails
DIGITS = 4  # decimals of drawn values (results.csv, the run's --set)


@dataclass(frozen=True)
class FreeDraw:
    """One ``random:`` entry drawn from free space."""

    key: str  # robots.NAME.pose, or robots.NAME.commands.N.goto
    where: Location
    region: tuple[float, float, float, float]  # xmin, xmax, ymin, ymax
    clearance: float  # m from any obstacle (the robot's radius and a margin)
    yaw: tuple[float, float] = (-math.pi, math.pi)

    @property
    def goal(self) -> bool:
        return self.key.endswith(".goto")

    @property
    def robot(self) -> str:
        return self.key.split(".")[1]

    def columns(self) -> tuple[str, ...]:
        return (f"{self.key}.x", f"{self.key}.y") + (() if self.goal else (f"{self.key}.yaw",))


def parse(key: str, value: Any, where: Location) -> FreeDraw:
    """A ``{region, clearance, yaw}`` mapping for ``key``; a located error when it is not one."""
    parts = key.split(".")
    pose = len(parts) == 3 and parts[0] == "robots" and parts[2] == "pose"
    goal = len(parts) == 5 and parts[0] == "robots" and parts[2] == "commands" and parts[4] == "goto"
    if not (pose or goal):
        raise UsageError(f"'{key}' cannot be drawn from free space: a region draws a robot's pose "
                         "(robots.NAME.pose) or a goal (robots.NAME.commands.N.goto)", location=where,
                         hint="Other keys take [LOW, HIGH].")
    unknown = set(value) - {"region", "clearance", "yaw"}
    if unknown:
        raise UsageError(f"unknown key '{sorted(unknown)[0]}' in a free-space draw", location=where,
                         hint="A free-space draw takes region: [xmin, xmax, ymin, ymax], clearance: m "
                              "and (poses) yaw: [LOW, HIGH].")
    region = _numbers(value.get("region"), 4, "region", where)
    if region is None or not (region[0] < region[1] and region[2] < region[3]):
        raise UsageError("region must be [xmin, xmax, ymin, ymax] with xmin < xmax and ymin < ymax",
                         location=where, hint="e.g. region: [-4, -0.5, 1, 4.5]")
    clearance = value.get("clearance", 0.3)
    if isinstance(clearance, bool) or not isinstance(clearance, (int, float)) or not 0 <= clearance <= 10:
        raise UsageError(f"clearance must be a distance in m from 0 to 10, got {clearance!r}", location=where)
    yaw = _numbers(value.get("yaw", [-math.pi, math.pi]), 2, "yaw", where)
    if goal and "yaw" in value:
        raise UsageError("a goal is drawn as x and y: drop 'yaw'", location=where)
    if yaw is None or not yaw[0] <= yaw[1]:
        raise UsageError("yaw must be [LOW, HIGH] in rad", location=where, hint="e.g. yaw: [-3.14, 3.14]")
    return FreeDraw(key, where, region, float(clearance), yaw)  # type: ignore[arg-type]


def _numbers(value: Any, n: int, name: str, where: Location) -> tuple[float, ...] | None:
    if not isinstance(value, list) or len(value) != n or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and abs(v) <= 1e4
            for v in value):
        raise UsageError(f"{name} must be a list of {n} numbers, got {value!r}", location=where)
    return tuple(float(v) for v in value)


def rng_for(sweep_seed: int, index: int) -> np.random.Generator:
    """The stream of run ``index``'s draws."""
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence([sweep_seed, index, 0x66726565])))


def starts(scenario: Any) -> dict[str, tuple[float, float]]:
    """Each robot's x, y as the scenario gives it (fleets aside: their goals are not drawn)."""
    out = {}
    for robot in scenario.robots:
        pose = robot.pose
        if robot.count is None:
            x = pose.xyz[0] if pose.xyz is not None else pose.x or 0.0
            y = pose.xyz[1] if pose.xyz is not None else pose.y or 0.0
            out[robot.name] = (float(x), float(y))
    return out


def draw(draws: tuple[FreeDraw, ...], world: WorldPlan, starts: dict[str, tuple[float, float]],
         rng: np.random.Generator, note: str) -> list[tuple[str, str]]:
    """The (key, value text) pairs of one run's draws in ``world``: poses, then goals (reached
    from the robots' ``starts``, or the poses drawn here)."""
    from mobot_cli.assets.world import occupancy

    starts = dict(starts)
    floor = occupancy.floor_under(world, [])
    corners = [(d.region[a], d.region[b]) for d in draws for a in (0, 1) for b in (2, 3)]
    grid = _grid(world, [*corners, *starts.values()])
    occ = occupancy.drivable(world, grid, floor)  # never off the floor's edge
    out: list[tuple[str, str]] = []
    for d in sorted(draws, key=lambda d: d.goal):  # poses first: goals are reached from them
        # a pose anywhere in its cell: the inflation reaches half a cell's diagonal further; a goal
        # is a cell's centre, checked as the goal's planner checks it
        blocked = occ.inflated(d.clearance + (0.0 if d.goal else CELL * math.sqrt(0.5)))
        cells = _free_cells(blocked, grid, d.region)
        if not cells.size:
            raise UsageError(f"{d.key}: no free place in region {list(d.region)} at clearance "
                             f"{d.clearance:g} m ({note})", location=d.where,
                             hint="Widen the region or lower the clearance.")
        if d.goal:
            if d.robot not in starts:
                raise UsageError(f"{d.key}: no robot '{d.robot}' in the scenario to reach the goal from",
                                 location=d.where)
            x, y = _reachable(d, blocked, grid, cells, starts[d.robot], rng, note)
            out += [(f"{d.key}.x", _text(x)), (f"{d.key}.y", _text(y))]
        else:
            x, y = _point(grid, cells, rng)
            yaw = d.yaw[0] + (d.yaw[1] - d.yaw[0]) * float(rng.random())
            starts[d.robot] = (x, y)
            out += [(f"{d.key}.x", _text(x)), (f"{d.key}.y", _text(y)), (f"{d.key}.yaw", _text(yaw))]
    order = [c for d in draws for c in d.columns()]
    return sorted(out, key=lambda kv: order.index(kv[0]))


def _grid(world: WorldPlan, points: list[tuple[float, float]]):
    """A grid over the world's bodies and ``points``, its bounds from each shape's reach around
    its body (cheaper than the exact shadows of a world of a thousand cylinders)."""
    from mobot_cli.assets.world import occupancy
    from mobot_cli.common.raster import Grid

    xs, ys = [p[0] for p in points], [p[1] for p in points]
    for body in world.bodies:
        for shape in body.shapes:
            if shape.kind in ("plane", "mesh"):
                floor = occupancy.floor_under(world, [])
                return occupancy.grid_for(world, CELL, (floor + occupancy.BAND[0], floor + occupancy.BAND[1]),
                                          also=points)
            size = shape.size if shape.kind == "box" else (shape.size[0] * 2, shape.size[0] * 2, shape.size[-1])
            reach = math.hypot(*shape.xyz) + math.hypot(*size) / 2
            xs += [body.xyz[0] - reach, body.xyz[0] + reach]
            ys += [body.xyz[1] - reach, body.xyz[1] + reach]
    margin = occupancy.MARGIN
    return Grid.covering(min(xs) - margin, max(xs) + margin, min(ys) - margin, max(ys) + margin, CELL)


def _free_cells(blocked: np.ndarray, grid, region: tuple[float, float, float, float]) -> np.ndarray:
    """(ix, iy) of the free cells whose whole square lies in ``region``."""
    ix = np.arange(grid.nx)
    iy = np.arange(grid.ny)
    x0 = grid.x0 + ix * grid.cell
    y0 = grid.y0 + iy * grid.cell
    in_x = (x0 >= region[0] - 1e-9) & (x0 + grid.cell <= region[1] + 1e-9)
    in_y = (y0 >= region[2] - 1e-9) & (y0 + grid.cell <= region[3] + 1e-9)
    mask = ~blocked & in_y[:, None] & in_x[None, :]
    ys, xs = np.nonzero(mask)
    return np.column_stack([xs, ys])


def _point(grid, cells: np.ndarray, rng: np.random.Generator) -> tuple[float, float]:
    ix, iy = cells[int(rng.integers(len(cells)))]
    u, v = rng.random(2).tolist()
    return grid.x0 + (int(ix) + u) * grid.cell, grid.y0 + (int(iy) + v) * grid.cell


def _reachable(d: FreeDraw, blocked: np.ndarray, grid, cells: np.ndarray, start: tuple[float, float],
               rng: np.random.Generator, note: str) -> tuple[float, float]:
    from mobot_cli.timeline.planner import astar

    here = grid.cell_of(*start)
    if here is None or blocked[here[1], here[0]]:
        raise UsageError(f"{d.key}: the robot's start ({start[0]:.2f}, {start[1]:.2f}) is within the goal's "
                         f"clearance {d.clearance:g} m of an obstacle ({note})", location=d.where,
                         hint="Draw the start with at least the goal's clearance.")
    for _ in range(TRIES):
        ix, iy = cells[int(rng.integers(len(cells)))]
        if astar(blocked, here, (int(ix), int(iy))).cells:
            return grid.centre(int(ix), int(iy))
    raise UsageError(f"{d.key}: none of {TRIES} goals drawn in region {list(d.region)} is reachable from "
                     f"({start[0]:.2f}, {start[1]:.2f}) at clearance {d.clearance:g} m ({note})", location=d.where,
                     hint="Widen the region or lower the clearance.")


def _text(value: float) -> str:
    return json.dumps(round(value, DIGITS) + 0.0)
