"""The resolved scenario: one YAML document that reloads to the same Plan.

Fleets are expanded, defaults and detected drive values filled in, paths made absolute and
times written as the exact step times they were rounded to. A robot's ``sensors:`` is written
as the scenario gave it (rates as the step rates they became): its description, written beside
it with its args, supplies every other sensor value, so scenarios without ``sensors:`` resolve
to the same document as before sensors existed.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from mobot_cli.plan import CommandStep, DriveSpec, GoalControl, GoalStep, Plan, RobotPlan, TwistStep
from mobot_cli.scenario.expect_resolve import expect_document
from mobot_cli.scenario.goals import area_form
from mobot_cli.scenario.model import RobotSpec, Scenario
from mobot_cli.scenario.units import steps
from mobot_cli.sim.holonomic import KINDS as HOLONOMIC

DRIVE_KEYS = ("odometry", "left_joints", "right_joints", "wheel_radius", "wheel_separation",
              "wheel_separation_multiplier", "wheel_radius_multiplier", "max_wheel_torque",
              "max_wheel_acceleration", "twist_feedback")
CAR_KEYS = ("wheelbase", "max_steering_angle")  # an Ackermann drive's own


def resolved_document(scenario: Scenario, plan: Plan, base_dir: Path) -> dict[str, Any]:
    """A plain dict that validates as a Scenario and resolves to ``plan`` again."""
    rate = plan.physics.rate_hz
    by_name = {robot.name: robot for robot in plan.robots}
    robots = []
    for spec in scenario.robots:
        names = [spec.name] if spec.count is None else [spec.name.replace("{i}", str(i)) for i in range(spec.count)]
        robots.extend(_robot(spec, by_name[name], base_dir, rate) for name in names)
    implicit = {spec.name for spec in scenario.robots if "description" not in spec.model_fields_set}
    for entry in robots:  # the world's own robot model, named without a description: keep it so
        if entry["name"] in implicit and entry["name"] in plan.world.robot_models:
            del entry["description"], entry["args"]
    return {
        "version": 1,
        "name": scenario.name,
        "world": _world(scenario, base_dir),
        **({"skip_missing": True} if scenario.skip_missing else {}),
        "physics": {"rate_hz": rate, "gravity": list(plan.physics.gravity),
                    "solver_iterations": plan.physics.solver_iterations,
                    **({"engine": plan.physics.engine} if plan.physics.engine != "bullet" else {}),
                    **({"renderer": plan.physics.renderer} if plan.physics.renderer != "auto" else {})},
        "duration": plan.total_steps / rate,
        "seed": plan.seed,
        "settle": plan.settle_steps / rate,
        "log": {"rate_hz": scenario.log.rate_hz or rate / plan.log_every, "formats": list(scenario.log.formats),
                **({"images": scenario.log.images} if scenario.log.images != "raw" else {})},
        "robots": robots,
        **({"faults": scenario.faults.model_dump(exclude_defaults=True)}
           if scenario.faults.model_dump(exclude_defaults=True) else {}),
        **_events(scenario, plan, base_dir),
        **expect_document(plan.expectations, rate),
        **_ros2(scenario, plan),
        **_movers(scenario, rate),
    }


def _world(scenario: Scenario, base_dir: Path) -> Any:
    """A world file as an absolute path, a generated world with every parameter, a name as given."""
    if not isinstance(scenario.world, str):
        return scenario.world.document()
    local_world = base_dir / scenario.world
    return str(local_world.resolve()) if local_world.is_file() else scenario.world


def _movers(scenario: Scenario, rate: int) -> dict[str, Any]:
    """``movers:`` as given (fleets stay fleets), each ``at`` the exact step time it was rounded to."""
    if not scenario.movers:
        return {}
    out = []
    for spec in scenario.movers:
        entry = spec.model_dump(mode="json", exclude_defaults=True)
        if spec.at:
            entry["at"] = steps(spec.at, rate) / rate
        out.append(entry)
    return {"movers": out}


def _ros2(scenario: Scenario, plan: Plan) -> dict[str, Any]:
    """``ros2:`` as given, its timeout the exact step time it was rounded to."""
    if scenario.ros2 is None:
        return {}
    out = scenario.ros2.model_dump(exclude_defaults=True)
    if plan.ros2 is not None and plan.ros2.cmd_vel_timeout_steps is not None:
        out["cmd_vel_timeout"] = plan.ros2.cmd_vel_timeout_steps / plan.physics.rate_hz
    return {"ros2": out}


def _events(scenario: Scenario, plan: Plan, base_dir: Path) -> dict[str, Any]:
    """``events:`` in step order, spawned robots written like the scenario's own robots."""
    if not plan.events:
        return {}
    rate = plan.physics.rate_hz
    specs = {event.spawn.name: event.spawn for event in scenario.events if event.spawn is not None}
    out: list[dict[str, Any]] = []
    for event in plan.events:
        entry: dict[str, Any] = {"at": event.step / rate}
        if event.spawn is not None:
            entry["spawn"] = _robot(specs[event.spawn.name], event.spawn, base_dir, rate)
        else:
            entry["delete"] = event.delete
        out.append(entry)
    return {"events": out}


def _robot(spec: RobotSpec, robot: RobotPlan, base_dir: Path, rate: int) -> dict[str, Any]:
    local = base_dir / spec.description
    description = str(local.resolve()) if local.exists() else spec.description
    pose = robot.pose
    out: dict[str, Any] = {
        "name": robot.name,
        "namespace": robot.namespace,
        "description": description,
        "args": {k: v if isinstance(v, str) else _text(v) for k, v in spec.args.items()},
        "pose": {"xyz": [pose.xyz[0], pose.xyz[1], "auto" if pose.z_auto else pose.xyz[2]],
                 "quat": list(pose.quat)},
    }
    if robot.drive is not None:
        out["drive"] = _drive(robot.drive)
    if spec.sensors:
        out["sensors"] = _sensors(spec, rate)
    out["commands"] = _commands(robot, rate)
    return out


def _drive(drive: DriveSpec) -> dict[str, Any]:
    car = drive.kind == "ackermann"
    holonomic = drive.kind in HOLONOMIC
    out: dict[str, Any] = {"type": "ackermann" if car else "holonomic" if holonomic else "diff_drive"}
    for key in DRIVE_KEYS + (CAR_KEYS if car else ("wheelbase",) if holonomic else ()):
        value = getattr(drive, key)
        if value is not None:
            out[key] = list(value) if isinstance(value, tuple) else value
    return out


def _sensors(spec: RobotSpec, rate: int) -> dict[str, Any]:
    """The scenario's own ``sensors:`` (the description supplies the rest), rates as step rates."""
    out: dict[str, Any] = {}
    for key, entry in spec.sensors.items():
        if entry.enabled is False:
            out[key] = False
            continue
        fields = entry.model_dump(exclude={"enabled"}, exclude_none=True)
        if entry.rate_hz is not None:
            fields["rate_hz"] = rate / max(1, steps(1.0 / entry.rate_hz, rate))
        out[key] = _plain(fields)
    return out


def _plain(value: Any) -> Any:
    """Tuples as lists, all the way down: YAML's safe dumper writes no tuples."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def _commands(robot: RobotPlan, rate: int) -> list[dict[str, Any]]:
    """Commands as written: a stop that ends a command becomes that command's ``for``."""
    out: list[dict[str, Any]] = []
    cmds = [c for c in robot.commands if isinstance(c, CommandStep)]
    i = 0
    while i < len(cmds):
        cmd = cmds[i]
        entry: dict[str, Any] = {"at": cmd.step / rate, "linear": cmd.linear, "angular": cmd.angular}
        if cmd.linear_y:
            entry["linear_y"] = cmd.linear_y
        nxt = cmds[i + 1] if i + 1 < len(cmds) else None
        if nxt is not None and not (nxt.linear or nxt.angular or nxt.linear_y) and (
                cmd.linear or cmd.angular or cmd.linear_y):
            entry["for"] = (nxt.step - cmd.step) / rate
            i += 1
        out.append(entry)
        i += 1
    return out + [_goal(c, rate) if isinstance(c, GoalStep) else _twist(c, rate)
                  for c in robot.commands if not isinstance(c, CommandStep)]


def _goal(goal: GoalStep, rate: int) -> dict[str, Any]:
    """A goal command with every setting written out."""
    c = goal.control
    entry: dict[str, Any] = {"at": goal.step / rate}
    if goal.kind == "goto":
        (x, y), = goal.points
        entry["goto"] = {"x": x, "y": y, **({"yaw": goal.yaw} if goal.yaw is not None else {}),
                         "tolerance": c.tolerance}
    elif goal.kind == "coverage":
        entry["coverage"] = {"area": area_form(goal.area), "spacing": goal.spacing}
    else:
        entry[goal.kind] = [list(point) for point in goal.points]
    if goal.kind != "goto":
        entry["tolerance"] = c.tolerance
    if goal.laps is not None:
        entry["laps"] = goal.laps
    if c.timeout is not None:
        entry["timeout"] = c.timeout / rate
    entry.update(localization=c.localization, max_linear=c.max_linear, max_angular=c.max_angular,
                 acceleration=c.linear_acceleration, angular_acceleration=c.angular_acceleration)
    if c.planner is not None:
        entry.update(planner=c.planner, inflation=c.inflation)
    if c.local:
        entry["local"] = c.local
    default = GoalControl()  # the metrics' settings only when given: resolved scenarios stay as they were
    if c.stuck_time != default.stuck_time:
        entry["stuck_time"] = c.stuck_time
    if c.danger_distance != default.danger_distance:
        entry["danger_distance"] = c.danger_distance
    return entry


def _twist(cmd: TwistStep, rate: int) -> dict[str, Any]:
    entry: dict[str, Any] = {"at": cmd.step / rate, "linear": cmd.linear, "angular": cmd.angular}
    if cmd.linear_y:
        entry["linear_y"] = cmd.linear_y
    if cmd.hold is not None:
        entry["for"] = cmd.hold / rate
    return entry


def _text(value: Any) -> str:
    return ("true" if value else "false") if isinstance(value, bool) else str(value)
