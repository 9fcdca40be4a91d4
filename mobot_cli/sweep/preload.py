"""What a sweep's fork server does once (multiprocessing's preload), so that every worker forked
from it starts warm: it imports the run, both engines and the records a run writes (what a first
run would otherwise import lazily: summary.json's model, the kinematic engine's ray casting, ...),
looks up the versions a summary records, and connects the PyBullet client the workers' runs take
in turn (``CLIENT``: each forked worker has its own copy of it; connecting one costs ~15 ms).
Sweeps with ``--pictures`` preload sweep.preload_pictures, which adds the drawing of
trajectory.png with its fonts and the floor plan under the tracks."""

import mobot_cli.record.movers_csv  # noqa: F401  (made by every run with CSV, whether movers come or not)
import mobot_cli.record.summary  # noqa: F401  (summary.json, written at the end of every run)
import mobot_cli.run  # noqa: F401
import mobot_cli.sim.kinematic.world  # noqa: F401  (either engine may run)
import mobot_cli.sim.sensing.raycast  # noqa: F401  (the kinematic engine's static world)
import mobot_cli.sim.sensing.render  # noqa: F401  (every World asks it about a GPU renderer)
from mobot_cli.record import recording
from mobot_cli.sim.bullet.clients import connect

recording.preload()
CLIENT = connect()[0]
