"""Checks that need the physics but not a run: a world builds, the robots spawn where asked."""

from __future__ import annotations

from mobot_cli.errors import Location, SpawnError
from mobot_cli.plan import Physics, Plan, RobotPlan, SpawnPose, WorldPlan
from mobot_cli.sim.bullet.world import World
from mobot_cli.sim.engine import world_for


def check_world(world: WorldPlan) -> None:
    """Build the world in PyBullet once (every mesh loads), then drop it."""
    with World(Physics(), world):
        pass


def check_spawns(plan: Plan) -> None:
    """Build the plan's world and spawn its robots as a run would; SpawnError when one is refused."""
    with world_for(plan) as world:
        for robot in plan.robots:
            world.spawn(robot)


def check_robot(name: str, urdf: str, root_link: str, source: str) -> None:
    """Load a robot's URDF text into PyBullet on an empty floor, as a run spawns it; SpawnError
    (or a DescriptionError) when a run would fail to."""
    robot = RobotPlan(name=name, namespace=f"/{name}", frame_prefix=f"{name}/", urdf=urdf,
                      root_link=root_link, pose=SpawnPose(z_auto=True), drive=None, source=source)
    with World(Physics(), WorldPlan()) as world:
        try:
            world.spawn(robot)
        except SpawnError as exc:
            if not exc.message.startswith("PyBullet could not load"):
                raise
            raise SpawnError(exc.message, location=Location(file=source),
                             hint="`mobot run` would fail the same way: PyBullet's URDF importer refuses the "
                                  "text mobot made of the description (`mobot xacro` prints a xacro "
                                  "file's).") from None
