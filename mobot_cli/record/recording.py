"""The run folder as a timeline's consumer: one place for `mobot run` and `mobot serve --out`.

    DIR/scenario.yaml      the resolved scenario (or world) the run started from
    DIR/odom/, DIR/bag/    per robot, however it entered the world (the sinks)
    DIR/sensors/           per robot with sensors, opened at the first reading
    DIR/trajectory.png     drawn when the recording closes
    DIR/summary.json       the RunRecord, written last

A name used again after its robot was deleted (a live world) is recorded as ``<name>__2``.
"""

from __future__ import annotations

import platform
import time
from pathlib import Path
from typing import TYPE_CHECKING, Sequence

from mobot_cli import __version__
from mobot_cli.common.files import write_text_atomic
from mobot_cli.common.installed import version
from mobot_cli.errors import OutputError, SimulationFault, cannot_write
from mobot_cli.plan import Plan
from mobot_cli.record.life import Life, rounded
from mobot_cli.record.outcome import SUMMARY, Status
from mobot_cli.record.sinks import CsvSink
from mobot_cli.timeline.expect import Checker, Result
from mobot_cli.timeline.goals import GoalEnded, GoalStarted
from mobot_cli.timeline.records import Deleted, Reading, Record, Sample, Sink, Spawned

if TYPE_CHECKING:  # the record's classes are made when it is written (record/outcome.py)
    from mobot_cli.record.summary import LiveInfo, RunRecord


class Recording:
    """Takes a timeline's records into ``out_dir``; ``close`` writes the RunRecord last.

    A file that cannot be written (a full disk, a read-only folder, a name too long) raises an
    OutputError naming it, once; ``close`` then still finishes what it can and writes a
    summary.json with status ``error`` and that message, where it can.
    """

    def __init__(self, plan: Plan, out_dir: Path, resolved_yaml: str, durable: bool = True,
                 pictures: bool = True):
        self.plan, self.out_dir = plan, out_dir
        self.durable = durable  # summary.json flushed to disk here (a sweep flushes it itself)
        self.checker = Checker(plan)
        self.sinks: list[Sink] = []
        self.failure: OutputError | None = None  # the first write that failed
        self.results: list[Result] = []
        self.last_step = 0
        self._keys: dict[str, str] = {}  # robot name -> its name in the record
        self._lives: dict[str, Life] = {}  # record name -> life, in order of arrival
        self._renamed = False
        self._sensor_files = False
        self._readers: list[Sink] = []  # the sinks that take readings (not Sink's no-op), made at the first
        self._started = time.perf_counter()
        made = not out_dir.exists()
        try:
            out_dir.mkdir(parents=True, exist_ok=True)
            (out_dir / SUMMARY).unlink(missing_ok=True)  # a reused folder must not look finished early
            write_text_atomic(out_dir / "scenario.yaml", resolved_yaml, durable=False)  # summary.json is
            if plan.generated_world:  # a world made from a seed, kept to open in Gazebo or map
                from mobot_cli.assets.world.generate.make import GENERATED_FILE

                write_text_atomic(out_dir / GENERATED_FILE, plan.generated_world, durable=False)
            self.sinks = make_sinks(plan, out_dir, self.checker.sweeps, pictures)
        except OSError as exc:
            failure = self._failed(exc)
            self._save(self._record(Status.ERROR, str(failure), 0, None))
            if made:
                _remove_if_empty(out_dir)  # nothing written, not even the summary: leave nothing
            raise failure from exc
        self.sinks.append(self.checker)
        self.checker.metric_value = self._metric_value

    def __call__(self, record: Record) -> None:
        """Take one record of the timeline (the Consumer interface)."""
        try:
            if isinstance(record, Sample):
                self._sample(record)
            elif isinstance(record, Reading):  # the two kinds that come many times a second first
                self._reading(record)
            elif isinstance(record, Spawned):
                self._spawned(record)
            elif isinstance(record, GoalStarted):
                self._lives[self._keys[record.robot]].started(record, self.plan.physics.rate_hz)
            elif isinstance(record, GoalEnded):
                key = self._keys[record.robot]
                self._lives[key].ended(record, self.plan.physics.rate_hz)
                self.checker.goal_ended(key, record)
            elif isinstance(record, Deleted):
                key = self._keys.pop(record.name)
                self._lives[key].deleted_at = record.step / self.plan.physics.rate_hz
                for sink in self.sinks:
                    sink.deleted(record.step, key)
        except OSError as exc:
            raise self._failed(exc) from exc

    def _metric_value(self, robot: str, command: int | None, name: str) -> float | None:
        """A metric of a robot (``command``: of that goal command; None: over its life) as the
        record will hold it, for ``metric`` checks; None when not measured."""
        life = self._lives.get(robot)
        if life is None or life.last is None:
            return None
        rate = self.plan.physics.rate_hz
        record = life.record(life.deleted_at if life.deleted_at is not None else self.last_step / rate, rate)
        source = record.metrics if command is None else \
            next((g for g in record.goals if g.command == command), None)
        value = getattr(source, name, None)
        return None if value is None else float(value)

    def _failed(self, exc: OSError) -> OutputError:
        """The first failed write, as the error to report: later ones follow from it (a full
        disk stays full)."""
        if self.failure is None:
            self.failure = cannot_write(exc.filename or self.out_dir, exc)
        return self.failure

    def _spawned(self, record: Spawned) -> None:
        name, lives = record.robot.name, 1
        key = name
        while key in self._lives:
            lives += 1
            key = f"{name}__{lives}"
        self._renamed = self._renamed or key != name
        self._keys[name] = key
        self._lives[key] = Life(key, record.robot, record.step / self.plan.physics.rate_hz,
                                 rate=self.plan.physics.rate_hz)
        for sink in self.sinks:
            sink.spawned(record.step, key, record.robot)

    def _reading(self, record: Reading) -> None:
        key = self._keys[record.robot]
        life = self._lives[key]
        life.readings[record.sensor.name] = life.readings.get(record.sensor.name, 0) + 1
        if not self._sensor_files:  # a run without sensors never makes DIR/sensors/
            from mobot_cli.record.sensor_files import SensorFilesSink

            files = SensorFilesSink(self.plan, self.out_dir)
            for known in self._lives.values():
                files.spawned(0, known.name, known.plan)
            self.sinks.insert(0, files)
            self._sensor_files = True
            self._readers = [sink for sink in self.sinks if type(sink).reading is not Sink.reading]
        for sink in self._readers:
            sink.reading(key, record)

    def _sample(self, sample: Sample) -> None:
        if self._renamed:
            sample = Sample(sample.step, {self._keys[n]: s for n, s in sample.states.items()}, sample.complete,
                            sample.movers)
        for sink in self.sinks:
            sink.write(sample)
        lives = self._lives
        for key, state in sample.states.items():
            lives[key].add(state, sample.step)
        self.last_step = sample.step

    def close(self, status: Status, error: str | None = None, steps: int | None = None,
              live: LiveInfo | None = None, said: Sequence[str] = (),
              fault: SimulationFault | None = None) -> RunRecord:
        """Close every writer and write summary.json last (``said``: notices from during the run;
        ``fault``: what ended the run, when it names a robot); returns the record.

        Raises OutputError when a file could not be written here (an earlier failure was
        raised when it happened); every writer is closed all the same."""
        raised = self.failure
        try:
            for sink in self.sinks:
                try:
                    sink.close()
                except OSError as exc:
                    self._failed(exc)
        finally:
            if self.failure is not None:
                status, error = Status.ERROR, str(self.failure)
            elif self.plan.expectations and status == Status.OK:
                self.results = self.checker.results()
            record = self._record(status, error, self.last_step if steps is None else steps, live, said, fault)
            self._save(record)
        if self.failure is not raised:
            raise self.failure
        return record

    def _save(self, record: RunRecord) -> None:
        """Write summary.json; when even that fails, the failure is the error to report."""
        try:
            record.save(self.out_dir, self.durable)
        except OSError as exc:
            self._failed(exc)

    def _record(self, status: Status, error: str | None, steps: int, live: LiveInfo | None,
                said: Sequence[str] = (), fault: SimulationFault | None = None) -> RunRecord:
        from mobot_cli.record.summary import ExpectationResult, Expectations, RunRecord, Versions

        wall = time.perf_counter() - self._started
        plan, sim_time = self.plan, steps / self.plan.physics.rate_hz
        expectations = None
        if self.results:
            failed = sum(not r.passed for r in self.results)
            expectations = Expectations(passed=len(self.results) - failed, failed=failed,
                                        results=[ExpectationResult(**r.as_dict()) for r in self.results])
        fault_record = self._fault(fault)  # before the robots' records: it marks a goal failed
        return RunRecord(
            status=status, error=error, scenario=plan.name, world=plan.world.name, seed=plan.seed,
            versions=Versions(mobot=__version__, pybullet=version("pybullet"), python=platform.python_version()),
            steps=steps, sim_time=rounded(sim_time), wall_time=round(wall, 3),
            real_time_factor=round(sim_time / wall, 2) if wall > 0 else None,
            physics_rate_hz=plan.physics.rate_hz, log_rate_hz=rounded(plan.physics.rate_hz / plan.log_every),
            notices=[*plan.notices, *said, *self._disagreements()],
            robots={key: life.record(life.deleted_at if life.deleted_at is not None else sim_time,
                                     plan.physics.rate_hz)
                    for key, life in self._lives.items() if life.last is not None},
            expectations=expectations, live=live, fault=fault_record)

    def _fault(self, fault: SimulationFault | None):
        """The fault's record, its robot's running goal marked failed; None unless a robot is named."""
        from mobot_cli.record.summary import FaultRecord

        if fault is None or fault.robot is None or fault.step is None:
            return None
        key = self._keys.get(fault.robot)
        if key is not None:
            self._lives[key].failed(fault.kind or "fault")
        return FaultRecord(robot=fault.robot, step=fault.step, time=rounded(fault.step / self.plan.physics.rate_hz),
                           kind=fault.kind or "fault")

    def _disagreements(self) -> list[str]:
        """A notice for each robot whose odometry strayed from the truth beyond the tolerance."""
        tolerance, rate = self.plan.physics.faults.odom_tolerance, self.plan.physics.rate_hz
        return [f"robot '{key}': odometry and ground truth disagree by {life.worst[0]:.2f} m at "
                f"{life.worst[1] / rate:g} s (step {life.worst[1]}), beyond faults.odom_tolerance {tolerance:g} m"
                for key, life in self._lives.items() if life.worst[0] > tolerance]


def make_sinks(plan: Plan, out_dir: Path, sweeps: dict | None = None, pictures: bool = True) -> list[Sink]:
    """The sinks a plan's ``formats`` ask for; trajectory.png draws ``sweeps`` (the checker's), unless
    ``pictures`` is False (sweeps draw none unless asked: `mobot plot` draws any run folder later)."""
    sinks: list[Sink] = []
    if "csv" in plan.formats:
        sinks.append(CsvSink(plan, out_dir))
    if "mcap" in plan.formats:
        from mobot_cli.record.bag import BagSink  # imports rosbags: only when a bag is asked for

        sinks.append(BagSink(plan, out_dir))
    if "csv" in plan.formats:
        from mobot_cli.record.movers_csv import MoversCsvSink

        sinks.append(MoversCsvSink(out_dir, plan.physics.rate_hz))  # movers.csv, when there are movers
    if not pictures:
        return sinks
    from mobot_cli.record.trajectory import TrajectorySink

    sinks.append(TrajectorySink(plan, out_dir, sweeps))  # every run; last, as it draws when closed
    return sinks


def _remove_if_empty(folder: Path) -> None:
    try:
        folder.rmdir()
    except OSError:
        pass


def preload() -> None:
    """Look up what every summary records, once (a sweep's fork server, for all its workers)."""
    version("pybullet")
