"""mobot from Python: ``Simulation`` steps a world on the same timeline as `mobot run`."""

from mobot_cli.api.sensors import Scan
from mobot_cli.api.simulation import Simulation
from mobot_cli.run.timeline import Reading
from mobot_cli.run.record import RunRecord, Status
from mobot_cli.sim.state import RobotState

__all__ = ["Reading", "RobotState", "RunRecord", "Scan", "Simulation", "Status"]
