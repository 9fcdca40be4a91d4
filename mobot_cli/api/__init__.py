"""mobot from Python: ``Simulation`` steps a world on the same timeline as `mobot run`."""

from mobot_cli.api.sensors import Range, Scan
from mobot_cli.api.simulation import Simulation
from mobot_cli.record.summary import RunRecord, Status
from mobot_cli.sim.state import RobotState
from mobot_cli.timeline.records import Reading

__all__ = ["Range", "Reading", "RobotState", "RunRecord", "Scan", "Simulation", "Status"]
