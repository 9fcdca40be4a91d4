"""The floor's edges on a grid: where a wheeled robot would drive off what it stands on.

The map (occupancy.py) holds what rises into the band above the floor, as map_server expects.
A planner must also keep off what falls away below it: the edge of a raised platform or stage,
a stairwell, the end of a building's floor slab in a world without a ground plane. Under each
cell's centre the floor is looked for straight down from the band's bottom (the static world's
triangles and planes, cast with Embree as lidars are: sim/sensing/raycast.py); a cell is an
edge where there is none within ``DEPTH``, or where it lies more than the band's bottom
(``occupancy.BAND[0]``, 0.02 m: the rise the map counts as an obstacle) below a neighbouring
cell's floor: the foot of the drop. A gentle ramp (less than 0.02 m a cell) is no edge.
"""

from __future__ import annotations

import functools

import numpy as np

from mobot_cli.common.raster import Grid
from mobot_cli.plan import WorldPlan

DEPTH = 100.0  # m: no floor within this below a cell is no floor at all


@functools.lru_cache(maxsize=8)  # a run's goals plan on the same world and grid again and again
def edges(world: WorldPlan, grid: Grid, top: float, step: float) -> np.ndarray:
    """The cells of ``grid`` off the floor's edge (see the module's docstring), the floor looked
    for below ``top``; none where the static world cannot be cast at (a body PyBullet alone
    knows, URDF text: its floor is unknown here, so no edge is made up). Cached: read-only."""
    heights = floor_heights(world, grid, top)
    if heights is None:
        out = grid.empty()
    else:
        higher = np.full(heights.shape, -np.inf)  # the highest floor of the four neighbours
        np.maximum(higher[1:, :], heights[:-1, :], out=higher[1:, :])
        np.maximum(higher[:-1, :], heights[1:, :], out=higher[:-1, :])
        np.maximum(higher[:, 1:], heights[:, :-1], out=higher[:, 1:])
        np.maximum(higher[:, :-1], heights[:, 1:], out=higher[:, :-1])
        with np.errstate(invalid="ignore"):  # -inf - -inf between two cells of no floor: not a drop
            out = ~np.isfinite(heights) | (higher - heights > step)
    out.flags.writeable = False
    return out


def floor_heights(world: WorldPlan, grid: Grid, top: float) -> np.ndarray | None:
    """The highest floor below ``top`` under each cell's centre ([iy, ix]; -inf where none
    within DEPTH), or None when the static world cannot be cast at."""
    from mobot_cli.sim.sensing.raycast import embree_available, static_scene

    if not embree_available():
        return None
    scene = static_scene(world)
    if not scene.complete:
        return None
    xs = grid.x0 + (np.arange(grid.nx) + 0.5) * grid.cell
    ys = grid.y0 + (np.arange(grid.ny) + 0.5) * grid.cell
    x, y = np.meshgrid(xs, ys)
    count = x.size
    origins = np.column_stack([x.ravel(), y.ravel(), np.full(count, top)])
    down = np.broadcast_to(np.array([0.0, 0.0, -1.0]), (count, 3))
    along = scene.cast(origins, down, np.full(count, DEPTH, np.float32)).astype(float)
    return (top - along).reshape(grid.ny, grid.nx)
