"""`mobot xacro FILE [NAME:=VALUE]...`: print the expanded URDF, like ROS's xacro."""

from __future__ import annotations

from pathlib import Path

import typer

from mobot_cli.cli.args import parse_mappings


def xacro(
    ctx: typer.Context,
    file: str = typer.Argument(..., help="A .xacro/.urdf path or a bundled robot name."),
    mappings: list[str] = typer.Argument(None, metavar="[NAME:=VALUE]...", help="xacro arguments."),
) -> None:
    """Print the expanded URDF of a xacro file or bundled robot, mesh paths resolved."""
    from mobot_cli.assets.description.describe import expand_to_text

    text = expand_to_text(file, parse_mappings(mappings or []), Path.cwd())
    ctx.obj.stdout.write(text if text.endswith("\n") else text + "\n")
