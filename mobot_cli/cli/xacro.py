"""`mobot xacro FILE [NAME:=VALUE]...`: print the expanded URDF, like ROS's xacro."""

from __future__ import annotations

from pathlib import Path

import typer

from mobot_cli.cli import output
from mobot_cli.cli.args import parse_mappings


def xacro(
    ctx: typer.Context,
    file: str = typer.Argument(..., help="A .xacro/.urdf path or a bundled robot name."),
    mappings: list[str] = typer.Argument(None, metavar="[NAME:=VALUE]...", help="xacro arguments."),
    skip_missing: bool = typer.Option(False, "--skip-missing",
                                      help="Leave a mesh that cannot be found as written, with a warning."),
) -> None:
    """Print the expanded URDF of a xacro file or bundled robot, mesh paths resolved."""
    from mobot_cli.assets.description.describe import expand_to_text

    notices: list = []
    text = expand_to_text(file, parse_mappings(mappings or []), Path.cwd(), skip_missing, notices)
    ctx.obj.stdout.write(text if text.endswith("\n") else text + "\n")
    output.notices(ctx.obj, [str(n) for n in notices])
