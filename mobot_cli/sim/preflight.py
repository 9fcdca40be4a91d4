"""Checks that need the physics but not a run: a world builds, the robots spawn where asked."""

from __future__ import annotations

from mobot_cli.plan import Physics, Plan, WorldPlan
from mobot_cli.sim.bullet.world import World
from mobot_cli.sim.engine import open_world


def check_world(world: WorldPlan) -> None:
    """Build the world in PyBullet once (every mesh loads), then drop it."""
    with World(Physics(), world):
        pass


def check_spawns(plan: Plan) -> None:
    """Build the plan's world and spawn its robots as a run would; SpawnError when one is refused."""
    with open_world(plan.physics, plan.world, seed=plan.seed) as world:
        for robot in plan.robots:
            world.spawn(robot)
