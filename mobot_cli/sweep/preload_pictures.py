"""A sweep's fork server's preload with ``--pictures``: sweep.preload and the drawing of
trajectory.png, with its fonts and the floor plan under the tracks."""

import mobot_cli.assets.world.floorlevel  # noqa: F401  (trajectory.png's floor plan)
import mobot_cli.sweep.preload  # noqa: F401
from mobot_cli.record import trajectory

trajectory.preload()
