"""Scenario to Plan: robots loaded, fleets expanded, poses as quaternions, times as whole steps."""

from __future__ import annotations

import math
from pathlib import Path

from mobot_cli.assets.world.loaded import LoadedWorld
from mobot_cli.assets.world.worldplan import load_world
from mobot_cli.common import cache
from mobot_cli.errors import MobotError, ScenarioError
from mobot_cli.plan import FaultLimits, Physics, Plan, Ros2Settings
from mobot_cli.scenario.events import resolve_events
from mobot_cli.scenario.expect_resolve import resolve_expectations
from mobot_cli.scenario.model import Scenario
from mobot_cli.scenario.movers import resolve_movers
from mobot_cli.scenario.robots import RobotResolver, unlisted_robots
from mobot_cli.scenario.source import Source
from mobot_cli.scenario.units import steps
from mobot_cli.scenario.world_model import GeneratedWorld

DEFAULT_LOG_RATE_HZ = 50  # the log runs at most this fast when log.rate_hz is not given


def resolve(scenario: Scenario, source: Source) -> Plan:
    """Turn a validated scenario into a Plan; every problem is a located MobotError."""
    rate = scenario.physics.rate_hz
    total = steps(scenario.duration, rate)
    if total < 1:
        raise ScenarioError(f"duration {scenario.duration} s is shorter than one physics step",
                            location=source.locate_key(("duration",)))
    log_rate = scenario.log.rate_hz
    if log_rate is not None and log_rate > rate:
        raise ScenarioError(f"log.rate_hz {log_rate:g} is above physics.rate_hz {rate}",
                            location=source.locate_key(("log", "rate_hz")), hint="Log at most once per physics step.")
    log_every = max(1, steps(1.0 / log_rate, rate)) if log_rate else math.ceil(rate / DEFAULT_LOG_RATE_HZ)
    notices = []
    if log_rate is not None and abs(rate / log_every - log_rate) > 1e-9:
        notices.append(f"log.rate_hz {scenario.log.rate_hz:g} is not a whole number of physics steps at "
                       f"{rate} Hz: logging every {log_every} steps ({rate / log_every:.4g} Hz)")
    given = scenario.faults
    faults = FaultLimits(max_tilt=math.radians(given.max_tilt), flying_time=given.flying_time,
                         max_speed=given.max_speed, odom_tolerance=given.odom_tolerance)
    physics = Physics(rate_hz=rate, gravity=tuple(scenario.physics.gravity),
                      solver_iterations=scenario.physics.solver_iterations, engine=scenario.physics.engine,
                      faults=faults, renderer=scenario.physics.renderer)
    base_dir = source.file.parent.resolve() if source.file else Path.cwd()
    world, generated = _world(scenario, source, base_dir)
    notices.extend(world.notices)
    ctx = RobotResolver(rate, steps(scenario.settle, rate), total, base_dir=base_dir, source=source,
                        world=world, skip_missing=scenario.skip_missing)
    robots = tuple(robot for index, spec in enumerate(scenario.robots)
                   for robot in ctx.plans(spec, ("robots", index)))
    robots, events = resolve_events(scenario.events, robots, ctx)
    notices.extend(unlisted_robots(world, [*robots, *(e.spawn for e in events if e.spawn is not None)]))
    notices.extend(ctx.notices)
    notices.extend([cache.warning()] if cache.warning() else [])  # an unsafe cache folder: off, said once
    expectations, expect_notices = resolve_expectations(scenario, source, robots, events, log_every, total)
    notices.extend(expect_notices)
    return Plan(name=scenario.name, physics=physics, world=world.plan, robots=robots,
                total_steps=total, settle_steps=ctx.settle, log_every=log_every, seed=scenario.seed,
                formats=tuple(dict.fromkeys(scenario.log.formats)), events=events,
                notices=tuple(dict.fromkeys(notices)), expectations=expectations, ros2=_ros2(scenario),
                generated_world=generated,
                movers=resolve_movers(scenario, source, world.plan), images=scenario.log.images)


def _ros2(scenario: Scenario) -> Ros2Settings | None:
    """The ``ros2:`` block's settings, times in physics steps; None without one (or disabled)."""
    spec = scenario.ros2
    if spec is None or not spec.enabled:
        return None
    timeout = None if spec.cmd_vel_timeout is None else max(1, steps(spec.cmd_vel_timeout, scenario.physics.rate_hz))
    return Ros2Settings(node=spec.node, namespace=spec.namespace, domain_id=spec.domain_id,
                        cmd_vel_timeout_steps=timeout,
                        ignore_fastdds_type_information=spec.ignore_fastdds_type_information,
                        world_frame=spec.world_frame, map=spec.map)


def world_of(scenario: Scenario, source: Source) -> LoadedWorld:
    """The scenario's world alone (a sweep draws poses in it before preparing the run)."""
    return _world(scenario, source, source.file.parent.resolve() if source.file else Path.cwd())[0]


def _world(scenario: Scenario, source: Source, base_dir: Path) -> tuple[LoadedWorld, str]:
    """The scenario's world and, for a generated one, its SDF text; errors inside a world file
    keep their own file and line."""
    if isinstance(scenario.world, GeneratedWorld):
        from mobot_cli.assets.world.generate.make import load_generated

        spec = scenario.world.generate
        return load_generated(spec.kind, spec.seed, spec.parameters())
    try:
        return load_world(scenario.world, base_dir, skip_missing=scenario.skip_missing), ""
    except MobotError as exc:
        if exc.location.file is not None:
            raise
        raise type(exc)(exc.message, location=source.locate_key(("world",)), hint=exc.hint) from None


