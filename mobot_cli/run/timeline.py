"""The fixed-step timeline: spawn, apply command scripts, step, and yield log samples.

It never writes files; sinks consume what it yields.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass
from typing import Iterator

from mobot_cli.errors import MobotError
from mobot_cli.sim.plan import Event, Plan
from mobot_cli.sim.state import RobotState
from mobot_cli.sim.world import World


@dataclass(frozen=True)
class Sample:
    """The state of every robot after ``step`` physics steps."""

    step: int
    states: dict[str, RobotState]


def simulate(plan: Plan) -> Iterator[Sample]:
    """Run ``plan`` to its end, yielding a Sample every ``log_every`` steps and at the last step."""
    with World(plan.physics, plan.world, seed=plan.seed) as world:
        script = Script(plan)
        for robot in plan.robots:
            world.spawn(robot)
        for step in range(plan.total_steps + 1):
            script.apply(world, step)
            if step % plan.log_every == 0 or step == plan.total_steps:
                yield sample(world, step)
            if step < plan.total_steps:
                world.step()


def sample(world: World, step: int) -> Sample:
    """The state of every robot in the world, in spawn order."""
    return Sample(step, {name: world.read(name) for name in world.names()})


def apply_event(world: World, event: Event) -> None:
    """Spawn or delete one robot: the path scenario events and live requests share."""
    if event.spawn is not None:
        world.spawn(event.spawn)
    else:
        world.remove(event.delete)


class Script:
    """A plan's events and command scripts, indexed by the step they happen at."""

    def __init__(self, plan: Plan):
        self.rate_hz = plan.physics.rate_hz
        self.events: dict[int, list[Event]] = defaultdict(list)
        self.commands: dict[int, list[tuple[str, float, float]]] = defaultdict(list)
        for event in plan.events:
            self.events[event.step].append(event)
        spawned = [event.spawn for event in plan.events if event.spawn is not None]
        for robot in (*plan.robots, *spawned):
            for cmd in robot.commands:
                self.commands[cmd.step].append((robot.name, cmd.linear, cmd.angular))

    def apply(self, world: World, step: int) -> None:
        """Events due at ``step``, then commands: one "at" t is in force in the row logged at t."""
        for event in self.events.get(step, ()):
            try:
                apply_event(world, event)
            except MobotError as exc:
                raise type(exc)(f"event at {step / self.rate_hz:g} s: {exc.message}",
                                location=exc.location, hint=exc.hint) from None
        self.command(world, step)

    def command(self, world: World, step: int, present_only: bool = False) -> None:
        """Send the commands due at ``step`` (a live world skips robots deleted meanwhile)."""
        for name, linear, angular in self.commands.get(step, ()):
            if not present_only or name in world.names():
                world.set_command(name, linear, angular)
