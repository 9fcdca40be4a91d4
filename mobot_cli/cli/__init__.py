"""The `mobot` command: one Typer app, one place that turns errors into exit codes.

`main()` runs it on the process's streams; `invoke()` runs it on captured ones and returns
the exit code and what it printed, for tests and scripts. Commands print only to the
Environment they find in Typer's context object (`ctx.obj`).

Command modules import heavy libraries (pybullet, pydantic, xacro) inside their functions
so that `mobot --help` stays fast.
"""

from __future__ import annotations

import contextlib
import sys
from dataclasses import dataclass, replace
from typing import Iterable, Optional

import typer

from mobot_cli import __version__
from mobot_cli.cli import check, inspect, run, xacro
from mobot_cli.cli import plot as plot_command
from mobot_cli.cli import sweep as sweep_command
from mobot_cli.cli import cmd, delete, goto, lockstep, odom, scan, serve, spawn, stop
from mobot_cli.cli import view as view_command
from mobot_cli.cli import list as list_command  # not `list`: that would shadow the builtin here
from mobot_cli.cli.environment import Environment
from mobot_cli.cli.output import report_error
from mobot_cli.errors import ExitCode, MobotError

app = typer.Typer(
    name="mobot",
    help="Spawn wheeled robots into worlds and see what they do: headless, from one YAML file.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,  # plain help: Rich formatting costs ~150 ms on every --help
    context_settings={"help_option_names": ["-h", "--help"]},
)


def _version(ctx: typer.Context, value: bool) -> None:
    if value:
        ctx.obj.stdout.write(f"mobot {__version__}\n")
        raise typer.Exit()


@app.callback()
def _root(
    traceback: bool = typer.Option(False, "--traceback", help="Show a Python traceback on errors (for bug reports)."),
    version: Optional[bool] = typer.Option(None, "--version", callback=_version, is_eager=True,
                                           help="Print the version and exit."),
) -> None:
    # Declared here for parsing and --help; _execute has read --traceback already (_traceback_asked).
    del traceback, version


app.command("run")(run.run)
app.command("check")(check.check)
app.command("inspect")(inspect.inspect)
app.command("xacro")(xacro.xacro)
app.command("plot")(plot_command.plot)
app.command("sweep")(sweep_command.sweep)
app.command("serve")(serve.serve)
app.command("spawn")(spawn.spawn)
app.command("delete")(delete.delete)
app.command("list")(list_command.list_)
app.command("cmd")(cmd.cmd)
app.command("goto", context_settings={"ignore_unknown_options": True})(goto.goto)  # X, Y may be negative
app.command("odom")(odom.odom)
app.command("scan")(scan.scan)
app.command("stop")(stop.stop)
app.command("pause")(lockstep.pause)
app.command("resume")(lockstep.resume)
app.command("step", context_settings={"ignore_unknown_options": True})(lockstep.step)  # N may be negative: refused
app.command("reset")(lockstep.reset)
app.command("state")(lockstep.state)
app.command("teleport")(lockstep.teleport)
app.command("features")(lockstep.features)
app.command("view")(view_command.view)


@dataclass(frozen=True)
class Outcome:
    """What one command did: its exit code and everything it printed."""

    exit_code: int
    stdout: str
    stderr: str


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script: run the command line on the real streams, exit with its code."""
    args = sys.argv[1:] if argv is None else list(argv)
    sys.exit(int(_execute(args, Environment.from_process())))


def invoke(args: Iterable[object], *, stdin: str | None = None, env: Environment | None = None) -> Outcome:
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
    return Outcome(int(code), env.stdout.getvalue(), env.stderr.getvalue())


def _usage_error_class() -> type[Exception]:
    """Click's base exception for bad command lines, wherever this Typer keeps Click."""
    try:
        from typer._click.exceptions import ClickException  # Typer >= 0.20 vendors Click
    except ImportError:
        from click.exceptions import ClickException  # older Typer depends on Click itself
    return ClickException


UsageProblem = _usage_error_class()


def _execute(args: list[str], env: Environment) -> int:
    """Run one command line on env; the one place where exceptions become exit codes."""
    if _traceback_asked(args):
        env = replace(env, traceback=True)
    try:
        # Click prints --help itself, to sys.stdout: point the sys streams at env's for the call.
        with contextlib.redirect_stdout(env.stdout), contextlib.redirect_stderr(env.stderr):
            result = app(args=args, prog_name="mobot", standalone_mode=False, obj=env)
        return int(result) if isinstance(result, int) else ExitCode.OK
    except MobotError as exc:
        if env.traceback:
            raise
        report_error(env, exc)
        return exc.exit_code
    except typer.Exit as exc:
        return exc.exit_code
    except typer.Abort:
        return ExitCode.INTERRUPTED
    except UsageProblem as exc:
        exc.show(file=env.stderr)
        return ExitCode.BAD_INPUT
    except KeyboardInterrupt:  # `mobot: interrupted` is said once, by the entry point (__main__.py)
        if env.traceback:
            raise
        return ExitCode.INTERRUPTED


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
