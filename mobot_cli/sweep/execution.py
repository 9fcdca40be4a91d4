"""A sweep's execution: the Executor it runs on, the sweep folder, resuming, and rows written as runs finish."""

from __future__ import annotations

import json
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Protocol

from mobot_cli.common.files import check_out_folder
from mobot_cli.errors import UsageError, cannot_write
from mobot_cli.record.summary import SUMMARY
from mobot_cli.sweep.expand import Sweep
from mobot_cli.sweep.guard import LOCK_FILE, FolderLock, check_unlocked
from mobot_cli.sweep.results import (
    ResultsCsv,
    columns,
    folder,
    goal_summary,
    read_rows,
    rewrite_sorted,
    row,
    sweep_document,
    write_document,
)
from mobot_cli.sweep.syncer import Syncer
from mobot_cli.sweep.task import FAILED, Task, TaskResult

Progress = Callable[[int, int, int], None]  # (runs done, runs failed, runs in the sweep)


class Executor(Protocol):
    """Something that runs tasks and reports each outcome as it comes."""

    name: str
    jobs: int
    timeout: float | None

    def prestart(self, count: int | None = None) -> None: ...

    def start(self) -> None: ...

    def close(self) -> None: ...

    def run(self, tasks: list[Task], on_done: Callable[[TaskResult], None]) -> None: ...


@dataclass
class SweepReport:
    """How the sweep went; ``rows`` are results.csv's rows by run index."""

    out_dir: Path
    document: dict[str, Any]
    rows: dict[int, dict[str, str]] = field(default_factory=dict)
    skipped: int = 0  # runs finished by an earlier, resumed sweep

    @property
    def failed(self) -> list[dict[str, str]]:
        return [r for _, r in sorted(self.rows.items()) if r["status"] == FAILED]


def check_out_dir(sweep: Sweep, out_dir: Path, resume: bool) -> dict[int, dict[str, str]]:
    """Refuse to mix sweeps in one folder, or to race a live one; with resume, the rows already
    finished."""
    check_out_folder(out_dir)
    if out_dir.is_dir():
        check_unlocked(out_dir)
    header = columns(sweep.keys, sweep.robots(), sweep.measured())
    stored = out_dir / "sweep.json"
    if not resume:
        if stored.exists():
            raise UsageError(f"{out_dir} already holds a sweep",
                             hint="Add --resume to finish it, or choose another --out.")
        if out_dir.exists() and any(p.name != LOCK_FILE for p in out_dir.iterdir()):
            raise UsageError(f"{out_dir} is not empty", hint="Choose a new or empty folder for --out.")
        return {}
    if not stored.exists():
        raise UsageError(f"nothing to resume: {stored} does not exist",
                         hint="Give --out the folder of the sweep to finish.")
    try:
        before = json.loads(stored.read_text(encoding="utf-8"))
        same = ([(r["run"], r["seed"], r["params"]) for r in before["runs"]]
                == [(v.index, v.seed, dict(v.params)) for v in sweep.variants]
                and before["scenario"] == str(sweep.spec.scenario))
        rows = read_rows(out_dir / "results.csv", header) if same else None
    except (OSError, ValueError, KeyError, TypeError):
        same, rows = False, None
    if not same or rows is None:
        raise UsageError(f"the sweep in {out_dir} was made with other runs or columns than these",
                         hint="Resume with the same scenario, values and seed, or choose another --out.")
    return rows


def run_sweep(sweep: Sweep, out_dir: Path, executor: Executor, done_rows: dict[int, dict[str, str]],
              progress: Progress | None = None, pictures: bool = True) -> SweepReport:
    """Run every run not in ``done_rows``, holding the folder's lock; Ctrl-C stops it, keeping the
    finished rows; ``pictures`` draws each run's trajectory.png. A file of the sweep folder that
    cannot be written stops it with an OutputError."""
    try:
        (out_dir / "runs").mkdir(parents=True, exist_ok=True)
        with FolderLock(out_dir):
            return _run(sweep, out_dir, executor, done_rows, progress, pictures)
    except OSError as exc:
        raise cannot_write(exc.filename or out_dir, exc) from exc


def _run(sweep: Sweep, out_dir: Path, executor: Executor, done_rows: dict[int, dict[str, str]],
         progress: Progress | None, pictures: bool = True) -> SweepReport:
    total = len(sweep.variants)
    header = columns(sweep.keys, sweep.robots(), sweep.measured())
    document = sweep_document(sweep, executor.name, executor.jobs, executor.timeout)
    write_document(out_dir / "sweep.json", document)
    report = SweepReport(out_dir, document, dict(done_rows), skipped=len(done_rows))
    todo = [v for v in sweep.variants if v.index not in done_rows]
    tasks = [Task(v.index, sweep.prepared[v.index].plan, sweep.prepared[v.index].resolved_yaml,
                  str((out_dir / folder(v.index, total)).resolve()), pictures) for v in todo]
    results = ResultsCsv(out_dir / "results.csv", header)
    syncer = Syncer()  # each run's summary.json to disk, while the next runs go on

    def on_done(outcome: TaskResult) -> None:
        run_dir = folder(outcome.index, total)
        if outcome.files is not None:
            _unpack(out_dir / run_dir, outcome.files)
        syncer.add(out_dir / run_dir / SUMMARY)
        values = row(sweep.variants[outcome.index], outcome, run_dir)
        results.append(values)
        report.rows[outcome.index] = values
        if progress:
            progress(len(report.rows), len(report.failed), total)

    if progress:
        progress(len(report.rows), len(report.failed), total)
    status = "interrupted"
    try:
        executor.run(tasks, on_done)
        syncer.close()
        status = "complete"
    except OSError:  # results.csv cannot be written (a full disk): the sweep stops
        status = "error"
        raise
    finally:
        try:
            syncer.close()  # an interrupted sweep's finished summaries are flushed too
        except OSError:
            pass  # the sweep is ending on another error already, or was interrupted
        results.close()
        rewrite_sorted(out_dir / "results.csv", header, report.rows)
        failed = len(report.failed)
        document.update(status=status, counts={"total": total, "passed": len(report.rows) - failed,
                                               "failed": failed, "not_run": total - len(report.rows)})
        measured = sweep.measured()
        if measured:  # robots with goals: their success rate over the runs
            document["goals"] = goal_summary(report.rows.values(), measured)
        write_document(out_dir / "sweep.json", document)
    return report


def _unpack(run_dir: Path, files: dict[str, bytes]) -> None:
    """Write a run folder that was made on another machine."""
    if run_dir.exists():
        shutil.rmtree(run_dir)
    for rel, data in files.items():
        path = run_dir / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
