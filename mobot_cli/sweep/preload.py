"""What a sweep's fork server imports once (multiprocessing's preload), so that every worker
forked from it starts warm: the run, both engines, the drawing of trajectory.png with its
fonts, the floor under the robots, the versions a summary records. Without it, each worker's
first run paid ~80 ms for these, on top of its imports."""

import mobot_cli.assets.world.floorlevel  # noqa: F401  (trajectory.png's floor plan)
import mobot_cli.run.execute  # noqa: F401
import mobot_cli.run.trajectory  # noqa: F401  (every run's picture sink)
import mobot_cli.sim.kinematic  # noqa: F401  (either engine may run)
from mobot_cli.common import classcode
from mobot_cli.run import picture, recording

picture.preload()
recording.preload()
classcode.save()  # the classes made here, for the next sweep's server (it ends without exit handlers)
