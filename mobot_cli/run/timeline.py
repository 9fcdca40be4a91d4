"""The fixed-step timeline: spawn, apply command scripts, step, and yield log samples.

It never writes files; sinks consume what it yields.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass
from typing import Iterator

from mobot_cli.sim.plan import Plan
from mobot_cli.sim.state import RobotState
from mobot_cli.sim.world import World


@dataclass(frozen=True)
class Sample:
    """The state of every robot after ``step`` physics steps."""

    step: int
    states: dict[str, RobotState]


def simulate(plan: Plan) -> Iterator[Sample]:
    """Run ``plan`` to its end, yielding a Sample every ``log_every`` steps and at the last step."""
    schedule: dict[int, list[tuple[str, float, float]]] = defaultdict(list)
    for robot in plan.robots:
        for cmd in robot.commands:
            schedule[cmd.step].append((robot.name, cmd.linear, cmd.angular))
    with World(plan.physics, plan.world, seed=plan.seed) as world:
        for robot in plan.robots:
            world.spawn(robot)
        names = [robot.name for robot in plan.robots]
        for step in range(plan.total_steps + 1):
            # A command "at" t is in force from t on, so the row logged at t already shows it.
            for name, linear, angular in schedule.get(step, ()):
                world.set_command(name, linear, angular)
            if step % plan.log_every == 0 or step == plan.total_steps:
                yield Sample(step, {name: world.read(name) for name in names})
            if step < plan.total_steps:
                world.step()
