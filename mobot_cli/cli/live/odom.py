"""`mobot odom NAME [--follow]`: a robot's odometry, ground truth and command."""

from __future__ import annotations

import typer

from mobot_cli.cli.live import common


def odom(
    ctx: typer.Context,
    name: str = typer.Argument(..., help="The robot to read."),
    follow: bool = typer.Option(False, "--follow", "-f", help="Keep printing readings until Ctrl-C."),
    rate: float = typer.Option(10.0, "--rate", help="Readings per second (wall clock) with --follow."),
    endpoint: common.Endpoint = None,
    timeout: common.Timeout = 5.0,
    json_: common.JsonLines = False,
) -> int:
    """Print a robot's odometry (odom frame = its spawn pose), ground truth and command."""
    env = ctx.obj
    with common.client(endpoint, timeout) as world:
        return common.read_or_follow(env, world, "odom", {"name": name}, common.odom_line,
                                          follow, rate, json_)
