"""One exception family and one table of exit codes for every stage of mobot.

Every error carries where it happened (file, line, key) and a hint saying what to do.
Only ``mobot_cli.cli`` turns these into printed text and exit codes.
"""

from __future__ import annotations

import errno
from dataclasses import dataclass
from enum import IntEnum
from pathlib import Path
from typing import Iterable


class ExitCode(IntEnum):
    """Process exit codes, as DESIGN.md lists them."""

    OK = 0
    EXPECTATION_FAILED = 1
    BAD_INPUT = 2
    SIMULATION_FAULT = 3
    NO_LIVE_WORLD = 4
    INTERRUPTED = 130


@dataclass(frozen=True)
class Location:
    """Where an error is: a file, optionally a 1-based line, optionally a dotted key."""

    file: str | Path | None = None
    line: int | None = None
    key: str | None = None

    def __str__(self) -> str:
        parts = []
        if self.file is not None:
            parts.append(_origin(self.file) + (f":{self.line}" if self.line else ""))
        if self.key:
            parts.append(f"key {shown(self.key, 80)}")
        return ", ".join(parts)


def _origin(file: str | Path) -> str:
    """A path as is; a command-line origin (``--set KEY=VALUE``) on one line and cut short."""
    if not (isinstance(file, str) and file.startswith("--")):
        return str(file)
    text = " ".join(file.split())
    return text if len(text) <= 100 else text[:97] + "..."


class MobotError(Exception):
    """Base of every error mobot reports to a user; never shown with a traceback."""

    exit_code: ExitCode = ExitCode.BAD_INPUT

    def __init__(self, message: str, *, location: Location | None = None, hint: str | None = None):
        super().__init__(message)
        self.message = message
        self.location = location or Location()
        self.hint = hint

    def __str__(self) -> str:
        where = str(self.location)
        text = f"{where}: {self.message}" if where else self.message
        if not self.hint:
            return text
        return f"{text} {self.hint}" if text.endswith((".", "?", "!")) else f"{text}. {self.hint}"


class UsageError(MobotError):
    """Command-line arguments are malformed."""


class ScenarioError(MobotError):
    """The scenario file or a --set override is malformed or invalid."""


class ResourceError(MobotError):
    """A file, package or URI could not be found or read."""


class DescriptionError(MobotError):
    """A robot description (URDF, xacro) is broken."""


class WorldError(MobotError):
    """A world file is broken."""


class SpawnError(MobotError):
    """A robot cannot be placed where it was asked to be."""


class OutputError(MobotError):
    """A file of the output folder cannot be written: a full disk, a read-only folder, a bad --out.

    Exit 2, as for bad input: the fix is on the user's side (free space, pick another --out)."""


_WRITE_HINTS = {
    errno.ENOSPC: "Free some space or pick another --out.",
    errno.EDQUOT: "Free some space (your disk quota is used up) or pick another --out.",
    errno.EFBIG: "The file reached the size limit of this process (ulimit -f): raise the limit, or log less "
                 "(a shorter duration, a lower log.rate_hz).",
    errno.EROFS: "The file system is read-only: pick another --out.",
    errno.EACCES: "Pick a folder you may write to with --out.",
    errno.EPERM: "Pick a folder you may write to with --out.",
    errno.ENAMETOOLONG: "Use shorter names (scenario, robots, namespaces) or a shorter --out path.",
    errno.ENOTDIR: "--out must be a folder, or a path where one can be made.",
    errno.EEXIST: "--out must be a folder, or a path where one can be made.",
    errno.EISDIR: "Remove the folder that is in the way, or pick another --out.",
}


def cannot_write(path: str | Path, exc: OSError) -> OutputError:
    """``cannot write PATH: No space left on device [Errno 28]``, with what to do about it."""
    reason = f"{exc.strerror} [Errno {exc.errno}]" if exc.strerror and exc.errno else str(exc) or repr(exc)
    return OutputError(f"cannot write {path}: {reason}",
                       hint=_WRITE_HINTS.get(exc.errno, "Check the disk, or pick another --out."))


class SimulationFault(MobotError):
    """The physics went wrong during a run: a NaN state, a robot that left the world, tipped over,
    flew or ran away (docs/faults.md). ``robot``, ``step`` and ``kind`` say which, when and what,
    where known (``kind``: non_finite, out_of_world, tipped_over, flying, runaway, off_floor)."""

    exit_code = ExitCode.SIMULATION_FAULT

    def __init__(self, message: str, *, location: Location | None = None, hint: str | None = None,
                 robot: str | None = None, step: int | None = None, kind: str | None = None):
        super().__init__(message, location=location, hint=hint)
        self.robot, self.step, self.kind = robot, step, kind


class LiveWorldError(MobotError):
    """No live world answers at the endpoint (or it stopped answering)."""

    exit_code = ExitCode.NO_LIVE_WORLD


class RequestRefused(MobotError):
    """The live world refused a request; ``result`` is its simulation_interfaces-style code."""

    def __init__(self, result: str, message: str, *, hint: str | None = None):
        super().__init__(f"{result}: {message}", hint=hint)
        self.result = result


@dataclass(frozen=True)
class Notice:
    """A problem worth telling the user that does not stop the run."""

    message: str
    location: Location = Location()

    def __str__(self) -> str:
        where = str(self.location)
        return f"{where}: {self.message}" if where else self.message


def shown(value: object, limit: int = 60) -> str:
    """A user's value as an error message quotes it: its repr (one line), at most ``limit`` characters."""
    if value is None or isinstance(value, bool):
        return {None: "null", True: "true", False: "false"}[value]  # as the YAML spells them
    text = repr(value)
    if len(text) <= limit:
        return text
    quote = text[0] if text[0] in "'\"" else ""
    return text[: limit - 4] + "..." + quote


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """Return ' Did you mean 'x'?' for the closest choice, or a list of valid ones."""
    import difflib  # only when a name is misspelt

    choices = sorted(set(choices))
    close = difflib.get_close_matches(word, choices, n=1, cutoff=0.6)
    if close:
        return f"Did you mean '{close[0]}'?"
    if choices and len(choices) <= 12:
        return "Valid: " + ", ".join(f"'{c}'" for c in choices) + "."
    return ""
