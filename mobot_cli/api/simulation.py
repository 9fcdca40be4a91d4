"""A world on mobot's timeline, stepped by your own code: the Python door to `mobot run`.

The same Timeline that `mobot run` and `mobot serve` drive, with the same records: open a
scenario (or a bare world), command robots, step, read their odometry and ground truth,
spawn and delete, and get the run folder on close. A command given at step ``n`` is in force
from step ``n`` on, exactly as a scenario's ``{at: n / rate_hz, ...}`` command, so a loop that
sends a script's commands at the script's steps writes the same files as `mobot run`.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Iterable, Mapping

from pydantic import ValidationError

from mobot_cli.api.cameras import CameraImage, Wanted, image_of, pick_camera
from mobot_cli.api.numbers import bounded
from mobot_cli.api.sensors import Latest, Range, Scan, pick, range_of, robot_plan
from mobot_cli.errors import MobotError, SimulationFault, UsageError, did_you_mean
from mobot_cli.plan import Plan, RobotPlan
from mobot_cli.record.recording import Recording
from mobot_cli.record.summary import RunRecord, Status
from mobot_cli.scenario.goal_model import GoalFields, GotoSpec
from mobot_cli.scenario.goals import goal_step
from mobot_cli.scenario.limits import MAX_ANGULAR_SPEED, MAX_SECONDS, MAX_SPEED
from mobot_cli.scenario.prepare import Prepared, prepare_target
from mobot_cli.scenario.units import steps
from mobot_cli.sim.engine import world_for
from mobot_cli.sim.state import RobotState
from mobot_cli.timeline.goals import GoalEnded, GoalStarted
from mobot_cli.timeline.loop import Timeline
from mobot_cli.timeline.records import Reading


class Simulation:
    """One world on one timeline; use as a context manager, or call ``close()``."""

    def __init__(self, prepared: Prepared, out: Path | str | None = None):
        self.plan: Plan = prepared.plan
        self._world = world_for(self.plan)
        try:
            self._timeline = Timeline(self.plan, self._world)
            self._timeline.start()  # the robots are placed and checked before any file is written
            self._recording = None
            if out is not None:
                self._recording = Recording(self.plan, Path(out), prepared.resolved_yaml)
                self._timeline.attach(self._recording)
            else:
                self._timeline.attach(lambda record: None)
            self._goals: dict[str, GoalStarted | GoalEnded] = {}  # robot -> its last goal's record
            self._timeline.attach(self._goal_record)
            self._latest = Latest(self.plan.physics.rate_hz)  # every sensor's last reading
            self._timeline.attach(self._latest)
            self._cameras = Wanted()  # cameras asked for: rendered as their frames pass
            self._timeline.attach(self._cameras)
        except BaseException:
            self._world.close()
            raise
        self._base_dir = Path.cwd()
        self._closed = False
        self._fault: SimulationFault | None = None  # what ended it, for summary.json's fault record
        self.record: RunRecord | None = None

    @classmethod
    def open(cls, target: str | Path | None = None, *, out: Path | str | None = None,
             overrides: Iterable[str] = (), seed: int | None = None) -> "Simulation":
        """A scenario file (.yaml), or a world (bundled name or file) with no robots yet.

        ``overrides`` are ``--set`` items (``"robots.mobot.pose.x=2"``); ``out`` is the run
        folder written on close (None: no files).
        """
        items = list(overrides) + ([f"seed={seed}"] if seed is not None else [])
        return cls(prepare_target(None if target is None else str(target), items), out)

    # -- time -------------------------------------------------------------------------------

    @property
    def step_count(self) -> int:
        """Physics steps taken since t = 0."""
        return self._timeline.step

    @property
    def t(self) -> float:
        """Simulated seconds since t = 0 (whole steps)."""
        return self._timeline.step / self.plan.physics.rate_hz

    @property
    def rate_hz(self) -> int:
        return self.plan.physics.rate_hz

    def step(self, n: int = 1) -> None:
        """Advance ``n`` physics steps: what is due at each step (script, log row), then physics."""
        self._open()
        if isinstance(n, bool) or not isinstance(n, int) or n < 0:
            raise UsageError(f"step takes a whole number of steps >= 0, got {n!r}")
        timeline = self._timeline
        for _ in range(n):
            timeline.tick()
            timeline.advance()

    def run_for(self, seconds: float) -> None:
        """Advance ``seconds`` of simulated time (rounded to whole steps)."""
        self._open()
        self.step(steps(bounded("run_for: seconds", seconds, "s", MAX_SECONDS, low=0.0), self.rate_hz))

    def settle(self, seconds: float) -> None:
        """``run_for(seconds)``; in a Gymnasium env's reset, when this world holds the end of the
        same settle kept before, that state is put back instead of stepping: the same state, byte
        for byte (sim/bullet/settled.py)."""
        self._open()
        n = steps(bounded("settle: seconds", seconds, "s", MAX_SECONDS, low=0.0), self.rate_hz)
        timeline, world = self._timeline, self._world
        key = world.settle_key(n, (self.plan.log_every, self.plan.total_steps)) if timeline.idle() else None
        marks = world.resettle(key)
        if marks is not None:
            timeline.restore_marks(marks)
            return
        self.step(n)
        if key is not None:
            world.keep_settled(key, timeline.marks())

    # -- robots -----------------------------------------------------------------------------

    @property
    def robots(self) -> list[str]:
        """The names of the robots in the world, in spawn order."""
        return list(self._timeline.robots)

    def state(self, name: str) -> RobotState:
        """A robot's command, odometry (odom frame = its spawn pose) and ground truth now."""
        self._known(name)
        return self._world.read(name)

    def command(self, name: str, linear: float = 0.0, angular: float = 0.0, *,
                duration: float | None = None, linear_y: float = 0.0) -> None:
        """Hold a body twist (m/s, rad/s; ``linear_y`` sideways, holonomic robots only) from this
        step on; with ``duration``, stop after it."""
        self._known(name)
        if not self._world.has_drive(name):
            raise UsageError(f"robot '{name}' has no drive wheels: it does not take velocity commands")
        # Checked before the world sees them: a NaN or 1e308 twist would poison the robot's state.
        linear = bounded(f"command '{name}': linear", linear, "m/s", MAX_SPEED)
        angular = bounded(f"command '{name}': angular", angular, "rad/s", MAX_ANGULAR_SPEED)
        linear_y = bounded(f"command '{name}': linear_y", linear_y, "m/s", MAX_SPEED)
        if duration is not None:
            duration = bounded(f"command '{name}': duration", duration, "s", MAX_SECONDS, low=0.0, strict=True)
        span = None if duration is None else steps(duration, self.rate_hz)
        try:
            self._timeline.command(name, linear, angular, span, linear_y)
        except ValueError as exc:  # sideways, and the robot is not holonomic
            raise UsageError(str(exc), hint="Only mecanum and omni bases take linear_y.") from None

    def goto(self, name: str, x: float, y: float, yaw: float | None = None, **settings) -> None:
        """Drive to (x, y) (then turn to ``yaw``) with the goal controller of a scenario's
        ``goto`` command, from this step on; ``settings``: tolerance, timeout (s), localization,
        max_linear, max_angular, acceleration, angular_acceleration, planner ("astar": plan around
        the world's obstacles), inflation (m), local ("dwb": avoid what the robot's lidar sees),
        stuck_time (s), danger_distance (m). A running goal is cancelled."""
        self._known(name)
        if not self._world.has_drive(name):
            raise UsageError(f"robot '{name}' has no drive wheels: it cannot drive to a goal")
        if settings.get("local") and not any(s.kind == "lidar" for s in self._timeline.robots[name].sensors):
            raise UsageError(f"goto '{name}': local: {settings['local']} avoids what the robot's lidar sees, "
                             "and it has no lidar")
        tolerance = settings.pop("tolerance", None)
        try:
            fields = GoalFields(goto=GotoSpec(x=x, y=y, yaw=yaw, tolerance=tolerance), **settings)
            state = self._world.read(name)
            goal = goal_step(fields, self.step_count, -1, self.rate_hz, self.plan.world,
                             self._timeline.robots[name].footprint, lambda key: None, [],
                             start=(state.true_x, state.true_y, state.true_z))
        except ValidationError as exc:
            first = exc.errors()[0]
            raise UsageError(f"goto '{name}': {'.'.join(str(p) for p in first['loc'])}: {first['msg']}") from None
        except MobotError as exc:
            raise UsageError(f"goto '{name}': {exc.message}", hint=exc.hint) from None
        self._timeline.goto(name, goal)

    def goal_status(self, name: str) -> str | None:
        """How the robot's last goal stands: 'running', 'reached', 'reached_by_odometry_only',
        'timed_out', 'blocked', 'stuck', 'cancelled', 'unreachable'; None when it was never given one."""
        record = self._goals.get(name)
        return None if record is None else "running" if isinstance(record, GoalStarted) else record.status

    def _goal_record(self, record) -> None:
        if isinstance(record, (GoalStarted, GoalEnded)):
            self._goals[record.robot] = record

    def spawn(self, name: str, description: str, *, x: float = 0.0, y: float = 0.0, z: float | None = None,
              yaw: float = 0.0, args: Mapping[str, str] | None = None, namespace: str | None = None,
              hold=None) -> None:
        """Place a robot now (bundled name or .urdf/.xacro path), resting on the floor unless ``z``;
        ``hold``: "all" or {joint: position} holds joints its description leaves free (an arm)."""
        self._open()
        plan = robot_plan(name, description, rate_hz=self.rate_hz, x=x, y=y, z=z, yaw=yaw, args=args,
                          namespace=namespace, base_dir=self._base_dir, hold=hold)
        self._timeline.spawn(dataclasses.replace(plan, spawn_step=self.step_count), "request")

    def spawn_plan(self, plan: RobotPlan) -> None:
        """Place a robot resolved before (``api.sensors.robot_plan``), as ``spawn`` does: the same
        robot again in another Simulation without resolving its description again."""
        self._open()
        self._timeline.spawn(dataclasses.replace(plan, spawn_step=self.step_count), "request")

    def delete(self, name: str) -> None:
        """Take a robot out of the world now."""
        self._known(name)
        self._timeline.delete(name, "request")

    # -- movers (docs/movers.md) ---------------------------------------------------------------

    def add_mover(self, name: str, **fields) -> None:
        """A mover enters the world now; ``fields`` as a scenario's ``movers:`` item (shape, size,
        path, mode, speed, region, start): a path from where it is put, or a walker."""
        from mobot_cli.scenario.mover_model import MoverSpec
        from mobot_cli.scenario.movers import mover_plan

        self._open()
        try:
            spec = MoverSpec(name=name, **fields)
        except ValidationError as exc:
            raise UsageError(f"mover '{name}': {exc.errors()[0]['msg']}",
                             hint="Give the fields of a scenario's movers: item (docs/movers.md).") from None
        if spec.count is not None or spec.at:
            raise UsageError(f"mover '{name}': add one mover at a time, now (no count, no at)")
        self._timeline.add_mover(mover_plan(spec, name, self.rate_hz, source="request"))

    def remove_mover(self, name: str) -> None:
        """Take a mover (or a world's actor) out of the world now."""
        self._open()
        self._timeline.remove_mover(name)

    def movers(self) -> dict[str, tuple[float, float, float]]:
        """Every mover's x, y, yaw now (m, rad, world frame), by name."""
        self._open()
        return self._timeline.world.movers()

    # -- sensors ----------------------------------------------------------------------------

    def sensors(self, name: str) -> dict[str, str]:
        """A robot's sensors: name -> kind ('lidar', 'range', 'imu', 'contact')."""
        self._known(name)
        return {spec.name: spec.kind for spec in self._timeline.robots[name].sensors}

    def reading(self, name: str, sensor: str | None = None) -> Reading | None:
        """A sensor's latest reading (``step``, ``data``: ScanData, RangeData, ImuData or ContactData), None
        before its first; ``sensor`` may be left out when the robot has one."""
        self._known(name)
        spec = pick(name, self._timeline.robots[name].sensors, sensor, None)
        self._sense_now()
        return self._latest.get(name, spec.name)

    def scan(self, name: str, sensor: str | None = None) -> Scan | None:
        """A lidar's latest scan (beam angles and ranges, +inf: no return), None before its first;
        ``sensor`` may be left out when the robot has one lidar."""
        self._known(name)
        spec = pick(name, self._timeline.robots[name].sensors, sensor, "lidar")
        self._sense_now()
        return self._latest.scan(name, spec.name)

    def range(self, name: str, sensor: str | None = None) -> Range | None:
        """A range sensor's latest reading (``.range`` in metres, limits, field of view), None
        before its first; ``sensor`` may be left out when the robot has one range sensor."""
        self._known(name)
        spec = pick(name, self._timeline.robots[name].sensors, sensor, "range")
        self._sense_now()
        reading = self._latest.get(name, spec.name)
        return None if reading is None else range_of(reading, self._latest.rate_hz)

    def image(self, name: str, camera: str | None = None) -> CameraImage | None:
        """A camera's latest frame as numpy arrays (``rgb``, ``depth``), None before its first;
        ``camera`` may be left out when the robot has one. From the first ask on, the camera's
        frames are rendered as they come (docs/cameras.md)."""
        self._known(name)
        spec = pick_camera(name, self._timeline.robots[name].sensors, camera)
        self._sense_now()
        self._cameras.cameras.add((name, spec.name))
        reading = self._latest.get(name, spec.name)
        if reading is None:
            return None
        step, data = reading.step, reading.data
        if data.rgb is None and data.depth is None:  # its frame passed unrendered: the view now
            step, data = self.step_count, self._world.sense([(name, spec.name)])[0]
        from mobot_cli.ros.sensor_topics import sensor_frame

        frame = sensor_frame(self._timeline.robots[name], spec).frame
        return image_of(name, spec, step, data, self.plan.physics.rate_hz, frame)

    def _sense_now(self) -> None:
        """Take the readings due at this step now rather than as the next step begins, so that a
        reading of the world as it is now is there to be read (the timeline records them in their
        usual place when it ticks)."""
        for reading in self._timeline.sense_early():
            self._latest(reading)

    # -- the end ----------------------------------------------------------------------------

    def close(self, status: Status = Status.OK, error: str | None = None, *,
                fault: SimulationFault | None = None) -> RunRecord | None:
        """Record the state now, write summary.json (when recording) and free the world;
        ``fault``: the SimulationFault that ended it (summary.json's ``fault`` record)."""
        self._fault = fault or self._fault
        if self._closed:
            return self.record
        self._closed = True
        try:
            if self._recording is not None:
                self.record = self._finish(status, error)
        finally:
            self._world.close()
        return self.record

    def _finish(self, status: Status, error: str | None) -> RunRecord:
        try:
            if status != Status.FAULT:
                self._timeline.tick()  # what is due now, and the final row
                self._timeline.log()
        except Exception as exc:  # noqa: BLE001 - a world gone bad still gets its summary, saying why
            status, error = Status.ERROR, error or f"{type(exc).__name__}: {exc}"
        return self._recording.close(status, error, self.step_count,  # type: ignore[union-attr]
                                     said=self._timeline.notices, fault=self._fault)

    def __enter__(self) -> "Simulation":
        return self

    def __exit__(self, kind, exc, tb) -> None:
        if kind is None:
            self.close()
        elif issubclass(kind, KeyboardInterrupt):
            self.close(Status.INTERRUPTED)
        else:
            self.close(Status.FAULT if isinstance(exc, MobotError) else Status.ERROR, str(exc) or repr(exc),
                       fault=exc if isinstance(exc, SimulationFault) else None)

    def _open(self) -> None:
        if self._closed:
            raise UsageError("this simulation is closed")

    def _known(self, name: str) -> None:
        self._open()
        if name not in self._timeline.robots:
            hint = did_you_mean(name, self._timeline.robots) or "Simulation.robots lists them."
            raise UsageError(f"no robot named '{name}' in the world", hint=hint)
