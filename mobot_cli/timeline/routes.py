"""Routes of goals with ``planner: astar``: the world's occupancy grid, inflated, searched leg by leg.

The grid is the map `mobot map` writes (assets/world/occupancy.py) at ``CELL``, in the band
above the floor under the robot, covering the world and the goal's points; it is inflated by the
goal's ``inflation`` (the robot's footprint radius unless given), with the floor's edges
(assets/world/dropoffs.py: no floor, or the foot of a drop off a platform) as obstacles too.
Each leg (start to the first point, point to point, and for a patrol the last point back to the
first) is an A* search (planner.py) pruned to its turns. A start inside the inflation but clear
of the obstacle itself (a robot parked near a wall) leaves from the nearest free cell; a point
inside the inflation cannot be reached, and neither can a start inside an obstacle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mobot_cli.plan import GoalStep, WorldPlan
from mobot_cli.timeline.planner import astar, prune

CELL = 0.05  # m


@dataclass(frozen=True)
class Route:
    """The waypoints of a planned goal, or why it is unreachable."""

    lead: tuple[tuple[float, float], ...] = ()  # from the start to the first point (both included)
    lap: tuple[tuple[float, float], ...] = ()  # patrol: first point round to the first point; else to the last
    reason: str = ""
    length: float = 0.0  # m: the planned path's length, lead and one lap
    floor: float = 0.0  # the floor's height the band was measured from


def plan_route(world: WorldPlan | None, start: tuple[float, float, float], goal: GoalStep,
               floor: float | None = None) -> Route:
    """Plan ``goal``'s legs from ``start`` (the robot's x, y and root-link z); ``floor``: the
    floor's height when known already (a robot's next goal), else found under the start."""
    from mobot_cli.assets.world import occupancy

    points = list(goal.points)
    if floor is None:
        floor = occupancy.floor_under(world, [start]) if world is not None else 0.0
    band = (floor + occupancy.BAND[0], floor + occupancy.BAND[1])
    plan_world = world or WorldPlan()
    grid = occupancy.grid_for(plan_world, CELL, band, also=[start[:2], *points])
    occ = occupancy.drivable(plan_world, grid, floor)
    radius = goal.control.inflation
    blocked = occ.inflated(radius)
    here = grid.cell_of(*start[:2])
    if occ.occupied[here[1], here[0]]:
        return Route(reason=f"the start ({start[0]:.2f}, {start[1]:.2f}) is {_inside(occ, here)}")
    if blocked[here[1], here[0]]:
        here = _nearest_free(blocked, occ.occupied, here)
        if here is None:
            return Route(reason=f"the start ({start[0]:.2f}, {start[1]:.2f}) is inside an obstacle at "
                                f"this inflation ({radius:.2f} m) with no free cell around it")
    cells = [grid.cell_of(*p) for p in points]
    for i, (cell, point) in enumerate(zip(cells, points)):
        if occ.edges is not None and occ.edges[cell[1], cell[0]]:
            return Route(reason=f"{_name(goal, i)} ({point[0]:g}, {point[1]:g}) is {_inside(occ, cell)}")
        if blocked[cell[1], cell[0]]:
            return Route(reason=f"{_name(goal, i)} ({point[0]:g}, {point[1]:g}) is inside an obstacle at this "
                                f"inflation ({radius:.2f} m from obstacles)")
    lead, length = _leg(blocked, grid, here, cells[0], start[:2], points[0])
    if isinstance(lead, str):
        return Route(reason=lead.format(what=f"the start ({start[0]:.2f}, {start[1]:.2f})",
                                        to=f"{_name(goal, 0)} ({points[0][0]:g}, {points[0][1]:g})", r=radius))
    lap = [points[0]]
    ends = list(range(1, len(points))) + ([0] if goal.kind == "patrol" else [])
    before = 0
    for i in ends:
        leg, more = _leg(blocked, grid, cells[before], cells[i], points[before], points[i])
        if isinstance(leg, str):
            return Route(reason=leg.format(what=f"{_name(goal, before)} ({points[before][0]:g}, {points[before][1]:g})",
                                           to=f"{_name(goal, i)} ({points[i][0]:g}, {points[i][1]:g})", r=radius))
        lap += leg[1:]
        length += more
        before = i
    return Route(lead=tuple(lead), lap=tuple(lap), length=length, floor=floor)


def _leg(blocked: np.ndarray, grid, a: tuple[int, int], b: tuple[int, int],
         pa: tuple[float, float], pb: tuple[float, float]):
    """The waypoints from ``pa`` to ``pb`` (their own coordinates at the ends, cell centres
    between) and the path's length in m; or a message template when there is no path."""
    found = astar(blocked, a, b)
    if not found.cells:
        return "no path from {what} to {to} at this inflation ({r:.2f} m from obstacles)", 0.0
    turns = prune(blocked, found.cells)
    inner = [grid.centre(*c) for c in turns[1:-1]]
    points = [tuple(map(float, pa)), *inner, tuple(map(float, pb))]
    return points, sum(math.dist(p, q) for p, q in zip(points, points[1:]))


def _nearest_free(blocked: np.ndarray, occupied: np.ndarray, cell: tuple[int, int]) -> tuple[int, int] | None:
    """The free cell nearest ``cell`` reachable through cells clear of the obstacles themselves."""
    from collections import deque

    ny, nx = blocked.shape
    seen = {cell}
    queue = deque([cell])
    while queue:
        ix, iy = queue.popleft()
        if not blocked[iy, ix]:
            return ix, iy
        for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            n = (ix + dx, iy + dy)
            if 0 <= n[0] < nx and 0 <= n[1] < ny and n not in seen and not occupied[n[1], n[0]]:
                seen.add(n)
                queue.append(n)
    return None


def _inside(occ, cell: tuple[int, int]) -> str:
    """What an occupied cell is, for a message."""
    if occ.edges is not None and occ.edges[cell[1], cell[0]]:
        return "off the floor's edge (no floor there, or below a drop of more than " \
               f"{occ.band[0]:g} m from the floor beside it)"
    return "inside an obstacle"


def _name(goal: GoalStep, i: int) -> str:
    return "the goal" if goal.kind == "goto" else f"{goal.kind} point {i}"
