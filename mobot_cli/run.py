"""`mobot run` without the printing: plan in, run folder out, record returned."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Sequence

from mobot_cli.errors import MobotError, OutputError, SimulationFault
from mobot_cli.plan import Plan
from mobot_cli.record.outcome import Status
from mobot_cli.record.recording import Recording
from mobot_cli.sim.engine import world_for
from mobot_cli.timeline.expect import Result
from mobot_cli.timeline.loop import Attachment, Timeline

if TYPE_CHECKING:
    from mobot_cli.record.summary import RunRecord  # made at the end (record/outcome.py)

Progress = Callable[[int, int], None]


@dataclass
class RunResult:
    """The outcome of one run: its folder, its record, its expectations' results."""

    out_dir: Path
    record: RunRecord
    expectations: list[Result] = field(default_factory=list)  # empty when the run did not finish


def execute(plan: Plan, resolved_yaml: str, out_dir: Path, progress: Progress | None = None,
            attachments: Sequence[Attachment] = (),
            watch: Callable[[Timeline], None] | None = None, durable: bool = True,
            pictures: bool = True) -> RunResult:
    """Run a plan and write its run folder; summary.json is written last and says how it ended.

    ``attachments`` (the ROS 2 bridge) open after the robots are placed and close at the end;
    ``watch`` is called with the timeline once its robots are spawned, to attach more consumers
    (a live view). ``durable=False`` leaves flushing summary.json to disk to the caller (a sweep
    does it off the worker's clock); ``pictures=False`` draws no trajectory.png (a sweep's runs)."""
    with world_for(plan) as world:
        # The robots are spawned and checked before the folder is made: a spawn refused
        # (inside furniture, below the floor) leaves no run folder behind.
        timeline = Timeline(plan, world)
        timeline.start()
        recording = Recording(plan, out_dir, resolved_yaml, durable, pictures)
        status, error, fault = Status.OK, None, None
        opened: list[Attachment] = []
        try:
            timeline.attach(recording)  # the spawns' records: a robot's CSV opens here
            if watch is not None:
                watch(timeline)
            for attachment in attachments:
                attachment.open(timeline)
                opened.append(attachment)
            _play(timeline, progress)
        except OutputError as exc:  # a file of the run folder cannot be written
            status, error = Status.ERROR, str(exc)
            raise
        except MobotError as exc:
            status, error = Status.FAULT, str(exc)
            fault = exc if isinstance(exc, SimulationFault) else None
            raise
        except KeyboardInterrupt:
            status = Status.INTERRUPTED
            raise
        except Exception as exc:  # a bug, not bad input: summary.json must still not say "ok"
            status, error = Status.ERROR, str(exc) or repr(exc)
            raise
        finally:
            for attachment in opened:
                attachment.close()
            record = recording.close(status, error, said=timeline.notices, fault=fault)  # the world's too
    return RunResult(out_dir=out_dir, record=record, expectations=recording.results)


def _play(timeline: Timeline, progress: Progress | None) -> None:
    """Tick and step to the plan's last step, then tick it (its events and final row)."""
    total, every = timeline.plan.total_steps, timeline.plan.log_every
    tick, advance = timeline.tick, timeline.advance
    for step in range(timeline.step, total):
        tick()
        if progress and step % every == 0:
            progress(step, total)
        advance()
    tick()
    if progress:
        progress(total, total)
