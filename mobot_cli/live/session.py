"""What the live world knows between steps: its timeline, the record and the history.

The server owns the socket and the clock; everything a request does to the world goes
through here, on the world's own thread, and into the same Timeline `mobot run` plays.
Nothing here talks to ZeroMQ.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any, Callable

from mobot_cli.errors import MobotError, SimulationFault, SpawnError, did_you_mean
from mobot_cli.live import entity_state, protocol, schema, spawning
from mobot_cli.live.history import History
from mobot_cli.live.protocol import Refusal, Result
from mobot_cli.live.readings import LatestReadings
from mobot_cli.plan import Event, Plan, RobotPlan
from mobot_cli.record.recording import Recording
from mobot_cli.record.summary import LiveInfo, RunRecord, Status
from mobot_cli.scenario.goal_model import GoalFields, GotoSpec
from mobot_cli.scenario.goals import goal_step
from mobot_cli.scenario.mover_model import MAX_MOVERS
from mobot_cli.scenario.movers import mover_plan
from mobot_cli.scenario.units import spawn_pose, steps
from mobot_cli.sim.bullet.faults import FLOOR_OF_THE_WORLD
from mobot_cli.sim.bullet.world import World
from mobot_cli.sim.holonomic import KINDS as HOLONOMIC
from mobot_cli.timeline.goals import GoalEnded, GoalStarted
from mobot_cli.timeline.loop import NotInWorld, Timeline
from mobot_cli.timeline.records import Deleted, Record, Spawned

LIVE_GOAL = -1  # the command index of a goal a live request gave (not one of the scenario's)


class Session:
    """One live World on its Timeline, with the optional record (``out_dir``) and history."""

    def __init__(self, plan: Plan, world: World, out_dir: Path | None = None, resolved_yaml: str = ""):
        self.plan, self.world = plan, world
        self.rate_hz = plan.physics.rate_hz
        self.static_names = frozenset(body.name for body in plan.world.bodies)
        self.timeline = Timeline(plan, world, on_refused=self._refused)
        self.recording = Recording(plan, out_dir, resolved_yaml) if out_dir is not None else None
        self.history_file = History(out_dir, self.rate_hz) if out_dir is not None else None
        self.readings = LatestReadings()
        self.timeline.attach(self._record)
        # goto --wait: robot -> what to call when its goal ends (armed once that goal started)
        self._goal_waits: dict[str, tuple[Any, Callable[[dict[str, Any]], None]]] = {}
        self._armed: dict[str, tuple[Any, Callable[[dict[str, Any]], None]]] = {}

    @property
    def robots(self) -> dict[str, RobotPlan]:
        """The plans of the robots in the world."""
        return self.timeline.robots

    @property
    def step(self) -> int:
        return self.world.step_count

    def start(self) -> None:
        """Spawn the scenario's own robots."""
        self.timeline.start()

    def taken(self) -> set[str]:
        """Entity names in use: robots and the world's static models."""
        return set(self.robots) | self.static_names

    def _record(self, record: Record) -> None:
        if self.recording is not None:
            self.recording(record)
        self.readings.take(record)
        if isinstance(record, Spawned):
            self.history(op="spawn", name=record.robot.name, by=record.by, result="OK",
                         namespace=record.robot.namespace, source=record.robot.source,
                         pose=spawning.pose_fields(record.state))
        elif isinstance(record, Deleted):
            self.history(op="delete", name=record.name, by=record.by, result="OK",
                         **({"message": record.message} if record.message else {}))
        elif isinstance(record, GoalStarted) and record.robot in self._goal_waits:
            self._armed[record.robot] = self._goal_waits.pop(record.robot)
        elif isinstance(record, GoalEnded) and record.robot in self._armed:
            request_id, done = self._armed.pop(record.robot)
            done(self._goal_reply(request_id, record))

    def _refused(self, event: Event, exc: MobotError) -> None:
        """A scenario event that a live request made impossible is skipped and recorded."""
        when = f"event at {event.step / self.rate_hz:g} s"
        self.history(op="event", result=spawning.classify(exc).name, message=f"{when} skipped: {exc}")

    # -- spawning and deleting --------------------------------------------------------------

    def place(self, request: schema.Spawn, plan: RobotPlan, notices: list[str]) -> dict[str, Any]:
        """Name, frame and spawn a loaded robot now; the reply says where it is."""
        step = self.step
        name = spawning.final_name(request, self.taken())
        taken = {robot.namespace: n for n, robot in self.robots.items()}
        plan = spawning.named(plan, name, request.namespace, taken)
        reference = self.reference(request.reference_frame)
        if reference is not None:
            plan = dataclasses.replace(plan, pose=spawning.in_frame(plan.pose, self.world.read(reference)))
        plan = dataclasses.replace(plan, spawn_step=step)
        self.timeline.apply(Event(step=step, spawn=plan), "request")  # the scenario events' path
        return protocol.reply(request.id, name=name, namespace=plan.namespace, frame_prefix=plan.frame_prefix,
                              renamed=name != request.name, step=step, t=step / self.rate_hz,
                              pose=spawning.pose_fields(self.world.read(name)), source=plan.source,
                              notices=list(dict.fromkeys(notices)))

    def remove(self, name: str) -> None:
        """Delete a robot on request."""
        self.known(name)
        self.timeline.apply(Event(step=self.step, delete=name), "request")

    def add_mover(self, spec) -> None:
        """A mover enters now (a scenario's movers: item, one, now); refused when its name is taken."""
        if spec.count is not None or spec.at:
            raise Refusal(Result.INVALID_REQUEST, "spawn_mover adds one mover, now: no 'count', no 'at'")
        if len(self.world.movers()) >= MAX_MOVERS:
            raise Refusal(Result.LIMIT_EXCEEDED, f"the world holds {MAX_MOVERS} movers already")
        try:
            self.timeline.add_mover(mover_plan(spec, spec.name, self.rate_hz, source="request"))
        except SpawnError as exc:
            raise Refusal(Result.NAME_NOT_UNIQUE, exc.message) from None
        self.history(op="spawn_mover", name=spec.name, result="OK")

    def remove_mover(self, name: str) -> None:
        """A mover leaves now; NOT_FOUND when there is none of that name."""
        try:
            self.timeline.remove_mover(name)
        except NotInWorld as exc:
            raise Refusal(Result.NOT_FOUND, exc.message) from None
        self.history(op="delete_mover", name=name, result="OK")

    # -- commands ---------------------------------------------------------------------------

    def command(self, request: schema.Cmd) -> int | None:
        """Apply a twist now; returns the step at which a `for` ends it with a stop."""
        self.known(request.name)
        if not self.world.has_drive(request.name):
            raise Refusal(Result.OPERATION_FAILED, f"robot '{request.name}' has no drive wheels: it does "
                          "not take velocity commands")
        span = None if request.for_ is None else steps(request.for_, self.rate_hz)
        try:
            until = self.timeline.command(request.name, request.linear, request.angular, span, request.linear_y)
        except ValueError as exc:  # a sideways command to a robot that is not holonomic
            raise Refusal(Result.OPERATION_FAILED, str(exc)) from None
        sideways = {"linear_y": request.linear_y} if request.linear_y else {}
        self.history(op="cmd", name=request.name, result="OK", linear=request.linear, angular=request.angular,
                     **sideways, **{"for": request.for_})
        return until

    def goto(self, request: schema.Goto, done: Callable[[dict[str, Any]], None] | None = None) -> dict[str, Any]:
        """Start driving to a goal now (a goal already running ends 'cancelled'); ``done`` gets
        the reply when it ends. Refused for a goal inside an obstacle."""
        self.known(request.name)
        if not self.world.has_drive(request.name):
            raise Refusal(Result.OPERATION_FAILED,
                          f"robot '{request.name}' has no drive wheels: it cannot drive to a goal")
        try:
            fields = GoalFields(goto=GotoSpec(x=request.x, y=request.y, yaw=request.yaw, tolerance=request.tolerance),
                                timeout=request.timeout, localization=request.localization,
                                max_linear=request.max_linear, max_angular=request.max_angular,
                                planner=request.planner, inflation=request.inflation)
            state = self.world.read(request.name)
            goal = goal_step(fields, self.step, LIVE_GOAL, self.rate_hz, self.plan.world,
                             self.robots[request.name].footprint, lambda key: None, [],
                             start=(state.true_x, state.true_y, state.true_z))
        except (MobotError, ValueError) as exc:
            message = exc.message if isinstance(exc, MobotError) else str(exc).splitlines()[-1].strip()
            raise Refusal(Result.INVALID_REQUEST, f"goto request: {message}") from None
        if done is not None:
            self._goal_waits[request.name] = (request.id, done)
        self.timeline.goto(request.name, goal)
        self.history(op="goto", name=request.name, result="OK", x=request.x, y=request.y, yaw=request.yaw)
        return protocol.reply(request.id, name=request.name, step=self.step, t=self.step / self.rate_hz,
                              x=request.x, y=request.y, yaw=request.yaw)

    def _goal_reply(self, request_id: Any, ended: GoalEnded) -> dict[str, Any]:
        """How a goal ended, and where the robot is."""
        state = self.world.read(ended.robot) if ended.robot in self.robots else None
        return protocol.reply(request_id, name=ended.robot, step=ended.step, t=ended.step / self.rate_hz,
                              status=ended.status,
                              time=(ended.step - ended.started) / self.rate_hz,
                              error=ended.error if math.isfinite(ended.error) else None,
                              pose=spawning.pose_fields(state) if state is not None else None,
                              **({"reason": ended.reason} if ended.reason else {}))

    # -- lockstep: reset, entity states --------------------------------------------------------

    def reset(self) -> None:
        """ResetSimulation: the plan's world at t = 0 again, its step 0 ticked (the loop goes on
        from there). history.jsonl says so first; the robots' lives end and start again in the record."""
        self.history(op="reset", result="OK", resets=self.timeline.resets + 1)
        self.timeline.reset()
        self.timeline.tick()

    def entity_state(self, request_id: Any, name: str, reference_frame: str | None) -> dict[str, Any]:
        """GetEntityState: a robot's pose and twist in the world or a robot's frame."""
        self.known(name)
        ref = self.reference(reference_frame)
        state = entity_state.relative(self.world.kinematics(name),
                                      None if ref is None else self.world.kinematics(ref))
        return protocol.reply(request_id, name=name, reference_frame=ref or "world", step=self.step,
                              t=self.step / self.rate_hz, **entity_state.fields(state))

    def teleport(self, request: schema.SetState) -> dict[str, Any]:
        """SetEntityState: move a robot (checked like a spawn: INVALID_POSE) and set its twist."""
        self.known(request.name)
        ref = self.reference(request.reference_frame)
        pose = spawn_pose(request.pose)
        frame = None if ref is None else self.world.kinematics(ref)
        if ref is not None:
            pose = spawning.in_frame(pose, self.world.read(ref))
        twist = request.twist
        linear, angular = entity_state.world_twist(
            pose.xyz, (twist.linear.x, twist.linear.y, twist.linear.z),
            (twist.angular.x, twist.angular.y, twist.angular.z), frame)
        try:
            self.world.teleport(request.name, pose, linear, angular)
        except MobotError as exc:
            raise Refusal(Result.INVALID_POSE, str(exc)) from None
        state = self.world.kinematics(request.name)
        self.history(op="set_state", name=request.name, result="OK",
                     pose=spawning.pose_fields(self.world.read(request.name)))
        return protocol.reply(request.id, name=request.name, reference_frame="world", step=self.step,
                              t=self.step / self.rate_hz, **entity_state.fields(state))

    def states(self) -> list[dict[str, Any]]:
        """Every robot's world pose and twist, in spawn order (a step's reply)."""
        return [{"name": name, **entity_state.fields(self.world.kinematics(name))} for name in self.robots]

    def fault(self, exc: SimulationFault) -> bool:
        """Remove the robot the fault names (or those whose state went bad); False when none can be blamed."""
        names = self.world.names()
        bad = [exc.robot] if exc.robot in names else [name for name in names if not _healthy(self.world, name)]
        for name in bad:
            self.timeline.delete(name, "fault", message=str(exc), last_row=False)
            self.timeline.notices.append(f"robot '{name}' was taken out of the live world: {exc}")
        return bool(bad)

    # -- replies ----------------------------------------------------------------------------

    def listing(self, request_id: Any) -> dict[str, Any]:
        """Every robot's name, namespace, pose and command."""
        robots = []
        for name in self.world.names():
            state = self.world.read(name)
            robots.append({"name": name, "namespace": self.robots[name].namespace,
                           "pose": spawning.pose_fields(state), "has_drive": self.world.has_drive(name),
                           "cmd": self._cmd_fields(name, state), "bounds": _bounds(self.robots[name])})
        return protocol.reply(request_id, step=self.step, t=self.step / self.rate_hz, robots=robots)

    def odometry(self, request_id: Any, name: str) -> dict[str, Any]:
        """One robot's odometry (odom frame = spawn pose), ground truth and command now."""
        self.known(name)
        robot, s = self.robots[name], self.world.read(name)
        odom = {"x": s.odom_x, "y": s.odom_y, "yaw": s.odom_yaw, "vx": s.odom_vx, "wz": s.odom_wz}
        truth = {"x": s.true_x, "y": s.true_y, "z": s.true_z, "roll": s.true_roll, "pitch": s.true_pitch,
                 "yaw": s.true_yaw, "vx": s.true_vx, "wz": s.true_wz}
        if self._holonomic(name):
            odom["vy"], truth["vy"] = s.odom_vy, s.true_vy
        return protocol.reply(
            request_id, name=name, namespace=robot.namespace, step=self.step, t=self.step / self.rate_hz,
            frame_id=robot.frame_prefix + "odom", child_frame_id=robot.frame_prefix + robot.root_link,
            odom=odom, truth=truth, cmd=self._cmd_fields(name, s))

    def _holonomic(self, name: str) -> bool:
        drive = self.robots[name].drive
        return drive is not None and drive.kind in HOLONOMIC

    def _cmd_fields(self, name: str, state) -> dict[str, float]:
        """The command a reply shows: linear and angular, and linear_y for a holonomic robot."""
        fields = {"linear": state.cmd_linear, "angular": state.cmd_angular}
        if self._holonomic(name):
            fields["linear_y"] = state.cmd_linear_y
        return fields

    def scan(self, request_id: Any, name: str, sensor: str | None) -> dict[str, Any]:
        """A robot's latest reading of one sensor (default: its first lidar)."""
        self.known(name)
        return protocol.reply(request_id, **self.readings.reply_fields(self.robots[name], sensor, self.rate_hz))

    # -- checks and records -----------------------------------------------------------------

    def known(self, name: str) -> None:
        """NOT_FOUND unless a robot of that name is in the world."""
        if name not in self.robots:
            hint = did_you_mean(name, self.robots) or "`mobot list` shows the robots."
            raise Refusal(Result.NOT_FOUND, f"no robot named '{name}'. {hint}")

    def reference(self, ref: str | None) -> str | None:
        """The robot a request's pose (or state) is relative to; None for the world frame."""
        if ref in (None, "", "world"):
            return None
        if ref not in self.robots:
            raise Refusal(Result.NOT_FOUND, f"reference frame '{ref}' is not a robot in the world. "
                          + (did_you_mean(ref, self.robots) or "Use 'world' or a robot's name."))
        return ref

    def history(self, **record: Any) -> None:
        """One line in history.jsonl when recording."""
        if self.history_file is not None:
            self.history_file.write(self.step, record)

    def close(self, status: Status, error: str | None, live: LiveInfo) -> RunRecord | None:
        """End the record: the state at the last step (unless the world broke), then summary.json."""
        if self.recording is None:
            return None
        self.history_file.close()
        if status != Status.FAULT:
            self.timeline.log()
        said = self.timeline.notices  # the world's list: the drives' and the bridge's
        return self.recording.close(status, error, self.step, live, said=said)


def _healthy(world: World, name: str) -> bool:
    state = world.read(name)
    values = (state.true_x, state.true_y, state.true_z)
    return all(math.isfinite(v) for v in values) and state.true_z > FLOOR_OF_THE_WORLD


def _bounds(robot) -> dict[str, list[float]] | None:
    """The box round a robot's collision geometry in its root link's frame (joints at zero), or
    None when its plan does not say."""
    if robot.footprint is None or robot.heights is None:
        return None
    (xmin, xmax, ymin, ymax), (zmin, zmax) = robot.footprint, robot.heights
    return {"min": [xmin, ymin, zmin], "max": [xmax, ymax, zmax]}
