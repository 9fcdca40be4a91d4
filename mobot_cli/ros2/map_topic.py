"""``/map`` on ROS 2 (``ros2: {map: true}``): the world's occupancy grid, once, as map_server does.

The grid `mobot map WORLD` writes with its defaults (0.05 m cells, obstacles 0.02 to 2 m above
the floor, the world's extent and half a metre around it), as a nav_msgs/OccupancyGrid in the
``world`` frame (the frame ground truth and every robot's odom hang from), reliable and transient
local with a depth of 1 (a late subscriber, rviz or nav2's costmap, still gets it).
"""

from __future__ import annotations

from mobot_cli.plan import WorldPlan
from mobot_cli.ros.definitions import OCCUPANCY_GRID
from mobot_cli.ros.map_files import grid_cells, occupancy_grid_cdr

TOPIC = "/map"
FRAME = "world"
CELL = 0.05  # m, as `mobot map`'s default


def map_message(world: WorldPlan) -> bytes:
    """The world's grid as OccupancyGrid CDR, stamped at simulated time 0."""
    from mobot_cli.assets.world import occupancy

    floor = occupancy.floor_under(world, [])
    grid = occupancy.grid_for(world, CELL, (floor + occupancy.BAND[0], floor + occupancy.BAND[1]))
    occ = occupancy.occupancy(world, grid, floor)
    return occupancy_grid_cdr(grid_cells(occ.occupied), CELL, (grid.x0, grid.y0, 0.0), (0, 0), FRAME)


def publish_map(topics, world: WorldPlan) -> None:
    """Latch the map on ``/map`` (``topics``: ros2/publisher.py's Topics)."""
    from mobot_cli.ros2 import dds

    topics.publish(TOPIC, OCCUPANCY_GRID, map_message(world), dds.LATCHED)
