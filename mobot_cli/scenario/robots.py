"""Robot specs to RobotPlans: the one path that scenario robots, spawn events and live spawns take.

A ``RobotSpec`` (the scenario's robot entry; a live spawn request is validated into one too)
becomes a ``RobotPlan``: description loaded with its xacro args, drive and sensor overrides merged
(sensors.py), pose converted, command times rounded to whole steps, name and namespace claimed.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

from mobot_cli.assets.description.describe import load_robot
from mobot_cli.assets.description.drive import drive_from_joints
from mobot_cli.assets.description.holonomic import wheelbase_of
from mobot_cli.assets.description.joints import FREE
from mobot_cli.assets.description.robot import NO_DRIVE, RobotDescription
from mobot_cli.assets.description.steering import CANNOT_DRIVE
from mobot_cli.assets.description.torque import mass_torque
from mobot_cli.assets.world.loaded import LoadedWorld, WorldRobot
from mobot_cli.common.transforms import quat_from_rpy
from mobot_cli.errors import Location, MobotError, ScenarioError
from mobot_cli.plan import CommandStep, DriveSpec, GoalStep, RobotPlan, SpawnPose, TwistStep
from mobot_cli.scenario.goals import goal_step
from mobot_cli.scenario.holds import resolve_holds
from mobot_cli.scenario.model import DriveOverrides, RobotSpec
from mobot_cli.scenario.sensor_resolve import resolve_sensors
from mobot_cli.scenario.sensor_switches import arg_text
from mobot_cli.scenario.source import Source
from mobot_cli.scenario.units import spawn_pose, steps
from mobot_cli.sim.drive import default_separation_multiplier
from mobot_cli.sim.holonomic import KINDS as HOLONOMIC
from mobot_cli.sim.steering import angular_from_steering

# The scenario's drive.type of each detected kind (DESIGN.md).
DRIVE_TYPES = {"diff": "diff", "skid": "diff", "mecanum": "holonomic", "omni": "holonomic",
               "ackermann": "ackermann"}


class RobotResolver:
    """State shared while resolving robots: names seen, descriptions loaded once per args.

    ``source`` locates errors in a scenario file; without one (a live spawn) errors carry no
    location. ``settle`` and ``total`` are in physics steps.
    """

    def __init__(self, rate_hz: int, settle: int, total: int, *, base_dir: Path,
                 source: Source | None = None, world: LoadedWorld | None = None,
                 skip_missing: bool = False):
        self.rate_hz, self.settle, self.total = rate_hz, settle, total
        self.base_dir = base_dir
        self.skip_missing = skip_missing  # missing meshes: left out with a warning, not an error
        self.source = source
        self.world = world  # its robot models are robots when listed by name
        self.names: dict[str, tuple] = {}
        self.namespaces: dict[str, str] = {}
        self.loaded: dict[tuple, RobotDescription] = {}
        self.notices: list[str] = []

    def locate_key(self, path: tuple) -> Location | None:
        """Where ``path`` is in the scenario file, or None for a live request."""
        return self.source.locate_key(path) if self.source is not None else None

    def plans(self, spec: RobotSpec, path: tuple, spawn_step: int = 0) -> list[RobotPlan]:
        """One RobotPlan per robot (a fleet gives ``count`` of them), spawned at ``spawn_step``."""
        desc = self.describe(spec, path)
        drive = self.drive(spec, desc, path)
        sensors = resolve_sensors(spec, desc, path, self)
        commands = self.commands(spec, path, spawn_step, desc.footprint, drive)
        if drive is None:  # said here, not by describe(): a drive: naming the wheels silences it
            self.notices.extend(str(n) for n in desc.notices if n.message.startswith((NO_DRIVE, CANNOT_DRIVE)))
        holds = resolve_holds(spec, desc, drive, self.locate_key(path + ("hold",)), self.notices)
        if commands and drive is None and desc.refused_drive:
            raise ScenarioError(f"robot '{spec.name}' has commands but mobot cannot drive its "
                                f"{desc.refused_drive}", location=self.locate_key(path + ("commands",)),
                                hint="If its wheels turn on joints, name them to drive it as a differential "
                                     "drive: drive: {left_joints: [...], right_joints: [...]}. Otherwise leave its "
                                     "commands out: it is simulated as a passive body.")
        if commands and drive is None:
            what = f"world model '{spec.name}'" if self.world_robot(spec) is not None else f"'{spec.description}'"
            raise ScenarioError(f"robot '{spec.name}' has commands but no drive wheels were detected in "
                                f"{what}", location=self.locate_key(path + ("commands",)),
                                hint="Name its wheel joints: drive: {left_joints: [...], right_joints: [...]} "
                                     "(wheel_radius and wheel_separation too when its wheels cannot be measured).")
        self.check_sideways(spec, drive, path)
        self.check_local(spec, path, commands, sensors)
        in_world = self.world_robot(spec)
        if in_world is not None and "pose" not in spec.model_fields_set:
            members = [(spec.name, spec.namespace, SpawnPose(xyz=in_world.xyz, quat=in_world.quat))]
        elif spec.count is None:
            members = [(spec.name, spec.namespace, spawn_pose(spec.pose))]
        else:
            members = [(spec.name.replace("{i}", str(i)), None, SpawnPose(
                xyz=(x, y, 0.0), quat=quat_from_rpy(0.0, 0.0, yaw), z_auto=True))
                for i, (x, y, yaw) in enumerate(spec.poses)]
        out = []
        for name, namespace, pose in members:
            namespace = namespace or f"/{name}"
            self.claim(name, namespace, path)
            out.append(RobotPlan(name=name, namespace=namespace, frame_prefix=namespace.lstrip("/") + "/",
                                 urdf=desc.urdf, root_link=desc.root_link, pose=pose, drive=drive,
                                 commands=commands, spawn_step=spawn_step, source=str(desc.source),
                                 sensors=sensors, footprint=tuple(desc.footprint),
                                 heights=(desc.bottom_z, desc.top_z), holds=holds))
        return out

    def check_local(self, spec: RobotSpec, path: tuple, commands, sensors) -> None:
        """A goal with ``local:`` obstacle avoidance needs a lidar on the robot to see with."""
        if any(sensor.kind == "lidar" for sensor in sensors):
            return
        for cmd in commands:
            if isinstance(cmd, GoalStep) and cmd.control.local:
                raise ScenarioError(
                    f"robot '{spec.name}': goal 'local: {cmd.control.local}' avoids what the robot's lidar sees, "
                    "and it has no lidar", location=self.locate_key(path + ("commands", cmd.index, "local")),
                    hint="Give the robot a lidar (the bundled robot: args: {lidar: \"true\"}), or leave out 'local'.")

    def claim(self, name: str, namespace: str, path: tuple) -> None:
        """Reserve a robot name and namespace; a second use is an error."""
        if name in self.names:
            raise ScenarioError(f"robot name '{name}' is used twice", location=self.locate_key(path + ("name",)),
                                hint="Every robot needs a unique name, as Gazebo entities do.")
        if self.world is not None and name in self.world.static_models:
            raise ScenarioError(f"robot name '{name}' is already the name of a static model of the world",
                                location=self.locate_key(path + ("name",)),
                                hint="Every entity needs a unique name, as in Gazebo; pick another name.")
        if namespace in self.namespaces:
            raise ScenarioError(f"namespace '{namespace}' of '{name}' is already used by "
                                f"'{self.namespaces[namespace]}'", location=self.locate_key(path + ("namespace",)),
                                hint="Two robots in one namespace would share topics and TF frames.")
        self.names[name] = path
        self.namespaces[namespace] = name

    def describe(self, spec: RobotSpec, path: tuple) -> RobotDescription:
        """The checked description of ``spec`` with its args (loaded once per description and args)."""
        in_world = self.world_robot(spec)
        if in_world is not None:
            key = ("world model", in_world.name)
            if key not in self.loaded:
                from mobot_cli.assets.description.sdf import describe_world_robot

                self.loaded[key] = describe_world_robot(in_world, self.base_dir)
                self.notices.extend(_shown(self.loaded[key]))
            return self.loaded[key]
        args = {k: arg_text(v) for k, v in spec.args.items()}
        key = (spec.description, tuple(sorted(args.items())))
        if key not in self.loaded:
            try:
                self.loaded[key] = load_robot(spec.description, args, self.base_dir, self.skip_missing)
            except MobotError as exc:
                raise type(exc)(f"robot '{spec.name}': {exc}",
                                location=self.locate_key(path + ("description",))) from None
            self.notices.extend(_shown(self.loaded[key]))
        return self.loaded[key]

    def world_robot(self, spec: RobotSpec) -> WorldRobot | None:
        """The world's robot model this spec names (no description given), if any."""
        if self.world is None or "description" in spec.model_fields_set or spec.count is not None:
            return None
        return self.world.robot(spec.name)

    def check_sideways(self, spec: RobotSpec, drive: DriveSpec | None, path: tuple) -> None:
        """A located error for a sideways command (linear_y) to a robot whose drive is not holonomic."""
        if drive is not None and drive.kind in HOLONOMIC:
            return
        for i, cmd in enumerate(spec.commands):
            if cmd.linear_y:
                kind = f"a {drive.kind} drive" if drive is not None else "no drive"
                raise ScenarioError(f"robot '{spec.name}' has {kind}: it cannot move sideways "
                                    f"(linear_y {cmd.linear_y:g} m/s)",
                                    location=self.locate_key(path + ("commands", i, "linear_y")),
                                    hint="Only holonomic (mecanum, omni) bases take linear_y; set drive: "
                                         "{type: holonomic} if this one is, or drop linear_y.")

    def drive(self, spec: RobotSpec, desc: RobotDescription, path: tuple) -> DriveSpec | None:
        """The detected drive with the spec's overrides merged in, of the kind ``drive.type`` asks,
        its torque limit chosen last."""
        merged = self._drive_of_kind(spec, desc, path)
        if merged is None:
            return None
        if spec.drive is not None and spec.drive.max_wheel_torque is not None:
            return dataclasses.replace(merged, torque_source="scenario")
        if merged.torque_source in ("mass", "default"):  # the radius may be the scenario's
            torque = mass_torque(desc.total_mass, merged.wheel_radius,
                                 len(merged.left_joints) + len(merged.right_joints))
            merged = dataclasses.replace(merged, max_wheel_torque=torque, torque_source="mass")
        return merged

    def _drive_of_kind(self, spec: RobotSpec, desc: RobotDescription, path: tuple) -> DriveSpec | None:
        over = spec.drive
        if over is None:
            return desc.drive
        merged = self.merged_drive(spec, desc, path)
        return drive_kind(merged, over, desc)

    def merged_drive(self, spec: RobotSpec, desc: RobotDescription, path: tuple) -> DriveSpec:
        """The detected drive (or the one on the joints ``drive:`` names) with its values merged in."""
        over = spec.drive
        fields = {k: v for k, v in over.model_dump(exclude={"type"}).items() if v is not None}
        for key in ("left_joints", "right_joints"):
            if key in fields:
                fields[key] = tuple(fields[key])
        base = self.named_wheels(desc, fields, path)
        if "type" in over.model_fields_set:
            self.check_type(spec, desc, base, path)
        if base is not None:
            return dataclasses.replace(base, source=_source(base, fields), **fields)
        needed = ["left_joints", "right_joints", "wheel_radius", "wheel_separation"]
        missing = [k for k in needed if k not in fields]
        if missing:
            named = "left_joints" in fields and "right_joints" in fields
            raise ScenarioError(f"no drive wheels were detected in '{spec.description}' and drive: lacks "
                                + ", ".join(missing), location=self.locate_key(path + ("drive",)),
                                hint="The named joints' links have no cylinder, sphere or mesh collision to "
                                     "measure: give wheel_radius." if named else
                                "Name the wheel joints (left_joints, right_joints); radius and separation "
                                "come from their geometry.")
        return DriveSpec(source="scenario", **fields)

    def check_type(self, spec: RobotSpec, desc: RobotDescription, drive: DriveSpec | None, path: tuple) -> None:
        """A ScenarioError when ``drive.type`` or the detected drive is a car and the other is not: a
        robot is never driven as another type (a car's rear wheels as a diff drive). A base's wheels
        may be driven as diff or holonomic on request (drive_kind)."""
        wanted = "diff" if spec.drive.type == "diff_drive" else spec.drive.type
        found = DRIVE_TYPES.get(drive.kind, drive.kind) if drive is not None else None
        if found is None or found == wanted or "ackermann" not in (found, wanted):
            return  # diff <-> holonomic: the user's choice for the same wheels (drive_kind)
        hint = ("Cars are found from a gazebo_ros ackermann_drive or gz-sim AckermannSteering plugin, or from "
                "limited steering joints about the vertical that carry wheels (docs/ackermann.md)."
                if wanted == "ackermann" else f"Leave drive.type out, or set it to {found}.")
        raise ScenarioError(f"drive.type is {wanted}, but the drive detected in '{spec.description}' is {drive.kind} "
                            f"({', '.join(drive.steering_joints or drive.left_joints + drive.right_joints)}): "
                            "mobot drives a robot only as the type it is", hint=hint,
                            location=self.locate_key(path + ("drive", "type")))

    def named_wheels(self, desc: RobotDescription, fields: dict[str, Any], path: tuple) -> DriveSpec | None:
        """The detected drive, or the one on the joints drive: names, measured from their geometry."""
        detected = desc.drive
        left = fields.get("left_joints", detected.left_joints if detected else None)
        right = fields.get("right_joints", detected.right_joints if detected else None)
        if left is None or right is None:
            return detected
        if detected is not None and (left, right) == (detected.left_joints, detected.right_joints):
            return detected
        try:
            named = drive_from_joints(desc.urdf, tuple(left), tuple(right), source=desc.source,
                                      radius=fields.get("wheel_radius"),
                                      separation=fields.get("wheel_separation"))
        except MobotError as exc:
            raise ScenarioError(exc.message, location=self.locate_key(path + ("drive",)),
                                hint=exc.hint) from None
        if named is not None and detected is not None and detected.kind == "ackermann":
            # other driven wheels of the same car: it keeps its steering
            steering = tuple(s for s in detected.joint_signs if s[0] in detected.steering_joints)
            return dataclasses.replace(detected, left_joints=named.left_joints, right_joints=named.right_joints,
                                       wheel_radius=named.wheel_radius, wheel_separation=named.wheel_separation,
                                       joint_signs=named.joint_signs + steering)
        return named

    def start_of(self, spec: RobotSpec) -> tuple[float, float, float]:
        """Where a robot (its first, for a count) is spawned: x, y, and z as asked (0: to the floor)."""
        in_world = self.world_robot(spec)
        if in_world is not None and "pose" not in spec.model_fields_set:
            return in_world.xyz
        if spec.count is not None and spec.poses:
            x, y, _ = spec.poses[0]
            return (float(x), float(y), 0.0)
        return spawn_pose(spec.pose).xyz

    def commands(self, spec: RobotSpec, path: tuple, spawn_step: int = 0,
                 footprint: tuple[float, float, float, float] | None = None,
                 drive: DriveSpec | None = None) -> tuple:
        """The command script in whole steps; each robot holds still for ``settle`` after its spawn.

        Twists before the first goal are CommandSteps at fixed steps (a ``for`` adds a stop);
        from the first goal on, GoalSteps and TwistSteps start at their step or when the goal
        before them ends, whichever is later.
        """
        rate, out = self.rate_hz, []
        settled = spawn_step + self.settle
        free_from = settled  # the earliest step the next command may start at
        held = goal_seen = False  # held: the last twist holds until the next command
        for i, cmd in enumerate(spec.commands):
            key = path + ("commands", i)
            where = self.locate_key(key + ("at",) if cmd.at is not None else key)
            if cmd.at is None and held and not goal_seen:
                raise ScenarioError("command has no 'at' and the command before it holds until the next one",
                                    location=where, hint="Give it an 'at', or end the one before with 'for'.")
            at = free_from if cmd.at is None else steps(cmd.at, rate)
            if at < settled:
                window = (f"the first {self.settle / rate:g} s" if spawn_step == 0 else
                          f"{self.settle / rate:g} s from its spawn at {spawn_step / rate:g} s")
                raise ScenarioError(f"command at {cmd.at:g} s falls inside the settle window ({window})",
                                    location=where,
                                    hint="Robots hold still while they settle; start commands at or after 'settle'.")
            if at >= self.total:  # e.g. a run shortened with --duration: say so, don't refuse
                self.notices.append(f"{where}: command at {at / rate:g} s is at or after the end of the run "
                                    f"({self.total / rate:g} s) and is never sent")
                break
            if not goal_seen and out and at == free_from == out[-1].step and not held:
                out.pop()  # it starts as the one before ends: no stop between the two
            early = at < out[-1].step if goal_seen else at < free_from or (out and at <= out[-1].step)
            if cmd.at is not None and early:
                raise ScenarioError(f"command at {cmd.at:g} s starts before the previous one ends",
                                    location=where, hint="List commands in time order, each after the last 'for' ends.")
            free_from, held = at, cmd.for_ is None
            if cmd.goal is not None:
                world = self.world.plan if self.world is not None else None
                out.append(goal_step(cmd, at, i, rate, world, footprint,
                                     lambda k, key=key: self.locate_key(key + k), self.notices,
                                     start=self.start_of(spec)))
                goal_seen = True
            elif goal_seen:
                hold = None if cmd.for_ is None else max(1, steps(cmd.for_, rate))
                angular = self.angular(cmd, spec, drive, key)
                out.append(TwistStep(step=at, index=i, linear=cmd.linear, angular=angular, hold=hold,
                                     linear_y=cmd.linear_y))
            else:
                out.append(CommandStep(step=at, linear=cmd.linear, angular=self.angular(cmd, spec, drive, key),
                                       linear_y=cmd.linear_y))
                if cmd.for_ is not None:
                    free_from = at + max(1, steps(cmd.for_, rate))
                    if free_from < self.total:
                        out.append(CommandStep(step=free_from, linear=0.0, angular=0.0))
        return tuple(out)


    def angular(self, cmd, spec: RobotSpec, drive: DriveSpec | None, key: tuple) -> float:
        """A twist command's yaw rate: ``angular``, or a car's ``steering_angle`` through its wheelbase."""
        if cmd.steering_angle is None:
            return cmd.angular
        if drive is None or drive.kind != "ackermann":
            raise ScenarioError(f"robot '{spec.name}' has no steering (its drive is "
                                f"{drive.kind if drive is not None else 'none'}): steering_angle is for cars",
                                location=self.locate_key(key + ("steering_angle",)),
                                hint="Give 'angular' (rad/s) instead.")
        return angular_from_steering(cmd.linear, cmd.steering_angle, drive.wheelbase)


def drive_kind(drive: DriveSpec, over: DriveOverrides, desc: RobotDescription) -> DriveSpec:
    """The drive as the scenario's ``drive.type`` asks: None keeps the detected kind (also when
    ``drive:`` names other wheels), "diff" drives a holonomic base as diff or skid steer,
    "holonomic" a diff-detected base as mecanum (two or more wheels a side) or omni; a car stays
    a car (check_type refused any other type for it)."""
    detected, wanted = desc.drive, over.type
    given = over.wheel_separation_multiplier is not None
    if wanted is None:
        if detected is not None and detected.kind in HOLONOMIC and drive.kind not in HOLONOMIC:
            return holonomic_drive(drive, desc, detected.kind, given)
        return drive
    if wanted == "ackermann" or drive.kind == "ackermann":  # a detected car (check_type)
        return drive
    if wanted in ("diff", "diff_drive"):
        if drive.kind not in HOLONOMIC:
            return drive
        n = max(len(drive.left_joints), len(drive.right_joints))
        multiplier = drive.wheel_separation_multiplier
        if n > 1 and not given and drive.wheel_separation > 0 and drive.wheelbase > 0:
            multiplier = default_separation_multiplier(drive.wheel_separation, drive.wheelbase)
        return dataclasses.replace(drive, kind="diff", twist_feedback=over.twist_feedback,
                                   wheel_separation_multiplier=multiplier)
    if drive.kind in HOLONOMIC:
        return drive
    kind = "mecanum" if min(len(drive.left_joints), len(drive.right_joints)) > 1 else "omni"
    return holonomic_drive(drive, desc, kind, given)


def holonomic_drive(drive: DriveSpec, desc: RobotDescription, kind: str, given: bool) -> DriveSpec:
    """A diff drive's wheels driven as a holonomic base: no skid multiplier, a measured wheelbase."""
    wheelbase = drive.wheelbase or wheelbase_of(desc.urdf, drive.left_joints, drive.right_joints)
    multiplier = drive.wheel_separation_multiplier if given else 1.0
    return dataclasses.replace(drive, kind=kind, wheelbase=wheelbase, twist_feedback=False,
                              wheel_separation_multiplier=multiplier)


def _shown(desc: RobotDescription) -> list[str]:
    """The description's notices but the missing or refused drive and the joints left free, which
    plans() says when they apply."""
    return [str(n) for n in desc.notices if not n.message.startswith((NO_DRIVE, CANNOT_DRIVE, FREE))]


def unlisted_robots(world: LoadedWorld, robots) -> list[str]:
    """Warnings for the world's robot models that the scenario does not list (not simulated)."""
    names = {robot.name for robot in robots}
    return [f"world model '{r.name}' is a robot (not static, with joints) and is not simulated: "
            f"list it under robots: (- name: {r.name}) to drive it" for r in world.robots
            if r.name not in names]


def _source(detected: DriveSpec, fields: dict[str, Any]) -> str:
    layout = {"left_joints", "right_joints", "wheel_radius", "wheel_separation"}
    return "scenario" if layout <= fields.keys() else detected.source
