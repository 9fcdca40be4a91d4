"""A scenario's ``movers:`` to MoverPlans: fleets expanded, paths to keyframes, times to steps."""

from __future__ import annotations

from mobot_cli.errors import ScenarioError
from mobot_cli.plan import MoverPlan, WorldPlan
from mobot_cli.scenario.model import Scenario
from mobot_cli.scenario.mover_model import DEFAULT_SIZES, MAX_MOVERS, MoverSpec
from mobot_cli.scenario.source import Source
from mobot_cli.scenario.units import steps
from mobot_cli.sim.movers.script import path_keyframes


def resolve_movers(scenario: Scenario, source: Source, world: WorldPlan) -> tuple[MoverPlan, ...]:
    """Every mover of the scenario, in order; located errors for names used twice."""
    rate = scenario.physics.rate_hz
    taken = {actor.name: "an actor of the world" for actor in world.actors}
    out: list[MoverPlan] = []
    for index, spec in enumerate(scenario.movers):
        names = [spec.name.replace("{i}", str(i)) for i in range(spec.count)] if spec.count else [spec.name]
        for name in names:
            if name in taken:
                raise ScenarioError(f"mover name '{name}' is used twice (also {taken[name]})",
                                    location=source.locate_key(("movers", index, "name")),
                                    hint="Give every mover its own name.")
            taken[name] = f"movers[{index}]"
            out.append(mover_plan(spec, name, rate))
    if len(out) > MAX_MOVERS:
        raise ScenarioError(f"{len(out)} movers: at most {MAX_MOVERS}", location=source.locate_key(("movers",)),
                            hint="Use fewer or smaller fleets.")
    return tuple(out)


def mover_plan(spec: MoverSpec, name: str, rate: int, source: str = "scenario") -> MoverPlan:
    """One mover of a validated spec (``name``: its name, a fleet's {i} filled in)."""
    size = tuple(spec.size) if spec.size is not None else DEFAULT_SIZES[spec.shape]
    keyframes = path_keyframes([tuple(p) for p in spec.path], spec.speed, spec.mode) if spec.path else ()
    return MoverPlan(name=name, shape=spec.shape, size=size, keyframes=keyframes, loop=spec.mode != "once",
                     region=tuple(spec.region) if spec.region is not None else None, speed=spec.speed,
                     start=tuple(spec.start) if spec.start is not None else None, source=source,
                     spawn_step=steps(spec.at, rate))
