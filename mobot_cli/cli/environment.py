"""Where the CLI reads and writes: the streams, whether they are terminals, and --traceback.

Every command gets one Environment through Typer's context object and prints only to its
streams. `main()` builds it from the real process (the only place in the CLI that looks at
sys.stdin, sys.stdout and sys.stderr); tests and scripts build one on io.StringIO.
"""

from __future__ import annotations

import io
import os
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
        """The real streams of this process, each asked once whether it is a terminal. Standard
        output is kept for mobot alone (``_own_stdout``): what C libraries write there goes to
        standard error."""
        stdout_isatty = _isatty(sys.stdout)
        _own_stdout()
        return cls(stdin=sys.stdin, stdout=ProcessStream(sys.stdout), stderr=ProcessStream(sys.stderr),
                   stdout_isatty=stdout_isatty, stderr_isatty=_isatty(sys.stderr))

    @classmethod
    def captured(cls, stdin: str = "", **decisions: Any) -> "Environment":
        """Fresh io.StringIO streams: plain 80-column text unless `decisions` say otherwise."""
        decisions = {"color": False, "width": 80, **decisions}
        return cls(stdin=io.StringIO(stdin), stdout=io.StringIO(), stderr=io.StringIO(), **decisions)


def _own_stdout() -> None:
    """Give ``sys.stdout`` a descriptor of its own and point descriptor 1 at standard error.

    PyBullet, its mesh importers and other C code print warnings to descriptor 1 themselves
    (``b3Warning ... Unsupported texture image format``), where they would land inside
    ``--json`` answers, CSV on stdout and piped output. Silencing each call that might print
    misses the next one; this way whatever C code prints goes to standard error, and only what
    mobot writes through ``sys.stdout`` reaches standard output."""
    stream = sys.stdout
    try:
        if stream is None or stream.fileno() != 1:
            return
        stream.flush()
        own = os.dup(1)
        os.dup2(2, 1)
    except (OSError, ValueError, AttributeError, io.UnsupportedOperation):  # no real descriptor 1: nothing to guard
        return
    raw = io.FileIO(own, "w", closefd=True)
    # buffered, line-buffered or written through as the stream it replaces (PYTHONUNBUFFERED, a tty)
    binary = raw if isinstance(getattr(stream, "buffer", None), io.RawIOBase) else io.BufferedWriter(raw)
    sys.stdout = io.TextIOWrapper(binary, encoding=stream.encoding, errors=stream.errors,
                                  line_buffering=stream.line_buffering,
                                  write_through=getattr(stream, "write_through", False))


def _isatty(stream: Optional[TextIO]) -> bool:
    try:
        return stream is not None and stream.isatty()
    except (AttributeError, ValueError):  # closed, or not a real stream
        return False


class OutputClosed(Exception):
    """The reader of stdout or stderr has gone, as `mobot odom --follow | head -2`'s does once it has
    read two lines: not an error (cli._execute exits 0)."""

    def __init__(self, stream: "ProcessStream"):
        super().__init__(f"the reader of {stream.name} has gone")
        self.stream = stream


class ProcessStream:
    """sys.stdout or sys.stderr, whose broken pipe raises OutputClosed.

    A plain BrokenPipeError would be taken for any other one (a sweep worker's pipe, a socket),
    and Typer turns every EPIPE into a silent exit 1; OutputClosed is neither an OSError nor
    Click's, so it reaches cli._execute, which knows it was this stream.
    """

    def __init__(self, stream: TextIO):
        self._stream = stream

    def write(self, text: str) -> int:
        try:
            return self._stream.write(text)
        except BrokenPipeError:
            raise OutputClosed(self) from None

    def flush(self) -> None:
        try:
            self._stream.flush()
        except BrokenPipeError:
            raise OutputClosed(self) from None

    def discard(self) -> None:
        """Point the stream's file descriptor at /dev/null, so that what is still buffered, flushed
        at exit, goes nowhere instead of raising again (as Python's docs on SIGPIPE advise)."""
        devnull = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(devnull, self._stream.fileno())
        finally:
            os.close(devnull)

    def __getattr__(self, name: str) -> Any:  # isatty, fileno, encoding, name, ... as the stream's
        return getattr(self._stream, name)
