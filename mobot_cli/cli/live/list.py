"""`mobot list`: the robots in the live world, with their poses and commands."""

from __future__ import annotations

import typer

from mobot_cli.cli.live import common
from mobot_cli.errors import ExitCode


def list_(
    ctx: typer.Context,
    endpoint: common.Endpoint = None,
    timeout: common.Timeout = 5.0,
    json_: common.Json = False,
) -> int:
    """List the robots in the live world: name, namespace, pose, command."""
    with common.client(endpoint, timeout) as world:
        reply = common.checked(world.call("list"))
    if json_:
        common.json_out(ctx.obj, reply)
    else:
        common.robot_table(ctx.obj, reply["robots"])
    return ExitCode.OK
