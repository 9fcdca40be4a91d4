"""Coverage: the part of an area's free space that a robot's footprint has swept.

The area is cut into ``CELL`` squares; free cells are those inside the area and outside every
obstacle's shadow (the floor plan of trajectory.png). The footprint (the robot's collision
extent in its own frame, a rectangle) is laid down along the true path: between two poses it
sweeps their convex hull, taken whenever the robot has moved half a cell or turned
``TURN_STEP`` since the last one, so a turn on the spot sweeps its disc. The covered fraction
is swept free cells over free cells, each cell judged at its centre.
"""

from __future__ import annotations

import math

import numpy as np

from mobot_cli.assets.world.floorplan import convex_hull
from mobot_cli.assets.world.freespace import obstacle_mask
from mobot_cli.common.polygon import DEFAULT_FOOTPRINT
from mobot_cli.common.raster import Grid, fill_polygon
from mobot_cli.plan import WorldPlan

CELL = 0.02  # m, or coarser for large areas:
MAX_CELLS = 1000  # cells along the area's longer side at most
TURN_STEP = 0.05  # rad


class Sweep:
    """One robot's footprint swept over one area."""

    def __init__(self, area: tuple[tuple[float, float], ...], world: WorldPlan | None, footprint=None):
        xs, ys = [p[0] for p in area], [p[1] for p in area]
        self.area = area
        cell = max(CELL, max(max(xs) - min(xs), max(ys) - min(ys)) / MAX_CELLS)
        self.grid = Grid.covering(min(xs), max(xs), min(ys), max(ys), cell)
        inside = self.grid.empty()
        fill_polygon(inside, self.grid, area)
        self.free = inside & ~obstacle_mask(world, self.grid) if world is not None else inside
        self.free_cells = int(self.free.sum())
        self.swept = self.grid.empty()
        fx0, fx1, fy0, fy1 = footprint or DEFAULT_FOOTPRINT
        self.corners = ((fx0, fy0), (fx1, fy0), (fx1, fy1), (fx0, fy1))
        self.last: tuple[float, float, float] | None = None

    def add(self, x: float, y: float, yaw: float) -> None:
        """The robot is at (x, y, yaw): sweep from its last pose, once it has moved enough."""
        last = self.last
        if last is not None and math.hypot(x - last[0], y - last[1]) < self.grid.cell / 2 and \
                abs(math.remainder(yaw - last[2], math.tau)) < TURN_STEP:
            return
        points = self._footprint(x, y, yaw) + (self._footprint(*last) if last is not None else [])
        fill_polygon(self.swept, self.grid, convex_hull(points))
        self.last = (x, y, yaw)

    def _footprint(self, x: float, y: float, yaw: float) -> list[tuple[float, float]]:
        c, s = math.cos(yaw), math.sin(yaw)
        return [(x + c * px - s * py, y + s * px + c * py) for px, py in self.corners]

    @property
    def covered(self) -> np.ndarray:
        """The free cells swept so far."""
        return self.swept & self.free

    @property
    def fraction(self) -> float:
        """Swept free cells over free cells (0 when the area has no free space)."""
        return float((self.swept & self.free).sum()) / self.free_cells if self.free_cells else 0.0

    @property
    def free_area(self) -> float:
        """m^2 of free space in the area."""
        return self.free_cells * self.grid.cell ** 2
