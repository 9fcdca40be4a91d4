"""Where the CLI reads and writes: the streams, whether they are terminals, and --traceback.

Every command gets one Environment through Typer's context object and prints only to its
streams. `main()` builds it from the real process (the only place in the CLI that looks at
sys.stdin, sys.stdout and sys.stderr); tests and scripts build one on io.StringIO.
"""

from __future__ import annotations

import io
import sys
from dataclasses import dataclass
from typing import Any, Optional, TextIO


@dataclass(frozen=True)
class Environment:
    """The streams of one command and the decisions that depend on them."""

    stdin: TextIO
    stdout: TextIO
    stderr: TextIO
    stdout_isatty: bool = False  # a terminal: Rich may style and size output for it
    stderr_isatty: bool = False  # a terminal: progress bars are drawn there, and only then
    traceback: bool = False  # --traceback: errors propagate as Python exceptions, for bug reports
    color: Optional[bool] = None  # None: Rich decides (NO_COLOR, FORCE_COLOR, TERM, the terminal)
    width: Optional[int] = None  # columns for Rich; None: $COLUMNS, the terminal's width, else 80

    @classmethod
    def from_process(cls) -> "Environment":
        """The real streams of this process, each asked once whether it is a terminal."""
        return cls(stdin=sys.stdin, stdout=sys.stdout, stderr=sys.stderr,
                   stdout_isatty=_isatty(sys.stdout), stderr_isatty=_isatty(sys.stderr))

    @classmethod
    def captured(cls, stdin: str = "", **decisions: Any) -> "Environment":
        """Fresh io.StringIO streams: plain 80-column text unless `decisions` say otherwise."""
        decisions = {"color": False, "width": 80, **decisions}
        return cls(stdin=io.StringIO(stdin), stdout=io.StringIO(), stderr=io.StringIO(), **decisions)


def _isatty(stream: Optional[TextIO]) -> bool:
    try:
        return stream is not None and stream.isatty()
    except (AttributeError, ValueError):  # closed, or not a real stream
        return False
