"""The `mobot` Typer app: every command, its options and help; `dispatch` runs a command line.

Command modules import heavy libraries (pybullet, pydantic, xacro) inside their functions
so that `mobot --help` stays fast.
"""

from __future__ import annotations

from typing import Optional

import typer

from mobot_cli import __version__
from mobot_cli.cli import barn, check, inspect, run, serve, xacro
from mobot_cli.cli import map as map_command
from mobot_cli.cli import plot as plot_command
from mobot_cli.cli import sweep as sweep_command
from mobot_cli.cli import view as view_command
from mobot_cli.cli.environment import Environment
from mobot_cli.cli.live import cmd, delete, goto, lockstep, odom, scan, spawn, stop
from mobot_cli.cli.live import list as list_command  # not `list`: that would shadow the builtin here
from mobot_cli.cli.startup import collect_garbage
from mobot_cli.errors import ExitCode

app = typer.Typer(
    name="mobot",
    help="Spawn wheeled robots into worlds and see what they do: headless, from one YAML file.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,  # plain help: Rich formatting would slow every --help
    context_settings={"help_option_names": ["-h", "--help"]},
)


def _version(ctx: typer.Context, value: bool) -> None:
    if value:
        ctx.obj.stdout.write(f"mobot {__version__}\n")
        raise typer.Exit()


@app.callback()
def _root(
    ctx: typer.Context,
    traceback: bool = typer.Option(False, "--traceback", help="Show a Python traceback on errors (for bug reports)."),
    version: Optional[bool] = typer.Option(None, "--version", callback=_version, is_eager=True,
                                           help="Print the version and exit."),
) -> None:
    # Declared here for parsing and --help; _execute has read --traceback already (_traceback_asked).
    del traceback, version
    if ctx.invoked_subcommand != "run":  # a run starts it once its scenario is loaded (cli/run.py)
        collect_garbage()


# The commands by group, in the order `mobot --help` lists them. Commands whose arguments may be
# negative numbers read dashes as values, not as options.
NEGATIVES = {"ignore_unknown_options": True}

# Scenario files: run to their end, check, look inside, plot, sweep.
app.command("run")(run.run)
app.command("check")(check.check)
app.command("inspect")(inspect.inspect)
app.command("xacro")(xacro.xacro)
app.command("plot")(plot_command.plot)
app.command("sweep")(sweep_command.sweep)
app.command("map", context_settings=NEGATIVES)(map_command.map_)  # --origin -6,-5
app.command("barn")(barn.barn)

# The live world (cli/serve.py) and its clients (cli/live/, sharing cli/live/common.py's options).
app.command("serve")(serve.serve)
app.command("spawn")(spawn.spawn)
app.command("delete")(delete.delete)
app.command("list")(list_command.list_)
app.command("cmd")(cmd.cmd)
app.command("goto", context_settings=NEGATIVES)(goto.goto)  # X, Y
app.command("odom")(odom.odom)
app.command("scan")(scan.scan)
app.command("stop")(stop.stop)

# Live clients for lockstep control, as ROS 2's simulation_interfaces (cli/live/lockstep.py).
app.command("pause")(lockstep.pause)
app.command("resume")(lockstep.resume)
app.command("step", context_settings=NEGATIVES)(lockstep.step)  # N, refused when negative
app.command("reset")(lockstep.reset)
app.command("state")(lockstep.state)
app.command("teleport")(lockstep.teleport)
app.command("features")(lockstep.features)

# The browser view of run folders.
app.command("view")(view_command.view)


def _usage_error_class() -> type[Exception]:
    """Click's base exception for bad command lines, wherever this Typer keeps Click."""
    try:
        from typer._click.exceptions import ClickException  # Typer >= 0.20 vendors Click
    except ImportError:
        from click.exceptions import ClickException  # older Typer depends on Click itself
    return ClickException


UsageProblem = _usage_error_class()


def dispatch(args: list[str], env: Environment) -> int:
    """Run one command line through Typer on env's streams; Click's own outcomes become exit codes
    (MobotError and KeyboardInterrupt propagate to the caller, cli._execute)."""
    try:
        result = app(args=args, prog_name="mobot", standalone_mode=False, obj=env)
        return int(result) if isinstance(result, int) else ExitCode.OK
    except typer.Exit as exc:
        return exc.exit_code
    except typer.Abort:
        return ExitCode.INTERRUPTED
    except UsageProblem as exc:
        exc.show(file=env.stderr)
        return ExitCode.BAD_INPUT
