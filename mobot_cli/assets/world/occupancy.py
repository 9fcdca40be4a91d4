"""A world's occupancy grid: the floor plan (floorplan.py) rasterised, as a map for planners.

A cell is occupied when static collision geometry reaching into the height band above the
floor covers its centre (common/raster.py: polygons by their inside, walls seen edge-on by
every cell they cross) — the same shadows trajectory.png draws. Everything else in the grid is
free: a world file knows its whole inside, so nothing is unknown. Inflation grows the occupied
cells by a radius (cells whose centres lie within it of an occupied cell's centre), as a
costmap's lethal inflation does for a round robot of that radius.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from mobot_cli.assets.world.floorplan import BAND, MeshShadow, body_shadows, body_shapes
from mobot_cli.assets.world.freespace import obstacle_mask, probed_floor
from mobot_cli.common.raster import Grid, dilate
from mobot_cli.plan import WorldPlan

MARGIN = 0.5  # m of free cells around the world's geometry when no extent is given
MAX_CELLS = 25_000_000  # a 5,000 x 5,000 grid: 250 m square at 0.05 m


@dataclass(frozen=True)
class Occupancy:
    """``occupied[iy, ix]`` over ``grid`` (row 0 at the lowest y); ``floor`` is the height the band
    was measured from and ``band`` the band itself (m above the floor)."""

    grid: Grid
    occupied: np.ndarray
    floor: float = 0.0
    band: tuple[float, float] = BAND
    edges: np.ndarray | None = None  # ``drivable``: the floor's edges among the occupied cells

    def inflated(self, radius: float) -> np.ndarray:
        """The occupied cells grown by ``radius`` (m)."""
        # 1e-9: 0.3 / 0.1 is 2.9999999999999996 in floats, and a radius of 3 cells must reach 3 cells
        return inflate(self.occupied, radius / self.grid.cell + 1e-9) if radius > 0 else self.occupied.copy()


def floor_under(world: WorldPlan, starts: list[tuple[float, float, float]]) -> float:
    """The floor the band is measured from: under ``starts`` (robots' root links), or under the
    origin at z = 0 without them (a floor at or a little above z = 0, or a ground's top up to
    floorlevel.RAISED above it when the floor below lies far down, or z = 0 itself)."""
    from mobot_cli.assets.world.floorlevel import floor_level

    if starts:
        return floor_level(world, list(starts), body_shapes)
    return probed_floor(world)


def world_bounds(world: WorldPlan, band: tuple[float, float]) -> tuple[float, float, float, float] | None:
    """xmin, xmax, ymin, ymax of the static geometry in ``band`` (absolute heights), or None."""
    xs: list[float] = []
    ys: list[float] = []
    for _, parts in body_shadows(world, band):
        for part in parts:
            if not isinstance(part, MeshShadow):
                xs.extend(p[0] for p in part)
                ys.extend(p[1] for p in part)
                continue
            extent = part.extent()
            if extent is not None:
                xs += extent[:2]
                ys += extent[2:]
    if not xs:
        return None
    return min(xs), max(xs), min(ys), max(ys)


def grid_for(world: WorldPlan, resolution: float, band: tuple[float, float],
             origin: tuple[float, float] | None = None, size: tuple[float, float] | None = None,
             also: list[tuple[float, float]] = ()) -> Grid:
    """The grid a map covers: from ``origin`` (its lower-left corner) over ``size`` (m) when
    given, else the world's geometry in the band (and the points ``also``) with MARGIN around
    it; with nothing in the band, all of its geometry (a bare floor's extent)."""
    bounds = world_bounds(world, band) or world_bounds(world, (-math.inf, math.inf))
    xs = [p[0] for p in also] + (list(bounds[:2]) if bounds else [])
    ys = [p[1] for p in also] + (list(bounds[2:]) if bounds else [])
    if not xs:
        xs, ys = [-1.0, 1.0], [-1.0, 1.0]
    if origin is None:
        left, low = min(xs) - MARGIN, min(ys) - MARGIN
        if size is None:
            return _checked(Grid.covering(left, max(xs) + MARGIN, low, max(ys) + MARGIN, resolution))
        origin = ((min(xs) + max(xs) - size[0]) / 2, (min(ys) + max(ys) - size[1]) / 2)  # centred
    if size is None:
        size = (max(xs) + MARGIN - origin[0], max(ys) + MARGIN - origin[1])
        if size[0] <= 0 or size[1] <= 0:
            raise ValueError(f"origin ({origin[0]:g}, {origin[1]:g}) lies beyond the world's far corner: "
                             "give --size too")
    nx, ny = math.ceil(size[0] / resolution - 1e-9), math.ceil(size[1] / resolution - 1e-9)
    return _checked(Grid(float(origin[0]), float(origin[1]), resolution, max(1, nx), max(1, ny)))


def _checked(grid: Grid) -> Grid:
    if grid.nx * grid.ny > MAX_CELLS:
        raise ValueError(f"the map would have {grid.nx} x {grid.ny} cells, more than {MAX_CELLS:,}: "
                         "give a coarser --resolution or a smaller --size")
    return grid


def occupancy(world: WorldPlan, grid: Grid, floor: float = 0.0, band: tuple[float, float] = BAND) -> Occupancy:
    """The cells of ``grid`` that static geometry between ``floor + band`` covers."""
    return Occupancy(grid, _mask(world, grid, (floor + band[0], floor + band[1])).copy(), floor, band)


def drivable(world: WorldPlan, grid: Grid, floor: float = 0.0, band: tuple[float, float] = BAND) -> Occupancy:
    """``occupancy`` with the floor's edges occupied too (dropoffs.py: no floor there, or the foot
    of a drop): what a planner or a spawn must keep off, beyond what the map shows."""
    from mobot_cli.assets.world.dropoffs import edges

    occ = occupancy(world, grid, floor, band)
    off = edges(world, grid, floor + band[0], band[0])
    return Occupancy(grid, occ.occupied | off, floor, band, off)


@functools.lru_cache(maxsize=8)  # a run's goals plan on the same world, band and grid again and again
def _mask(world: WorldPlan, grid: Grid, band: tuple[float, float]) -> np.ndarray:
    mask = obstacle_mask(world, grid, band)
    mask.flags.writeable = False
    return mask


def inflate(mask: np.ndarray, cells: float) -> np.ndarray:
    """``mask`` grown by a disc of ``cells`` cells (centre to centre)."""
    return dilate(mask, cells)
