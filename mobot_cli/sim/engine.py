"""The engine a plan asks for: every door builds its World here."""

from __future__ import annotations

from mobot_cli.plan import Physics, WorldPlan
from mobot_cli.sim.bullet.world import World


def open_world(physics: Physics, world: WorldPlan, seed: int = 0) -> World:
    """A World for ``physics.engine``: "bullet" (sim/bullet/world.py) or "kinematic" (sim/kinematic/world.py)."""
    if physics.engine == "kinematic":
        from mobot_cli.sim.kinematic.world import KinematicWorld  # the physics engine never loads it

        return KinematicWorld(physics, world, seed=seed)
    return World(physics, world, seed=seed)
