"""`mobot inspect ROBOT [NAME:=VALUE]...`: links and joints, mass, footprint, drive wheels."""

from __future__ import annotations

from pathlib import Path

import typer

from mobot_cli.cli import output
from mobot_cli.cli.args import parse_mappings
from mobot_cli.errors import ExitCode


def inspect(
    ctx: typer.Context,
    robot: str = typer.Argument(..., help="A bundled robot name or a .urdf/.xacro path."),
    mappings: list[str] = typer.Argument(None, metavar="[NAME:=VALUE]...", help="xacro arguments."),
    json_: bool = typer.Option(False, "--json", help="Print the result as JSON."),
    skip_missing: bool = typer.Option(
        False, "--skip-missing", help="Leave out visuals and collisions whose meshes are missing, with a warning."),
) -> int:
    """Show a robot's link/joint tree, total mass, footprint and detected drive."""
    from mobot_cli.assets.description.describe import load_robot
    from mobot_cli.assets.description.robot import inspect_summary

    desc = load_robot(robot, parse_mappings(mappings or []), Path.cwd(), skip_missing)
    summary = inspect_summary(desc)
    if json_:
        output.emit_json(ctx.obj, summary)
    else:
        output.notices(ctx.obj, (str(n) for n in desc.notices))
        output.inspect_tree(ctx.obj, summary)
    return ExitCode.OK
