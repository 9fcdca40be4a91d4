"""The one timeline every door drives: `mobot run`, `mobot serve` and whatever steps a world.

A Timeline owns the order of things within a physics step: scripted events, then the command
scripts and the ends of timed commands, then the goal drivers (timeline/goals.py), then the log row,
then the sensor readings due; requests of a live world enter between steps through the same
``spawn``, ``delete``, ``command`` and ``goto`` a script uses. It never writes files: it hands
records (``Spawned``, ``Deleted``, ``Sample``, ``Reading``, ``GoalStarted``, ``GoalEnded``) to
consumers, and the run folder's writers take them from there. A sensor reads at its own rate:
at its robot's spawn step and every ``every`` steps after it, all sensors due at one step
computed together. Inputs from other threads (a ROS 2 ``/cmd_vel``) queue up and enter through
an input polled at the start of every ``tick``, on the world's own thread, whichever loop drives it.
"""

from __future__ import annotations

import dataclasses
from collections import defaultdict
from typing import Callable, Iterator, Protocol

from mobot_cli.errors import MobotError, SpawnError
from mobot_cli.plan import CommandStep, Event, GoalStep, MoverPlan, Plan, RobotPlan, SensorSpec
from mobot_cli.sim.bullet.world import World
from mobot_cli.sim.clearance import REACH_MARGIN
from mobot_cli.sim.engine import world_for
from mobot_cli.timeline.goals import Driver
from mobot_cli.timeline.metrics import REACH as METRICS_REACH
from mobot_cli.timeline.records import Consumer, Deleted, Reading, Record, Sample, Spawned


class Attachment(Protocol):
    """Something that rides along a timeline, such as the ROS 2 bridge: ``open`` attaches its
    consumer and inputs, ``close`` ends it after the last step."""

    def open(self, timeline: "Timeline") -> None: ...

    def close(self) -> None: ...

    def flush(self) -> None:
        """Send what it holds back now: the world is about to wait (a paused live world)."""


class NameTaken(SpawnError):
    """A robot's name or namespace is already in the world."""


class NotInWorld(MobotError):
    """No robot of that name is in the world."""


class Timeline:
    """``plan``'s world on one clock: spawns, deletes, command scripts and the log cadence."""

    def __init__(self, plan: Plan, world: World, on_refused: Callable[[Event, MobotError], None] | None = None):
        self.plan, self.world = plan, world
        self.rate_hz = plan.physics.rate_hz
        self.robots: dict[str, RobotPlan] = {}  # the plans of the robots in the world, in spawn order
        self._namespaces: set[str] = set()  # theirs (a fleet's spawns: not N^2 looks)
        self._held: list[Record] | None = []  # records made before a consumer is attached
        self._consumers: list[Consumer] = []
        self._consume: Consumer = self._held.append
        self._inputs: list[Callable[[], None]] = []
        self._on_refused = on_refused  # None: a refused scripted event ends the run
        # Said during the run (the ROS 2 bridge's drops, the world's stalled wheels): summary.json's,
        # after the plan's. The world's own list, so what the world says is in it too.
        self.notices: list[str] = world.notices
        self.resets = 0
        # ``advance()``: one physics step. The world's own step, bound once: no call in between on
        # every step (the world of a timeline is never replaced).
        self.advance: Callable[[], None] = world.step
        self._schedule()

    def _schedule(self) -> None:
        """What the plan has due, from t = 0 on: its events, command scripts and log cadence."""
        plan = self.plan
        self._events: dict[int, list[Event]] = defaultdict(list)
        self._commands: dict[int, list[tuple[str, float, float, float]]] = defaultdict(list)
        self._stops: dict[str, int] = {}  # robot -> step at which its timed command ends
        self._drivers: dict[str, Driver] = {}  # robot -> the driver of its goals (and what follows them)
        self._logged = -1  # the step of the last complete sample
        self._ticked = -1  # the step of the last tick
        self._log_every, self._total = plan.log_every, plan.total_steps
        # step -> the sensors due then: (robot name, its plan, sensor); empty without sensors
        self._due: dict[int, list[tuple[str, RobotPlan, SensorSpec]]] = {}
        # readings sensed ahead of this step's tick, with the plan of the robot each is of
        self._early: tuple[int, list[tuple[RobotPlan, Reading]]] | None = None
        # robot name (or "all") -> how far its clearance is measured, for `clearance` expectations
        self._clearance: dict[str, float] = {}
        for exp in plan.expectations:
            if exp.kind == "clearance":
                reach = exp.limit("min") + REACH_MARGIN
                self._clearance[exp.robot] = max(reach, self._clearance.get(exp.robot, 0.0))
        for event in plan.events:
            self._events[event.step].append(event)
        self._movers: dict[int, list] = defaultdict(list)  # step -> the scenario's movers entering then
        for mover in plan.movers:
            self._movers[mover.spawn_step].append(mover)
        self._moving = bool(plan.world.actors or plan.movers)  # log rows carry the movers' poses
        self._movers_logged = -1  # world.movers_moved() when they were last on a log row
        spawned = [event.spawn for event in plan.events if event.spawn is not None]
        for robot in (*plan.robots, *spawned):
            for cmd in robot.commands:
                if isinstance(cmd, CommandStep):  # goals and what follows them: a Driver's
                    self._commands[cmd.step].append((robot.name, cmd.linear, cmd.angular, cmd.linear_y))

    @property
    def step(self) -> int:
        """Physics steps taken since t = 0."""
        return self.world.step_count

    @property
    def finished(self) -> bool:
        """The plan's duration is over (a live world may go on past it)."""
        return self.step >= self.plan.total_steps

    def attach(self, consumer: Consumer) -> None:
        """Send every record to ``consumer`` from now on; the first one attached also gets the
        records made before (the spawns of ``start``)."""
        if self._held is not None:
            held, self._held = self._held, None
            self._consumers = [consumer]
            for record in held:
                consumer(record)
        else:
            self._consumers.append(consumer)
        consumers = self._consumers
        self._consume = consumers[0] if len(consumers) == 1 else lambda r: [c(r) for c in consumers]

    def add_input(self, poll: Callable[[], None]) -> None:
        """Call ``poll`` at the start of every tick, on this thread; it may command, spawn or
        delete (a thread-safe queue drained here is how other threads reach the world)."""
        self._inputs.append(poll)

    def start(self, by: str = "scenario") -> None:
        """Spawn the plan's own robots at t = 0."""
        for robot in self.plan.robots:
            self.spawn(robot, by)

    def reset(self) -> None:
        """Back to t = 0 as the plan starts (ResetSimulation's SCOPE_ALL): every robot leaves
        (its last row, then ``Deleted`` by "reset"), the world is rebuilt at step 0, scripts and
        events start over and the plan's robots are spawned again (``Spawned`` by "reset").
        The caller ticks step 0, as a loop does after ``start``."""
        for name in list(self.robots):
            self.delete(name, "reset")
        self.world.reset()
        self._schedule()
        self.resets += 1
        self.start("reset")

    def tick(self) -> None:
        """Everything due at the current step, in order: inputs, events, commands, ends of timed
        commands, the log row, sensor readings."""
        # Runs every physics step: each check is one dict lookup or one truth test.
        step = self.world.step_count
        if self._inputs:
            for poll in self._inputs:
                poll()
        if step in self._events:
            for event in self._events[step]:
                self._scripted(event)
        if step in self._movers:
            for mover in self._movers[step]:
                self.world.add_mover(mover)
        if step in self._commands:
            for name, linear, angular, linear_y in self._commands[step]:
                if name in self.robots:  # a live world may have deleted it meanwhile
                    self.world.set_command(name, linear, angular, linear_y)
        if self._stops:
            for name, until in list(self._stops.items()):
                if step >= until:
                    del self._stops[name]
                    self.world.set_command(name, 0.0, 0.0)
        if self._drivers:
            self._drive(step)
        if step % self._log_every == 0 or step == self._total:
            self._log(step)
        if self._early is not None:
            self._hand_early(step)
        if self._due:
            due = self._due.pop(step, None)
            if due:
                self._read(step, due)
        self._ticked = step

    def idle(self) -> bool:
        """Nothing is due but log rows: no events, commands, goals, sensors, movers or inputs."""
        return not (self._events or self._commands or self._stops or self._drivers or self._due or self._early
                    or self._movers or self._moving or self._inputs or self._clearance)

    def marks(self) -> tuple[int, int]:
        """The last log row's step and the last tick's (sim/bullet/settled.py keeps them)."""
        return self._logged, self._ticked

    def restore_marks(self, marks: tuple[int, int]) -> None:
        """Put back what ``marks`` gave, with the world's state of that time."""
        self._logged, self._ticked = marks

    def sense_early(self) -> list[Reading]:
        """Take the readings due at this step now, before its tick, and return them (once); the tick
        hands them to the consumers in their usual place (after the log row), so every record
        is as a plain tick makes it. The world does not move before the tick and each sensor has
        its own noise generator, so the readings are the same; not at a step where an input or
        a scenario event could change the world first (then: none)."""
        step = self.step
        if step not in self._due or self._ticked == step or step in self._events or self._inputs:
            return []
        due = [entry for entry in self._due.pop(step) if self.robots.get(entry[0]) is entry[1]]
        data = self.world.sense([(name, sensor.name) for name, _, sensor in due]) if due else []
        taken = [(robot, Reading(step, name, sensor, reading)) for (name, robot, sensor), reading in zip(due, data)]
        for name, robot, sensor in due:
            self._due.setdefault(step + max(1, sensor.every), []).append((name, robot, sensor))
        self._early = (step, taken)
        return [reading for _, reading in taken]

    def _hand_early(self, step: int) -> None:
        early_step, readings = self._early
        self._early = None
        if early_step != step:
            return
        for robot, reading in readings:
            if self.robots.get(reading.robot) is robot:  # not deleted (or replaced) since it was sensed
                self._consume(reading)
                driver = self._drivers.get(reading.robot)
                if driver is not None and driver.sees:
                    driver.see(reading.sensor, reading.data)

    def _drive(self, step: int) -> None:
        for name, driver in list(self._drivers.items()):
            if 0 <= driver.wake <= step:
                driver.tick(step)
            if driver.finished:
                del self._drivers[name]

    def log(self) -> None:
        """A complete sample now, once per step."""
        self._log(self.world.step_count)

    def _log(self, step: int) -> None:
        if self._logged != step:
            self._logged = step
            movers = None
            if self._moving and self.world.movers_moved() != self._movers_logged:
                self._movers_logged = self.world.movers_moved()
                movers = self.world.movers()
            self._consume(Sample(step, self.world.states(self.robots), True, movers))

    def _read(self, step: int, due: list[tuple[str, RobotPlan, SensorSpec]]) -> None:
        """Take the readings due now (of robots still in the world) and schedule the next ones."""
        # Once per reading (a 10 Hz lidar: every 24th step): each line is one look-up or call.
        robots, consume, later = self.robots, self._consume, self._due
        due = [entry for entry in due if robots.get(entry[0]) is entry[1]]
        if not due:
            return
        data = self.world.sense([(entry[0], entry[2].name) for entry in due])
        drivers = self._drivers
        for entry, reading in zip(due, data):
            sensor = entry[2]
            consume(Reading(step, entry[0], sensor, reading))
            driver = drivers.get(entry[0])
            if driver is not None and driver.sees:  # a goal avoiding obstacles on this lidar
                driver.see(sensor, reading)
            later.setdefault(step + max(1, sensor.every), []).append(entry)

    # -- what events and requests do --------------------------------------------------------

    def spawn(self, robot: RobotPlan, by: str) -> None:
        """Place a robot now (SpawnError when refused); it gets a row at once unless the log
        row of this step is still to come."""
        if robot.name in self.robots or robot.namespace in self._namespaces:
            raise NameTaken(f"robot '{robot.name}' or namespace '{robot.namespace}' is already in the world")
        self.world.spawn(robot)
        self.robots[robot.name] = robot
        self._namespaces.add(robot.namespace)
        if self._clearance:
            reach = max(self._clearance.get(robot.name, 0.0), self._clearance.get("all", 0.0))
            if reach:
                self.world.watch_clearance(robot.name, reach)
        if any(isinstance(cmd, GoalStep) for cmd in robot.commands):
            self.world.watch_clearance(robot.name, METRICS_REACH)  # the goals' metrics
        state = self.world.read(robot.name)
        self._consume(Spawned(self.step, robot, by, state))
        script = [cmd for cmd in robot.commands if not isinstance(cmd, CommandStep)]
        if script:
            self._drivers[robot.name] = self._driver(robot.name, script)
        if self._logged == self.step or self.step % self.plan.log_every:
            self._consume(Sample(self.step, {robot.name: state}, complete=False))
        late = self._ticked == self.step  # a live spawn after this step's tick: one period on
        for sensor in robot.sensors:
            at = self.step + max(1, sensor.every) if late else self.step
            self._due.setdefault(at, []).append((robot.name, robot, sensor))

    def delete(self, name: str, by: str, message: str | None = None, last_row: bool = True) -> None:
        """Take a robot out now; its state at this step is its last row (unless its state broke)."""
        if last_row and self._logged != self.step:
            self._consume(Sample(self.step, {name: self.world.read(name)}, complete=False))
        self._cancel(name)
        self.world.remove(name)
        self._namespaces.discard(self.robots.pop(name).namespace)
        self._stops.pop(name, None)
        self._consume(Deleted(self.step, name, by, message))

    def command(self, name: str, linear: float, angular: float, steps: int | None = None,
                linear_y: float = 0.0) -> int | None:
        """Hold a twist (``linear_y``: sideways, holonomic drives only); with ``steps``, stop after
        that many steps. Returns the stop step. A goal the robot is driving to ends ``cancelled``;
        a twist the drive cannot follow is a ValueError and changes nothing."""
        if linear_y:
            self.world.set_command(name, linear, angular, linear_y)  # refused before any goal ends
        self._cancel(name)
        self.world.set_command(name, linear, angular, linear_y)
        self._stops.pop(name, None)
        if steps is None:
            return None
        until = self._stops[name] = self.step + max(1, steps)
        return until

    def goto(self, name: str, goal: GoalStep) -> None:
        """Start driving to ``goal`` now (a goal already running ends ``cancelled``)."""
        self._cancel(name)
        self._stops.pop(name, None)
        self.world.watch_clearance(name, METRICS_REACH)  # the goal's metrics
        driver = self._drivers[name] = self._driver(name, [dataclasses.replace(goal, step=self.step)])
        driver.tick(self.step)

    def _driver(self, name: str, script: list) -> Driver:
        # Records go through self._consume as it is when they are made (a consumer may attach later).
        return Driver(name, script, self.world, self.rate_hz, lambda record: self._consume(record), self.plan.world,
                      self.robots[name].footprint)

    def _cancel(self, name: str) -> None:
        driver = self._drivers.pop(name, None)
        if driver is not None:
            driver.cancel(self.step)

    def add_mover(self, mover: MoverPlan) -> None:
        """A mover enters the world now (SpawnError: its name is taken); log rows carry it from now on."""
        self.world.add_mover(dataclasses.replace(mover, spawn_step=self.step))
        self._moving = True

    def remove_mover(self, name: str) -> None:
        """A mover leaves the world now (NotInWorld: there is none of that name)."""
        try:
            self.world.remove_mover(name)
        except KeyError:
            raise NotInWorld(f"no mover named '{name}' is in the world") from None

    def apply(self, event: Event, by: str) -> None:
        """One spawn or delete event: the path scenario events and live requests share."""
        if event.spawn is not None:
            self.spawn(event.spawn, by)
        else:
            if event.delete not in self.robots:
                raise NotInWorld(f"no robot named '{event.delete}' is in the world")
            self.delete(event.delete, by)

    def _scripted(self, event: Event) -> None:
        try:
            self.apply(event, "scenario")
        except MobotError as exc:
            if self._on_refused is None:
                raise type(exc)(f"event at {event.step / self.rate_hz:g} s: {exc.message}",
                                location=exc.location, hint=exc.hint) from None
            self._on_refused(event, exc)


def simulate(plan: Plan) -> Iterator[Record]:
    """Play ``plan`` in a world of its own from start to end, yielding its records as they come."""
    with world_for(plan) as world:
        records: list[Record] = []
        timeline = Timeline(plan, world)
        timeline.attach(records.append)
        timeline.start()
        tick, advance = timeline.tick, timeline.advance
        for _ in range(plan.total_steps):
            tick()
            if records:
                yield from records
                records.clear()
            advance()
        tick()
        yield from records
