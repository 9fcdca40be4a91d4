"""Scenario to Plan: robots loaded, fleets expanded, poses as quaternions, times as whole steps."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any

from mobot_cli.assets.description import RobotDescription, load_robot
from mobot_cli.errors import MobotError, ScenarioError, did_you_mean
from mobot_cli.scenario.model import RobotSpec, Scenario
from mobot_cli.scenario.units import quat_from_rpy, spawn_pose, steps
from mobot_cli.scenario.yamlsource import Source
from mobot_cli.sim.plan import CommandStep, DriveSpec, Physics, Plan, RobotPlan, SpawnPose, WorldPlan

BUNDLED_WORLDS = ("empty",)
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
    physics = Physics(rate_hz=rate, gravity=tuple(scenario.physics.gravity),
                      solver_iterations=scenario.physics.solver_iterations)
    ctx = _Context(scenario, source, total, steps(scenario.settle, rate))
    robots = tuple(robot for index, spec in enumerate(scenario.robots) for robot in ctx.robots(index, spec))
    notices.extend(ctx.notices)
    return Plan(name=scenario.name, physics=physics, world=_world(scenario, source), robots=robots,
                total_steps=total, settle_steps=ctx.settle, log_every=log_every, seed=scenario.seed,
                formats=tuple(dict.fromkeys(scenario.log.formats)),
                notices=tuple(dict.fromkeys(notices)))


def _world(scenario: Scenario, source: Source) -> WorldPlan:
    if scenario.world in BUNDLED_WORLDS:
        return WorldPlan(name=scenario.world)
    raise ScenarioError(f"world '{scenario.world}' is not available", location=source.locate_key(("world",)),
                        hint=("Loading Gazebo SDF worlds is not implemented in this version; "
                              if scenario.world.endswith((".world", ".sdf")) else "")
                        + did_you_mean(scenario.world, BUNDLED_WORLDS))


class _Context:
    """State shared while resolving robots: names seen, descriptions loaded once per args."""

    def __init__(self, scenario: Scenario, source: Source, total: int, settle: int):
        self.scenario, self.source, self.total, self.settle = scenario, source, total, settle
        self.base_dir = source.file.parent.resolve() if source.file else Path.cwd()
        self.names: dict[str, tuple] = {}
        self.namespaces: dict[str, str] = {}
        self.loaded: dict[tuple, RobotDescription] = {}
        self.notices: list[str] = []

    def robots(self, index: int, spec: RobotSpec):
        """Yield one RobotPlan per robot (a fleet gives ``count`` of them)."""
        path = ("robots", index)
        desc = self.describe(spec, path)
        drive = self.drive(spec, desc, path)
        commands = self.commands(spec, path)
        if commands and drive is None:
            raise ScenarioError(f"robot '{spec.name}' has commands but no drive wheels were detected in "
                                f"'{spec.description}'", location=self.source.locate_key(path + ("commands",)),
                                hint="Add drive: {left_joints, right_joints, wheel_radius, wheel_separation}.")
        if spec.count is None:
            members = [(spec.name, spec.namespace, spawn_pose(spec.pose))]
        else:
            members = [(spec.name.replace("{i}", str(i)), None, SpawnPose(
                xyz=(x, y, 0.0), quat=quat_from_rpy(0.0, 0.0, yaw), z_auto=True))
                for i, (x, y, yaw) in enumerate(spec.poses)]
        for name, namespace, pose in members:
            self.claim(name, namespace or f"/{name}", path)
            namespace = namespace or f"/{name}"
            yield RobotPlan(name=name, namespace=namespace, frame_prefix=namespace.lstrip("/") + "/",
                            urdf=desc.urdf, root_link=desc.root_link, pose=pose, drive=drive,
                            commands=commands, source=str(desc.source))

    def claim(self, name: str, namespace: str, path: tuple) -> None:
        if name in self.names:
            raise ScenarioError(f"robot name '{name}' is used twice", location=self.source.locate_key(path + ("name",)),
                                hint="Every robot needs a unique name, as Gazebo entities do.")
        if namespace in self.namespaces:
            raise ScenarioError(f"namespace '{namespace}' of '{name}' is already used by "
                                f"'{self.namespaces[namespace]}'", location=self.source.locate_key(path + ("namespace",)),
                                hint="Two robots in one namespace would share topics and TF frames.")
        self.names[name] = path
        self.namespaces[namespace] = name

    def describe(self, spec: RobotSpec, path: tuple) -> RobotDescription:
        args = {k: _arg_text(v) for k, v in spec.args.items()}
        key = (spec.description, tuple(sorted(args.items())))
        if key not in self.loaded:
            try:
                self.loaded[key] = load_robot(spec.description, args, self.base_dir)
            except MobotError as exc:
                raise type(exc)(f"robot '{spec.name}': {exc}",
                                location=self.source.locate_key(path + ("description",))) from None
            self.notices.extend(str(n) for n in self.loaded[key].notices)
        return self.loaded[key]

    def drive(self, spec: RobotSpec, desc: RobotDescription, path: tuple) -> DriveSpec | None:
        over = spec.drive
        if over is None:
            return desc.drive
        fields = {k: v for k, v in over.model_dump(exclude={"type"}).items() if v is not None}
        for key in ("left_joints", "right_joints"):
            if key in fields:
                fields[key] = tuple(fields[key])
        if desc.drive is not None:
            return dataclasses.replace(desc.drive, source=_source(desc.drive, fields), **fields)
        needed = ["left_joints", "right_joints", "wheel_radius", "wheel_separation"]
        missing = [k for k in needed if k not in fields]
        if missing:
            raise ScenarioError(f"no drive wheels were detected in '{spec.description}' and drive: lacks "
                                + ", ".join(missing), location=self.source.locate_key(path + ("drive",)),
                                hint="Name the wheel joints and give their radius and separation.")
        return DriveSpec(source="scenario", **fields)

    def commands(self, spec: RobotSpec, path: tuple) -> tuple[CommandStep, ...]:
        rate, out = self.scenario.physics.rate_hz, []
        free_from = self.settle
        for i, cmd in enumerate(spec.commands):
            where = self.source.locate_key(path + ("commands", i, "at"))
            at = steps(cmd.at, rate)
            if at < self.settle:
                raise ScenarioError(f"command at {cmd.at:g} s falls inside the settle window "
                                    f"(the first {self.scenario.settle:g} s)", location=where,
                                    hint="Robots hold still while they settle; start commands at or after 'settle'.")
            if at >= self.total:  # e.g. a run shortened with --duration: say so, don't refuse
                self.notices.append(f"{where}: command at {cmd.at:g} s is at or after the end of the run "
                                    f"({self.total / rate:g} s) and is never sent")
                break
            if at < free_from or (out and at <= out[-1].step):
                raise ScenarioError(f"command at {cmd.at:g} s starts before the previous one ends",
                                    location=where, hint="List commands in time order, each after the last 'for' ends.")
            out.append(CommandStep(step=at, linear=cmd.linear, angular=cmd.angular))
            free_from = at
            if cmd.for_ is not None:
                free_from = at + max(1, steps(cmd.for_, rate))
                if free_from < self.total:
                    out.append(CommandStep(step=free_from, linear=0.0, angular=0.0))
        return tuple(out)


def _source(detected: DriveSpec, fields: dict[str, Any]) -> str:
    layout = {"left_joints", "right_joints", "wheel_radius", "wheel_separation"}
    return "scenario" if layout <= fields.keys() else detected.source


def _arg_text(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


