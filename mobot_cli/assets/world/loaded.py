"""What loading a world gives: the WorldPlan for the simulation, the world's robot models and
what `mobot check` reports (shared by the warm path, load.py, and the cold one, build.py)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from mobot_cli.plan import WorldPlan


@dataclass(frozen=True)
class WorldRobot:
    """A model of the world with joints: a robot when the scenario lists its name."""

    name: str
    urdf: str  # converted from SDF, mesh paths absolute
    xyz: tuple[float, float, float]
    quat: tuple[float, float, float, float]
    source: str  # the SDF file the model came from
    notices: tuple[str, ...] = ()


@dataclass(frozen=True)
class LoadedWorld:
    """A world ready for the simulation, its robots, what `mobot check` reports, and warnings."""

    plan: WorldPlan
    robots: tuple[WorldRobot, ...] = ()
    static_models: tuple[str, ...] = ()
    summary: dict[str, Any] = field(default_factory=dict)
    notices: tuple[str, ...] = ()

    def robot(self, name: str) -> WorldRobot | None:
        """The world's robot model named ``name``, if there is one."""
        return next((r for r in self.robots if r.name == name), None)
