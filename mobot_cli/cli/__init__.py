"""The `mobot` command: one place that turns errors into exit codes.

`main()` runs it on the process's streams; `invoke()` runs it on captured ones and returns
the exit code and what it printed, for tests and scripts. Commands print only to the
Environment they find in Typer's context object (`ctx.obj`).
"""

from __future__ import annotations

import contextlib
import sys
from dataclasses import dataclass, replace
from typing import Iterable

from mobot_cli.cli.environment import Environment, OutputClosed
from mobot_cli.cli.output import report_error
from mobot_cli.errors import ExitCode, MobotError


@dataclass(frozen=True)
class CommandResult:
    """What one command did: its exit code and everything it printed."""

    exit_code: int
    stdout: str
    stderr: str


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script: run the command line on the real streams, exit with its code."""
    args = sys.argv[1:] if argv is None else list(argv)
    sys.exit(int(_execute(args, Environment.from_process())))


def invoke(args: Iterable[object], *, stdin: str | None = None, env: Environment | None = None) -> CommandResult:
    """Run one mobot command in-process on captured streams; errors become exit codes as in main().

    Each argument is passed as str(arg), so paths and numbers may be given as they are. `stdin` is
    the text the command reads; `env` replaces the default Environment.captured(), e.g.
    Environment.captured(stderr_isatty=True) to draw progress bars (its streams must be StringIO).
    """
    if env is None:
        env = Environment.captured(stdin or "")
    elif stdin is not None:
        raise TypeError("give stdin through env: Environment.captured(stdin=...)")
    code = _execute([str(a) for a in args], env)
    return CommandResult(int(code), env.stdout.getvalue(), env.stderr.getvalue())


def _execute(args: list[str], env: Environment) -> int:
    """Run one command line on env; the one place where exceptions become exit codes."""
    if _traceback_asked(args):
        env = replace(env, traceback=True)
    try:
        try:
            # Click prints --help itself, to sys.stdout: point the sys streams at env's for the call.
            with contextlib.redirect_stdout(env.stdout), contextlib.redirect_stderr(env.stderr):
                from mobot_cli.cli.app import dispatch

                code = dispatch(args, env)
            # What is still buffered goes out now, where a reader that has gone is OutputClosed,
            # not at the interpreter's exit (an "Exception ignored" and exit 120).
            env.stdout.flush()
            return code
        except MobotError as exc:
            if env.traceback:
                raise
            try:
                report_error(env, exc)
                env.stdout.flush()
            except OutputClosed as closed:  # the error's exit code still says what went wrong
                closed.stream.discard()
            return exc.exit_code
        except KeyboardInterrupt:  # `mobot: interrupted` is said once, by the entry point (__main__.py)
            if env.traceback:
                raise
            return ExitCode.INTERRUPTED
    except OutputClosed as closed:
        # `mobot odom --follow | head -2`: the reader has what it wanted. Quiet and 0, as the reader
        # asked for no more, rather than the shell's 141 for a process killed by SIGPIPE
        # (git log | head, ls | head), which `set -o pipefail` would take for a failure.
        closed.stream.discard()
        return ExitCode.OK


def _traceback_asked(args: list[str]) -> bool:
    """--traceback among the root options, which Click reads up to the command's name.

    Read here, before Click runs, because the handler in _execute needs it and the
    Environment it hands to the commands is immutable.
    """
    for arg in args:
        if arg == "--traceback":
            return True
        if arg == "--" or not arg.startswith("-"):
            return False
    return False
