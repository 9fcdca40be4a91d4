"""The engine a plan asks for: every door builds its World here."""

from __future__ import annotations

from mobot_cli.plan import Physics, Plan, WorldPlan, renders
from mobot_cli.sim.bullet.world import World


def open_world(physics: Physics, world: WorldPlan, seed: int = 0, fresh: bool = False) -> World:
    """A World for ``physics.engine``: "bullet" (sim/bullet/world.py) or "kinematic" (sim/kinematic/world.py);
    ``fresh``: in a PyBullet client of its own, never a kept one (sim/bullet/clients.py)."""
    if physics.engine == "kinematic":
        from mobot_cli.sim.kinematic.world import KinematicWorld  # the physics engine never loads it

        return KinematicWorld(physics, world, seed=seed, fresh=fresh)
    return World(physics, world, seed=seed, fresh=fresh)


def world_for(plan: Plan) -> World:
    """The World a plan runs in (a client of its own when a robot has a camera)."""
    return open_world(plan.physics, plan.world, seed=plan.seed, fresh=renders(plan))
