"""`mobot odom NAME [--follow]`: a robot's odometry, ground truth and command."""

from __future__ import annotations

from typing import Optional

import typer

from mobot_cli.cli.live import common


def odom(
    ctx: typer.Context,
    name: str = typer.Argument(..., help="The robot to read."),
    follow: bool = typer.Option(False, "--follow", "-f", help="Keep printing readings until Ctrl-C."),
    rate: float = typer.Option(10.0, "--rate", help="Readings per second (wall clock) with --follow."),
    endpoint: Optional[str] = common.ENDPOINT,
    timeout: float = typer.Option(5.0, "--timeout", help=common.TIMEOUT_HELP),
    json_: bool = typer.Option(False, "--json", help="Print replies as JSON (one line each with --follow)."),
) -> int:
    """Print a robot's odometry (odom frame = its spawn pose), ground truth and command."""
    env = ctx.obj
    with common.client(endpoint, timeout) as world:
        return common.read_or_follow(env, world, "odom", {"name": name}, common.odom_line,
                                          follow, rate, json_)
