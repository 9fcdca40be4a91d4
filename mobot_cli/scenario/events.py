"""A scenario's `events:` to Plan events: spawns and deletes at whole steps, in time order.

Spawned robots go through the same RobotResolver as the scenario's robots (and live spawns).
Robot names stay unique over the whole scenario, deleted robots included, so every robot has
one odometry file. Commands a robot would get after its deletion are dropped.
"""

from __future__ import annotations

import dataclasses
from typing import Sequence

from mobot_cli.errors import ScenarioError, did_you_mean, shown
from mobot_cli.plan import Event, RobotPlan
from mobot_cli.scenario.model import EventSpec
from mobot_cli.scenario.robots import RobotResolver
from mobot_cli.scenario.units import steps


def resolve_events(specs: Sequence[EventSpec], robots: tuple[RobotPlan, ...],
                   ctx: RobotResolver) -> tuple[tuple[RobotPlan, ...], tuple[Event, ...]]:
    """Plan events sorted by step (ties keep file order); robots with commands past deletion cut."""
    rate = ctx.rate_hz
    order = sorted(range(len(specs)), key=lambda i: steps(specs[i].at, rate))
    alive = {robot.name for robot in robots}
    deleted: dict[str, int] = {}
    events: list[Event] = []
    for i in order:
        spec, path = specs[i], ("events", i)
        step = steps(spec.at, rate)
        if step >= ctx.total:
            ctx.notices.append(f"{ctx.locate_key(path + ('at',))}: event at {spec.at:g} s is at or after "
                               f"the end of the run ({ctx.total / rate:g} s) and never happens")
            continue
        if spec.delete is not None:
            if spec.delete not in alive:
                gone = f"It was deleted at {deleted[spec.delete] / rate:g} s." if spec.delete in deleted else ""
                raise ScenarioError(f"event at {spec.at:g} s deletes {shown(spec.delete)}, which is not in the "
                                    f"world then", location=ctx.locate_key(path + ("delete",)),
                                    hint=gone or did_you_mean(spec.delete, alive)
                                    or "Delete a robot listed in robots: or spawned by an earlier event.")
            alive.remove(spec.delete)
            deleted[spec.delete] = step
            events.append(Event(step=step, delete=spec.delete))
        else:
            (plan,) = ctx.plans(spec.spawn, path + ("spawn",), spawn_step=step)
            alive.add(plan.name)
            events.append(Event(step=step, spawn=plan))

    def cut(robot: RobotPlan) -> RobotPlan:
        end = deleted.get(robot.name)
        if end is None:
            return robot
        return dataclasses.replace(robot, commands=tuple(c for c in robot.commands if c.step < end))

    events = [dataclasses.replace(e, spawn=cut(e.spawn)) if e.spawn else e for e in events]
    return tuple(cut(robot) for robot in robots), tuple(events)
