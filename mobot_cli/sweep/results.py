"""results.csv and sweep.json: one row per finished run, appended as runs end.

Rows are appended (and flushed) in the order runs finish, so a sweep that is killed keeps
every finished row; when the sweep ends the file is rewritten in run order, so that it is
the same whatever the number of jobs (but for wall times).
"""

from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import Any, Iterable

from mobot_cli.common.files import write_json_atomic, write_text_atomic
from mobot_cli.common.numbers import number  # not run.sinks: that imports PyBullet into the sweep
from mobot_cli.sweep.expand import Sweep, Variant
from mobot_cli.sweep.task import ROBOT_METRICS, TaskResult

ROBOT_FIELDS = ("distance", "x", "y", "yaw", "collisions")


def columns(keys: Iterable[str], robots: Iterable[str], measured: Iterable[str] = ()) -> list[str]:
    """run, status, failure, seed, the swept keys, expectations, wall time, per robot figures
    (and the metrics of the ``measured`` robots, those with goals), folder and reason (free text
    last). A swept seed is the seed column, not a second one."""
    head = ["run", "status", "failure", "seed", *(k for k in keys if k != "seed"), "expect_passed",
            "expect_failed", "wall_time"]
    measured = set(measured)
    per_robot = [f"{name}.{f}" for name in robots
                 for f in (*ROBOT_FIELDS, *(ROBOT_METRICS if name in measured else ()))]
    return head + per_robot + ["folder", "reason"]


def row(variant: Variant, outcome: TaskResult, folder: str) -> dict[str, str]:
    """The results.csv row of one finished run."""
    out = {"run": str(variant.index), "status": outcome.status, "failure": outcome.failure,
           "seed": str(variant.seed), "expect_passed": str(outcome.expect_passed),
           "expect_failed": str(outcome.expect_failed), "wall_time": f"{outcome.wall_time:.3f}",
           "folder": folder, "reason": outcome.reason}
    out.update((key, value) for key, value in variant.params if key != "seed")  # the run's seed is there
    for name, figures in outcome.robots.items():
        for f in ROBOT_FIELDS:
            value = figures[f]
            out[f"{name}.{f}"] = str(value) if f == "collisions" else number(value)
        for f in ROBOT_METRICS:
            if f in figures:
                value = figures[f]
                out[f"{name}.{f}"] = "" if value is None else str(value).lower() if isinstance(value, (bool, str)) \
                    else number(value)
    return out


class ResultsCsv:
    """results.csv, opened for appending; a fresh file gets the header first."""

    def __init__(self, path: Path, header: list[str]):
        self.path, self.header = path, header
        fresh = not path.exists() or path.stat().st_size == 0
        self._file = path.open("a", encoding="utf-8", newline="")
        self._writer = csv.DictWriter(self._file, fieldnames=header, lineterminator="\n")
        if fresh:
            self._writer.writeheader()
            self._file.flush()

    def append(self, values: dict[str, str]) -> None:
        self._writer.writerow(values)
        self._file.flush()

    def close(self) -> None:
        self._file.close()


def read_rows(path: Path, header: list[str]) -> dict[int, dict[str, str]]:
    """Finished rows of an earlier (interrupted) sweep, by run index; a torn last line is dropped."""
    if not path.exists():
        return {}
    with path.open(encoding="utf-8", newline="") as f:
        reader = csv.DictReader(f)
        if reader.fieldnames != header:
            raise ValueError("the columns of results.csv differ from this sweep's")
        rows = {}
        for r in reader:
            if None in r or any(v is None for v in r.values()) or not r["run"].isdigit():
                continue
            rows[int(r["run"])] = r
    return rows


def rewrite_sorted(path: Path, header: list[str], rows: dict[int, dict[str, str]]) -> None:
    """Write every row in run order, atomically."""
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=header, lineterminator="\n")
    writer.writeheader()
    for index in sorted(rows):
        writer.writerow(rows[index])
    write_text_atomic(path, buffer.getvalue())


def sweep_document(sweep: Sweep, executor: str, jobs: int, timeout: float | None) -> dict[str, Any]:
    """sweep.json: what was swept and how; ``status`` and ``counts`` are updated as it runs."""
    spec = sweep.spec
    return {
        "name": sweep.name,
        "scenario": str(spec.scenario),
        "sweep_file": str(spec.sweep_file) if spec.sweep_file else None,
        "seed": sweep.seed,
        "set": [item for item, _ in spec.sets],
        "axes": [{"kind": a.kind, "keys": list(a.keys)} for a in spec.axes],
        "samples": spec.samples,
        "executor": executor,
        "jobs": jobs,
        "timeout": timeout,
        "runs": [{"run": v.index, "folder": folder(v.index, len(sweep.variants)), "seed": v.seed,
                  "params": dict(v.params)} for v in sweep.variants],
        "status": "running",
        "counts": {"total": len(sweep.variants), "passed": 0, "failed": 0},
    }


def goal_summary(rows: Iterable[dict[str, str]], measured: Iterable[str]) -> dict[str, dict[str, Any]]:
    """Per robot that drives to goals: how many runs measured it, its success rate, the mean SPL
    over those runs and the mean time of the successful ones (sweep.json's ``goals``)."""
    out = {}
    rows = list(rows)
    for name in dict.fromkeys(measured):
        judged = [r for r in rows if r.get(f"{name}.success") in ("true", "false")]
        won = [r for r in judged if r[f"{name}.success"] == "true"]
        spl = [float(r[f"{name}.spl"]) for r in judged if r.get(f"{name}.spl")]
        times = [float(r[f"{name}.time"]) for r in won if r.get(f"{name}.time")]
        out[name] = {"runs": len(judged), "successes": len(won),
                     "success_rate": round(len(won) / len(judged), 4) if judged else None,
                     "mean_spl": round(sum(spl) / len(spl), 4) if spl else None,
                     "mean_time": round(sum(times) / len(times), 4) if times else None}
    return out


def folder(index: int, total: int) -> str:
    """A run's folder inside the sweep folder: runs/0000, runs/0001, ..."""
    width = max(4, len(str(total - 1)))
    return f"runs/{index:0{width}d}"


def write_document(path: Path, document: dict[str, Any]) -> None:
    write_json_atomic(path, document)
