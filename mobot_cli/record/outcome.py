"""How a run ended and the file that says so: all a run needs of its record until it ends.

The record's classes (record/summary.py) are imported only when a run writes its summary.
"""

from __future__ import annotations

from enum import Enum

SUMMARY = "summary.json"


class Status(str, Enum):
    """How a run (or a live world) ended."""

    OK = "ok"
    FAULT = "fault"  # the simulation broke: a NaN state, a robot left the world
    ERROR = "error"  # a bug or an unexpected failure inside mobot
    INTERRUPTED = "interrupted"  # Ctrl-C or SIGTERM before the end
