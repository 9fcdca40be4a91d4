"""What a sweep's fork server imports once (multiprocessing's preload), so that every worker
forked from it starts warm: the run, both engines and the drawing of trajectory.png with its
fonts. Without it, each worker's first run paid ~80 ms for these, on top of its imports."""

import mobot_cli.run.execute  # noqa: F401
import mobot_cli.sim.kinematic  # noqa: F401  (either engine may run)
from mobot_cli.run.trajectory import preload

preload()
