"""`mobot list`: the robots in the live world, with their poses and commands."""

from __future__ import annotations

from typing import Optional

import typer

from mobot_cli.cli.live import common
from mobot_cli.errors import ExitCode


def list_(
    ctx: typer.Context,
    endpoint: Optional[str] = common.ENDPOINT,
    timeout: float = typer.Option(5.0, "--timeout", help=common.TIMEOUT_HELP),
    json_: bool = typer.Option(False, "--json", help="Print the reply as JSON."),
) -> int:
    """List the robots in the live world: name, namespace, pose, command."""
    with common.client(endpoint, timeout) as world:
        reply = common.checked(world.call("list"))
    if json_:
        common.json_out(ctx.obj, reply)
    else:
        common.robot_table(ctx.obj, reply["robots"])
    return ExitCode.OK
