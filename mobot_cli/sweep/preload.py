"""What a sweep's fork server imports once (multiprocessing's preload), so that every worker
forked from it starts warm: the run, both engines, the drawing of trajectory.png with its
fonts, the floor under the robots, the versions a summary records. Without it, each worker's
first run would load all of these again, on top of its imports."""

import mobot_cli.assets.world.floorlevel  # noqa: F401  (trajectory.png's floor plan)
import mobot_cli.run  # noqa: F401
import mobot_cli.sim.kinematic.world  # noqa: F401  (either engine may run)
from mobot_cli.record import recording, trajectory

trajectory.preload()
recording.preload()
