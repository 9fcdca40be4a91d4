"""The `mobot` command: one Typer app, one place that turns errors into exit codes.

Command modules import heavy libraries (pybullet, pydantic, xacro) inside their functions
so that `mobot --help` stays fast.
"""

from __future__ import annotations

import sys
from typing import Optional

import typer

from mobot_cli import __version__
from mobot_cli.cli import check, inspect, run, xacro
from mobot_cli.cli import plot as plot_command
from mobot_cli.cli import sweep as sweep_command
from mobot_cli.cli import cmd, delete, odom, serve, spawn, stop
from mobot_cli.cli import list as list_command  # not `list`: that would shadow the builtin here
from mobot_cli.cli.output import STATE, report_error
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


def _version(value: bool) -> None:
    if value:
        typer.echo(f"mobot {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    traceback: bool = typer.Option(False, "--traceback", help="Show a Python traceback on errors (for bug reports)."),
    version: Optional[bool] = typer.Option(None, "--version", callback=_version, is_eager=True,
                                           help="Print the version and exit."),
) -> None:
    STATE.traceback = traceback


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
app.command("odom")(odom.odom)
app.command("stop")(stop.stop)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script; returns (and exits with) an ExitCode."""
    code = _dispatch(argv)
    sys.exit(int(code))


def _usage_error_class() -> type[Exception]:
    """Click's base exception for bad command lines, wherever this Typer keeps Click."""
    try:
        from typer._click.exceptions import ClickException  # Typer >= 0.20 vendors Click
    except ImportError:
        from click.exceptions import ClickException  # older Typer depends on Click itself
    return ClickException


UsageProblem = _usage_error_class()


def _dispatch(argv: list[str] | None) -> int:
    STATE.traceback = "--traceback" in (argv if argv is not None else sys.argv[1:])
    try:
        result = app(args=argv, prog_name="mobot", standalone_mode=False)
        return int(result) if isinstance(result, int) else ExitCode.OK
    except MobotError as exc:
        if STATE.traceback:
            raise
        report_error(exc)
        return exc.exit_code
    except typer.Exit as exc:
        return exc.exit_code
    except typer.Abort:
        return ExitCode.INTERRUPTED
    except UsageProblem as exc:
        exc.show()
        return ExitCode.BAD_INPUT
    except KeyboardInterrupt:  # `mobot: interrupted` is printed by the entry point (__main__.py)
        if STATE.traceback:
            raise
        return ExitCode.INTERRUPTED
