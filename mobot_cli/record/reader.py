"""The one reader of run folders: `mobot check DIR`, `mobot plot`, `mobot view` and its replay.

A run folder may come from anyone (a download, an issue's attachment), so it is read as the live
world reads a client's request: every file is opened only when it is a regular file inside the
folder (no FIFO that blocks the open, no symlink out, no directory in a file's place) and no
larger than its limit; the plan is resolved again from scenario.yaml in a confined loader process
(record/plan_loader.py). Every fault is a RunFolderError: one located line, exit 2.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
import os
import stat
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator

from mobot_cli.errors import Location, UsageError
from mobot_cli.record.summary import SUMMARY, RunRecord

MIB = 1 << 20
LIMITS_VARIABLE = "MOBOT_RUN_FOLDER_LIMITS"
NOT_A_RUN_HINT = "Give the folder that mobot run --out, mobot serve --out or mobot sweep --out wrote."


@dataclass(frozen=True)
class ReadLimits:
    """The most a run folder's files may hold, and what resolving its scenario.yaml may take."""

    summary: int = 16 * MIB
    scenario: int = 1 * MIB
    csv: int = 256 * MIB  # a CSV file; an hour of one robot at 50 Hz is about 40 MiB
    csv_line: int = 64 * 1024  # characters in one CSV line
    sensors: int = 1024 * MIB  # one sensors/<robot>/<sensor> file
    bag: int = 4096 * MIB  # every file of bag/ together
    json: int = 16 * MIB  # sweep.json, history.jsonl
    plan_seconds: float = 10.0  # CPU seconds to resolve scenario.yaml (wall: six times as long)
    plan_memory: int = 1024 * MIB
    plan_reply: int = 64 * MIB  # the plan the loader process answers with, as JSON

    @classmethod
    def from_env(cls) -> "ReadLimits":
        """The defaults, with $MOBOT_RUN_FOLDER_LIMITS ("csv=512,bag=8192,plan_seconds=30": MiB;
        seconds for plan_seconds, characters for csv_line) over them; UsageError naming a bad entry."""
        text = os.environ.get(LIMITS_VARIABLE, "").strip()
        values: dict[str, Any] = {}
        names = {f.name for f in dataclasses.fields(cls)}
        for entry in filter(None, (part.strip() for part in text.split(","))):
            name, _, value = entry.partition("=")
            try:
                number = float(value)
            except ValueError:
                number = math.nan
            if name.strip() not in names or not math.isfinite(number) or not 0 < number <= 1 << 20:
                raise UsageError(f"{LIMITS_VARIABLE}: '{entry}' is not NAME=NUMBER with a NAME of "
                                 f"{', '.join(sorted(names))} and a number above 0",
                                 hint="Sizes are in MiB, plan_seconds in seconds of CPU time, csv_line in characters.")
            name = name.strip()
            values[name] = {"plan_seconds": number, "csv_line": int(number)}.get(name, int(number * MIB))
        return cls(**values)


class RunFolderError(UsageError):
    """A run folder, or a file in it, that cannot be read safely."""


def is_run_folder(path: Path) -> bool:
    """A folder that ``mobot run`` wrote (or began to write)."""
    return path.is_dir() and ((path / SUMMARY).is_file() or (path / "scenario.yaml").is_file())


def is_sweep_folder(path: Path) -> bool:
    """A folder that ``mobot sweep`` wrote: sweep.json and runs/NNNN/ folders."""
    return path.is_dir() and (path / "sweep.json").is_file() and (path / "runs").is_dir()


def sweep_runs(folder: Path) -> list[Path]:
    """The run folders of a sweep folder, in order (only those inside it)."""
    root = folder.resolve()
    return sorted(p for p in (folder / "runs").iterdir() if is_run_folder(p) and p.resolve().is_relative_to(root))


@dataclass
class RunFolder:
    """One run folder, opened for reading; every file read goes through ``checked`` or ``read_bytes``."""

    path: Path
    limits: ReadLimits = field(default_factory=ReadLimits)

    @classmethod
    def open(cls, path: Path, limits: ReadLimits | None = None) -> "RunFolder":
        """The run folder at ``path`` (UsageError when it is not one)."""
        if not is_run_folder(path):
            raise UsageError(f"'{path}' is not a run folder (it has no summary.json or scenario.yaml)",
                             hint="Give the folder that mobot run --out wrote.")
        return cls(path, limits or ReadLimits.from_env())

    @property
    def root(self) -> Path:
        return self.path.resolve()

    def checked(self, relative: str | Path, limit: int) -> Path | None:
        """The file's path when it may be read (None when absent): inside the folder, regular, small enough."""
        path = self.path / relative
        if not os.path.lexists(path):
            return None
        try:
            resolved = path.resolve(strict=True)
        except (OSError, RuntimeError):
            raise self._fault(relative, "is a broken or looping symlink") from None
        if not resolved.is_relative_to(self.root):
            raise self._fault(relative, "points outside the run folder")
        try:
            info = resolved.stat()
        except OSError as exc:
            raise self._fault(relative, f"cannot be read ({exc.strerror})") from None
        self._check_stat(relative, info, limit)
        return resolved

    def read_bytes(self, relative: str | Path, limit: int) -> bytes | None:
        """The file's bytes (None when absent), opened without blocking and checked on the open file."""
        path = self.checked(relative, limit)
        if path is None:
            return None
        try:
            fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOCTTY", 0))
        except OSError as exc:
            raise self._fault(relative, f"cannot be read ({exc.strerror})") from None
        try:
            with os.fdopen(fd, "rb") as f:
                self._check_stat(relative, os.fstat(fd), limit)  # the file opened, not the one looked at
                data = f.read(limit + 1)
        except OSError as exc:
            raise self._fault(relative, f"cannot be read ({exc.strerror})") from None
        if len(data) > limit:
            raise self._too_large(relative, limit)
        return data

    def read_text(self, relative: str | Path, limit: int) -> str | None:
        data = self.read_bytes(relative, limit)
        if data is None:
            return None
        try:
            return data.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise self._fault(relative, f"is not UTF-8 text (byte {exc.start})") from None

    def listing(self, folder: str, pattern: str) -> list[Path]:
        """Files of a sub-folder matching ``pattern``, relative to the run folder (the sub-folder itself checked)."""
        sub = self.path / folder
        if not sub.is_dir():
            return []
        if not sub.resolve().is_relative_to(self.root):
            raise self._fault(folder, "points outside the run folder")
        return sorted(p.relative_to(self.path) for p in sub.glob(pattern))

    # -- what the folder holds --------------------------------------------------------------

    def summary(self) -> RunRecord | None:
        """summary.json validated; None when there is none (a killed run), RunFolderError when damaged."""
        data = self.read_bytes(SUMMARY, self.limits.summary)
        if data is None:
            return None
        record = RunRecord.parse(data)
        if record is None:
            raise self._fault(SUMMARY, "is not a record mobot wrote")
        return record

    def plan(self, notices: list[str], missing: str):
        """The plan resolved again from scenario.yaml, confined; None (with a notice) when there is
        none, RunFolderError when it is refused or does not resolve."""
        from mobot_cli.record.plan_loader import load_plan

        if self.checked("scenario.yaml", self.limits.scenario) is None:
            notices.append(f"{self.path / 'scenario.yaml'} is missing: {missing}")
            return None
        return load_plan(self.path, self.limits)

    def csv_rows(self, relative: str | Path) -> tuple[list[str], list[list[str]]]:
        """A CSV file's header and rows as text (a row cut short by a killed run included)."""
        text = self.read_text(relative, self.limits.csv) or ""
        # A NUL byte is text in a field on Python 3.11 and later, an error of the whole file before:
        # made a character that no number reads, it is the same on every Python.
        text = text.replace("\x00", "\ufffd")
        rows: list[list[str]] = []
        reader = csv.reader(io.StringIO(text, newline=""))
        try:
            for row in reader:
                if len(row) > 4096 or any(len(cell) > self.limits.csv_line for cell in row):
                    raise csv.Error("field larger than field limit")
                rows.append(row)
        except csv.Error:
            raise self._fault(relative, f"not a CSV line of at most {self.limits.csv_line} "
                                        "characters a field", line=reader.line_num) from None
        return (rows[0] if rows else []), rows[1:]

    def numeric_rows(self, relative: str | Path) -> tuple[list[str], list[list[float]]]:
        """A CSV's header and its whole rows of finite numbers; damaged rows (cut short, NaN, text) are left out."""
        header, rows = self.csv_rows(relative)
        out = []
        for row in rows:
            if len(row) != len(header):
                continue
            try:
                values = [float(v) for v in row]
            except ValueError:
                continue
            if all(math.isfinite(v) for v in values):
                out.append(values)
        return header, out

    def odometry(self) -> list[Path]:
        """odom/<robot>.csv files, relative to the folder."""
        return self.listing("odom", "*.csv")

    def bag_folder(self) -> Path | None:
        """bag/ when every file in it may be handed to the bag reader (regular, inside, within the size limit)."""
        bag = self.path / "bag"
        if not os.path.lexists(bag):
            return None
        if not bag.is_dir():
            raise self._fault("bag", "is not a folder")
        if not bag.resolve().is_relative_to(self.root):
            raise self._fault("bag", "points outside the run folder")
        total = 0
        for entry in sorted(bag.iterdir()):
            path = self.checked(entry.relative_to(self.path), self.limits.bag)
            total += path.stat().st_size
            if total > self.limits.bag:
                raise self._too_large("bag", self.limits.bag)
        return bag

    def json(self, relative: str) -> Any:
        """A JSON file of the folder (sweep.json); None when absent or not JSON."""
        text = self.read_text(relative, self.limits.json)
        try:
            return None if text is None else json.loads(text)
        except (ValueError, RecursionError):
            return None

    def history(self) -> Iterator[dict[str, Any]]:
        """history.jsonl of a live world: one event a line (lines that are not JSON objects left out)."""
        for line in (self.read_text("history.jsonl", self.limits.json) or "").splitlines():
            try:
                event = json.loads(line)
            except (ValueError, RecursionError):
                continue
            if isinstance(event, dict):
                yield event

    # -- faults -----------------------------------------------------------------------------

    def _check_stat(self, relative: str | Path, info: os.stat_result, limit: int) -> None:
        if stat.S_ISDIR(info.st_mode):
            raise self._fault(relative, "is a folder where a file should be")
        if not stat.S_ISREG(info.st_mode):
            raise self._fault(relative, "is not a regular file (a FIFO, socket or device is not read)")
        if info.st_size > limit:
            raise self._too_large(relative, limit)

    def _too_large(self, relative: str | Path, limit: int) -> RunFolderError:
        size = f"{limit // MIB} MiB" if limit % MIB == 0 else f"{limit} bytes"
        error = self._fault(relative, f"is larger than {size}, the most mobot reads of it")
        error.hint = f"If the file is genuine, raise the limit: {LIMITS_VARIABLE}=NAME=MIB (see docs/security.md)."
        return error

    def _fault(self, relative: str | Path, what: str, line: int | None = None) -> RunFolderError:
        where = Location(file=self.path / relative, line=line) if line else Location(file=self.path)
        message = what if line else f"{Path(relative).as_posix()} {what}"
        return RunFolderError(message, location=where, hint="The run folder is damaged or was not written by mobot.")
