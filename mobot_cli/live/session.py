"""What the live world knows between steps: its World, the plans of its robots and the record.

The server owns the socket and the clock; everything a request does to the world goes
through here, on the world's own thread. Nothing here talks to ZeroMQ.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from mobot_cli.errors import MobotError, SimulationFault, did_you_mean
from mobot_cli.live import protocol, schema, spawning
from mobot_cli.live.protocol import Refusal, Result
from mobot_cli.live.recorder import Recorder
from mobot_cli.run.timeline import apply_event
from mobot_cli.scenario.units import steps
from mobot_cli.sim.plan import Event, Plan, RobotPlan
from mobot_cli.sim.world import FLOOR_OF_THE_WORLD, World


class Session:
    """One live World with its robots' plans, pending `cmd --for` stops and the recorder."""

    def __init__(self, plan: Plan, world: World, recorder: Recorder | None = None):
        self.plan, self.world, self.recorder = plan, world, recorder
        self.rate_hz = plan.physics.rate_hz
        self.robots: dict[str, RobotPlan] = {}  # the plans of the robots in the world
        self.stops: dict[str, int] = {}  # robot -> step at which its `cmd --for` ends
        self.static_names = frozenset(body.name for body in plan.world.bodies)

    def taken(self) -> set[str]:
        """Entity names in use: robots and the world's static models."""
        return set(self.robots) | self.static_names

    @property
    def step(self) -> int:
        return self.world.step_count

    # -- spawning and deleting --------------------------------------------------------------

    def start(self) -> None:
        """Spawn the scenario's own robots."""
        for robot in self.plan.robots:
            self.world.spawn(robot)
            self._added(robot, "scenario")

    def place(self, request: schema.Spawn, plan: RobotPlan, notices: list[str]) -> dict[str, Any]:
        """Name, frame and spawn a loaded robot now; the reply says where it is."""
        step = self.step
        name = spawning.final_name(request, self.taken())
        taken = {robot.namespace: n for n, robot in self.robots.items()}
        plan = spawning.named(plan, name, request.namespace, taken)
        reference = self.reference(request)
        if reference is not None:
            plan = dataclasses.replace(plan, pose=spawning.in_frame(plan.pose, self.world.read(reference)))
        plan = dataclasses.replace(plan, spawn_step=step)
        apply_event(self.world, Event(step=step, spawn=plan))  # the scenario events' path
        self._added(plan, "request", requested=request.name)
        return protocol.reply(request.id, name=name, namespace=plan.namespace, frame_prefix=plan.frame_prefix,
                              renamed=name != request.name, step=step, t=step / self.rate_hz,
                              pose=spawning.pose_fields(self.world.read(name)), source=plan.source,
                              notices=list(dict.fromkeys(notices)))

    def scripted(self, event: Event) -> None:
        """A scenario event; one that a live request made impossible is skipped and recorded."""
        when = f"event at {event.step / self.rate_hz:g} s"
        try:
            if event.spawn is not None:
                taken = {robot.namespace: n for n, robot in self.robots.items()}
                if event.spawn.name in self.robots or event.spawn.namespace in taken:
                    raise Refusal(Result.NAME_NOT_UNIQUE, f"robot '{event.spawn.name}' or namespace "
                                  f"'{event.spawn.namespace}' is already in the world")
                apply_event(self.world, event)
                self._added(event.spawn, "scenario")
            else:
                self.known(event.delete)
                self.remove(event.delete, "scenario")
        except (Refusal, MobotError) as exc:
            result = exc.result if isinstance(exc, Refusal) else spawning.classify(exc)
            self.history(op="event", result=result.name, message=f"{when} skipped: {exc}")

    def _added(self, plan: RobotPlan, how: str, requested: str | None = None) -> None:
        self.robots[plan.name] = plan
        if self.recorder:
            self.recorder.spawned(plan.name, self.step, plan.namespace, plan.source)
        pose = spawning.pose_fields(self.world.read(plan.name))
        self.history(op="spawn", name=plan.name, by=how, result="OK", namespace=plan.namespace,
                     source=plan.source, pose=pose, **({"requested": requested} if requested else {}))

    def remove(self, name: str, how: str, message: str | None = None) -> None:
        """Delete a robot (a request, or a fault took it out of the world)."""
        apply_event(self.world, Event(step=self.step, delete=name))
        self.robots.pop(name, None)
        self.stops.pop(name, None)
        if self.recorder:
            self.recorder.deleted(name, self.step)
        self.history(op="delete", name=name, by=how, result="OK", **({"message": message} if message else {}))

    # -- commands ---------------------------------------------------------------------------

    def command(self, request: schema.Cmd) -> int | None:
        """Apply a twist now; returns the step at which a `for` ends it with a stop."""
        self.known(request.name)
        if not self.world.has_drive(request.name):
            raise Refusal(Result.OPERATION_FAILED, f"robot '{request.name}' has no drive wheels: it does "
                          "not take velocity commands")
        self.world.set_command(request.name, request.linear, request.angular)
        self.stops.pop(request.name, None)
        until = None
        if request.for_ is not None:
            until = self.step + max(1, steps(request.for_, self.rate_hz))
            self.stops[request.name] = until
        self.history(op="cmd", name=request.name, result="OK", linear=request.linear, angular=request.angular,
                     **{"for": request.for_})
        return until

    def due_stops(self) -> None:
        """Stop the robots whose `cmd --for` ends at this step."""
        for name, until in list(self.stops.items()):
            if self.step >= until:
                del self.stops[name]
                self.world.set_command(name, 0.0, 0.0)

    def fault(self, exc: SimulationFault) -> bool:
        """Remove robots whose state went bad; False when none can be blamed."""
        bad = [name for name in self.world.names() if not _healthy(self.world, name)]
        for name in bad:
            self.remove(name, "fault", message=str(exc))
        return bool(bad)

    # -- replies ----------------------------------------------------------------------------

    def listing(self, request_id: Any) -> dict[str, Any]:
        """Every robot's name, namespace, pose and command."""
        robots = []
        for name in self.world.names():
            state = self.world.read(name)
            robots.append({"name": name, "namespace": self.robots[name].namespace,
                           "pose": spawning.pose_fields(state), "has_drive": self.world.has_drive(name),
                           "cmd": {"linear": state.cmd_linear, "angular": state.cmd_angular}})
        return protocol.reply(request_id, step=self.step, t=self.step / self.rate_hz, robots=robots)

    def odometry(self, request_id: Any, name: str) -> dict[str, Any]:
        """One robot's odometry (odom frame = spawn pose), ground truth and command now."""
        self.known(name)
        robot, s = self.robots[name], self.world.read(name)
        return protocol.reply(
            request_id, name=name, namespace=robot.namespace, step=self.step, t=self.step / self.rate_hz,
            frame_id=robot.frame_prefix + "odom", child_frame_id=robot.frame_prefix + robot.root_link,
            odom={"x": s.odom_x, "y": s.odom_y, "yaw": s.odom_yaw, "vx": s.odom_vx, "wz": s.odom_wz},
            truth={"x": s.true_x, "y": s.true_y, "z": s.true_z, "roll": s.true_roll, "pitch": s.true_pitch,
                   "yaw": s.true_yaw, "vx": s.true_vx, "wz": s.true_wz},
            cmd={"linear": s.cmd_linear, "angular": s.cmd_angular})

    # -- checks and records -----------------------------------------------------------------

    def known(self, name: str) -> None:
        """NOT_FOUND unless a robot of that name is in the world."""
        if name not in self.robots:
            hint = did_you_mean(name, self.robots) or "`mobot list` shows the robots."
            raise Refusal(Result.NOT_FOUND, f"no robot named '{name}'. {hint}")

    def reference(self, request: schema.Spawn) -> str | None:
        """The robot a spawn pose is relative to; None for the world frame."""
        ref = request.reference_frame
        if ref in (None, "", "world"):
            return None
        if ref not in self.robots:
            raise Refusal(Result.NOT_FOUND, f"reference frame '{ref}' is not a robot in the world. "
                          + (did_you_mean(ref, self.robots) or "Use 'world' or a robot's name."))
        return ref

    def history(self, **record: Any) -> None:
        """One line in history.jsonl when recording."""
        if self.recorder:
            self.recorder.history(self.step, record)


def _healthy(world: World, name: str) -> bool:
    state = world.read(name)
    values = (state.true_x, state.true_y, state.true_z)
    return all(math.isfinite(v) for v in values) and state.true_z > FLOOR_OF_THE_WORLD
